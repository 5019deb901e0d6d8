"""Rotation-modulation north finder (P3): instrument model and exact sensor simulation.

One single-axis gyro and one accelerometer sit on a table that turns continuously
about its normal. Their outputs are sinusoids in the table angle whose amplitudes
carry the horizontal Earth rate (heading, latitude) and the tilt of the table
(pitch, roll); biases stay constant and drop out. This module holds the parameters,
the exact geometry and the simulation; :mod:`inserr.northfinder.filter` estimates,
:mod:`inserr.northfinder.bounds` gives the Cramér-Rao bound and
:mod:`inserr.northfinder.study` runs Monte Carlo studies. The derivation is in
``docs/tutorials/northfinding.md``.

Frames and conventions (all angles rad, rates rad/s, SI otherwise):

* n: local-level East-North-Up. b: the instrument base, right-front-up, with
  ``C_b^n = rot_z(-heading) @ rot_x(pitch) @ rot_y(roll)`` (:mod:`inserr.core.rotations`),
  heading clockwise from north.
* t: the table frame, turned about ``b_z`` by the table angle
  ``alpha = table_rate * t`` (``C_t^b = rot_z(alpha)``; a positive rate turns the
  table counter-clockwise seen from above). At ``alpha = 0`` the gyro axis lies in
  the b y-z plane: the encoder zero is defined by the gyro.
* Gyro sensitive axis in t: ``[0, cos th1, sin th1]`` (``th1`` = tilt toward the
  rotation axis). Accelerometer axis in t:
  ``[-sin phi cos eta, cos phi cos eta, sin eta]`` (``phi`` = azimuth from the gyro
  axis about ``t_z``, ``eta`` = tilt toward the rotation axis).

With ``w^b = C_n^b [0, Omega cos L, Omega sin L]`` and ``f^b = C_n^b [0, 0, g]`` the
outputs are exactly (no small angles)::

    gyro  = A cos(alpha) + B sin(alpha) + eps'
    accel = C cos(alpha) + D sin(alpha) + nabla'

    A = cos th1 w_y          B = -cos th1 w_x
    C = cos eta (cos phi f_y - sin phi f_x)
    D = -cos eta (cos phi f_x + sin phi f_y)
    eps'   = gyro bias  + sin th1 (w_z + table_rate)
    nabla' = accel bias + sin eta f_z

The sensors are integrating (angle and velocity increments per sample, as FOGs and
accelerometers with a V/F converter deliver them), so every sum of samples over a
filter period is an exact integral of the model above.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike
from scipy.signal import lfilter

from inserr.core import earth
from inserr.core.errors import InputError, require_finite
from inserr.core.rotations import body_to_nav
from inserr.core.units import (
    DEG,
    DEG_PER_HOUR,
    DEG_PER_S,
    DEG_PER_SQRT_HOUR,
    MICRO_G,
    MICRO_G_PER_SQRT_HZ,
)

#: Largest pitch or roll accepted: the finder is for a roughly level base, and the
#: pitch/roll inversion from the accelerometer is singular at 90 deg.
MAX_TILT = 45.0 * DEG
#: Largest sensor mounting angle accepted (they are small calibration angles).
MAX_MOUNTING = 30.0 * DEG
#: Names of the filter states, in order.
STATES = ("A", "B", "C", "D", "eps", "nabla")

_E_X = np.array([1.0, 0.0, 0.0])
_E_Y = np.array([0.0, 1.0, 0.0])
_E_Z = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class Pose:
    """Where the instrument stands and how its base is oriented.

    Parameters
    ----------
    lat : float
        Geodetic latitude, rad, strictly inside (-pi/2, pi/2).
    heading : float
        Heading of the base's front axis ``b_y``, rad, clockwise from north (any
        value; it is wrapped to [0, 2 pi)).
    pitch, roll : float
        Tilt of the base, rad, ``|.| <=`` :data:`MAX_TILT` (45 deg).
    height : float
        Height above the ellipsoid, m (only enters normal gravity).
    """

    lat: float
    heading: float
    pitch: float = 0.0
    roll: float = 0.0
    height: float = 0.0

    def __post_init__(self) -> None:
        lat = require_finite(self.lat, "lat")
        if abs(lat) >= math.pi / 2:
            raise InputError(
                "lat",
                f"latitude {math.degrees(lat):g} deg is at or beyond a pole, where the horizontal "
                "Earth rate Omega cos(L) vanishes and north is undefined",
                "give |latitude| < 90 deg (the heading bound grows as 1/cos L toward the pole)",
            )
        object.__setattr__(self, "heading", require_finite(self.heading, "heading") % (2 * math.pi))
        for name in ("pitch", "roll"):
            v = require_finite(getattr(self, name), name)
            if abs(v) > MAX_TILT:
                raise InputError(
                    name,
                    f"{math.degrees(v):g} deg is beyond the {math.degrees(MAX_TILT):g} deg the "
                    "finder accepts",
                    "level the base to within a few degrees",
                )
        require_finite(self.height, "height")

    @classmethod
    def from_degrees(
        cls, lat: float, heading: float, pitch: float = 0.0, roll: float = 0.0, height: float = 0.0
    ) -> Pose:
        """Build a pose from angles in degrees.

        Parameters
        ----------
        lat, heading, pitch, roll : float
            deg.
        height : float
            m.

        Returns
        -------
        Pose
            Angles in rad.
        """
        return cls(lat * DEG, heading * DEG, pitch * DEG, roll * DEG, height)

    @property
    def gravity(self) -> float:
        """Normal gravity magnitude at the site.

        Returns
        -------
        float
            m/s^2.
        """
        return earth.gravity(self.lat, self.height)


@dataclass(frozen=True)
class Instrument:
    """The rotating table and how the two sensors are mounted on it.

    Parameters
    ----------
    table_rate : float
        Table rate about ``b_z``, rad/s, non-zero (sign = direction). Default 6 deg/s.
    sample_rate : float
        Sensor output rate, Hz. Default 100 Hz.
    filter_period : float
        Kalman filter period, s; must hold a whole number of samples and less than
        half a table turn. Default 1 s.
    gyro_tilt : float
        ``th1``: tilt of the gyro axis from the table plane toward ``+t_z``, rad.
    accel_azimuth : float
        ``phi``: azimuth of the accelerometer axis from the gyro axis about ``+t_z``, rad.
    accel_tilt : float
        ``eta``: tilt of the accelerometer axis toward ``+t_z``, rad.
    """

    table_rate: float = 6.0 * DEG_PER_S
    sample_rate: float = 100.0
    filter_period: float = 1.0
    gyro_tilt: float = 0.0
    accel_azimuth: float = 0.0
    accel_tilt: float = 0.0

    def __post_init__(self) -> None:
        rate = require_finite(self.table_rate, "table_rate")
        if rate == 0.0:
            raise InputError(
                "table_rate",
                "a table at rest does not modulate the sensors, so bias and signal are inseparable",
                "give a non-zero table rate, e.g. 6 deg/s",
            )
        fs = require_finite(self.sample_rate, "sample_rate")
        period = require_finite(self.filter_period, "filter_period")
        if fs <= 0:
            raise InputError("sample_rate", f"must be > 0 Hz, got {fs:g}", "give e.g. 100 Hz")
        if period <= 0:
            raise InputError("filter_period", f"must be > 0 s, got {period:g}", "give e.g. 1 s")
        m = fs * period
        if m < 1 - 1e-9 or abs(m - round(m)) > 1e-9 * max(1.0, m):
            raise InputError(
                "filter_period",
                f"{period:g} s holds {m:g} samples at {fs:g} Hz, not a whole number >= 1",
                "choose a period that is a multiple of the sample interval",
            )
        if abs(rate) * period >= math.pi:
            # The period mean of cos(alpha) shrinks as sinc(rate*T/2) and vanishes at a
            # full turn: the filter would lose the signal.
            raise InputError(
                "table_rate",
                f"{abs(rate) / DEG_PER_S:g} deg/s turns the table half a turn or more per "
                f"{period:g} s filter period",
                "lower the table rate or shorten the filter period",
            )
        for name in ("gyro_tilt", "accel_azimuth", "accel_tilt"):
            v = require_finite(getattr(self, name), name)
            if abs(v) > MAX_MOUNTING:
                raise InputError(
                    name,
                    f"{math.degrees(v):g} deg is not a small mounting angle",
                    f"give |angle| <= {math.degrees(MAX_MOUNTING):g} deg",
                )

    @property
    def samples_per_period(self) -> int:
        """Number of sensor samples in one filter period.

        Returns
        -------
        int
        """
        return int(round(self.sample_rate * self.filter_period))

    @property
    def gyro_axis(self) -> np.ndarray:
        """Gyro sensitive axis in the table frame t.

        Returns
        -------
        ndarray (3,)
            Unit vector.
        """
        t = self.gyro_tilt
        return np.array([0.0, math.cos(t), math.sin(t)])

    @property
    def accel_axis(self) -> np.ndarray:
        """Accelerometer sensitive axis in the table frame t.

        Returns
        -------
        ndarray (3,)
            Unit vector.
        """
        p, e = self.accel_azimuth, self.accel_tilt
        return np.array([-math.sin(p) * math.cos(e), math.cos(p) * math.cos(e), math.sin(e)])


@dataclass(frozen=True)
class SensorGrade:
    """Errors of the single gyro and the single accelerometer, SI units.

    Defaults are the grade of issue #7: gyro ARW 0.001 deg/sqrt(h), bias 0.05 deg/h,
    bias instability 0.005 deg/h; accelerometer VRW 10 micro-g/sqrt(Hz), bias
    100 micro-g.

    Parameters
    ----------
    gyro_arw : float
        Angle random walk, rad/sqrt(s) (square root of the two-sided white rate PSD).
    gyro_bias : float
        Constant gyro bias, rad/s.
    gyro_bias_instability : float
        Steady-state 1 sigma of a first-order Gauss-Markov bias, rad/s.
    gyro_correlation_time : float
        Its correlation time, s. Default 300 s (a typical Allan-minimum time of a
        navigation FOG; the analysis shows the answer hardly depends on it).
    accel_vrw : float
        Velocity random walk, m/s/sqrt(s) = (m/s^2)/sqrt(Hz).
    accel_bias : float
        Constant accelerometer bias, m/s^2.
    accel_bias_instability, accel_correlation_time : float
        Gauss-Markov accelerometer bias, m/s^2 and s (default none).
    """

    gyro_arw: float = 0.001 * DEG_PER_SQRT_HOUR
    gyro_bias: float = 0.05 * DEG_PER_HOUR
    gyro_bias_instability: float = 0.005 * DEG_PER_HOUR
    gyro_correlation_time: float = 300.0
    accel_vrw: float = 10.0 * MICRO_G_PER_SQRT_HZ
    accel_bias: float = 100.0 * MICRO_G
    accel_bias_instability: float = 0.0
    accel_correlation_time: float = 300.0

    def __post_init__(self) -> None:
        for name in ("gyro_arw", "gyro_bias_instability", "accel_vrw", "accel_bias_instability"):
            v = require_finite(getattr(self, name), name)
            if v < 0:
                raise InputError(name, f"a noise level must be >= 0, got {v:g}")
        for name in ("gyro_bias", "accel_bias"):
            require_finite(getattr(self, name), name)
        for name in ("gyro_correlation_time", "accel_correlation_time"):
            v = require_finite(getattr(self, name), name)
            if v <= 0:
                raise InputError(name, f"must be > 0 s, got {v:g}", "give e.g. 300 s")

    def without_noise(self) -> SensorGrade:
        """The same constant biases with no random errors (for noise-free checks).

        Returns
        -------
        SensorGrade
            ARW, VRW and bias instabilities zero; biases (rad/s, m/s^2) kept.
        """
        return replace(
            self, gyro_arw=0.0, gyro_bias_instability=0.0, accel_vrw=0.0, accel_bias_instability=0.0
        )

    def replace(self, **changes) -> SensorGrade:
        """A copy with some fields changed.

        Parameters
        ----------
        **changes
            Field names and new values, SI units.

        Returns
        -------
        SensorGrade
        """
        return replace(self, **changes)


def earth_rate_n(lat: ArrayLike) -> np.ndarray:
    """Earth rate in ENU, ``Omega [0, cos L, sin L]``.

    Parameters
    ----------
    lat : float or array
        Latitude, rad.

    Returns
    -------
    ndarray (..., 3)
        rad/s.
    """
    lat = np.asarray(lat, dtype=float)
    return earth.OMEGA_IE * np.stack([np.zeros_like(lat), np.cos(lat), np.sin(lat)], axis=-1)


def body_vectors(
    lat: ArrayLike, heading: ArrayLike, pitch: ArrayLike, roll: ArrayLike, g: ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    """Earth rate and specific force at rest, resolved in the base frame b.

    Parameters
    ----------
    lat, heading, pitch, roll : float or array
        rad (broadcast together).
    g : float or array
        Gravity magnitude, m/s^2.

    Returns
    -------
    w_b : ndarray (..., 3)
        ``C_n^b [0, Omega cos L, Omega sin L]``, rad/s.
    f_b : ndarray (..., 3)
        ``C_n^b [0, 0, g]``, m/s^2.
    """
    c_nb = np.swapaxes(body_to_nav(heading, pitch, roll), -1, -2)
    w_b = np.einsum("...ij,...j->...i", c_nb, earth_rate_n(lat))
    f_b = c_nb[..., :, 2] * np.asarray(g, dtype=float)[..., None]
    return w_b, f_b


def coefficients_from_body(w_b: np.ndarray, f_b: np.ndarray, instrument: Instrument) -> np.ndarray:
    """Modulation amplitudes ``[A, B, C, D]`` from body-frame Earth rate and specific force.

    Parameters
    ----------
    w_b : ndarray (..., 3)
        Earth rate in the base frame, rad/s.
    f_b : ndarray (..., 3)
        Specific force in the base frame, m/s^2.
    instrument : Instrument
        Mounting angles (rad).

    Returns
    -------
    ndarray (..., 4)
        A, B in rad/s, C, D in m/s^2 (see the module docstring).
    """
    c1 = math.cos(instrument.gyro_tilt)
    ce = math.cos(instrument.accel_tilt)
    cp, sp = math.cos(instrument.accel_azimuth), math.sin(instrument.accel_azimuth)
    return np.stack(
        [
            c1 * w_b[..., 1],
            -c1 * w_b[..., 0],
            ce * (cp * f_b[..., 1] - sp * f_b[..., 0]),
            -ce * (cp * f_b[..., 0] + sp * f_b[..., 1]),
        ],
        axis=-1,
    )


def true_coefficients(pose: Pose, instrument: Instrument, grade: SensorGrade) -> np.ndarray:
    """The six filter states ``[A, B, C, D, eps', nabla']`` for a pose and instrument.

    ``eps'`` and ``nabla'`` hold the constant biases plus the constant projections of
    the up-axis Earth rate, table rate and specific force (see the module docstring).

    Parameters
    ----------
    pose : Pose
        Truth (rad, m).
    instrument : Instrument
        Table rate (rad/s) and mounting angles (rad).
    grade : SensorGrade
        Constant biases (rad/s, m/s^2).

    Returns
    -------
    ndarray (6,)
        A, B, eps' in rad/s; C, D, nabla' in m/s^2.
    """
    w_b, f_b = body_vectors(pose.lat, pose.heading, pose.pitch, pose.roll, pose.gravity)
    abcd = coefficients_from_body(w_b, f_b, instrument)
    eps = grade.gyro_bias + math.sin(instrument.gyro_tilt) * (w_b[2] + instrument.table_rate)
    nabla = grade.accel_bias + math.sin(instrument.accel_tilt) * f_b[2]
    return np.concatenate([abcd, [eps, nabla]])


def coefficient_jacobian(pose: Pose, instrument: Instrument) -> np.ndarray:
    """``d[A, B, C, D] / d[heading, lat, pitch, roll]`` at a pose, analytic (4 x 4).

    Derivatives of ``w^b = R^T rot_z(heading) w^n(lat)`` and ``f^b = R^T [0, 0, g(lat)]``
    with ``R = rot_x(pitch) rot_y(roll)``: ``dR/dpitch = [e_x x] R`` and
    ``dR/droll = R [e_y x]``. ``dg/dlat`` (Somigliana) is included.

    Parameters
    ----------
    pose : Pose
        Where to differentiate (rad, m).
    instrument : Instrument
        Mounting angles (rad).

    Returns
    -------
    ndarray (4, 4)
        Rows A, B (rad/s per rad) and C, D (m/s^2 per rad); columns heading, lat,
        pitch, roll.
    """
    c_nb = body_to_nav(pose.heading, pose.pitch, pose.roll).T
    r_mat = body_to_nav(0.0, pose.pitch, pose.roll)  # R = rot_x(pitch) rot_y(roll)
    r_t = r_mat.T
    w_b, f_b = body_vectors(pose.lat, pose.heading, pose.pitch, pose.roll, pose.gravity)
    # The same vectors in the level frame that turns with the base's heading (R v^b).
    w_l = r_mat @ w_b
    f_l = r_mat @ f_b
    dw_dlat_n = earth.OMEGA_IE * np.array([0.0, -math.sin(pose.lat), math.cos(pose.lat)])
    step = 1e-6  # rad; central difference: truncation ~1e-14, round-off ~1e-9 m/s^2/rad
    dg_dlat = (
        earth.gravity(pose.lat + step, pose.height) - earth.gravity(pose.lat - step, pose.height)
    ) / (2 * step)
    dw = np.stack(
        [
            r_t @ np.cross(_E_Z, w_l),  # heading: d rot_z(h)/dh = [e_z x] rot_z(h)
            c_nb @ dw_dlat_n,  # latitude
            -r_t @ np.cross(_E_X, w_l),  # pitch: d R^T/dpitch = -R^T [e_x x]
            -np.cross(_E_Y, w_b),  # roll: d R^T/droll = -[e_y x] R^T
        ],
        axis=-1,
    )
    df = np.stack(
        [
            np.zeros(3),
            c_nb[:, 2] * dg_dlat,
            -r_t @ np.cross(_E_X, f_l),
            -np.cross(_E_Y, f_b),
        ],
        axis=-1,
    )
    # Columns of dw/df are body-frame vectors; map each through the (linear) sensor projection.
    return np.stack(
        [coefficients_from_body(dw[:, k], df[:, k], instrument) for k in range(4)], axis=-1
    )


@dataclass(frozen=True)
class SensorData:
    """Simulated increments of the two sensors.

    Attributes
    ----------
    gyro : ndarray (n_runs, n_samples)
        Angle increments, rad, one per sample interval.
    accel : ndarray (n_runs, n_samples)
        Velocity increments, m/s.
    sample_interval : float
        s.
    """

    gyro: np.ndarray
    accel: np.ndarray
    sample_interval: float


def table_angle_integrals(
    instrument: Instrument, t0: ArrayLike, dt: float
) -> tuple[np.ndarray, np.ndarray]:
    """Exact ``int cos(alpha) dt`` and ``int sin(alpha) dt`` over ``[t0, t0 + dt]``.

    Written as ``dt * sinc(rate dt / 2) * cos/sin(alpha at mid-interval)``, which avoids
    the cancellation of ``(sin a1 - sin a0) / rate`` at low rates.

    Parameters
    ----------
    instrument : Instrument
        Table rate, rad/s.
    t0 : float or array
        Interval starts, s.
    dt : float
        Interval length, s.

    Returns
    -------
    int_cos, int_sin : ndarray
        s, shaped like ``t0``.
    """
    rate = instrument.table_rate
    mid = rate * (np.asarray(t0, dtype=float) + 0.5 * dt)
    k = dt * np.sinc(rate * dt / (2.0 * math.pi))  # np.sinc(x) = sin(pi x) / (pi x)
    return k * np.cos(mid), k * np.sin(mid)


def _table_integral_matrices(instrument: Instrument, n: int) -> np.ndarray:
    """``int rot_z(alpha(t)) dt`` over each sample interval, shape (n, 3, 3), s."""
    h = 1.0 / instrument.sample_rate
    ci, si = table_angle_integrals(instrument, np.arange(n) * h, h)
    m = np.zeros((n, 3, 3))
    m[:, 0, 0] = ci
    m[:, 0, 1] = -si
    m[:, 1, 0] = si
    m[:, 1, 1] = ci
    m[:, 2, 2] = h
    return m


def run_seed(seed: int, run: int) -> np.random.SeedSequence:
    """Seed sequence of one Monte Carlo run: the same numbers however runs are chunked.

    Parameters
    ----------
    seed : int
        Master seed, >= 0.
    run : int
        Run index, >= 0.

    Returns
    -------
    numpy.random.SeedSequence
    """
    return np.random.SeedSequence(entropy=int(seed), spawn_key=(int(run),))


def _gauss_markov(drive: np.ndarray, sigma: float, tau: float, h: float) -> np.ndarray:
    """First-order Gauss-Markov sequences from unit normals, stationary from the start.

    ``b[0] = sigma * drive[0]``, ``b[j] = a b[j-1] + sigma sqrt(1 - a^2) drive[j]`` with
    ``a = exp(-h / tau)`` (the exact discretisation); rows are independent runs.
    """
    a = math.exp(-h / tau)
    x = drive * (sigma * math.sqrt(1.0 - a * a))
    x[:, 0] = sigma * drive[:, 0]
    return lfilter([1.0], [1.0, -a], x, axis=-1)


def simulate(
    pose: Pose,
    instrument: Instrument,
    grade: SensorGrade,
    duration: float,
    *,
    n_runs: int = 1,
    seed: int = 0,
    first_run: int = 0,
) -> SensorData:
    """Simulate the gyro and accelerometer increments on the rotating table.

    Geometry is exact: the sensor axes are turned by ``rot_z(alpha)`` and projected
    on ``C_n^b`` times the Earth rate (plus the table rate) and the specific force,
    and each sample is the exact integral over its interval.

    Parameters
    ----------
    pose, instrument, grade
        Truth. ``grade`` supplies bias (constant), bias instability (first-order
        Gauss-Markov, held constant within a sample since ``tau >> 1/sample_rate``),
        ARW and VRW (white).
    duration : float
        s; rounded down to whole filter periods (at least one).
    n_runs : int
        Independent Monte Carlo runs (rows of the output).
    seed : int
        Run ``first_run + i`` draws from :func:`run_seed` ``(seed, first_run + i)``, so a
        run's noise depends only on the seed and its index.
    first_run : int
        Index of the first run (for chunked Monte Carlo).

    Returns
    -------
    SensorData
        Increments of shape (n_runs, n_samples).
    """
    n_periods = n_filter_periods(instrument, duration)
    n = n_periods * instrument.samples_per_period
    h = 1.0 / instrument.sample_rate
    w_b, f_b = body_vectors(pose.lat, pose.heading, pose.pitch, pose.roll, pose.gravity)
    m = _table_integral_matrices(instrument, n)
    # The table frame turns at table_rate about b_z relative to b, so the gyro sees it too.
    w_it = w_b + instrument.table_rate * _E_Z
    gyro_true = np.einsum("i,nij,j->n", w_it, m, instrument.gyro_axis)
    accel_true = np.einsum("i,nij,j->n", f_b, m, instrument.accel_axis)

    noise = np.empty((4, n_runs, n))
    for i in range(n_runs):
        rng = np.random.default_rng(run_seed(seed, first_run + i))
        noise[:, i, :] = rng.standard_normal((4, n))
    gyro = gyro_true + h * grade.gyro_bias + grade.gyro_arw * math.sqrt(h) * noise[0]
    accel = accel_true + h * grade.accel_bias + grade.accel_vrw * math.sqrt(h) * noise[1]
    if grade.gyro_bias_instability > 0:
        gyro += h * _gauss_markov(
            noise[2], grade.gyro_bias_instability, grade.gyro_correlation_time, h
        )
    if grade.accel_bias_instability > 0:
        accel += h * _gauss_markov(
            noise[3], grade.accel_bias_instability, grade.accel_correlation_time, h
        )
    return SensorData(gyro=gyro, accel=accel, sample_interval=h)


def n_filter_periods(instrument: Instrument, duration: float) -> int:
    """Whole filter periods in a duration.

    Parameters
    ----------
    instrument : Instrument
        Filter period, s.
    duration : float
        s, > 0.

    Returns
    -------
    int
        >= 1; InputError if the duration holds less than one period.
    """
    d = require_finite(duration, "duration")
    if d <= 0:
        raise InputError("duration", f"must be positive, got {d:g} s", "give a positive duration")
    n = int(math.floor(d / instrument.filter_period + 1e-9))
    if n < 1:
        raise InputError(
            "duration",
            f"{d:g} s is shorter than one {instrument.filter_period:g} s filter period",
            "give a positive duration of at least one filter period",
        )
    return n


def mirror_pose(pose: Pose) -> tuple[float, float]:
    """Heading and latitude of the *other* solution that fits the same A, B exactly.

    The gyro only senses the Earth rate's components in the table plane, so the
    Earth-rate vector reflected through that plane, ``w' = w - 2 (w . b_z) b_z``,
    produces identical outputs (its component along ``b_z`` only enters the gyro
    constant ``eps'``, inseparable from the unknown bias); the accelerometer sees the
    same gravity direction. Used to demonstrate the two-fold ambiguity that only the
    user's declaration of the hemisphere resolves.

    Parameters
    ----------
    pose : Pose
        Truth (rad).

    Returns
    -------
    heading, lat : float
        Of the mirror solution, rad (heading in [0, 2 pi)).
    """
    c_bn = body_to_nav(pose.heading, pose.pitch, pose.roll)
    w_n = earth_rate_n(pose.lat)
    z_n = c_bn[:, 2]
    w_m = w_n - 2.0 * float(w_n @ z_n) * z_n
    # The mirrored world keeps the same up (gravity), so pitch and roll are unchanged;
    # its north is the horizontal part of w', at azimuth beta clockwise from true north.
    beta = math.atan2(w_m[0], w_m[1])
    heading = (pose.heading - beta) % (2 * math.pi)
    lat = math.atan2(w_m[2], math.hypot(w_m[0], w_m[1]))
    return heading, lat


__all__ = [
    "MAX_MOUNTING",
    "MAX_TILT",
    "STATES",
    "Instrument",
    "Pose",
    "SensorData",
    "SensorGrade",
    "body_vectors",
    "coefficient_jacobian",
    "coefficients_from_body",
    "earth_rate_n",
    "mirror_pose",
    "n_filter_periods",
    "run_seed",
    "simulate",
    "table_angle_integrals",
    "true_coefficients",
]
