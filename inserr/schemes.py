"""Indexing schemes: open-loop rotation tables (data) and closed-loop planners (small objects).

Every scheme turns a vehicle motion and a duration into a
:class:`~inserr.table.TableSchedule` with its one method ``plan(motion, duration)``.
Every scheme starts at t = 0 with a stop at its first position (``heading-isolation``:
an isolation hold, which is its stop, see :class:`HeadingIsolation`; ``continuous``
with ``stop = 0`` has no opening stop because none was asked for).

* Open-loop schemes are data: a start position and a cycle of PSINS-style rows
  (gimbal, angle, rotation time, dwell), repeated. ``none``, ``continuous``,
  ``two-position``, ``four-position``, ``four-position-modified``,
  ``eight-position``, ``sixteen-position`` (the PSINS sixteen-position table),
  ``sixteen-position-inserr`` and ``custom`` differ only in their tables.
* Closed-loop schemes decide the next step from the state of the run (the IMU
  heading, which depends on the vehicle's yaw): ``flexible-two-position`` (P0's
  rule, threshold or zero-crossing stop test), ``heading-isolation``, and
  ``nulling-two-position`` (inserr's heading-motion-aware rule, see
  ``docs/schemes.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from inserr.errors import InputError
from inserr.motion import Motion
from inserr.table import ScheduleBuilder, TableSchedule, imu_heading_offset, isolation_angle

DEG = math.pi / 180.0


# ---------------------------------------------------------------------------------------
# Open-loop schemes: tables of steps
# ---------------------------------------------------------------------------------------
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


# ---------------------------------------------------------------------------------------
# Closed-loop schemes
# ---------------------------------------------------------------------------------------
def _imu_heading(motion: Motion, t: np.ndarray, a: np.ndarray, mounting) -> np.ndarray:
    """IMU heading (rad) of a single-axis table at outer angle ``a`` on ``motion``, times ``t``."""
    return motion.heading_at(t) + imu_heading_offset(motion.tilt, a, 0.0, mounting)


def _best_sample(score: np.ndarray, ok: np.ndarray, rtol: float = 1e-9) -> int:
    """Index of the smallest ``score`` among ``ok`` samples (all if none), earliest of ties.

    Values within ``rtol`` (relative to the score's range, at least 1e-12) of the
    minimum count as ties, so round-off cannot pick a later sample of a flat score.
    """
    pool = np.flatnonzero(ok) if np.any(ok) else np.arange(len(score))
    vals = score[pool]
    tol = max(1e-12, rtol * float(np.ptp(score)))
    return int(pool[np.flatnonzero(vals <= vals.min() + tol)[0]])


@dataclass(frozen=True)
class FlexibleTwoPosition:
    """P0's flexible dual-position rule (as reconstructed in the paper digest).

    Running sums over the *stop* phases only, sampled at ``f``:
    ``Sc = sum cos(psi_imu)``, ``Ss = sum sin(psi_imu)``. One cycle:

    1. stop ``Ts``; turn forward and stop when ``|cos psi + Sc/(f Ts)| < delta`` and
       ``sin psi`` has the sign opposite to ``Ss``;
    2. stop ``Ts``; turn +180 deg;
    3. stop ``Ts``; turn backward and stop when ``|sin psi + Ss/(f Ts)| < delta`` and
       ``cos psi`` has the sign opposite to ``Sc``;
    4. stop ``Ts``; turn -180 deg.

    ``variant="crossing"`` replaces the ``< delta`` test by a sign change of the
    expression between samples (with the same sign condition). A sum that vanishes
    to round-off (``|S| <= 1e-9 f Ts``, e.g. when every stop spans whole revolutions
    of the IMU heading, as on a vehicle turning at 6 deg/s with 300 s stops) sets no
    sign condition: its sign would be noise.

    Fallback. The rule can fail: ``|Sc/(f Ts)| > 1`` has no root, and a yawing
    vehicle can carry psi past the window or hold it still (a vehicle turning at
    the table rate in the table's direction freezes psi for the whole turn). If no
    sample of one full turn (360 deg of table angle) passes the test, the table
    stops at the *best* sample of that turn instead of turning again: the one with
    the smallest ``|expression|`` among the samples that meet the sign condition (all
    samples if none does), the earliest (shortest turn) among equal values. A
    fallback turn is therefore always shorter than 360 deg, and it stops where the
    next stop cancels as much of the residue as one turn can reach. Choosing the
    best sample needs the IMU heading over the coming turn: the planner reads it
    from the vehicle motion, i.e. it assumes the heading over one turn (60 s at
    6 deg/s) is predictable; the regular stop test uses only the present sample.
    (The earlier fallback kept turning into a second revolution: 16 fallback turns of
    360.06 to 720 deg in 6 h of a steady 6 deg/s vehicle turn; comparison in
    ``docs/schemes.md``.) Fallback
    turns are labelled ``"variable turn (fallback)"`` and counted in
    ``meta["fallbacks"]``.

    Psi_imu is the true IMU heading (the INS's own heading differs by its heading
    error, arc-minutes, which does not move a 0.01 threshold).
    """

    rate: float
    stop: float
    delta: float = 0.01
    f: float = 100.0
    variant: str = "threshold"
    mounting: np.ndarray | None = field(default=None, compare=False)
    name: str = "flexible-two-position"

    def __post_init__(self) -> None:
        if self.variant not in ("threshold", "crossing"):
            raise InputError(
                "scheme.variant", f"unknown variant {self.variant!r}", "use threshold or crossing"
            )

    def _accumulate(self, motion, b: ScheduleBuilder, sums: np.ndarray) -> None:
        k0 = math.ceil(b.t * self.f - 1e-9)
        k1 = math.ceil((b.t + self.stop) * self.f - 1e-9)
        t = np.arange(k0, k1) / self.f
        h = motion.heading_at(t) + imu_heading_offset(motion.tilt, b.a, 0.0, self.mounting)
        sums += [np.cos(h).sum(), np.sin(h).sum()]

    def _variable_turn(
        self, motion, b: ScheduleBuilder, sums: np.ndarray, which: int, direction: float
    ) -> bool:
        """Turn until the stop test passes; returns True if the fallback was used."""
        w = self.rate
        per_turn = int(math.ceil(2 * math.pi / w * self.f))
        j = np.arange(1, per_turn + 1)
        t = b.t + j / self.f
        a = b.a + direction * w * j / self.f
        h = _imu_heading(motion, t, a, self.mounting)
        main, other = (np.cos(h), np.sin(h)) if which == 0 else (np.sin(h), np.cos(h))
        scale = self.f * self.stop
        expr = main + sums[which] / scale
        # A sum that is zero to round-off sets no sign condition (see the class docstring).
        s_other = np.sign(sums[1 - which]) if abs(sums[1 - which]) > 1e-9 * scale else 0.0
        sign_ok = (np.sign(other) == -s_other) | (s_other == 0)
        if self.variant == "threshold":
            hit = (np.abs(expr) < self.delta) & sign_ok
        else:
            prev = np.concatenate([[expr[0]], expr[:-1]])
            hit = (np.sign(expr) != np.sign(prev)) & sign_ok
        first = np.flatnonzero(hit)
        fallback = not len(first)
        # A fallback never takes a whole revolution (it would only return to the start).
        short = w * j / self.f < 2 * math.pi - 1e-9
        n = first[0] + 1 if len(first) else _best_sample(np.abs(expr[short]), sign_ok[short]) + 1
        b.rotate(
            "outer",
            direction * w * n / self.f,
            w,
            "variable turn" + (" (fallback)" if fallback else ""),
        )
        return fallback

    def plan(self, motion: Motion, duration: float) -> TableSchedule:
        """Run the rule over ``duration`` seconds of ``motion``."""
        b = ScheduleBuilder(0.0, 0.0, self.mounting)
        sums = np.zeros(2)
        fallbacks = 0
        phase = 0
        while b.t < duration:
            self._accumulate(motion, b, sums)
            b.stop(self.stop)
            if b.t >= duration:
                break
            if phase == 0:
                fallbacks += self._variable_turn(motion, b, sums, 0, +1.0)
            elif phase == 1:
                b.rotate("outer", math.pi, self.rate)
            elif phase == 2:
                fallbacks += self._variable_turn(motion, b, sums, 1, -1.0)
            else:
                b.rotate("outer", -math.pi, self.rate)
            phase = (phase + 1) % 4
        b.meta["fallbacks"] = fallbacks
        b.meta["stop_sums"] = sums.tolist()
        return b.build()


@dataclass(frozen=True)
class HeadingIsolation:
    """Two-position indexing with the vehicle's yaw removed by the table.

    The table steers the IMU heading along the static-base two-position pattern
    (hold ``Ts``, turn 180 deg at ``rate``, hold, turn 180 deg, hold, turn back, hold,
    turn back), compensating the vehicle yaw at every instant with the closed-form
    outer-gimbal angle of :func:`inserr.table.isolation_angle`. The motor therefore
    runs continuously; every reversal of the table rate counts as a motor start
    (``meta["isolation_reversals"]``).

    Why the run opens with an isolation *hold* (``kind == "isolate"``, label
    ``"hold 0"``, target rate 0) and not a literal stop: a stop is the phase in which
    the IMU keeps one orientation, so that a bias projects onto a fixed
    navigation-frame direction. Every other scheme gets that by freezing the gimbals
    because its navigation-frame attitude changes only with the vehicle; this scheme
    exists to remove the vehicle's yaw, so its stop freezes the IMU *heading* and the
    table absorbs the yaw. The hold starts at t = 0 at the first position (table
    angle 0, IMU heading ``h0`` = the vehicle's heading at t = 0 plus the mounting
    offset) and lasts ``stop``; on a vehicle that does not yaw it is a literal stop
    (the table angle stays constant, ``tests/test_schedule.py``). Freezing the
    gimbals instead would let the first position swing with the yaw, which is
    exactly what the scheme is built to prevent.
    """

    rate: float
    stop: float
    mounting: np.ndarray | None = field(default=None, compare=False)
    name: str = "heading-isolation"
    count_rate: float = 4.0  # Hz at which table-rate reversals are counted

    def plan(self, motion: Motion, duration: float) -> TableSchedule:
        """Schedule of isolation segments covering ``duration``."""
        h0 = float(_imu_heading(motion, np.array([0.0]), np.array([0.0]), self.mounting)[0])
        turn = math.pi / self.rate
        pattern = [(-1.0, "180"), (-1.0, "360"), (+1.0, "180"), (+1.0, "0")]
        b = ScheduleBuilder(0.0, 0.0, self.mounting)
        h = h0

        def angle_at(t: float, target: float) -> float:
            # Outer angle at time t; branch chosen next to the level-vehicle prediction.
            a = float(
                isolation_angle(motion.attitude(np.array([t]))[0], 0.0, self.mounting, target)
            )
            guess = b.a + float(motion.heading_at(t) - motion.heading_at(b.t)) - (target - h)
            return guess + math.remainder(a - guess, 2 * math.pi)

        b.isolate(self.stop, h, 0.0, angle_at(self.stop, h), 0.0, "hold 0")
        i = 0
        while b.t < duration:
            sign, lab = pattern[i % 4]
            a_end = angle_at(b.t + turn, h + sign * math.pi)
            b.isolate(turn, h, b.a, a_end, sign * self.rate, f"turn -> {lab}")
            h += sign * math.pi
            if b.t >= duration:
                break
            b.isolate(self.stop, h, b.a, angle_at(b.t + self.stop, h), 0.0, f"hold {lab}")
            i += 1
        sched = b.build()
        sched.meta["isolation_reversals"] = _count_reversals(
            sched, motion, duration, self.count_rate
        )
        return sched


def _count_reversals(sched: TableSchedule, motion: Motion, duration: float, rate_hz: float) -> int:
    """Sign changes of the outer-gimbal rate, sampled at ``rate_hz`` (chunked in time)."""
    n = 0
    last = 0.0
    chunk = 3600.0
    t0 = 0.0
    while t0 < duration:
        t = np.arange(t0, min(t0 + chunk, duration), 1.0 / rate_hz)
        a, _ = sched.angles_at(t, motion)
        d = np.diff(np.unwrap(a))
        s = np.sign(d[np.abs(d) > 1e-9])
        if len(s):
            seq = np.concatenate([[last], s]) if last else s
            n += int(np.count_nonzero(np.diff(seq)))
            last = s[-1]
        t0 += chunk
    return n


# ---------------------------------------------------------------------------------------
# Catalogue
# ---------------------------------------------------------------------------------------
SCHEMES = (
    "none",
    "continuous",
    "two-position",
    "four-position",
    "four-position-modified",
    "flexible-two-position",
    "heading-isolation",
    "nulling-two-position",
    "eight-position",
    "sixteen-position",
    "sixteen-position-inserr",
    "custom",
)


def build_scheme(name: str, rate: float, stop: float, **options):
    """Build a scheme by name.

    Parameters
    ----------
    name : str
        One of :data:`SCHEMES`.
    rate : float, rad/s
        Table rate (> 0).
    stop : float, s
        Stop (dwell) time (> 0; 0 allowed for ``continuous``).
    **options
        ``reversal`` (continuous, s), ``delta``/``variant``/``f`` (flexible),
        ``steps`` (custom: list of Step), ``mounting`` (3x3).

    Raises
    ------
    InputError
        Unknown scheme or bad parameters.
    """
    if name not in SCHEMES:
        raise InputError(
            "--scheme (scheme.name)",
            f"unknown scheme {name!r}",
            f"use one of: {', '.join(SCHEMES)}",
        )
    if not (math.isfinite(rate) and rate > 0):
        raise InputError("--rate (scheme.rate)", f"table rate must be > 0, got {rate!r}")
    if not (math.isfinite(stop) and stop >= 0) or (
        stop == 0 and name not in ("continuous", "none")
    ):
        raise InputError("--stop (scheme.stop)", f"stop time must be > 0 s, got {stop!r}")
    mounting = options.pop("mounting", None)
    if name == "none":
        s = none_scheme(rate, stop)
    elif name == "continuous":
        s = continuous(rate, stop, options.pop("reversal", 0.0))
    elif name == "two-position":
        s = two_position(rate, stop)
    elif name in ("four-position", "four-position-modified"):
        s = four_position(rate, stop, modified=name.endswith("modified"))
    elif name == "eight-position":
        s = eight_position(rate, stop)
    elif name == "sixteen-position":
        s = sixteen_position(rate, stop)
    elif name == "sixteen-position-inserr":
        s = sixteen_position_inserr(rate, stop)
    elif name == "flexible-two-position":
        return FlexibleTwoPosition(rate, stop, mounting=mounting, **options)
    elif name == "heading-isolation":
        return HeadingIsolation(rate, stop, mounting=mounting)
    elif name == "nulling-two-position":
        from inserr.nulling import NullingTwoPosition

        return NullingTwoPosition(rate, stop, mounting=mounting, **options)
    else:  # custom
        steps = options.pop("steps", None)
        if not steps:
            raise InputError(
                "scheme.steps",
                "a custom scheme needs a table of steps",
                "add [[scheme.steps]] rows",
            )
        s = TableScheme("custom", tuple(steps), rate, stop)
    if options:
        raise InputError("scheme", f"option(s) {sorted(options)} do not apply to {name}")
    if mounting is not None:
        s = TableScheme(s.name, s.steps, s.rate, s.first_dwell, s.start, s.start_label, mounting)
    return s
