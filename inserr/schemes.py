"""Indexing schemes: open-loop rotation tables (data) and closed-loop planners (small objects).

Every scheme turns a vehicle motion and a duration into a
:class:`~inserr.table.TableSchedule` with its one method ``plan(motion, duration)``.
Every scheme starts at t = 0 with a stop at its first position.

* Open-loop schemes are data: a start position and a cycle of PSINS-style rows
  (gimbal, angle, rotation time, dwell), repeated. ``none``, ``continuous``,
  ``two-position``, ``four-position``, ``four-position-modified``,
  ``eight-position``, ``sixteen-position`` and ``custom`` differ only in their
  tables.
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
            b.stop(duration, self.start_label)
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


# Dual-axis sequences: 180 deg turns of the outer (azimuth, z) and inner (x) gimbals.
# Eight-position: z+ x+ z+ x+ z- x- z- x-, the order commonly reproduced in the
# dual-axis rotation literature after Yuan, Liao & Han, "Error compensation of an
# optical gyro INS by multi-axis rotation", Meas. Sci. Technol. 23, 025102 (2012).
# Its cycle integral of C_s^n vanishes for all three axes, rotation phases included,
# and each gimbal's net turn is zero, so the scale-factor x rate terms cancel; the
# misalignment x rate terms do not (tests/test_cycle.py).
# Sixteen-position: the eight-position order followed by the same order started on
# the inner gimbal (x+ z+ x+ z+ x- z- x- z-). inserr chose this completion by an
# exhaustive search over +-180 deg turn sequences as one that also cancels the
# misalignment x rate terms, which is the stated purpose of 16-position schemes;
# the cancellation is verified in closed form in tests, not taken on trust.
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


def eight_position(rate: float, stop: float) -> TableScheme:
    """Dual-axis eight-position cycle (see module comment for the order and source)."""
    return TableScheme(
        "eight-position", tuple(_dual_axis_steps(_EIGHT, stop, "P")), rate, stop, start_label="P0"
    )


def sixteen_position(rate: float, stop: float) -> TableScheme:
    """Dual-axis sixteen-position: eight-position, then the same started on the inner gimbal."""
    steps = _dual_axis_steps(_EIGHT, stop, "P") + _dual_axis_steps(_EIGHT_INNER_FIRST, stop, "Q")
    return TableScheme("sixteen-position", tuple(steps), rate, stop, start_label="P0")


# ---------------------------------------------------------------------------------------
# Closed-loop schemes
# ---------------------------------------------------------------------------------------
def _imu_heading(motion: Motion, t: np.ndarray, a: np.ndarray, mounting) -> np.ndarray:
    """IMU heading (rad) of a single-axis table at outer angle ``a`` on ``motion``, times ``t``."""
    return motion.heading_at(t) + imu_heading_offset(motion.tilt, a, 0.0, mounting)


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
    expression between samples (with the same sign condition).

    Fallback (the rule can fail: ``|Sc/(f Ts)| > 1`` has no root, and a yawing
    vehicle can carry psi past the window): if no sample of the first full turn
    passes the test, the table keeps turning and stops at the first sample that
    meets the sign condition with ``|expression|`` within ``delta`` of the smallest
    value seen in the first turn; after a second full turn it stops at once. Each
    fallback is counted in ``meta["fallbacks"]``.

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
        j = np.arange(1, 2 * per_turn + 1)
        t = b.t + j / self.f
        a = b.a + direction * w * j / self.f
        h = _imu_heading(motion, t, a, self.mounting)
        main, other = (np.cos(h), np.sin(h)) if which == 0 else (np.sin(h), np.cos(h))
        expr = main + sums[which] / (self.f * self.stop)
        s_other = np.sign(sums[1 - which])
        sign_ok = (np.sign(other) == -s_other) | (s_other == 0)
        if self.variant == "threshold":
            hit = (np.abs(expr) < self.delta) & sign_ok
        else:
            prev = np.concatenate([[expr[0]], expr[:-1]])
            hit = (np.sign(expr) != np.sign(prev)) & sign_ok
        first = np.flatnonzero(hit[:per_turn])
        fallback = False
        if len(first):
            n = first[0] + 1
        else:
            fallback = True
            best = np.min(np.abs(expr[:per_turn]) + np.where(sign_ok[:per_turn], 0.0, np.inf))
            late = np.flatnonzero(
                (np.abs(expr[per_turn:]) <= best + self.delta) & sign_ok[per_turn:]
            )
            n = per_turn + (late[0] + 1 if len(late) else per_turn)
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
