"""Closed-form cycle integrals of periodic indexing schemes on a static base.

Over one cycle a constant IMU-frame bias ``b`` (gyro or accelerometer) contributes
``(integral of C_s^n dt) b`` to the navigation-frame error integral. A scheme cancels
horizontal biases when the horizontal block of that integral (rows E, N; columns
IMU x, y) vanishes. Stops contribute ``C dwell``. A turn of one gimbal at rate r
from angle x0 to x1 contributes ``(F(x1) - F(x0)) / r`` through the antiderivatives

    F_z(x) = [[sin x, cos x, 0], [-cos x, sin x, 0], [0, 0, x]]   (d/dx F_z = rot_z(x))
    F_x(x) = [[x, 0, 0], [0, sin x, cos x], [0, -cos x, sin x]]   (d/dx F_x = rot_x(x))

During a turn about one gimbal axis the IMU rate ``w^s`` is constant (the axis is
fixed in both frames), so the scale-factor/misalignment x table-rate term
``integral C_s^n K w^s dt`` is also closed-form: ``(integral of C_s^n dt over the
turn) K w^s``. It does not vanish unless each gimbal turns as much one way as the
other: that is why reversal matters.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from inserr.errors import InputError
from inserr.imu import MISALIGNMENT_INDEX, MISALIGNMENTS
from inserr.motion import Motion
from inserr.rotations import rot_x, rot_z
from inserr.schemes import TableScheme


def f_z(x: float) -> np.ndarray:
    """Antiderivative of ``rot_z(x)`` with respect to x."""
    s, c = math.sin(x), math.cos(x)
    return np.array([[s, c, 0.0], [-c, s, 0.0], [0.0, 0.0, x]])


def f_x(x: float) -> np.ndarray:
    """Antiderivative of ``rot_x(x)`` with respect to x."""
    s, c = math.sin(x), math.cos(x)
    return np.array([[x, 0.0, 0.0], [0.0, s, c], [0.0, -c, s]])


@dataclass(frozen=True)
class CycleIntegrals:
    """Cycle integrals of a periodic scheme (static vehicle).

    Attributes
    ----------
    cycle_time : float, s
    full : (3, 3) s
        Integral of ``C_s^n`` over one cycle (rows ENU, columns IMU x, y, z).
    stops : (3, 3) s
        Contribution of the stops.
    turns : (3, 3) s
        Contribution of the turns.
    scale_factor : (3, 3) rad
        ``integral C_s^n diag(e_i) w^s dt`` over the turns, column i = unit
        scale-factor error on IMU axis i (table rate only, Earth rate excluded).
    misalignment : (3, 6) rad
        Same for unit misalignments in the order xy, xz, yx, yz, zx, zy.
    motor_starts : int
        Motor starts per cycle.
    """

    cycle_time: float
    full: np.ndarray
    stops: np.ndarray
    turns: np.ndarray
    scale_factor: np.ndarray
    misalignment: np.ndarray
    motor_starts: int

    @property
    def horizontal(self) -> np.ndarray:
        """Horizontal block (rows E, N; columns IMU x, y), s."""
        return self.full[:2, :2]

    @property
    def residual_drift_fraction(self) -> float:
        """Largest |element| of the horizontal block divided by the cycle time."""
        return float(np.max(np.abs(self.horizontal)) / self.cycle_time)

    @property
    def motor_starts_per_hour(self) -> float:
        """Motor starts per hour of operation."""
        return self.motor_starts * 3600.0 / self.cycle_time


def cycle_integrals(scheme: TableScheme, motion: Motion | None = None) -> CycleIntegrals:
    """Closed-form integrals over one cycle of an open-loop scheme on a static vehicle.

    Parameters
    ----------
    scheme : TableScheme
        An open-loop scheme with a non-empty cycle.
    motion : Motion, optional
        Static vehicle attitude (heading, pitch, roll); default level, heading 0
        (body = ENU).

    Raises
    ------
    InputError
        For closed-loop or non-periodic schemes.
    """
    if not isinstance(scheme, TableScheme) or not scheme.steps:
        name = getattr(scheme, "name", str(scheme))
        raise InputError(
            "--scheme",
            f"{name} has no fixed cycle",
            "cycle integrals exist for periodic open-loop schemes; use `inserr drift` for this one",
        )
    motion = motion or Motion()
    if not isinstance(motion, Motion) or type(motion) is not Motion:
        raise InputError("motion", "cycle integrals are defined on a static base")
    c_bn = motion.attitude(np.array([0.0]))[0]
    m = np.eye(3) if scheme.mounting is None else scheme.mounting
    a, b = scheme.start
    stops = np.zeros((3, 3))
    turns = np.zeros((3, 3))
    sf = np.zeros((3, 3))
    mis = np.zeros((3, 6))
    starts = 0
    # The cycle repeats: the turn before the first one is the last turn of the cycle.
    prev_sign = math.copysign(1.0, scheme.steps[-1].angle)
    prev_dwell = scheme.steps[-1].dwell
    for s in scheme.steps:
        t_turn = s.rotation_time if s.rotation_time is not None else abs(s.angle) / scheme.rate
        r = s.angle / t_turn
        if s.gimbal == "outer":
            integ = (f_z(a + s.angle) - f_z(a)) / r @ rot_x(b) @ m
            w_s = r * (rot_x(b) @ m).T @ np.array([0.0, 0.0, 1.0])
            a += s.angle
        else:
            integ = rot_z(a) @ (f_x(b + s.angle) - f_x(b)) / r @ m
            w_s = r * m.T @ np.array([1.0, 0.0, 0.0])
            b += s.angle
        integ_n = c_bn @ integ
        turns += integ_n
        for i in range(3):
            sf[:, i] += integ_n[:, i] * w_s[i]
        for j, name in enumerate(MISALIGNMENTS):
            row, col = MISALIGNMENT_INDEX[name]
            mis[:, j] += integ_n[:, row] * w_s[col]
        sign = math.copysign(1.0, s.angle)
        if prev_dwell > 0 or sign != prev_sign:
            starts += 1
        prev_sign, prev_dwell = sign, s.dwell
        stops += c_bn @ rot_z(a) @ rot_x(b) @ m * s.dwell
    cycle = scheme.cycle_time
    return CycleIntegrals(cycle, stops + turns, stops, turns, sf, mis, starts)
