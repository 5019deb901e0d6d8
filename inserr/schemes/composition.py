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
from inserr.model.timeline import Timeline
from inserr.schemes.turntable import TableSchedule, gimbal_axis_b
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
