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

from inserr.core.errors import InputError
from inserr.core.imu import MISALIGNMENT_INDEX, MISALIGNMENTS
from inserr.core.rotations import rot_x, rot_z
from inserr.schemes.open_loop import TableScheme
from inserr.schemes.vehicle_motion import Motion, heading_sign


def f_z(x: float) -> np.ndarray:
    """Antiderivative ``F_z(x)`` of ``rot_z(x)`` with respect to x.

    Parameters
    ----------
    x : float
        Angle, rad.

    Returns
    -------
    ndarray, shape (3, 3)
        ``F_z(x)``, with ``d/dx F_z = rot_z``.
    """
    s, c = math.sin(x), math.cos(x)
    return np.array([[s, c, 0.0], [-c, s, 0.0], [0.0, 0.0, x]])


def f_x(x: float) -> np.ndarray:
    """Antiderivative ``F_x(x)`` of ``rot_x(x)`` with respect to x.

    Parameters
    ----------
    x : float
        Angle, rad.

    Returns
    -------
    ndarray, shape (3, 3)
        ``F_x(x)``, with ``d/dx F_x = rot_x``.
    """
    s, c = math.sin(x), math.cos(x)
    return np.array([[x, 0.0, 0.0], [0.0, s, c], [0.0, -c, s]])


def g_z(x: float) -> np.ndarray:
    """Antiderivative ``G_z(x)`` of :func:`f_z` (second antiderivative of ``rot_z``).

    Parameters
    ----------
    x : float
        Angle, rad.

    Returns
    -------
    ndarray, shape (3, 3)
        ``G_z(x)``, with ``d/dx G_z = F_z``.
    """
    s, c = math.sin(x), math.cos(x)
    return np.array([[-c, s, 0.0], [-s, -c, 0.0], [0.0, 0.0, 0.5 * x * x]])


def g_x(x: float) -> np.ndarray:
    """Antiderivative ``G_x(x)`` of :func:`f_x` (second antiderivative of ``rot_x``).

    Parameters
    ----------
    x : float
        Angle, rad.

    Returns
    -------
    ndarray, shape (3, 3)
        ``G_x(x)``, with ``d/dx G_x = F_x``.
    """
    s, c = math.sin(x), math.cos(x)
    return np.array([[0.5 * x * x, 0.0, 0.0], [0.0, -c, s], [0.0, -s, -c]])


@dataclass(frozen=True)
class CycleIntegrals:
    """Cycle integrals of a periodic scheme (static vehicle).

    Attributes
    ----------
    cycle_time : float, s
        Duration of one cycle (turns and their dwells).
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
    mean_excursion : (3, 3) s
        Cycle average of the running integral ``U(t) = int_0^t C_s^n dt`` (from the
        start of the run, first stop included), per unit IMU-frame bias.
    mean_excursion_scale_factor : (3, 3) rad
    mean_excursion_misalignment : (3, 6) rad
        The same for the scale-factor and misalignment x table-rate terms.
    motor_starts : int
        Motor starts per cycle.

    Notes
    -----
    A zero cycle integral is necessary but not sufficient. With gyro forcing
    ``u = dU/dt``, ``chi = psi + U`` obeys ``chi' = -Omega x chi + Omega x U(t)``: the
    cycle mean of ``U`` is an attitude offset acting as the drift ``Omega x mean(U)``
    (:meth:`equivalent_drift`; perpendicular to Omega, so its effect is bounded),
    and the periodic rest of ``U`` forces the Schuler loop at the cycle frequency
    (see ``docs/theory.md``, resonance).
    """

    cycle_time: float
    full: np.ndarray
    stops: np.ndarray
    turns: np.ndarray
    scale_factor: np.ndarray
    misalignment: np.ndarray
    mean_excursion: np.ndarray
    mean_excursion_scale_factor: np.ndarray
    mean_excursion_misalignment: np.ndarray
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

    @staticmethod
    def equivalent_drift(earth_rate_n: np.ndarray, excursion: np.ndarray) -> np.ndarray:
        """``Omega x mean(U)`` column by column: equivalent gyro drift (ENU) per unit error.

        For a bias excursion (s) the result is dimensionless (drift per unit bias);
        for a scale-factor or misalignment excursion (rad) it is rad/s per unit error.

        Parameters
        ----------
        earth_rate_n : (3,) array, rad/s
            Earth rate resolved in ENU (:attr:`inserr.core.earth.Site.earth_rate_n`).
        excursion : (3, k) array
            A mean excursion (rows ENU), e.g. :attr:`mean_excursion` (s) or
            :attr:`mean_excursion_scale_factor` (rad).

        Returns
        -------
        ndarray, shape (3, k)
            Equivalent drift per unit error, resolved in ENU.
        """
        return np.cross(earth_rate_n, np.asarray(excursion).T).T


def cycle_integrals(scheme: TableScheme, motion: Motion | None = None) -> CycleIntegrals:
    """Closed-form integrals over one cycle of an open-loop scheme on a static vehicle.

    Parameters
    ----------
    scheme : TableScheme
        An open-loop scheme with a non-empty cycle.
    motion : Motion, optional
        Static vehicle attitude (heading, pitch, roll); default level, heading 0
        (body = ENU).

    Returns
    -------
    CycleIntegrals
        Integrals of ``C_s^n`` over one cycle (s, or rad for the rate terms).

    Raises
    ------
    InputError
        For closed-loop or non-periodic schemes, or a non-static motion.
    """
    if not isinstance(scheme, TableScheme) or not scheme.steps:
        name = getattr(scheme, "name", str(scheme))
        raise InputError(
            "scheme.name",
            f"{name} has no fixed cycle",
            "cycle integrals exist for periodic open-loop schemes; use `inserr drift` for this one",
        )
    motion = motion or Motion()
    if not motion.is_static:
        raise InputError("motion", "cycle integrals are defined on a static base")
    c_bn = motion.attitude(np.array([0.0]))[0]
    m = np.eye(3) if scheme.mounting is None else scheme.mounting
    a, b = scheme.start
    acc = _Accumulator()
    # The run opens with the first dwell: it sets the origin of the running integrals.
    first = c_bn @ rot_z(a) @ rot_x(b) @ m
    u0 = first * scheme.first_dwell
    starts = 0
    # The cycle repeats: the turn before the first one is the last turn of the cycle.
    prev_sign = math.copysign(1.0, scheme.steps[-1].angle)
    prev_dwell = scheme.steps[-1].dwell
    for s in scheme.steps:
        t_turn = s.rotation_time if s.rotation_time is not None else abs(s.angle) / scheme.rate
        r = s.angle / t_turn
        if s.gimbal == "outer":
            left, right = c_bn, rot_x(b) @ m
            f0, f1, g0, g1 = f_z(a), f_z(a + s.angle), g_z(a), g_z(a + s.angle)
            w_s = r * (rot_x(b) @ m).T @ np.array([0.0, 0.0, 1.0])
            a += s.angle
        else:
            left, right = c_bn @ rot_z(a), m
            f0, f1, g0, g1 = f_x(b), f_x(b + s.angle), g_x(b), g_x(b + s.angle)
            w_s = r * m.T @ np.array([1.0, 0.0, 0.0])
            b += s.angle
        single = left @ ((f1 - f0) / r) @ right
        double = left @ ((g1 - g0) / r**2 - f0 * t_turn / r) @ right
        acc.turn(single, double, t_turn, w_s)
        sign = math.copysign(1.0, s.angle)
        if prev_dwell > 0 or sign != prev_sign:
            starts += 1
        prev_sign, prev_dwell = sign, s.dwell
        acc.stop(c_bn @ rot_z(a) @ rot_x(b) @ m, s.dwell)
    cycle = scheme.cycle_time
    return CycleIntegrals(
        cycle_time=cycle,
        full=acc.stops + acc.turns,
        stops=acc.stops,
        turns=acc.turns,
        scale_factor=acc.u_sf,
        misalignment=acc.u_mis,
        mean_excursion=u0 + acc.s_bias / cycle,
        mean_excursion_scale_factor=acc.s_sf / cycle,
        mean_excursion_misalignment=acc.s_mis / cycle,
        motor_starts=starts,
    )


class _Accumulator:
    """Running first integrals ``U`` and their time integrals ``S`` over a cycle."""

    def __init__(self) -> None:
        self.stops = np.zeros((3, 3))
        self.turns = np.zeros((3, 3))
        self.s_bias = np.zeros((3, 3))
        self.u_sf = np.zeros((3, 3))
        self.s_sf = np.zeros((3, 3))
        self.u_mis = np.zeros((3, 6))
        self.s_mis = np.zeros((3, 6))

    @property
    def u_bias(self) -> np.ndarray:
        return self.stops + self.turns

    def stop(self, c: np.ndarray, dwell: float) -> None:
        self.s_bias += self.u_bias * dwell + c * dwell**2 / 2
        self.s_sf += self.u_sf * dwell
        self.s_mis += self.u_mis * dwell
        self.stops += c * dwell

    def turn(self, single: np.ndarray, double: np.ndarray, t_turn: float, w_s: np.ndarray) -> None:
        self.s_bias += self.u_bias * t_turn + double
        self.turns += single
        # Rate terms: the unit error K = e_row e_col^T gives C e_row (w_s)_col.
        sf1 = single * w_s[None, :]
        sf2 = double * w_s[None, :]
        rows = [MISALIGNMENT_INDEX[n] for n in MISALIGNMENTS]
        mis1 = np.column_stack([single[:, r] * w_s[c] for r, c in rows])
        mis2 = np.column_stack([double[:, r] * w_s[c] for r, c in rows])
        self.s_sf += self.u_sf * t_turn + sf2
        self.s_mis += self.u_mis * t_turn + mis2
        self.u_sf += sf1
        self.u_mis += mis1


def scenario_cycle(scen) -> tuple[TableScheme, Motion, str]:
    """The scheme of a scenario and the static base its cycle integrals are taken on.

    Cycle integrals are defined on a static base: a moving base is held at its
    attitude at t = 0.

    Parameters
    ----------
    scen : Scenario
        ``scheme.name`` must be given (a periodic open-loop scheme).

    Returns
    -------
    scheme : TableScheme
    base : Motion
        Static, at the scenario's heading, pitch and roll at t = 0.
    description : str
        The base in words.
    """
    if not scen.given("scheme.name"):
        raise InputError("scheme.name", "no scheme given", "name a periodic open-loop scheme")
    m = scen.motion
    h0 = float(m.heading_at(0.0))
    base = Motion(heading=h0, pitch=m.pitch, roll=m.roll)
    if h0 == 0.0 and m.pitch == 0.0 and m.roll == 0.0:
        desc = "level, heading 0 (body = ENU)"
    else:
        # Written back in the scenario's declared sense (the motion holds clockwise).
        k = heading_sign(scen.heading_convention)
        desc = (
            f"heading {math.degrees(k * h0):g} deg, pitch {math.degrees(m.pitch):g} deg, "
            f"roll {math.degrees(m.roll):g} deg"
        )
    if type(m) is not Motion:
        desc += f" (the scenario's {m.name} motion held at its t = 0 attitude)"
    steps = scen.scheme_options.get("steps") if scen.scheme_name == "custom" else None
    if steps:
        # A cycle integral means something only over a cycle that brings the table
        # back to its start: each gimbal's turns must add up to whole revolutions.
        for gimbal in ("outer", "inner"):
            net = sum(s.angle for s in steps if s.gimbal == gimbal)
            turns = net / (2.0 * math.pi)
            if abs(turns - round(turns)) > 1e-9:
                raise InputError(
                    "scheme.steps",
                    f"the custom cycle turns the {gimbal} gimbal by {math.degrees(net):g} deg "
                    "in all, so it does not return to its start",
                    "make each gimbal's angles add up to a multiple of 360 deg",
                )
    return scen.scheme(), base, desc
