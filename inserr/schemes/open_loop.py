"""Open-loop indexing schemes: rotation tables (data), repeated for the whole run.

A start position and a cycle of PSINS-style rows (gimbal, angle, rotation time,
dwell), repeated: ``none``, ``continuous``, ``two-position``, ``four-position``,
``four-position-modified``, ``eight-position``, ``sixteen-position`` (the PSINS
sixteen-position table), ``sixteen-position-inserr`` and ``custom`` differ only in
their tables. Every scheme starts at t = 0 with a stop at its first position
(``continuous`` with ``stop = 0`` has no opening stop because none was asked for),
unless it is asked to start with its first turn (``start="turn"``, the scenario's
``scheme.start``; :func:`with_start`), as P2 writes its cycle. A ``custom`` table
opens with a stop of ``scheme.stop``, which may be zero (the run then opens with the
table's first turn).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from inserr.core.errors import InputError
from inserr.schemes.turntable import ScheduleBuilder, TableSchedule
from inserr.schemes.vehicle_motion import Motion

DEG = math.pi / 180.0

#: Opening phases of a scheme (``scheme.start``): a stop at the first position (every
#: scheme's default), or the first turn at once.
SCHEME_STARTS = ("stop", "turn")


@dataclass(frozen=True)
class Step:
    """One row of a rotation table: turn ``gimbal`` by ``angle``, then dwell.

    Parameters
    ----------
    gimbal : {"outer", "inner"}
    angle : float, rad (signed)
    dwell : float, s
        Stop after the turn.
    rotation_time : float, s, optional
        Duration of the turn; default ``|angle| / rate`` of the scheme.
    label : str
        Name of the position reached (e.g. "C").
    """

    gimbal: str
    angle: float
    dwell: float
    rotation_time: float | None = None
    label: str = ""

    def __post_init__(self) -> None:
        # A 0 deg "turn" is a stop: its turn time |angle| / rate would be zero and its
        # rate 0 / 0, so it is refused here rather than divided by later.
        if not (math.isfinite(self.angle) and self.angle != 0.0):
            raise ValueError(f"step {self.label!r}: a step must turn (angle {self.angle!r})")


@dataclass(frozen=True)
class TableScheme:
    """An open-loop scheme: start position, first dwell, and a repeated cycle of steps.

    Parameters
    ----------
    name : str
    steps : tuple of Step
        One cycle; it must return the gimbals to the start position (mod 360 deg)
        for the cycle integrals to be meaningful.
    rate : float, rad/s
        Table rate (all gimbals).
    first_dwell : float, s
        Stop at the start position before the first step.
    start : (outer, inner) rad
    start_label : str
    mounting : (3, 3) or None
        IMU mounting on the inner gimbal.
    """

    name: str
    steps: tuple[Step, ...]
    rate: float
    first_dwell: float
    start: tuple[float, float] = (0.0, 0.0)
    start_label: str = "start"
    mounting: np.ndarray | None = field(default=None, compare=False)

    @property
    def cycle_time(self) -> float | None:
        """Duration of one cycle, s (None for a scheme without steps)."""
        if not self.steps:
            return None
        return sum(self._turn_time(s) + s.dwell for s in self.steps)

    def _turn_time(self, s: Step) -> float:
        return s.rotation_time if s.rotation_time is not None else abs(s.angle) / self.rate

    def plan(self, motion: Motion, duration: float) -> TableSchedule:
        """Repeat the table until ``duration`` (the last segment may run past it)."""
        b = ScheduleBuilder(*self.start, mounting=self.mounting)
        if not self.steps:
            b.stop(duration, f"stop {self.start_label}")
            return b.build()
        b.stop(self.first_dwell, f"stop {self.start_label}")
        while b.t < duration:
            for s in self.steps:
                rate = abs(s.angle) / self._turn_time(s)
                b.rotate(
                    s.gimbal, s.angle, rate, f"{s.gimbal} {math.degrees(s.angle):+g} -> {s.label}"
                )
                b.stop(s.dwell, f"stop {s.label}")
                if b.t >= duration:
                    break
        return b.build(cycle=self.cycle_time)


def with_start(scheme: TableScheme, start: str) -> TableScheme:
    """``scheme`` with the opening phase ``start`` (one of :data:`SCHEME_STARTS`).

    ``"turn"`` drops the opening stop (``first_dwell = 0``): the run begins with the
    table's first step, and each cycle then ends with the stop at the start position.
    A scheme without steps (``none``) has no turn to begin with and is returned as it is.

    Raises
    ------
    InputError
        For an unknown opening phase.
    """
    if start not in SCHEME_STARTS:
        raise InputError(
            "scheme.start",
            f"unknown opening phase {start!r}",
            f"use one of: {', '.join(SCHEME_STARTS)}",
        )
    if start == "stop" or not scheme.steps:
        return scheme
    return replace(scheme, first_dwell=0.0)


def none_scheme(rate: float, stop: float) -> TableScheme:
    """No indexing: the table holds its start position for the whole run."""
    return TableScheme("none", (), rate, stop)


def continuous(rate: float, stop: float, reversal: float = 0.0) -> TableScheme:
    """Continuous rotation about the azimuth axis, optionally reversing every ``reversal`` s.

    The run opens with a stop of ``stop`` seconds at the start position (every
    scheme starts with a stop); then the table turns one revolution per row.
    With ``reversal > 0`` the direction flips every ``reversal`` seconds (rounded to
    whole revolutions), which cancels the gyro scale-factor x table-rate term.
    """
    rev = 2 * math.pi
    if reversal > 0:
        n = max(1, round(reversal * rate / rev))
        steps = tuple(Step("outer", rev, 0.0, label="+rev") for _ in range(n)) + tuple(
            Step("outer", -rev, 0.0, label="-rev") for _ in range(n)
        )
    else:
        steps = (Step("outer", rev, 0.0, label="+rev"),)
    return TableScheme("continuous", steps, rate, stop)


def two_position(rate: float, stop: float) -> TableScheme:
    """P0's traditional dual-position cycle: +180, +180, -180, -180 with a stop after each."""
    pi = math.pi
    steps = (
        Step("outer", pi, stop, label="180"),
        Step("outer", pi, stop, label="360"),
        Step("outer", -pi, stop, label="180"),
        Step("outer", -pi, stop, label="0"),
    )
    return TableScheme("two-position", steps, rate, stop, start_label="0")


def four_position(rate: float, stop: float, modified: bool = False) -> TableScheme:
    """P2's four-position cycle A(-135) ->C(+45) ->D(+135) ->B(-45) ->A.

    ``modified=True`` lengthens the stops at A and D to ``stop + 2 / rate`` (rate in
    rad/s), P2's fix that makes the cycle integral of the horizontal projection
    vanish, rotation phases included.
    """
    extra = 2.0 / rate if modified else 0.0
    steps = (
        Step("outer", 180 * DEG, stop, label="C"),
        Step("outer", 90 * DEG, stop + extra, label="D"),
        Step("outer", -180 * DEG, stop, label="B"),
        Step("outer", -90 * DEG, stop + extra, label="A"),
    )
    name = "four-position-modified" if modified else "four-position"
    return TableScheme(name, steps, rate, stop + extra, start=(-135 * DEG, 0.0), start_label="A")


# Dual-axis sequences: 180 deg turns of the outer (azimuth, body z) and inner (x) gimbals.
# Sources (see docs/schemes.md, "Sources of the dual-axis sequences"):
# * sixteen-position is the sixteen-row table of the PSINS toolbox demo
#   demos/test_RSINS_2_axis.m (Gongmin Yan, Northwestern Polytechnical University;
#   file dated 07/09/2024, release "PSINS 2024.11.09", github.com/WangShanpeng/PSINS),
#   taken as tabulated, before that file's own "improved-16" reordering of rows 9-16.
# * eight-position and sixteen-position-inserr are inserr's own orders. No published
#   text of an eight-position dual-axis sequence was found; the text of Yuan, Liao & Han,
#   Meas. Sci. Technol. 23 (2012) 025102, often cited for a sixteen-sequence scheme, was
#   not available, so no sequence here is attributed to it.
# Every property claimed below is checked in closed form in tests/test_cycle.py.

#: PSINS demos/test_RSINS_2_axis.m, rows 1-16: (IMU axis, sign of the 180 deg turn).
#: PSINS turns about the IMU's own axes (attrottt: C_b^n <- C_b^n rv2m(U angle)); see
#: :func:`_imu_axis_steps` for the translation to gimbal turns. The demo then relabels
#: x as y ("change to Y-Z"), a choice of which IMU axis lies on the inner gimbal.
PSINS_SIXTEEN = (
    ("z", +1),
    ("x", -1),
    ("z", +1),
    ("x", -1),
    ("x", -1),
    ("z", +1),
    ("x", -1),
    ("z", +1),
    ("z", -1),
    ("x", +1),
    ("z", -1),
    ("x", +1),
    ("x", +1),
    ("z", -1),
    ("x", +1),
    ("z", -1),
)
# Eight-position (inserr's order, gimbal turns): z+ x+ z+ x+ z- x- z- x-. Its cycle
# integral of C_s^n vanishes for all three axes, rotation phases included, and each
# gimbal's net turn is zero, so the scale-factor x rate terms cancel; the misalignment x
# rate terms do not.
_EIGHT = (
    ("outer", +1),
    ("inner", +1),
    ("outer", +1),
    ("inner", +1),
    ("outer", -1),
    ("inner", -1),
    ("outer", -1),
    ("inner", -1),
)
# sixteen-position-inserr: the eight-position order followed by the same order started on
# the inner gimbal, found by an exhaustive search over +-180 deg gimbal-turn sequences as
# one that also cancels the misalignment x rate terms while each gimbal stays within one
# revolution (0..360 deg).
_EIGHT_INNER_FIRST = (
    ("inner", +1),
    ("outer", +1),
    ("inner", +1),
    ("outer", +1),
    ("inner", -1),
    ("outer", -1),
    ("inner", -1),
    ("outer", -1),
)


def _dual_axis_steps(seq, stop: float, prefix: str) -> list[Step]:
    return [Step(g, s * math.pi, stop, label=f"{prefix}{i + 1}") for i, (g, s) in enumerate(seq)]


def _imu_axis_steps(seq, stop: float, prefix: str = "P") -> list[Step]:
    """Gimbal steps of a table of 180 deg turns about the IMU's own x and z axes.

    With the IMU mounted square on the inner gimbal (``C_s^b = rot_z(a) rot_x(b)``), a
    turn about IMU x is a turn of the inner gimbal, and a turn by ``t`` about IMU z is
    a turn of the outer gimbal by ``t cos b`` (``b`` a multiple of 180 deg here), since
    ``rot_x(b) rot_z(t) = rot_z(t cos b) rot_x(b)``.
    """
    b = 0.0
    steps = []
    for i, (axis, sign) in enumerate(seq):
        angle = sign * math.pi
        if axis == "x":
            steps.append(Step("inner", angle, stop, label=f"{prefix}{i + 1}"))
            b += angle
        else:
            steps.append(Step("outer", round(math.cos(b)) * angle, stop, label=f"{prefix}{i + 1}"))
    return steps


def eight_position(rate: float, stop: float) -> TableScheme:
    """Dual-axis eight-position cycle, gimbal turns z+ x+ z+ x+ z- x- z- x- (inserr's order).

    No published text of an eight-position dual-axis sequence was found
    (``docs/schemes.md``); the order is inserr's. It cancels the cycle integral of
    ``C_s^n`` on all three axes and the scale-factor x rate terms, not the
    misalignment x rate terms.
    """
    return TableScheme(
        "eight-position", tuple(_dual_axis_steps(_EIGHT, stop, "P")), rate, stop, start_label="P0"
    )


def sixteen_position(rate: float, stop: float) -> TableScheme:
    """Dual-axis sixteen-position cycle of the PSINS toolbox (Gongmin Yan).

    Source: ``demos/test_RSINS_2_axis.m`` of PSINS (Northwestern Polytechnical
    University; file dated 07/09/2024, release "PSINS 2024.11.09",
    github.com/WangShanpeng/PSINS), its table of sixteen 180 deg turns about the IMU's
    own axes, rows 1-16 as tabulated (before the file's "improved-16" reordering):
    z+ x- z+ x- x- z+ x- z+ z- x+ z- x+ x+ z- x+ z- (:data:`PSINS_SIXTEEN`). In gimbal
    turns (:func:`_imu_axis_steps`): outer +, inner -, outer -, inner -, inner -,
    outer -, inner -, outer +, outer -, inner +, outer +, inner +, inner +, outer +,
    inner +, outer -. PSINS stops ``T0`` before and ``T1`` after each turn; here each
    position is held ``stop`` once.

    The cycle integral of ``C_s^n``, the scale-factor x rate and the misalignment x
    rate integrals all vanish; the inner gimbal travels 720 deg (0 to -720 and back).
    """
    steps = _imu_axis_steps(PSINS_SIXTEEN, stop)
    return TableScheme("sixteen-position", tuple(steps), rate, stop, start_label="P0")


def sixteen_position_inserr(rate: float, stop: float) -> TableScheme:
    """inserr's sixteen-position order: eight-position, then the same started on the inner gimbal.

    Same exact cancellations as :func:`sixteen_position` with each gimbal kept within
    one revolution (0..360 deg), at the price of larger cycle means of the rate
    terms (``docs/schemes.md``).
    """
    steps = _dual_axis_steps(_EIGHT, stop, "P") + _dual_axis_steps(_EIGHT_INNER_FIRST, stop, "Q")
    return TableScheme("sixteen-position-inserr", tuple(steps), rate, stop, start_label="P0")
