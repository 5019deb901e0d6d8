"""Design sweeps: the Cartesian grid of scenario changes, validated before any work starts.

A sweep varies scenario values over a grid; each grid *point* is one scenario (the
base scenario with some keys changed) and one drift analysis. This module only
defines and checks the grid; :mod:`inserr.sweep_run` runs it on Dask,
:mod:`inserr.sweep_store` keeps the per-point records of an output directory and
:mod:`inserr.sweep_plots` draws the summary.

Parameter syntax (``--param NAME=VALUES``)
------------------------------------------
``NAME`` is either a scenario flag of ``inserr drift`` without its dashes
(``stop``, ``rate``, ``gyro-bias``, ``lat``, ``hours``, ``scheme``, ``yaw-swing``, ...)
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
A point's identity (:attr:`Point.id`) is a hash of the base scenario and the
point's changes, so a point keeps its identity when the grid grows or is
reordered (that is what makes resuming safe). Each point gets its own seed,
derived from the base seed and its changes (unless ``scenario.seed`` is swept),
so no random state is shared between points and the numbers do not depend on
which worker ran which point.
"""

from __future__ import annotations

import argparse
import hashlib
import itertools
import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from inserr.errors import InputError
from inserr.scenario import SCHEMA, Scenario, all_keys
from inserr.units import UNITS, parse_quantity

#: Kinds of scenario values that cannot be swept (lists of names, tables of steps).
UNSWEEPABLE = ("list", "table-list")

_BRACKET = re.compile(r"^\[(?P<inner>[^\[\]]*)\]\s*(?P<unit>.*)$")


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

        Returns ``(None, name)`` when the values are not all single numbers of one
        kind (names, x,y,z triples, pairs): plots then space them evenly.
        """
        if self.key is None:
            return None, self.name
        section, _, k = self.key.partition(".")
        kind, _, _ = SCHEMA[section][k]
        if kind in ("float", "int"):
            try:
                return [float(v) for v in self.values], self.name
            except ValueError:
                return None, self.name
        if kind not in UNITS or any("[" in v for v in self.values):
            return None, self.name
        unit = self.unit or _written_unit(self.values[0])
        if unit not in UNITS[kind]:
            return None, self.name
        try:
            nums = [
                float(parse_quantity(v, kind, self.name, default_unit=unit)) / UNITS[kind][unit]
                for v in self.values
            ]
        except InputError:
            return None, self.name
        return nums, f"{self.name} ({unit})" if unit else self.name


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
        Stable identity: hash of the base scenario and the changes.
    seed : int
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
    """A validated sweep: base scenario, parameters and points (in grid order)."""

    base: Scenario
    params: tuple[Param, ...]
    points: tuple[Point, ...] = field(repr=False)

    @property
    def shape(self) -> tuple[int, ...]:
        """Number of values of each parameter."""
        return tuple(len(p.values) for p in self.params)

    def payload(self, point: Point) -> str:
        """What a worker needs to run ``point``, as JSON text (opaque to Dask's graph)."""
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
    """Split ``"60,300"`` or ``"[1,2,3] deg/h,0.5 deg/h"`` into values (commas in brackets stay)."""
    items: list[str] = []
    depth = 0
    cur: list[str] = []
    for ch in text:
        if ch == "[":
            depth += 1
            if depth > 1:
                raise InputError(
                    f"--param {name}", "nested brackets", "write e.g. [0.01,0.02,0.03]"
                )
        elif ch == "]":
            depth -= 1
            if depth < 0:
                raise InputError(
                    f"--param {name}", "']' without '['", "write e.g. [0.01,0.02,0.03]"
                )
        if ch == "," and depth == 0:
            items.append("".join(cur).strip())
            cur = []
        else:
            cur.append(ch)
    if depth:
        raise InputError(f"--param {name}", "unclosed '['", "write e.g. [0.01,0.02,0.03]")
    items.append("".join(cur).strip())
    if items == [""]:
        raise InputError(f"--param {name}", "empty list of values", f"give e.g. {name}=V1,V2")
    for v in items:
        if not v:
            raise InputError(
                f"--param {name}", f"empty value in {text!r}", "remove the extra comma"
            )
    dup = sorted({v for v in items if items.count(v) > 1})
    if dup:
        raise InputError(
            f"--param {name}", f"duplicated value(s) {', '.join(dup)}", "list each value once"
        )
    return items


def _unbracket(value: str, name: str) -> str:
    """``"[1,2,3] deg/h"`` -> ``"1,2,3 deg/h"``; other values unchanged."""
    if "[" not in value:
        return value
    m = _BRACKET.match(value)
    if not m:
        raise InputError(
            f"--param {name}",
            f"cannot read {value!r}",
            "write [x,y,z] followed by an optional unit",
        )
    return f"{m.group('inner').strip()} {m.group('unit').strip()}".strip()


def _written_unit(value: str) -> str:
    m = re.match(r"^\s*[-+0-9.eE]+\s*(.*)$", value)
    return m.group(1).strip() if m else ""


def _flatten(nested: dict[str, dict[str, Any]]) -> dict[str, Any]:
    return {f"{s}.{k}": v for s, table in nested.items() for k, v in table.items()}


def parse_param(text: str) -> Param:
    """Parse one ``NAME=V1,V2,...`` (see the module docstring for the value syntax).

    Raises
    ------
    InputError
        Missing ``=``, unknown name, a key that cannot be swept, empty or
        duplicated values, malformed brackets.
    """
    from inserr.cli.flags import FLAGS, YAW_SWING, flags_to_dict

    name, eq, rest = text.partition("=")
    name = name.strip().removeprefix("--")
    if not eq or not name:
        raise InputError(
            "--param", f"expected NAME=V1,V2,..., got {text!r}", "e.g. --param stop=60,300"
        )
    values = split_values(rest, name)
    if "." in name:
        section, _, k = name.partition(".")
        if section not in SCHEMA or k not in SCHEMA[section]:
            raise InputError(
                f"--param {name}", "unknown scenario key", f"use one of: {', '.join(all_keys())}"
            )
        kind = SCHEMA[section][k][0]
        if kind in UNSWEEPABLE:
            raise InputError(
                f"--param {name}", "this key cannot be swept", "sweep a scalar or x,y,z key"
            )
        changes = tuple({name: _raw_value(kind, _unbracket(v, name), name)} for v in values)
        return Param(name, tuple(values), changes, name)
    if name not in FLAGS and name != YAW_SWING:
        raise InputError(
            f"--param {name}",
            "unknown parameter",
            "use a flag name of inserr drift (e.g. stop, rate, gyro-bias, lat, scheme) "
            "or a dotted scenario key (e.g. scheme.stop)",
        )
    changes = []
    for v in values:
        ns = argparse.Namespace(**{name.replace("-", "_"): _unbracket(v, name)})
        try:
            changes.append(_flatten(flags_to_dict(ns)))
        except InputError as exc:
            raise InputError(f"--param {name}", f"value {v!r}: {exc.problem}", exc.fix) from None
    key, unit = (FLAGS[name][0], FLAGS[name][1]) if name in FLAGS else (None, None)
    return Param(name, tuple(values), tuple(changes), key, unit)


def _raw_value(kind: str, text: str, name: str) -> Any:
    """A dotted key's value as a scenario file would hold it (numbers for unit-less kinds)."""
    try:
        if kind == "float":
            return float(text)
        if kind == "int":
            return int(text)
    except ValueError:
        raise InputError(f"--param {name}", f"{text!r} is not a number") from None
    return text


def _canonical(obj: Any) -> str:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), default=str)


def point_identity(base: Scenario, changes: dict[str, Any]) -> tuple[str, int]:
    """(id, seed) of the point ``changes`` of ``base``: hashes, independent of grid order."""
    base_text = _canonical({"raw": base.raw, "dir": base_dir_text(base)})
    change_text = _canonical(changes)
    pid = hashlib.sha256(f"{base_text}|{change_text}".encode()).hexdigest()[:16]
    seed_hash = hashlib.sha256(f"{base.seed}|{change_text}".encode()).digest()
    return pid, int.from_bytes(seed_hash[:4], "big")


def build_grid(base: Scenario, param_texts: list[str]) -> Grid:
    """Parse and validate the ``--param`` texts into a :class:`Grid` over ``base``.

    Every point's scenario is built here (cheap next to its analysis) so that bad
    input is reported before any work starts.

    Raises
    ------
    InputError
        Bad syntax, unknown name, empty list, a parameter given twice, two
        parameters setting the same key, or a value that is invalid in every point.
    """
    if not param_texts:
        raise InputError("--param", "nothing to sweep", "give at least one --param NAME=V1,V2")
    params = tuple(parse_param(t) for t in param_texts)
    seen: dict[str, str] = {}
    for p in params:
        if p.name in seen.values():
            raise InputError(
                f"--param {p.name}", "given twice", "merge the values into one --param"
            )
        for key in {k for ch in p.changes for k in ch}:
            if key in seen:
                raise InputError(
                    f"--param {p.name}",
                    f"sets {key}, which --param {seen[key]} already sets",
                    "drop one of them",
                )
            seen[key] = p.name
    seed_swept = "scenario.seed" in seen
    points = []
    for index, combo in enumerate(itertools.product(*(range(len(p.values)) for p in params))):
        changes: dict[str, Any] = {}
        for p, i in zip(params, combo, strict=True):
            changes.update(p.changes[i])
        pid, seed = point_identity(base, changes)
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
                f"--param {params[j].name}",
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
                    f"--param {p.name}", f"value {v!r} is invalid in every point: {errors[0]}"
                )


def describe_grid(grid: Grid) -> dict[str, Any]:
    """Plain description of a grid (for the output directory's manifest and JSON output)."""
    return {
        "base_scenario": grid.base.raw,
        "base_dir": base_dir_text(grid.base),
        "params": [{"name": p.name, "values": list(p.values)} for p in grid.params],
        "points": [
            {"index": pt.index, "id": pt.id, "values": list(pt.values)} for pt in grid.points
        ],
    }


def base_dir_text(base: Scenario) -> str | None:
    """Absolute directory of the base scenario file (workers may run in another directory)."""
    return str(Path(base.base_dir).resolve()) if base.base_dir is not None else None
