"""Design sweeps: the Cartesian grid of scenario changes, validated before any work starts.

A sweep varies scenario values over a grid; each grid *point* is one scenario (the
base scenario with some keys changed) and one drift analysis. This module only
defines and checks the grid; :mod:`inserr.sweep.runner` runs it on Dask,
:mod:`inserr.sweep.store` keeps the per-point records of an output directory and
:mod:`inserr.sweep.figures` draws the summary.

Parameter syntax (``NAME=VALUES``: ``--param`` or ``sweep.parameters``)
-----------------------------------------------------------------------
``NAME`` is either a scenario flag of ``inserr drift`` without its dashes
(``stop``, ``rate``, ``gyro-bias``, ``lat``, ``duration``, ``scheme``, ``yaw-swing``, ...)
or a dotted scenario key (``scheme.stop``, ``imu.gyro_bias``, ``motion.period``).

``VALUES`` is a comma-separated list of values, each written exactly as after
the flag or in a scenario file:

* flag names take the flag's unit for bare numbers: ``stop=60,300`` (seconds),
  and accept an explicit unit too: ``stop=1 min,300``;
* dotted keys take scenario-file values, so quantities carry their unit:
  ``"scheme.stop=60 s,5 min"``; unit-less keys take numbers
  (``scheme.delta=0.005,0.01``) and text keys take words
  (``scheme.name=two-position,four-position``);
* a value with several components (an x,y,z IMU value, the AMP,PERIOD pair of
  ``yaw-swing``) goes in square brackets, with the unit after the bracket:
  ``gyro-bias=[0.01,0.02,0.03],0.02`` or
  ``"imu.gyro_bias=[0.01,0.02,0.03] deg/h,[0.02,0,0] deg/h"`` or
  ``yaw-swing=[6,60],[6,120]``. A single number still means all three axes.

Checks before any work
----------------------
Unknown names, empty lists, empty or duplicated values, malformed brackets, two
parameters setting the same key, and any value that is invalid in *every* point
it appears in (a wrong unit, a negative stop time) raise :class:`InputError`.
A point that is invalid only in combination (``stop=0`` is fine for
``continuous`` but not for ``two-position``) is kept in the grid with status
``invalid`` and its error message, and the rest of the sweep goes on.

Determinism
-----------
A point's identity (:attr:`Point.id`) is a hash of the base scenario, the
point's changes, the inserr version and the bytes of any file the point's
scenario reads (the ``motion.file`` heading history), so a point keeps its
identity when the grid grows or is reordered (that is what makes resuming safe),
and is computed again when the inserr version (bumped with every release that changes
results) or its input data change. Each point gets its own seed,
derived from the base seed and its changes (unless ``scenario.seed`` is swept),
so no random state is shared between points and the numbers do not depend on
which worker ran which point. The seed does not depend on the inserr version or
on file contents: a new version recomputes a point with the same random numbers.

Output directory
----------------
The default output directory is ``sweep-<slug>``, the slug made from the
scenario file's stem (or the scenario name when there is no file) with
:func:`slug`, so it is always a plain directory name.
"""

from __future__ import annotations

import argparse
import hashlib
import itertools
import json
import re
import unicodedata
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from inserr.core.errors import InputError
from inserr.core.units import UNITS, parse_quantity
from inserr.scenario.schema import SCHEMA, Scenario, all_keys, scenario_from_dict

#: Kinds of scenario values that cannot be swept (lists, tables of steps, switches).
UNSWEEPABLE = ("list", "int-list", "float-list", "table-list", "bool")
#: The sections a drift analysis reads: only their keys change a sweep's results.
SWEPT_SECTIONS = ("scenario", "site", "imu", "initial", "motion", "scheme", "output")

_BRACKET = re.compile(r"^\[(?P<inner>[^\[\]]*)\]\s*(?P<unit>.*)$")

#: Units of the two numbers of a ``yaw-swing`` value ``[AMP,PERIOD]``.
YAW_SWING_UNITS = "deg/s, s"


@dataclass(frozen=True)
class Param:
    """One swept parameter.

    Parameters
    ----------
    name : str
        As written by the user: a flag name (``"stop"``) or a dotted key (``"scheme.stop"``).
    values : tuple of str
        Each value as written (brackets included), used as the table cell.
    changes : tuple of dict
        For each value, the dotted scenario keys it sets and their raw values.
    key : str or None
        The main dotted key (None for ``yaw-swing``, which sets three keys).
    unit : str or None
        Unit of bare numbers (flag names only).
    """

    name: str
    values: tuple[str, ...]
    changes: tuple[dict[str, Any], ...]
    key: str | None
    unit: str | None = None

    def axis(self) -> tuple[list[float] | None, str]:
        """Numeric positions of the values for plots, and the axis label.

        Returns
        -------
        positions : list of float or None
            Each value as a number in the unit of the label (e.g. seconds for
            ``stop=1 min,300``), or None when the values are not all single
            numbers of one kind (names, x,y,z triples, pairs): plots then space
            them evenly.
        label : str
            The name, with the unit of the positions when they have one
            (``"stop (s)"``).
        """
        nums, unit = self._numeric()
        return nums, f"{self.name} ({unit})" if nums is not None and unit else self.name

    def _numeric(self) -> tuple[list[float] | None, str]:
        """Numeric positions of the values and their unit (``""`` for unit-less numbers)."""
        if self.key is None:
            return None, ""
        section, _, k = self.key.partition(".")
        kind = SCHEMA[section][k].kind
        if kind in ("float", "int"):
            try:
                return [float(v) for v in self.values], ""
            except ValueError:
                return None, ""
        if kind not in UNITS or any("[" in v for v in self.values):
            return None, ""
        unit = self.unit or _written_unit(self.values[0])
        if unit not in UNITS[kind]:
            return None, ""
        try:
            nums = [
                float(parse_quantity(v, kind, self.name, default_unit=unit)) / UNITS[kind][unit]
                for v in self.values
            ]
        except InputError:
            return None, ""
        return nums, unit

    def unit_of(self, value: str) -> str | None:
        """Unit a value is written in: its own unit, else the flag's unit for bare numbers.

        Parameters
        ----------
        value : str
            One of :attr:`values`, as written (``"60"``, ``"1 min"``, ``"[1,2,3] deg/h"``).

        Returns
        -------
        str or None
            ``"min"`` for ``"1 min"``; the flag's unit (``"s"`` for ``stop``) for a
            bare number or bracketed numbers; :data:`YAW_SWING_UNITS` for a bare
            ``yaw-swing`` pair; None for words and unit-less numbers.
        """
        inner, written = value, _written_unit(value)
        m = _BRACKET.match(value)
        if m:
            inner, written = m.group("inner"), m.group("unit").strip()
        if written:
            return written
        if not all(_is_number(x) for x in inner.split(",")):
            return None  # a word, or bracketed parts that carry their own units
        return YAW_SWING_UNITS if self.name == "yaw-swing" else self.unit

    def unit_shown(self) -> str:
        """Unit to print next to the parameter's name on a plot (``""`` for none).

        Returns
        -------
        str
            The unit of :meth:`axis` positions when the values are numeric; else
            the unit shared by all values, or the flag's unit if some values are
            bare numbers; else ``""`` (names, unit-less numbers, mixed units).
        """
        nums, unit = self._numeric()
        if nums is not None:
            return unit
        units = {self.unit_of(v) for v in self.values}
        if len(units) == 1:
            return next(iter(units)) or ""
        return self.unit if self.unit in units else ""

    def label(self) -> str:
        """Axis label: the name and, where one applies, the unit (``"rate (deg/s)"``).

        Returns
        -------
        str
        """
        unit = self.unit_shown()
        return f"{self.name} ({unit})" if unit else self.name

    def ticks(self) -> list[str]:
        """Tick text of each value, in the unit of :meth:`label`.

        Returns
        -------
        list of str
            Numbers in the label's unit when the values are numeric (``"60"`` for
            ``1 min`` under ``stop (s)``); otherwise each value as written, without
            its unit when that is the label's unit.
        """
        nums, _ = self._numeric()
        if nums is not None:
            return [f"{n:g}" for n in nums]
        unit = self.unit_shown()
        out = []
        for v in self.values:
            written = m.group("unit").strip() if (m := _BRACKET.match(v)) else _written_unit(v)
            if unit and written == unit:
                v = v[: len(v) - len(written)].rstrip()
            out.append(v)
        return out

    def value_texts(self) -> list[str]:
        """Each value with its unit, for titles (``"20 deg"``, ``"[6,60] (deg/s, s)"``).

        Returns
        -------
        list of str
        """
        unit = self.unit_shown()
        if not unit:
            return list(self.ticks())
        suffix = f" ({unit})" if "," in unit else f" {unit}"
        return [
            t + suffix if t != v or self.unit_of(v) == unit else t
            for t, v in zip(self.ticks(), self.values, strict=True)
        ]


@dataclass(frozen=True)
class Point:
    """One grid point: a value of every parameter.

    Attributes
    ----------
    index : int
        Position in the grid (Cartesian order, last parameter fastest).
    values : tuple of str
        The value of each parameter, as written.
    changes : dict
        Dotted scenario key -> raw value, including the point's ``scenario.seed``.
    id : str
        Stable identity: hash of the base scenario, the changes, the inserr
        version and the bytes of any file the point's scenario reads.
    seed : int
        Seed of the point's random numbers (see :func:`point_identity`).
    error : str
        Empty, or why this combination is not a valid scenario (status ``invalid``).
    """

    index: int
    values: tuple[str, ...]
    changes: dict[str, Any]
    id: str
    seed: int
    error: str = ""


@dataclass(frozen=True)
class Grid:
    """A validated sweep: base scenario, parameters and points (in grid order).

    Attributes
    ----------
    base : Scenario
        The scenario every point changes.
    params : tuple of Param
        The swept parameters, first one slowest in :attr:`points`.
    points : tuple of Point
        Every combination of values, in Cartesian order.
    """

    base: Scenario
    params: tuple[Param, ...]
    points: tuple[Point, ...] = field(repr=False)

    @property
    def shape(self) -> tuple[int, ...]:
        """Number of values of each parameter.

        Returns
        -------
        tuple of int
            One entry per parameter; the product is the number of points.
        """
        return tuple(len(p.values) for p in self.params)

    def payload(self, point: Point) -> str:
        """What a worker needs to run ``point``, as JSON text (opaque to Dask's graph).

        Parameters
        ----------
        point : Point
            A point of this grid.

        Returns
        -------
        str
            JSON with the point's id, the base scenario (raw values and directory)
            and the point's changes; :func:`inserr.sweep.runner.run_point` reads it.
        """
        return json.dumps(
            {
                "id": point.id,
                "base": self.base.raw,
                "base_dir": base_dir_text(self.base),
                "changes": point.changes,
            },
            default=str,
        )


def split_values(text: str, name: str) -> list[str]:
    """Split ``"60,300"`` or ``"[1,2,3] deg/h,0.5 deg/h"`` into values (commas in brackets stay).

    Parameters
    ----------
    text : str
        The part of ``--param`` after ``=``.
    name : str
        The parameter's name, for error messages.

    Returns
    -------
    list of str
        The values, stripped, in the order written.

    Raises
    ------
    InputError
        Empty list or value, duplicated values, nested or unbalanced brackets.
    """
    items: list[str] = []
    depth = 0
    cur: list[str] = []
    for ch in text:
        if ch == "[":
            depth += 1
            if depth > 1:
                raise InputError(
                    f"sweep.parameters[{name}]", "nested brackets", "write e.g. [0.01,0.02,0.03]"
                )
        elif ch == "]":
            depth -= 1
            if depth < 0:
                raise InputError(
                    f"sweep.parameters[{name}]", "']' without '['", "write e.g. [0.01,0.02,0.03]"
                )
        if ch == "," and depth == 0:
            items.append("".join(cur).strip())
            cur = []
        else:
            cur.append(ch)
    if depth:
        raise InputError(f"sweep.parameters[{name}]", "unclosed '['", "write e.g. [0.01,0.02,0.03]")
    items.append("".join(cur).strip())
    if items == [""]:
        raise InputError(
            f"sweep.parameters[{name}]", "empty list of values", f"give e.g. {name}=V1,V2"
        )
    for v in items:
        if not v:
            raise InputError(
                f"sweep.parameters[{name}]", f"empty value in {text!r}", "remove the extra comma"
            )
    dup = sorted({v for v in items if items.count(v) > 1})
    if dup:
        raise InputError(
            f"sweep.parameters[{name}]",
            f"duplicated value(s) {', '.join(dup)}",
            "list each value once",
        )
    return items


def _unbracket(value: str, name: str) -> str:
    """``"[1,2,3] deg/h"`` -> ``"1,2,3 deg/h"``; other values unchanged."""
    if "[" not in value:
        return value
    m = _BRACKET.match(value)
    if not m:
        raise InputError(
            f"sweep.parameters[{name}]",
            f"cannot read {value!r}",
            "write [x,y,z] followed by an optional unit",
        )
    return f"{m.group('inner').strip()} {m.group('unit').strip()}".strip()


def _written_unit(value: str) -> str:
    """Unit written after a number (``"1 min"`` -> ``"min"``; ``""`` for none or a word)."""
    m = re.match(r"^\s*([-+0-9.eE]+)\s*(.*)$", value)
    return m.group(2).strip() if m and _is_number(m.group(1)) else ""


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _flatten(nested: dict[str, dict[str, Any]]) -> dict[str, Any]:
    return {f"{s}.{k}": v for s, table in nested.items() for k, v in table.items()}


def parse_param(text: str) -> Param:
    """Parse one ``NAME=V1,V2,...`` (see the module docstring for the value syntax).

    Parameters
    ----------
    text : str
        One ``--param`` argument, e.g. ``"stop=60,300"`` (bare numbers in the
        flag's unit, here seconds) or ``"scheme.stop=60 s,5 min"``.

    Returns
    -------
    Param

    Raises
    ------
    InputError
        Missing ``=``, unknown name, a key that cannot be swept, empty or
        duplicated values, malformed brackets.
    """
    from inserr.scenario.flags import FLAGS, dest, flags_to_dict

    name, eq, rest = text.partition("=")
    name = name.strip().removeprefix("--")
    if not eq or not name:
        raise InputError(
            "sweep.parameters", f"expected NAME=V1,V2,..., got {text!r}", "e.g. stop=60,300"
        )
    field_ = f"sweep.parameters[{name}]"
    values = split_values(rest, name)
    if "." in name:
        section, _, k = name.partition(".")
        if section not in SCHEMA or k not in SCHEMA[section]:
            raise InputError(
                field_, "unknown scenario key", f"use one of: {', '.join(sweepable_keys())}"
            )
        spec = SCHEMA[section][k]
        if not _sweepable(name):
            raise InputError(
                field_,
                "this key cannot be swept",
                "sweep a scalar or x,y,z key the drift analysis reads",
            )
        changes = tuple({name: _raw_value(spec.kind, _unbracket(v, name), name)} for v in values)
        return Param(name, tuple(values), changes, name)
    flag = FLAGS.get(name)
    if flag is None or not all(_sweepable(key) for key in flag.keys):
        raise InputError(
            field_,
            "unknown parameter",
            "use a flag name of inserr drift (e.g. stop, rate, gyro-bias, lat, scheme) "
            "or a dotted scenario key (e.g. scheme.stop)",
        )
    changes = []
    for v in values:
        ns = argparse.Namespace(**{dest(name): _unbracket(v, name)})
        try:
            changes.append(_flatten(flags_to_dict(ns, [name])))
        except InputError as exc:
            raise InputError(field_, f"value {v!r}: {exc.problem}", exc.fix) from None
    if len(flag.keys) > 1:  # yaw-swing: AMP,PERIOD (and the motion type)
        return Param(name, tuple(values), tuple(changes), None, None)
    return Param(name, tuple(values), tuple(changes), flag.keys[0], flag.unit)


def _sweepable(key: str) -> bool:
    """A key of the drift analysis holding one value or one x,y,z (or six) value."""
    section, _, k = key.partition(".")
    if section not in SWEPT_SECTIONS:
        return False
    spec = SCHEMA[section][k]
    return spec.kind not in UNSWEEPABLE and spec.size != "list"


def sweepable_keys() -> list[str]:
    """Every dotted key a sweep may vary."""
    return [k for k in all_keys() if _sweepable(k)]


def _raw_value(kind: str, text: str, name: str) -> Any:
    """A dotted key's value as a scenario file would hold it (numbers for unit-less kinds)."""
    try:
        if kind == "float":
            return float(text)
        if kind == "int":
            return int(text)
    except ValueError:
        raise InputError(f"sweep.parameters[{name}]", f"{text!r} is not a number") from None
    return text


def _canonical(obj: Any) -> str:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), default=str)


def point_identity(
    base: Scenario, changes: dict[str, Any], *, digests: dict[Path, str] | None = None
) -> tuple[str, int]:
    """Identity and seed of the point ``changes`` of ``base``, independent of grid order.

    Parameters
    ----------
    base : Scenario
        The base scenario.
    changes : dict
        Dotted scenario key -> raw value set by the point (without its seed).
    digests : dict, optional
        Cache of file digests (path -> SHA-256), shared by the points of one grid
        so that a heading-history file is read once.

    Returns
    -------
    id : str
        16 hex digits: SHA-256 of the base scenario, the changes, the inserr
        version and the bytes of the file the point's scenario reads, if any
        (:func:`referenced_files`). A new version or an edited file gives a new
        id, so a resumed sweep computes the point again.
    seed : int
        32-bit seed from the base seed and the changes only, so that the random
        numbers of a point do not change with the version or the file.
    """
    import inserr

    files = {}
    for path in referenced_files(base, changes):
        if digests is not None and path in digests:
            files[str(path)] = digests[path]
            continue
        try:
            digest = hashlib.sha256(path.read_bytes()).hexdigest()
        except OSError as exc:
            digest = f"unreadable: {type(exc).__name__}"  # the point is invalid anyway
        if digests is not None:
            digests[path] = digest
        files[str(path)] = digest
    base_text = _canonical({"raw": base.raw, "dir": base_dir_text(base)})
    change_text = _canonical(changes)
    extra = _canonical({"inserr": inserr.__version__, "files": files})
    pid = hashlib.sha256(f"{base_text}|{change_text}|{extra}".encode()).hexdigest()[:16]
    seed_hash = hashlib.sha256(f"{base.seed}|{change_text}".encode()).digest()
    return pid, int.from_bytes(seed_hash[:4], "big")


def referenced_files(base: Scenario, changes: dict[str, Any]) -> list[Path]:
    """Files the scenario of a point reads: the ``motion.file`` of a heading history.

    Parameters
    ----------
    base : Scenario
        The base scenario (its directory resolves relative file names).
    changes : dict
        Dotted scenario key -> raw value set by the point.

    Returns
    -------
    list of Path
        Absolute paths (empty unless ``motion.type`` is ``heading-history`` and
        ``motion.file`` is set), resolved as :mod:`inserr.scenario.schema` does.
    """
    motion = base.raw.get("motion", {})
    kind = changes.get("motion.type", motion.get("type", SCHEMA["motion"]["type"].default))
    name = changes.get("motion.file", motion.get("file", ""))
    if kind != "heading-history" or not name:
        return []
    path = Path(str(name))
    if base.base_dir is not None and not path.is_absolute():
        path = Path(base.base_dir) / path
    return [path.resolve()]


def build_grid(base: Scenario, param_texts: list[str] | None = None) -> Grid:
    """Parse and validate the swept parameters into a :class:`Grid` over ``base``.

    Every point's scenario is built here (cheap next to its analysis) so that bad
    input is reported before any work starts.

    Parameters
    ----------
    base : Scenario
        The scenario every point changes; its ``sweep.parameters`` are the
        parameters unless ``param_texts`` is given. The grid's base is ``base``
        without its ``[sweep]`` section, so that a point keeps its identity when
        parameters are added.
    param_texts : list of str, optional
        ``NAME=V1,V2,...`` texts, in order (the last varies fastest).

    Returns
    -------
    Grid

    Raises
    ------
    InputError
        Bad syntax, unknown name, empty list, a parameter given twice, two
        parameters setting the same key, or a value that is invalid in every point.
    """
    if param_texts is None:
        param_texts = list(base.value("sweep.parameters"))
    if "sweep" in base.raw:
        raw = {k: v for k, v in base.raw.items() if k != "sweep"}
        base = scenario_from_dict(raw, base.base_dir, study=base.study, analysis=base.analysis)
    if not param_texts:
        raise InputError("sweep.parameters", "nothing to sweep", "give at least one NAME=V1,V2")
    params = tuple(parse_param(t) for t in param_texts)
    seen: dict[str, str] = {}
    for p in params:
        if p.name in seen.values():
            raise InputError(
                f"sweep.parameters[{p.name}]", "given twice", "merge the values into one parameter"
            )
        for key in {k for ch in p.changes for k in ch}:
            if key in seen:
                raise InputError(
                    f"sweep.parameters[{p.name}]",
                    f"sets {key}, which {seen[key]} already sets",
                    "drop one of them",
                )
            seen[key] = p.name
    seed_swept = "scenario.seed" in seen
    digests: dict[Path, str] = {}
    points = []
    for index, combo in enumerate(itertools.product(*(range(len(p.values)) for p in params))):
        changes: dict[str, Any] = {}
        for p, i in zip(params, combo, strict=True):
            changes.update(p.changes[i])
        pid, seed = point_identity(base, changes, digests=digests)
        if not seed_swept:
            changes["scenario.seed"] = seed
        else:
            seed = int(changes["scenario.seed"])
        error = ""
        try:
            base.with_changes(changes)
        except InputError as exc:
            error = str(exc)
        values = tuple(p.values[i] for p, i in zip(params, combo, strict=True))
        points.append(Point(index, values, changes, pid, seed, error))
    _reject_duplicate_points(params, points)
    _reject_hopeless_values(params, points)
    return Grid(base, params, tuple(points))


def _reject_duplicate_points(params: tuple[Param, ...], points: list[Point]) -> None:
    """Two values written differently but meaning the same (``60`` and ``60 s``) are one point."""
    first: dict[str, Point] = {}
    for pt in points:
        if pt.id in first:
            pairs = zip(first[pt.id].values, pt.values, strict=True)
            j = next(j for j, (a, b) in enumerate(pairs) if a != b)
            raise InputError(
                f"sweep.parameters[{params[j].name}]",
                f"values {first[pt.id].values[j]!r} and {pt.values[j]!r} are the same",
                "list each value once",
            )
        first[pt.id] = pt


def _reject_hopeless_values(params: tuple[Param, ...], points: list[Point]) -> None:
    """Raise for the first value that no point can run (a grid error, not a bad combination)."""
    for j, p in enumerate(params):
        for v in p.values:
            errors = [pt.error for pt in points if pt.values[j] == v]
            if errors and all(errors):
                raise InputError(
                    f"sweep.parameters[{p.name}]",
                    f"value {v!r} is invalid in every point: {errors[0]}",
                )


def describe_grid(grid: Grid) -> dict[str, Any]:
    """Plain description of a grid (for the output directory's manifest and JSON output).

    Parameters
    ----------
    grid : Grid

    Returns
    -------
    dict
        Base scenario (raw values and directory), parameters with their values,
        and each point's index, id and values; JSON-serialisable.
    """
    return {
        "base_scenario": grid.base.raw,
        "base_dir": base_dir_text(grid.base),
        "params": [{"name": p.name, "values": list(p.values)} for p in grid.params],
        "points": [
            {"index": pt.index, "id": pt.id, "values": list(pt.values)} for pt in grid.points
        ],
    }


def base_dir_text(base: Scenario) -> str | None:
    """Absolute directory of the base scenario file (workers may run in another directory).

    Parameters
    ----------
    base : Scenario

    Returns
    -------
    str or None
        None when the scenario came from flags only.
    """
    return str(Path(base.base_dir).resolve()) if base.base_dir is not None else None


#: Longest slug :func:`slug` returns (directory names stay readable and portable).
SLUG_MAX = 60


def slug(text: str) -> str:
    """A safe directory-name part: lowercase ASCII letters, digits, ``-`` and ``_``.

    Accents are dropped (``é`` -> ``e``), every other run of characters (spaces,
    ``:``, ``,``, ``/``, ``.``) becomes one ``-``, and the result is at most
    :data:`SLUG_MAX` characters with no leading or trailing ``-``/``_``.

    Parameters
    ----------
    text : str
        E.g. ``"sweep-quickstart: 72 h at rest, single- and dual-axis indexing"``.

    Returns
    -------
    str
        E.g. ``"sweep-quickstart-72-h-at-rest-single-and-dual-axis-indexing"``;
        ``"scenario"`` when nothing usable is left.
    """
    ascii_text = unicodedata.normalize("NFKD", text).encode("ascii", "ignore").decode()
    out = re.sub(r"[^a-z0-9_-]+", "-", ascii_text.lower())
    out = re.sub(r"-{2,}", "-", out).strip("-_")
    return out[:SLUG_MAX].rstrip("-_") or "scenario"


def default_out_dir(base: Scenario, scenario_file: str | Path | None = None) -> str:
    """Default output directory of a sweep: ``sweep-<slug>``, relative to the working directory.

    Parameters
    ----------
    base : Scenario
        The base scenario (its name is used when there is no file).
    scenario_file : str or Path, optional
        The scenario file given on the command line; its stem names the directory.

    Returns
    -------
    str
        E.g. ``"sweep-quickstart"`` for ``analyses/quickstart/quickstart.toml``,
        ``"sweep-scenario"`` for a scenario from flags only.
    """
    stem = Path(scenario_file).stem if scenario_file else base.name
    return f"sweep-{slug(stem)}"
