"""Rotation-modulation north finder (P3): Kalman filter and heading/latitude solution.

The filter (filterpy ``KalmanFilter``) estimates the six constants
``x = [A, B, C, D, eps', nabla']`` of :mod:`inserr.northfinder.instrument` from the sensor
increments summed over each filter period ``[t_k, t_k + T]``::

    z_g = (1/T) sum(gyro increments)  = [c_k, s_k, 0, 0, 1, 0] x + v_g
    z_a = (1/T) sum(accel increments) = [0, 0, c_k, s_k, 0, 1] x + v_a
    c_k = (1/T) int cos(alpha) dt,  s_k = (1/T) int sin(alpha) dt   (exact)

with ``var(v_g) = ARW^2 / T`` and ``var(v_a) = VRW^2 / T``. Each Monte Carlo run has
its own filterpy filter, fed one ``(2, 1)`` measurement column per period as filterpy's
``(dim_z, 1)`` contract requires (so its residual ``y``, ``S``, likelihood and
Mahalanobis distance are those of that run). The model is linear with a
data-independent H, so the covariance is the same in every run.

:func:`solve` then turns the constants into pitch, roll, heading and (unless given)
latitude, exactly (no small angles); ``docs/tutorials/northfinding.md`` has the algebra.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from filterpy.kalman import KalmanFilter
from numpy.typing import ArrayLike

from inserr.core import earth
from inserr.core.errors import InputError, require_latitude
from inserr.northfinder.instrument import Instrument, SensorData, SensorGrade, table_angle_integrals

#: Diffuse prior: 1 sigma of the initial state, in multiples of the largest physical
#: value (Earth rate for A, B, eps'; g for C, D, nabla'). Large enough that the prior
#: pulls the estimate by < 1e-10 of its size after a few minutes, small enough that
#: prior/measurement variance ratios (~1e11) stay well inside double precision.
PRIOR_SCALE_GYRO = 1e3
PRIOR_SCALE_ACCEL = 10.0
#: Fixed-point iterations of the latitude-dependent gravity in the unknown-latitude
#: solution: each one shrinks the error by ~(dg/dL / g) * tilt < 1e-3.
GRAVITY_ITERATIONS = 6
#: Hemisphere names a user declares, and the sign of the Earth rate's component along
#: the table normal that each selects.
HEMISPHERES = {"north": 1, "south": -1}


def hemisphere_sign(hemisphere: int | str) -> int:
    """The declared hemisphere as the sign the solver uses.

    Parameters
    ----------
    hemisphere : {"north", "south", 1, -1}
        The user's declaration.

    Returns
    -------
    int
        +1 for north, -1 for south.
    """
    if isinstance(hemisphere, str) and hemisphere.strip().lower() in HEMISPHERES:
        return HEMISPHERES[hemisphere.strip().lower()]
    if not isinstance(hemisphere, str) and hemisphere in (1, -1):
        return int(hemisphere)
    raise InputError(
        "hemisphere",
        f"must be 'north' (+1) or 'south' (-1), got {hemisphere!r}",
        "declare the hemisphere the instrument stands in",
    )


def hemisphere_name(sign: int) -> str:
    """``"north"`` for +1, ``"south"`` for -1 (see :func:`hemisphere_sign`).

    Parameters
    ----------
    sign : int
        +1 or -1.

    Returns
    -------
    str
    """
    return "north" if hemisphere_sign(sign) > 0 else "south"


def measurement_rows(instrument: Instrument, n_periods: int) -> np.ndarray:
    """Measurement matrices ``H_k`` of the filter periods ``k = 0 .. n_periods - 1``.

    Parameters
    ----------
    instrument : Instrument
        Table rate (rad/s) and filter period (s).
    n_periods : int
        Number of filter periods.

    Returns
    -------
    ndarray (n_periods, 2, 6)
        Rows ``[c_k, s_k, 0, 0, 1, 0]`` and ``[0, 0, c_k, s_k, 0, 1]`` with ``c_k, s_k``
        the period means of ``cos(alpha)`` and ``sin(alpha)`` (dimensionless).
    """
    period = instrument.filter_period
    c, s = table_angle_integrals(instrument, np.arange(n_periods) * period, period)
    h = np.zeros((n_periods, 2, 6))
    h[:, 0, 0] = c / period
    h[:, 0, 1] = s / period
    h[:, 0, 4] = 1.0
    h[:, 1, 2] = c / period
    h[:, 1, 3] = s / period
    h[:, 1, 5] = 1.0
    return h


def period_measurements(data: SensorData, instrument: Instrument) -> np.ndarray:
    """Mean gyro rate and mean specific force over each filter period.

    The known table-rate leakage ``sin(th1) * table_rate`` of a tilted gyro is removed
    here so that ``eps'`` starts near zero (it would otherwise be up to ~0.1 rad/s and
    spoil the conditioning of a diffuse prior).

    Parameters
    ----------
    data : SensorData
        Angle increments (rad) and velocity increments (m/s), (n_runs, n_samples).
    instrument : Instrument
        Sample rate (Hz), filter period (s), gyro tilt (rad) and table rate (rad/s).

    Returns
    -------
    ndarray (n_periods, 2, n_runs)
        Rows: gyro rad/s, accelerometer m/s^2.
    """
    m = instrument.samples_per_period
    n_runs, n = data.gyro.shape
    n_periods = n // m
    period = instrument.filter_period
    g = data.gyro[:, : n_periods * m].reshape(n_runs, n_periods, m).sum(axis=-1) / period
    a = data.accel[:, : n_periods * m].reshape(n_runs, n_periods, m).sum(axis=-1) / period
    g -= math.sin(instrument.gyro_tilt) * instrument.table_rate
    return np.stack([g.T, a.T], axis=1)


def make_filter(instrument: Instrument, grade: SensorGrade) -> KalmanFilter:
    """A filterpy ``KalmanFilter`` for the six constants of one run.

    ``x`` is a (6, 1) column (zero) and ``P`` the diffuse prior. ``F = I``; ``Q`` lets
    ``eps'`` and ``nabla'`` wander as a random walk with the short-time rate of the
    Gauss-Markov bias instability, ``2 sigma^2 / tau`` per second (a random walk, not a
    decaying Gauss-Markov state, because ``eps'`` also holds constant terms that must
    not decay). ``R = diag(ARW^2, VRW^2) / T``. ``H`` changes every period and is passed
    to ``update`` (see :func:`measurement_rows`).

    Parameters
    ----------
    instrument : Instrument
        Filter period T (s).
    grade : SensorGrade
        The filter's noise model: ARW (rad/sqrt(s)) and VRW (m/s/sqrt(s)), both > 0,
        bias instabilities (rad/s, m/s^2) and correlation times (s).

    Returns
    -------
    filterpy.kalman.KalmanFilter
        ``dim_x = 6``, ``dim_z = 2``; states in rad/s and m/s^2.
    """
    if grade.gyro_arw <= 0 or grade.accel_vrw <= 0:
        raise InputError(
            "grade",
            "the filter needs non-zero ARW and VRW to weight its measurements",
            "give the sensors' white noise (noise-free data may still be fed in)",
        )
    period = instrument.filter_period
    kf = KalmanFilter(dim_x=6, dim_z=2)
    kf.x = np.zeros((6, 1))
    gyro0 = PRIOR_SCALE_GYRO * earth.OMEGA_IE
    accel0 = PRIOR_SCALE_ACCEL * earth.GAMMA_P
    kf.P = np.diag([gyro0, gyro0, accel0, accel0, gyro0, accel0]) ** 2
    kf.F = np.eye(6)
    q = np.zeros(6)
    q[4] = 2.0 * grade.gyro_bias_instability**2 / grade.gyro_correlation_time * period
    q[5] = 2.0 * grade.accel_bias_instability**2 / grade.accel_correlation_time * period
    kf.Q = np.diag(q)
    kf.R = np.diag([grade.gyro_arw**2, grade.accel_vrw**2]) / period
    return kf


@dataclass(frozen=True)
class FilterOutput:
    """States and covariance after every filter update.

    Attributes
    ----------
    times : ndarray (n_periods,)
        End of each filter period, s.
    x : ndarray (n_periods, 6, n_runs)
        ``[A, B, C, D, eps', nabla']`` per run (rad/s, m/s^2).
    P : ndarray (n_periods, 6, 6)
        Filter covariance, (rad/s)^2 and (m/s^2)^2 (the same in every run: it does
        not depend on the data).
    """

    times: np.ndarray
    x: np.ndarray
    P: np.ndarray


def run_filter(z: np.ndarray, instrument: Instrument, grade: SensorGrade) -> FilterOutput:
    """Run one Kalman filter per Monte Carlo run over period measurements ``z``.

    Each run gets its own filterpy ``KalmanFilter`` and every update receives that
    run's measurement as a ``(2, 1)`` column, as filterpy's ``(dim_z, 1)`` contract
    asks. (Passing all runs as the columns of one ``(2, n_runs)`` block gives the same
    states, because the gain does not depend on the data, but filterpy's residual,
    likelihood and Mahalanobis distance assume one column and would be wrong; and
    filterpy 2.0.0 skips its reshape of ``z`` when ``H`` is given, so a 1-D ``z``
    would broadcast ``z - H x`` to a wrong shape without an error.) The cost is about
    30 microseconds per run and period, well below that of simulating the samples.

    Parameters
    ----------
    z : ndarray (n_periods, 2, n_runs)
        Period means from :func:`period_measurements`: gyro rad/s, accelerometer m/s^2.
    instrument : Instrument
        The estimator's instrument (table rate rad/s, filter period s).
    grade : SensorGrade
        Sets R and Q (the filter's noise model), independent of how the data were made.

    Returns
    -------
    FilterOutput
    """
    z = np.asarray(z, dtype=float)
    if z.ndim != 3 or z.shape[1] != 2 or z.shape[2] < 1:
        raise InputError("z", f"expected shape (n_periods, 2, n_runs >= 1), got {z.shape}")
    n_periods, _, n_runs = z.shape
    rows = measurement_rows(instrument, n_periods)
    xs = np.empty((n_periods, 6, n_runs))
    ps = np.empty((n_periods, 6, 6))
    for run in range(n_runs):
        kf = make_filter(instrument, grade)
        for k in range(n_periods):
            kf.predict()
            kf.update(z[k, :, run : run + 1], H=rows[k])
            xs[k, :, run] = kf.x[:, 0]
            if run == 0:
                ps[k] = kf.P
    times = (np.arange(n_periods) + 1) * instrument.filter_period
    return FilterOutput(times=times, x=xs, P=ps)


@dataclass(frozen=True)
class Solution:
    """Attitude and latitude solved from the filter states (arrays of any shape, rad).

    ``ambiguous`` is True where the mirror root (see
    :func:`inserr.northfinder.instrument.mirror_pose`)
    lies in the same hemisphere, so the hemisphere alone does not confirm the root
    (roughly ``|lat|`` < twice the table's tilt toward the equator). The chosen root is
    still right while that tilt is less than ``|lat|``; beyond, it is the mirror.
    """

    heading: np.ndarray
    lat: np.ndarray
    pitch: np.ndarray
    roll: np.ndarray
    ambiguous: np.ndarray


def level_from_accel(
    c: ArrayLike, d: ArrayLike, g: ArrayLike, instrument: Instrument, model: str = "exact"
) -> tuple[np.ndarray, np.ndarray]:
    """Pitch and roll from the accelerometer amplitudes ``C, D``.

    ``model="exact"`` undoes the mounting exactly:
    ``[C0, D0] = rot(-phi) [C, D] / cos(eta)``, then ``sin(pitch) = C0 / g`` and
    ``cos(pitch) sin(roll) = D0 / g``. ``model="p3"`` uses P3's first-order mounting
    terms ``C0 = C - phi D``, ``D0 = D + phi C`` and ignores ``cos(eta)``.

    Parameters
    ----------
    c, d : array
        Accelerometer cosine and sine amplitudes, m/s^2.
    g : array
        Gravity magnitude, m/s^2 (broadcast with ``c``).
    instrument : Instrument
        Accelerometer mounting angles ``phi``, ``eta`` (rad) as calibrated.
    model : "exact" or "p3"
        Inversion model.

    Returns
    -------
    pitch, roll : ndarray
        rad.
    """
    phi, eta = instrument.accel_azimuth, instrument.accel_tilt
    if model == "exact":
        cp, sp = math.cos(phi), math.sin(phi)
        c0 = (cp * c - sp * d) / math.cos(eta)
        d0 = (sp * c + cp * d) / math.cos(eta)
    elif model == "p3":
        c0 = c - phi * d
        d0 = d + phi * c
    else:
        raise InputError("model", f"unknown model {model!r}", "use 'exact' or 'p3'")
    pitch = np.arcsin(np.clip(c0 / g, -1.0, 1.0))
    roll = np.arcsin(np.clip(d0 / (g * np.cos(pitch)), -1.0, 1.0))
    return pitch, roll


def _level_axes(pitch: ArrayLike, roll: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Columns r1, r2, r3 of ``R = rot_x(pitch) rot_y(roll)`` (body axes, heading-level frame)."""
    sp, cp, sr, cr = np.sin(pitch), np.cos(pitch), np.sin(roll), np.cos(roll)
    zero = np.zeros_like(sp)
    r1 = np.stack([cr, sp * sr, -cp * sr])
    r2 = np.stack([zero, cp, sp])
    r3 = np.stack([sr, -sp * cr, cp * cr])
    return r1, r2, r3


def heading_latitude(
    w_x: ArrayLike,
    w_y: ArrayLike,
    pitch: ArrayLike,
    roll: ArrayLike,
    *,
    lat: float | None = None,
    hemisphere: int = 1,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Heading and latitude from the Earth rate's table-plane components ``w_x, w_y``.

    Parameters
    ----------
    w_x, w_y : array
        ``w^b_x = -B / cos(th1)`` and ``w^b_y = A / cos(th1)``, rad/s.
    pitch, roll : array
        rad.
    lat : float, optional
        Known latitude, rad. Then ``w^l = [-W_N sin h, W_N cos h, W_U]`` is known up to
        the heading and ``r1 . w^l = w_x``, ``r2 . w^l = w_y`` are linear in
        ``(sin h, cos h)``.
    hemisphere : +1 or -1
        The user's declaration (north or south), used when ``lat`` is None.
        ``w^l = w_x r1 + w_y r2 + lam r3`` with ``lam^2 = Omega^2 - w_x^2 - w_y^2``;
        the root has ``sign(lam) = hemisphere`` (the elevated celestial pole above the
        table plane). The data cannot supply this bit: both roots fit them exactly.

    Returns
    -------
    heading, lat, ambiguous : arrays
        rad in [0, 2 pi) and (-pi/2, pi/2); ``ambiguous`` as in :class:`Solution`.
    """
    r1, r2, r3 = _level_axes(pitch, roll)
    if lat is not None:
        w_n = earth.OMEGA_IE * math.cos(lat)
        w_u = earth.OMEGA_IE * math.sin(lat)
        cos_h = (w_y - r2[2] * w_u) / (w_n * r2[1])
        sin_h = (r1[1] * w_n * cos_h - (w_x - r1[2] * w_u)) / (w_n * r1[0])
        heading = np.mod(np.arctan2(sin_h, cos_h), 2 * math.pi)
        shape = np.shape(heading)
        return heading, np.full(shape, lat), np.zeros(shape, dtype=bool)
    lam2 = np.maximum(earth.OMEGA_IE**2 - w_x**2 - w_y**2, 0.0)
    lam = hemisphere * np.sqrt(lam2)
    in_plane = w_x * r1 + w_y * r2
    w = in_plane + lam * r3
    heading = np.mod(np.arctan2(-w[0], w[1]), 2 * math.pi)
    lat_hat = np.arctan2(w[2], np.hypot(w[0], w[1]))
    # The mirror root has up-component in_plane_z - lam r3_z; same sign => ambiguous.
    mirror_up = in_plane[2] - lam * r3[2]
    ambiguous = hemisphere * mirror_up > 0
    return heading, lat_hat, ambiguous


def solve(
    x: np.ndarray,
    instrument: Instrument,
    *,
    lat: float | None = None,
    hemisphere: int = 1,
    height: float = 0.0,
    model: str = "exact",
) -> Solution:
    """Pitch, roll, heading and latitude from filter states ``x`` (6, ...).

    Parameters
    ----------
    x : ndarray (6, ...)
        ``[A, B, C, D, eps', nabla']`` (rad/s, m/s^2), any trailing shape.
    instrument : Instrument
        Mounting angles as calibrated (the estimator's knowledge).
    lat : float, optional
        Known latitude, rad; if None it is estimated too.
    hemisphere : +1 or -1
        The hemisphere the user declares (north or south; see
        :func:`hemisphere_sign`); only used when ``lat`` is None. Never taken from
        the data, which cannot tell the two roots apart.
    height : float
        m, for normal gravity.
    model : "exact" or "p3"
        ``"p3"`` reproduces P3's small-angle mounting model (``cos th1 = cos eta = 1``,
        first-order ``phi``); ``"exact"`` inverts the exact geometry.

    Returns
    -------
    Solution
        Heading, latitude, pitch and roll in rad, shaped like ``x[0]``.
    """
    hemisphere = hemisphere_sign(hemisphere)
    if lat is not None:
        require_latitude(lat, "lat")
    x = np.asarray(x, dtype=float)
    a, b, c, d = x[0], x[1], x[2], x[3]
    c1 = math.cos(instrument.gyro_tilt) if model == "exact" else 1.0
    w_x, w_y = -b / c1, a / c1
    g = earth.gravity(lat if lat is not None else 0.0, height)
    g = np.full(np.shape(a), g)
    iterations = 1 if lat is not None else GRAVITY_ITERATIONS
    for _ in range(iterations):
        pitch, roll = level_from_accel(c, d, g, instrument, model)
        heading, lat_hat, ambiguous = heading_latitude(
            w_x, w_y, pitch, roll, lat=lat, hemisphere=hemisphere
        )
        # Normal gravity depends on latitude only through sin^2(L), as earth.gravity does.
        g = _gravity_array(lat_hat, height)
    return Solution(heading=heading, lat=lat_hat, pitch=pitch, roll=roll, ambiguous=ambiguous)


def _gravity_array(lat: np.ndarray, height: float) -> np.ndarray:
    """:func:`inserr.core.earth.gravity` over an array of latitudes (rad) -> m/s^2, same shape."""
    return np.broadcast_to(np.asarray(earth.gravity(lat, height), dtype=float), np.shape(lat))


def wrap_angle(angle: ArrayLike) -> np.ndarray:
    """Wrap an angle difference to [-pi, pi).

    Parameters
    ----------
    angle : array
        rad.

    Returns
    -------
    ndarray
        rad, in [-pi, pi).
    """
    return np.mod(np.asarray(angle) + math.pi, 2 * math.pi) - math.pi
