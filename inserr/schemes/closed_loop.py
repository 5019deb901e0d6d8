"""Closed-loop indexing rules: the next step depends on the run (the IMU heading).

``flexible-two-position`` (P0's rule, threshold or zero-crossing stop test) and
``heading-isolation`` live here; ``nulling-two-position`` (inserr's heading-motion-aware
rule) has its own module, :mod:`inserr.schemes.nulling`. Each is a small frozen object
whose one method ``plan(motion, duration)`` returns a
:class:`~inserr.schemes.turntable.TableSchedule`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from inserr.core.errors import InputError
from inserr.schemes.turntable import (
    ScheduleBuilder,
    TableSchedule,
    imu_heading_offset,
    isolation_angle,
)
from inserr.schemes.vehicle_motion import Motion


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
    outer-gimbal angle of :func:`inserr.schemes.turntable.isolation_angle`. The motor therefore
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
