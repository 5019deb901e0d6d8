"""The motions a schedule is designed for, and the held-out motions that test it.

A motion is written as a small JSON-able *spec* (SI units: rad, rad/s, s) so that it
can travel to a Dask worker, name an evaluation in the cache and label a table row;
:func:`build_motion` turns a spec back into a
:class:`~inserr.schemes.vehicle_motion.Motion`. The ``[design]`` section of the
scenario declares the set (``design.motions``):

* ``grid``: every combination of ``periods`` x ``amplitudes`` x ``headings`` of a yaw
  swing, at the scenario's pitch and roll (``headings`` absent: the scenario's);
* ``grid+draws``: the grid, then ``draws`` training draws as ``random`` (the grid
  keeps the figure a design is judged on; the draws vary what the grid holds fixed,
  heading above all, and fill the periods between the grid's, where an open-loop
  cycle can resonate unseen);
* ``random``: ``draws`` seeded draws of a yaw swing, period log-uniform in
  ``period_range``, peak yaw rate uniform in ``amplitude_range``, heading, pitch and
  roll uniform in their ranges (a range absent: the scenario's value);
* ``scenario``: the scenario's own ``[motion]`` (a static base, a turn, a heading
  history, one swing);
* ``files``: heading histories (CSV ``time_s, heading_deg``, as ``motion.file``) at
  the scenario's pitch and roll.

The held-out motions (``design.held_out`` of them) are seeded draws from the same
ranges as ``random`` but from another stream of the seed (:data:`HELD_OUT_STREAM`;
the training draws use :data:`DESIGN_STREAM`), so they never coincide with a design
set: the optimizer never sees them.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from inserr.core.errors import InputError
from inserr.core.units import DEG
from inserr.scenario.schema import Scenario
from inserr.schemes.vehicle_motion import HeadingHistory, Motion, Turn, YawSwing

#: Seed streams (``np.random.default_rng([seed, stream])``) of the two random sets.
DESIGN_STREAM = 0
HELD_OUT_STREAM = 1


@dataclass(frozen=True)
class MotionCase:
    """One motion of a set.

    Attributes
    ----------
    spec : dict
        JSON-able description, SI: ``type`` (``static``, ``yaw-swing``, ``turn``,
        ``heading-history``), ``heading``, ``pitch``, ``roll`` (rad), and per type
        ``amplitude`` (rad/s) and ``period`` (s), ``rate`` (rad/s), or ``file`` (path)
        and ``sha256`` (of the file's bytes, so an edited file is a new motion).
    label : str
        Short text for tables (degrees and seconds).
    """

    spec: dict[str, Any] = field(compare=False)
    label: str = ""

    @property
    def key(self) -> str:
        """Canonical JSON of the spec (what names the motion in the cache)."""
        return canonical(self.spec)

    @property
    def period(self) -> float | None:
        """Swing period, s (None unless a yaw swing)."""
        return self.spec.get("period")

    @property
    def amplitude(self) -> float | None:
        """Peak yaw rate, rad/s (None unless a yaw swing)."""
        return self.spec.get("amplitude")


def canonical(obj: Any) -> str:
    """Canonical JSON (sorted keys, floats as ``repr``) of a JSON-able object."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), allow_nan=False)


def _swing(
    heading: float, pitch: float, roll: float, amplitude: float, period: float
) -> MotionCase:
    spec = {
        "type": "yaw-swing",
        "heading": float(heading),
        "pitch": float(pitch),
        "roll": float(roll),
        "amplitude": float(amplitude),
        "period": float(period),
    }
    return MotionCase(spec, swing_label(spec))


def swing_label(spec: dict[str, Any]) -> str:
    """``"T 120 s, 6 deg/s, hdg 15"``-style label of a yaw-swing spec."""
    return (
        f"T {spec['period']:.4g} s, {spec['amplitude'] / DEG:.3g} deg/s, "
        f"hdg {spec['heading'] / DEG:.4g}, pitch {spec['pitch'] / DEG:.3g}, "
        f"roll {spec['roll'] / DEG:.3g}"
    )


def from_motion(motion: Motion, base_dir: Path | None = None, file: str = "") -> MotionCase:
    """The case of a scenario's own motion.

    Parameters
    ----------
    motion : Motion
        The scenario's motion.
    base_dir : Path, optional
        Directory relative heading-history file names are relative to.
    file : str
        The heading-history file as the scenario names it.
    """
    common = {
        "heading": float(motion.heading),
        "pitch": float(motion.pitch),
        "roll": float(motion.roll),
    }
    if isinstance(motion, YawSwing):
        return _swing(motion.heading, motion.pitch, motion.roll, motion.amplitude, motion.period)
    if isinstance(motion, Turn):
        spec = {"type": "turn", **common, "rate": float(motion.rate)}
        return MotionCase(spec, f"turn {motion.rate / DEG:g} deg/s")
    if isinstance(motion, HeadingHistory):
        return _history_case(file, base_dir, motion.pitch, motion.roll)
    spec = {"type": "static", **common}
    return MotionCase(spec, f"static, hdg {motion.heading / DEG:g}")


def _history_case(file: str, base_dir: Path | None, pitch: float, roll: float) -> MotionCase:
    path = Path(file)
    if base_dir is not None and not path.is_absolute():
        path = base_dir / path
    if not path.is_file():
        raise InputError("design.files", f"heading history file {str(path)!r} not found")
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    spec = {
        "type": "heading-history",
        "heading": 0.0,
        "pitch": float(pitch),
        "roll": float(roll),
        "file": str(path.resolve()),
        "sha256": digest,
    }
    return MotionCase(spec, f"history {path.name}")


def build_motion(spec: dict[str, Any]) -> Motion:
    """The :class:`~inserr.schemes.vehicle_motion.Motion` of a spec (:class:`MotionCase`).

    Raises
    ------
    InputError
        A heading-history file that is missing, unreadable or changed since the spec.
    """
    kind = spec["type"]
    common = {"heading": spec["heading"], "pitch": spec["pitch"], "roll": spec["roll"]}
    if kind == "static":
        return Motion(**common)
    if kind == "yaw-swing":
        return YawSwing(**common, amplitude=spec["amplitude"], period=spec["period"])
    if kind == "turn":
        return Turn(**common, rate=spec["rate"])
    if kind == "heading-history":
        path = Path(spec["file"])
        try:
            data = path.read_bytes()
        except OSError as exc:
            raise InputError("design.files", f"cannot read {path} ({exc})") from None
        if hashlib.sha256(data).hexdigest() != spec["sha256"]:
            raise InputError("design.files", f"{path} changed during the design", "rerun")
        try:
            arr = np.loadtxt(path, delimiter=",", comments="#", ndmin=2)
        except ValueError as exc:
            raise InputError(
                "design.files", f"cannot read {path}: {exc}", "two columns: time_s, heading_deg"
            ) from None
        if arr.ndim != 2 or arr.shape[1] != 2:
            raise InputError("design.files", f"{path} needs two columns: time_s, heading_deg")
        return HeadingHistory(
            pitch=spec["pitch"],
            roll=spec["roll"],
            times=arr[:, 0],
            headings=np.unwrap(arr[:, 1] * DEG),
        )
    raise ValueError(f"unknown motion type {kind!r}")  # specs are made here, never typed


def _range(scen: Scenario, key: str, default: float) -> tuple[float, float]:
    """A two-value range of the ``[design]`` section (absent: ``default`` twice)."""
    values = scen.value(key)
    if not values:
        return default, default
    if len(values) != 2 or not values[0] <= values[1]:
        raise InputError(key, f"expected two values LOW, HIGH, got {values}", "e.g. 20, 1200 s")
    return float(values[0]), float(values[1])


def random_motions(scen: Scenario, n: int, stream: int) -> list[MotionCase]:
    """``n`` seeded yaw swings drawn from the ``[design]`` ranges.

    Parameters
    ----------
    scen : Scenario
        Supplies ``scenario.seed``, the ranges and the defaults of absent ranges.
    n : int
        Number of draws.
    stream : int
        :data:`DESIGN_STREAM` or :data:`HELD_OUT_STREAM`: independent draws for the
        same seed.

    Returns
    -------
    list of MotionCase
        Period log-uniform, every other value uniform in its range.
    """
    m = scen.motion
    p_lo, p_hi = _range(scen, "design.period_range", 60.0)
    a_lo, a_hi = _range(scen, "design.amplitude_range", 0.0)
    h_lo, h_hi = _range(scen, "design.heading_range", m.heading)
    pi_lo, pi_hi = _range(scen, "design.pitch_range", m.pitch)
    r_lo, r_hi = _range(scen, "design.roll_range", m.roll)
    if p_lo <= 0:
        raise InputError("design.period_range", "periods must be > 0 s", "e.g. 20, 1200 s")
    if max(abs(pi_lo), abs(pi_hi)) >= math.pi / 2:
        raise InputError("design.pitch_range", "must be within (-90, 90) deg")
    rng = np.random.default_rng([scen.seed, stream])
    u = rng.random((n, 5))  # one row per motion: the draws do not depend on n's order
    out = []
    for row in u:
        period = math.exp(math.log(p_lo) + row[0] * (math.log(p_hi) - math.log(p_lo)))
        out.append(
            _swing(
                h_lo + row[2] * (h_hi - h_lo),
                pi_lo + row[3] * (pi_hi - pi_lo),
                r_lo + row[4] * (r_hi - r_lo),
                a_lo + row[1] * (a_hi - a_lo),
                round(period, 3),  # a period a table can print; the draw stays seeded
            )
        )
    return out


def design_motions(scen: Scenario) -> list[MotionCase]:
    """The motion set of ``design.motions`` (see the module docstring).

    Raises
    ------
    InputError
        An empty set, a bad range or a missing file.
    """
    kind = scen.value("design.motions")
    m = scen.motion
    if kind == "scenario":
        return [from_motion(m, scen.base_dir, scen.raw.get("motion", {}).get("file", ""))]
    if kind == "files":
        files = scen.value("design.files")
        if not files:
            raise InputError("design.files", "no heading-history files", "list CSV files")
        return [_history_case(f, scen.base_dir, m.pitch, m.roll) for f in files]
    if kind in ("random", "grid+draws"):
        n = scen.value("design.draws")
        if n < 1:
            raise InputError("design.draws", f"must be >= 1, got {n}", "e.g. 36")
        draws = random_motions(scen, n, DESIGN_STREAM)
        if kind == "random":
            return draws
        return _grid(scen) + draws
    return _grid(scen)


def _grid(scen: Scenario) -> list[MotionCase]:
    """The ``grid`` motions (periods x amplitudes x headings)."""
    m = scen.motion
    periods = scen.value("design.periods")
    amplitudes = scen.value("design.amplitudes")
    headings = scen.value("design.headings") or (m.heading,)
    if not periods or not amplitudes:
        raise InputError("design.periods", "the grid needs periods and amplitudes")
    if min(periods) <= 0:
        raise InputError("design.periods", "periods must be > 0 s")
    return [_swing(h, m.pitch, m.roll, a, p) for h in headings for a in amplitudes for p in periods]


def held_out_motions(scen: Scenario) -> list[MotionCase]:
    """The ``design.held_out`` held-out motions (empty when 0).

    Raises
    ------
    InputError
        A negative count or a bad range.
    """
    n = scen.value("design.held_out")
    if n < 0:
        raise InputError("design.held_out", f"must be >= 0, got {n}", "e.g. 36")
    return random_motions(scen, n, HELD_OUT_STREAM) if n else []
