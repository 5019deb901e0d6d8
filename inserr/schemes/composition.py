"""Composition of a table schedule and a vehicle motion into the IMU attitude timeline.

``C_s^n(t) = C_b^n(t) C_s^b(t)`` and the IMU angular velocity relative to n is
``w_ns^n = w_nb^n + C_b^n w_bs^b``. Where that is constant (a stop on a static or
steadily turning vehicle, a table turn on a static vehicle, a table turn about an
axis parallel to a steady vehicle turn) the interval is represented exactly by a
single constant-rate interval. Elsewhere (yaw swing, table turning on a tilted
yawing vehicle, heading isolation) the interval is cut into sub-steps on a global
grid of ``substep`` seconds whose node attitudes are exact and whose rates are the
geodesic ones; because the grid is global, a periodic motion produces the same
sub-steps period after period and the discretization cache serves them.
"""

from __future__ import annotations

import math

import numpy as np

from inserr.core.errors import InputError
from inserr.core.rotations import rot_x, rot_z_times
from inserr.model.attitude_history import Pieces
from inserr.model.timeline import Timeline
from inserr.schemes.turntable import TableSchedule, gimbal_axis_b, table_dcm
from inserr.schemes.vehicle_motion import Motion


def build_timeline(
    table: TableSchedule, motion: Motion, duration: float, substep: float = 1.0
) -> Timeline:
    """The :class:`~inserr.model.timeline.Timeline` of IMU attitude over ``[0, duration]``.

    Parameters
    ----------
    table : TableSchedule
        Output of a scheme's ``plan``.
    motion : Motion
        Vehicle motion.
    duration : float, s
    substep : float, s
        Sub-step of continuous motion (default 1 s; see ``docs/theory.md`` for the
        accuracy this gives and ``tests/test_schedule.py`` for its convergence).
    """
    if not (math.isfinite(duration) and duration > 0):
        raise InputError("duration", f"must be a positive time, got {duration!r}", "give e.g. 72 h")
    if not (math.isfinite(substep) and substep > 0):
        raise InputError("substep", f"must be > 0 s, got {substep!r}")
    m_breaks, m_const = motion.pieces(duration)
    breaks = np.union1d(np.concatenate([table.t0[table.t0 < duration], [duration]]), m_breaks)
    breaks = breaks[breaks <= duration]

    times: list[np.ndarray] = []
    omegas: list[np.ndarray] = []
    labels: list[str] = []
    exact_flags: list[np.ndarray] = []

    seg = np.clip(
        np.searchsorted(table.t0, 0.5 * (breaks[:-1] + breaks[1:]), side="right") - 1,
        0,
        len(table) - 1,
    )
    # Vehicle rate at each piece's middle and attitude at its start, for all pieces at once.
    w_nb_all = motion.rate_n(0.5 * (breaks[:-1] + breaks[1:]))
    c_bn_all = motion.attitude(breaks[:-1])
    pieces = zip(breaks[:-1], breaks[1:], seg, w_nb_all, c_bn_all, strict=True)
    for a, b, k, w_nb, c_bn in pieces:
        if b - a <= 1e-9:
            continue
        kind = table.kind[k]
        # A constant-rate piece of a heading history may be still even if the motion is not.
        moving = not motion.is_static and (not m_const or np.any(w_nb != 0))
        exact = False
        w = np.zeros(3)
        if kind == "stop":
            exact = m_const or not moving
            w = w_nb
        elif kind == "rotate":
            axis_b = gimbal_axis_b(table.gimbal[k], float(table.a0[k]))
            w_bs_n = c_bn @ axis_b * table.rate[k]
            if not moving:
                exact = True
                w = w_bs_n
            elif m_const and np.linalg.norm(np.cross(w_bs_n, w_nb)) < 1e-15:
                exact = True
                w = w_bs_n + w_nb
        if exact:
            times.append(np.array([a]))
            omegas.append(w[None, :])
            exact_flags.append(np.array([True]))
            labels.append(table.labels[k])
        else:
            g0 = math.floor(a / substep) + 1
            g1 = math.ceil(b / substep) - 1
            grid = np.arange(g0, g1 + 1) * substep
            grid = grid[(grid > a + 1e-9) & (grid < b - 1e-9)]
            nodes = np.concatenate([[a], grid])
            times.append(nodes)
            omegas.append(np.full((len(nodes), 3), np.nan))
            exact_flags.append(np.zeros(len(nodes), dtype=bool))
            labels.extend([table.labels[k]] * len(nodes))

    t = np.concatenate(times + [np.array([duration])])
    w = np.concatenate(omegas)
    exact = np.concatenate(exact_flags)
    c_sn = _attitudes(table, motion, t)
    if np.any(~exact):
        from inserr.core.rotations import log_so3

        idx = np.flatnonzero(~exact)
        rel = c_sn[idx + 1] @ np.swapaxes(c_sn[idx], -1, -2)
        w[idx] = log_so3(rel) / (t[idx + 1] - t[idx])[:, None]
    return Timeline(
        t,
        c_sn,
        w,
        tuple(labels),
        motor_starts=table.motor_starts(),
        meta={"table": table, "motion": motion, "exact_intervals": int(exact.sum())},
    )


def _attitudes(
    table: TableSchedule, motion: Motion, t: np.ndarray, chunk: int = 200_000
) -> np.ndarray:
    """Exact ``C_s^n`` at the node times, in chunks to bound memory."""
    out = np.empty((len(t), 3, 3))
    for i in range(0, len(t), chunk):
        tt = t[i : i + chunk]
        out[i : i + chunk] = motion.attitude(tt) @ table.dcm_at(tt, motion)
    return out


class ScheduleHistory:
    """The exact IMU attitude of a table schedule on a vehicle motion, as smooth pieces.

    ``C_s^n(t) = C_b^n(t) C_s^b(t)`` with the vehicle's ``C_b^n`` and the table's
    ``C_s^b = rot_z(a) rot_x(b) C_s^t``, and ``w_ns^n = w_nb^n + C_b^n w_bs^b`` with the
    gimbal rates (``w_bs^b = a' e_z + b' rot_z(a) e_x``). Nothing is sub-stepped: the
    fast engine (:mod:`inserr.model.fast_propagation`) samples this continuous motion
    where its quadrature needs it. Pieces are cut at every table segment and at the
    motion's own breakpoints (a heading history's samples), so the attitude is
    analytic inside each. In an isolation segment the outer-gimbal rate follows from
    the implicit function theorem: with ``psi(t, a)`` the IMU heading,
    ``a' = (target_rate - d psi / dt) / (d psi / d a)``.

    Parameters
    ----------
    table : TableSchedule
        Output of a scheme's ``plan``.
    motion : Motion
        Vehicle motion.
    duration : float, s
        Length of the run.
    """

    def __init__(self, table: TableSchedule, motion: Motion, duration: float):
        if not (math.isfinite(duration) and duration > 0):
            raise InputError("duration", f"must be a positive time, got {duration!r}")
        self.table = table
        self.motion = motion
        self._duration = float(duration)
        m_breaks, _ = motion.pieces(duration)
        breaks = np.union1d(np.concatenate([table.t0[table.t0 < duration], [duration]]), m_breaks)
        breaks = breaks[breaks <= duration]
        keep = np.concatenate([[True], np.diff(breaks) > 1e-9])
        breaks = breaks[keep]
        breaks[-1] = duration
        self._breaks = breaks
        mid = 0.5 * (breaks[:-1] + breaks[1:])
        self._segment = np.clip(np.searchsorted(table.t0, mid, side="right") - 1, 0, len(table) - 1)
        # Per table segment, for evaluate (called on tens of thousands of points per run).
        self._kind = np.array(table.kind)
        self._outer = np.array([g == "outer" for g in table.gimbal], dtype=bool)

    @property
    def duration(self) -> float:
        """Length of the run, s."""
        return self._duration

    def pieces(self) -> Pieces:
        """Table segments cut at the motion's breakpoints; bandwidth vehicle + gimbal rate."""
        a, b = self._breaks[:-1], self._breaks[1:]
        k = self._segment
        kind = np.array(self.table.kind)[k]
        vehicle = self.motion.rate_bound(a, b)
        gimbal = np.where(kind == "rotate", np.abs(self.table.rate[k]), 0.0)
        # Isolation: the table cancels the yaw, so the IMU turns at the target rate; the
        # vehicle still wobbles the tilt through the gimbal at its own bandwidth.
        iso = kind == "isolate"
        gimbal[iso] = np.abs(self.table.target_rate[k[iso]])
        # On a still vehicle an isolation hold is a stop in disguise: the table has nothing
        # to cancel. (An isolation turn is not a constant-rate turn on a tilted vehicle:
        # a constant heading rate about n's up axis needs a varying gimbal rate.)
        iso_still = iso & (vehicle == 0.0)
        still = ((kind == "stop") & (vehicle == 0.0)) | (iso_still & (gimbal == 0.0))
        stop = kind == "stop"
        table = np.full((len(k), 3, 3), np.nan)
        if np.any(stop):
            table[stop] = table_dcm(
                self.table.a0[k[stop]], self.table.b0[k[stop]], self.table.mounting
            )
        # Constant angular velocity: a still vehicle with the table stopped or turning, or
        # a vehicle turning at a constant rate (a turn, a piece of a heading history)
        # with the table stopped.
        steady = self.motion.constant_rate(a, b)
        constant = ((kind == "stop") & steady) | ((kind == "rotate") & (vehicle == 0.0))
        # Phase classes (with a periodic vehicle): stops see the vehicle through a fixed
        # table (class 0); isolation holds of one target heading are one function of the
        # vehicle phase each (classes 1, 2, ...).
        period = self.motion.repeat_period()
        phase_class = np.full(len(k), -1)
        if period is not None:
            phase_class[stop] = 0
            hold = (kind == "isolate") & (self.table.target_rate[k] == 0.0)
            if np.any(hold):
                target = np.round(np.mod(self.table.target_heading[k[hold]], 2 * np.pi), 9)
                _, cls = np.unique(target, return_inverse=True)
                phase_class[hold] = 1 + cls.reshape(-1)
        return Pieces(
            self._breaks,
            vehicle + gimbal,
            still,
            table,
            period,
            constant,
            phase_class,
        )

    def period(self) -> tuple[float, float] | None:
        """``(t0, P)``: the attitude history repeats with period P after t0, or None.

        An open-loop table repeats its cycle; the vehicle repeats its own period (a
        static base any). P is the least common multiple of the two (when they are
        commensurate to 1e-9 and P leaves at least two periods in the run), and the
        schedule's segments after t0 are checked to recur after P (same kinds, gimbals,
        durations, rates, and angles modulo a full turn; isolation segments also the
        same target heading modulo a full turn and target rate).

        A closed-loop rule declares no cycle, but what it flew may still repeat: on a
        static base the nulling rule's stops all take the minimum and heading isolation
        holds the same headings for the same times. Its least *realized* period, a
        whole number of segments (at most :data:`REALIZED_SEGMENTS`) found by the same
        recurrence check, is returned then.
        """
        cycle = self.table.cycle
        vehicle = self.motion.repeat_period()
        if not self.motion.is_static and vehicle is None:
            return None
        if not cycle:
            # No table cycle: one stop held for the whole run (the "none" scheme) repeats
            # with the vehicle, or with any period on a static base (an hour).
            if len(self.table) == 1 and self.table.kind[0] == "stop":
                return 0.0, (vehicle if vehicle is not None else 3600.0)
            return _realized_period(self.table, vehicle, self._duration)
        period = float(cycle) if vehicle is None else _common_period(float(cycle), vehicle)
        if period is None or 2 * period > self._duration:
            return None
        for t0 in np.unique(np.concatenate([[0.0], self.table.t0[1:2]])):
            if _recurs(self.table, float(t0), period, self._duration):
                return float(t0), period
        return None

    def timeline(self, substep: float = 1.0) -> Timeline:
        """The same history as a :class:`~inserr.model.timeline.Timeline` (:func:`build_timeline`).

        Continuous motion is cut into ``substep``-second sub-steps of constant rate: the
        model of the step-by-step engine, exact for stops and turns on a still vehicle.
        """
        return build_timeline(self.table, self.motion, self._duration, substep)

    def evaluate_vehicle(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``C_b^n`` (N, 3, 3) and ``w_nb^n`` (N, 3, rad/s, ENU) of the vehicle at times ``t``."""
        t = np.asarray(t, dtype=float)
        return rot_z_times(-self.motion.heading_at(t), self.motion.tilt), self.motion.rate_n(t)

    def evaluate(self, t: np.ndarray, piece: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``C_s^n`` (N, 3, 3) and ``w_ns^n`` (N, 3, rad/s, ENU) at times ``t`` of ``piece``."""
        t = np.asarray(t, dtype=float)
        k = self._segment[np.asarray(piece)]
        tab = self.table
        # Heading-only vehicle motion: C_b^n = rot_z(-H) C_tilt (two sines per time).
        c_bn = rot_z_times(-self.motion.heading_at(t), self.motion.tilt)
        w_nb = self.motion.rate_n(t)
        a, b = tab.angles_at(t, self.motion)
        plain = tab.mounting is None and not np.any(b)  # C_s^b = rot_z(a)
        kind = self._kind[k]
        outer = self._outer[k]
        rate = np.where(kind == "rotate", tab.rate[k], 0.0)
        a_dot = np.where(outer, rate, 0.0)
        b_dot = np.where(outer, 0.0, rate)
        iso = kind == "isolate"
        if np.any(iso):
            a_dot[iso] = self._isolation_rate(k[iso], c_bn[iso], w_nb[iso], a[iso], b[iso])
        w_bs = np.zeros((len(t), 3))
        w_bs[:, 2] = a_dot
        w_bs[:, 0] = b_dot * np.cos(a)
        w_bs[:, 1] = b_dot * np.sin(a)
        w = w_nb + np.einsum("nij,nj->ni", c_bn, w_bs)
        if plain:
            return _times_rot_z(c_bn, a), w
        return c_bn @ table_dcm(a, b, tab.mounting), w

    def _isolation_rate(self, k, c_bn, w_nb, a, b) -> np.ndarray:
        """Outer-gimbal rate that keeps the IMU heading on its target (rad/s), for
        segments ``k`` at vehicle attitudes ``c_bn``, rates ``w_nb`` and gimbal angles."""
        tab = self.table
        m = np.eye(3) if tab.mounting is None else tab.mounting
        u = rot_x(b) @ (m @ np.array([0.0, 1.0, 0.0]))  # IMU y axis before the outer gimbal
        ca, sa = np.cos(a), np.sin(a)
        ru = np.stack([ca * u[..., 0] - sa * u[..., 1], sa * u[..., 0] + ca * u[..., 1],
                       np.broadcast_to(u[..., 2], ca.shape)], axis=-1)  # rot_z(a) u  # fmt: skip
        v = np.einsum("nij,nj->ni", c_bn, ru)  # IMU y axis in n
        dv_dt = np.cross(w_nb, v)
        dv_da = np.einsum("nij,nj->ni", c_bn, np.cross(np.array([0.0, 0.0, 1.0]), ru))
        den = v[:, 0] ** 2 + v[:, 1] ** 2

        def dpsi(dv: np.ndarray) -> np.ndarray:
            # heading = atan2(E, N): d heading = (N dE - E dN) / (E^2 + N^2)
            return (v[:, 1] * dv[:, 0] - v[:, 0] * dv[:, 1]) / den

        return (tab.target_rate[k] - dpsi(dv_dt)) / dpsi(dv_da)


def _times_rot_z(m: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """``m @ rot_z(angle)`` for (N, 3, 3) ``m`` and N angles, column by column: columns
    ``c m_0 + s m_1``, ``-s m_0 + c m_1``, ``m_2``."""
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
    out = np.empty_like(m)
    out[:, :, 0] = c * m[:, :, 0] + s * m[:, :, 1]
    out[:, :, 1] = c * m[:, :, 1] - s * m[:, :, 0]
    out[:, :, 2] = m[:, :, 2]
    return out


def _common_period(a: float, b: float, most: int = 1000) -> float | None:
    """Least common multiple of two periods commensurate to 1e-9 (``p a = q b``), or None."""
    for p in range(1, most + 1):
        q = round(p * a / b)
        if q >= 1 and abs(p * a - q * b) <= 1e-9 * p * a:
            return p * a
    return None


#: Most segments per period :func:`_realized_period` tries. A closed-loop rule that
#: repeats does so within a few turns (the nulling rule on a static base: four
#: segments, 1320 s at 300 s stops); a longer search costs time on every run that does
#: not repeat.
REALIZED_SEGMENTS = 64


def _realized_period(
    table: TableSchedule, vehicle: float | None, duration: float
) -> tuple[float, float] | None:
    """``(t0, P)``, P the least whole number of segments after which ``table`` recurs (and
    a multiple of the vehicle's period ``vehicle`` if not None), from ``t0`` = 0 or the
    end of the first segment, with two periods in ``duration``; else None."""
    n = len(table)
    for t0 in np.unique(np.concatenate([[0.0], table.t0[1:2]])):
        j0 = int(np.searchsorted(table.t0, t0 - 1e-9))
        for m in range(1, REALIZED_SEGMENTS + 1):
            if j0 + 2 * m > n or 2 * (table.t0[j0 + m] - t0) > duration:
                break
            # A cheap necessary condition first: the next m segments last as long (to
            # 1e-9 s; a NaN fails it, as allclose would).
            step = table.duration[j0 + m : j0 + 2 * m] - table.duration[j0 : j0 + m]
            if not float(np.max(np.abs(step))) <= 1e-9:
                continue
            p = float(table.t0[j0 + m] - t0)
            period = p if vehicle is None else _common_period(p, vehicle)
            if period is None or 2 * period > duration:
                continue
            if _recurs(table, float(t0), period, duration):
                return float(t0), period
    return None


def _recurs(table: TableSchedule, t0: float, period: float, duration: float) -> bool:
    """Whether every segment starting in ``[t0, duration - period]`` recurs one period later."""
    k = np.flatnonzero((table.t0 >= t0 - 1e-9) & (table.t0 < duration - period - 1e-9))
    if not len(k):
        return False
    later = np.searchsorted(table.t0, table.t0[k] + period - 1e-6)
    if np.any(later >= len(table)):
        return False
    two_pi = 2.0 * np.pi

    def same_angle(x, y):
        return np.all(np.abs(np.remainder(x - y + np.pi, two_pi) - np.pi) < 1e-9)

    kind = np.array(table.kind)
    gimbal = np.array(table.gimbal)
    # An isolation segment's angle is a function of the vehicle attitude, its inner
    # angle and its target heading (the branch follows a0): it recurs when those do.
    iso = k[kind[k] == "isolate"]
    iso_later = later[kind[k] == "isolate"]
    return bool(
        np.all(np.abs(table.t0[later] - table.t0[k] - period) < 1e-6)
        and np.all(kind[later] == kind[k])
        and np.all(gimbal[later] == gimbal[k])
        and np.allclose(table.duration[later], table.duration[k], rtol=0, atol=1e-9)
        and np.allclose(table.rate[later], table.rate[k], rtol=0, atol=1e-15)
        and same_angle(table.a0[later], table.a0[k])
        and same_angle(table.b0[later], table.b0[k])
        and same_angle(table.target_heading[iso_later], table.target_heading[iso])
        and np.allclose(table.target_rate[iso_later], table.target_rate[iso], rtol=0, atol=1e-15)
    )
