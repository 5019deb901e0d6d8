"""Error injection for the nonlinear reference: IMU errors on ideal increments, initial PVA errors.

The linear model and the reference read the same budget objects
(:class:`~inserr.core.imu.ImuErrors`, :class:`~inserr.core.imu.InitialErrors`) and apply them
with the same definitions:

* Sensor model, IMU frame s (right-front-up), on *increments* over one sample
  interval ``dt``::

      measured = (I + K) ideal + bias dt + gauss_markov dt + noise,

  ``K = S + M`` (:attr:`~inserr.core.imu.ImuErrors.gyro_error_matrix`), ideal gyro
  increments in rad and accelerometer increments in m/s. Because ``K`` and the
  biases are constant, applying them to the increment is the exact integral of
  ``(I + K) w + b`` over the interval.
* White noise of density ``arw`` (rad/sqrt(s)) or ``vrw`` (m/s/sqrt(s)) gives
  independent increment errors of standard deviation ``arw sqrt(dt)``: the
  integral over ``dt`` of continuous white noise of the same two-sided PSD the
  covariance propagation uses (``ErrorModel.noise_intensity``).
* Gauss-Markov bias instability: the exact discrete AR(1) of the continuous
  first-order process at the sample interval, started from its stationary
  distribution (as the covariance propagation starts from ``sigma^2 I``), held
  constant over each sample.
* Initial errors (ENU, computed minus true): the computed attitude is
  ``C_s^n(computed) = expm(-[phi x]) C_s^n`` (first order ``(I - [phi x]) C_s^n``,
  the definition of phi in :mod:`inserr.model.psi_model`), the computed position is the true
  one moved by ``dr`` metres (``dlat = dr_N / R_M``, ``dlon = dr_E / (R_N cos L)``,
  the same radii that turn the reference's latitude/longitude back into metres),
  the computed velocity is ``dv``. With the vertical channel clamped (externally
  aided) the vertical velocity and position errors are not applied, exactly as
  the linear model drops them.

Random numbers come from :class:`numpy.random.Generator` streams spawned from one
:class:`numpy.random.SeedSequence` per run, one stream per noise process, so the
same seed gives the same numbers whatever chunk length the reference uses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.signal import lfilter

from inserr.core.earth import Site
from inserr.core.imu import ImuErrors, InitialErrors
from inserr.core.rotations import rot_axis

#: Names of the independent random streams of one run, in spawn order.
STREAMS = ("gyro_white", "accel_white", "gyro_markov", "accel_markov")


def child_seed(seed: np.random.SeedSequence, i: int) -> np.random.SeedSequence:
    """The ``i``-th child of ``seed``, the same as ``seed.spawn`` would give first time round.

    ``SeedSequence.spawn`` counts the children it has handed out, so spawning twice
    from one object gives different streams; deriving the child from the spawn key
    keeps a run reproducible however often its seed object is reused.

    Parameters
    ----------
    seed : numpy.random.SeedSequence
        Parent seed of the run.
    i : int
        Index of the child (position in :data:`STREAMS`).

    Returns
    -------
    numpy.random.SeedSequence
    """
    return np.random.SeedSequence(
        seed.entropy, spawn_key=(*seed.spawn_key, i), pool_size=seed.pool_size
    )


def draw_constants(
    imu: ImuErrors, init: InitialErrors, rng: np.random.Generator
) -> tuple[ImuErrors, InitialErrors]:
    """One draw of the constant errors read as zero-mean random constants.

    Every component (per axis, per misalignment, per initial-error component) is
    multiplied by an independent standard normal number, so its 1 sigma is the
    magnitude given in the budget: the reading behind the linear model's
    "RMS, unknown signs" (:func:`inserr.drift.unknown_signs.rms_norm`). Noise levels are kept.

    Parameters
    ----------
    imu : ImuErrors
        The budget (SI, IMU frame s); its magnitudes are the 1 sigma of the draw.
    init : InitialErrors
        Initial errors (rad, m/s, m, ENU), same reading.
    rng : numpy.random.Generator
        Source of the standard normal numbers.

    Returns
    -------
    (ImuErrors, InitialErrors)
        The drawn budget (same units and frames) and initial errors.
    """

    def scale(v: np.ndarray) -> np.ndarray:
        return v * rng.standard_normal(v.shape)

    drawn = imu.replace(
        gyro_bias=scale(imu.gyro_bias),
        accel_bias=scale(imu.accel_bias),
        gyro_scale_factor=scale(imu.gyro_scale_factor),
        accel_scale_factor=scale(imu.accel_scale_factor),
        gyro_misalignment=scale(imu.gyro_misalignment),
        accel_misalignment=scale(imu.accel_misalignment),
    )
    return drawn, InitialErrors(scale(init.attitude), scale(init.velocity), scale(init.position))


@dataclass
class Injector:
    """Corrupts the ideal increments of one run, sample after sample (stateful).

    Parameters
    ----------
    imu : ImuErrors
        Errors of this run (SI, IMU frame). Noise and bias instability are drawn
        only if ``noise`` is True.
    seed : numpy.random.SeedSequence, optional
        Entropy of this run's random streams (required when ``noise`` is True and
        the budget has a random part).
    noise : bool
        False: deterministic errors only (biases, scale factors, misalignments).

    Notes
    -----
    Call :meth:`apply` on consecutive blocks of samples, in time order; the
    Gauss-Markov state and the random streams carry over between calls.
    """

    imu: ImuErrors
    seed: np.random.SeedSequence | None = None
    noise: bool = True
    _rng: dict[str, np.random.Generator] = field(init=False, repr=False)
    _markov: dict[str, np.ndarray | None] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self._kg = np.eye(3) + self.imu.gyro_error_matrix
        self._ka = np.eye(3) + self.imu.accel_error_matrix
        random = self.noise and (
            self.imu.arw > 0 or self.imu.vrw > 0 or self.imu.has_bias_instability
        )
        if random and self.seed is None:
            raise ValueError("a seed is needed to draw noise")
        children = [child_seed(self.seed, i) for i in range(len(STREAMS))] if random else []
        self._rng = {
            name: np.random.default_rng(s) for name, s in zip(STREAMS, children, strict=False)
        }
        self._markov = {"gyro_markov": None, "accel_markov": None}

    def _white(self, stream: str, density: float, n: int, dt: float) -> np.ndarray | float:
        if not self.noise or density == 0.0:
            return 0.0
        return density * math.sqrt(dt) * self._rng[stream].standard_normal((n, 3))

    def _gauss_markov(
        self, stream: str, sigma: float, tau: float, n: int, dt: float
    ) -> np.ndarray | float:
        """Bias instability (rad/s or m/s^2) held over each of the next ``n`` samples."""
        if not self.noise or sigma == 0.0:
            return 0.0
        rng = self._rng[stream]
        if self._markov[stream] is None:
            self._markov[stream] = sigma * rng.standard_normal(3)  # stationary start
        a = math.exp(-dt / tau)
        drive = sigma * math.sqrt(1.0 - a * a) * rng.standard_normal((n, 3))
        # b_k = a b_{k-1} + drive_k, continued from the last state of the previous block.
        out, _ = lfilter([1.0], [1.0, -a], drive, axis=0, zi=(a * self._markov[stream])[None, :])
        self._markov[stream] = out[-1].copy()
        return out

    def apply(
        self, gyro: np.ndarray, accel: np.ndarray, dt: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Measured increments from ideal ones: scale factors, misalignments, biases, noise.

        Parameters
        ----------
        gyro : (n, 3) array
            Ideal angle increments, rad, IMU frame s.
        accel : (n, 3) array
            Ideal velocity increments (integrated specific force), m/s, IMU frame s.
        dt : float
            Sample interval, s.

        Returns
        -------
        gyro, accel : (n, 3) ndarray
            Measured increments (rad, m/s), IMU frame s.
        """
        n = len(gyro)
        imu = self.imu
        bg = imu.gyro_bias + self._gauss_markov(
            "gyro_markov", imu.gyro_bias_instability, imu.gyro_correlation_time, n, dt
        )
        ba = imu.accel_bias + self._gauss_markov(
            "accel_markov", imu.accel_bias_instability, imu.accel_correlation_time, n, dt
        )
        g = gyro @ self._kg.T + bg * dt + self._white("gyro_white", imu.arw, n, dt)
        a = accel @ self._ka.T + ba * dt + self._white("accel_white", imu.vrw, n, dt)
        return g, a


@dataclass(frozen=True)
class InitialState:
    """Computed (erroneous) initial navigation state, ENU, SI.

    Attributes
    ----------
    lat, lon : float
        Computed geodetic latitude and longitude, rad.
    height : float
        Computed height above the WGS84 ellipsoid, m.
    velocity : (3,) ndarray
        Computed velocity, m/s, ENU.
    c_sn : (3, 3) ndarray
        Computed IMU-to-ENU DCM ``C_s^n``.
    """

    lat: float
    lon: float
    height: float
    velocity: np.ndarray
    c_sn: np.ndarray


def perturbed_dcm(c_sn: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """Computed DCM ``expm(-[phi x]) C_s^n`` for a true attitude error ``phi``.

    Parameters
    ----------
    c_sn : (3, 3) array
        True ``C_s^n`` (IMU frame s to ENU).
    phi : (3,) array
        Attitude error, rad, ENU (computed minus true: E, N tilts, U heading error).

    Returns
    -------
    (3, 3) ndarray
        Computed ``C_s^n``.
    """
    phi = np.asarray(phi, dtype=float)
    angle = float(np.linalg.norm(phi))
    if angle == 0.0:
        return np.array(c_sn, dtype=float)
    return rot_axis(phi / angle, -angle) @ c_sn


def initial_state(
    site: Site, c_sn0: np.ndarray, init: InitialErrors, vertical: str = "clamped"
) -> InitialState:
    """The computed initial position, velocity and attitude of an IMU at rest with errors.

    See the module notes for the definitions; ``vertical="clamped"`` drops the
    vertical velocity and position errors (height is aided).

    Parameters
    ----------
    site : Site
        True position (lat, lon rad; height m); the vehicle is at rest.
    c_sn0 : (3, 3) array
        True initial ``C_s^n`` (IMU frame s to ENU).
    init : InitialErrors
        Attitude (rad), velocity (m/s) and position (m) errors, ENU, computed minus true.
    vertical : {"clamped", "free"}
        Vertical-channel mode.

    Returns
    -------
    InitialState
    """
    dv = np.array(init.velocity, dtype=float)
    dr = np.array(init.position, dtype=float)
    if vertical == "clamped":
        dv[2] = 0.0
        dr[2] = 0.0
    return InitialState(
        lat=site.lat + dr[1] / site.r_m,
        lon=site.lon + dr[0] / (site.r_n * math.cos(site.lat)),
        height=site.height + dr[2],
        velocity=dv,
        c_sn=perturbed_dcm(c_sn0, init.attitude),
    )


def position_error(site: Site, lat: np.ndarray, lon: np.ndarray, height: np.ndarray) -> np.ndarray:
    """Position error, ENU, computed minus true, of a computed latitude, longitude and height.

    Inverse of the mapping in :func:`initial_state` (same radii at the true site).

    Parameters
    ----------
    site : Site
        True position and radii of curvature.
    lat, lon : float or array
        Computed geodetic latitude and longitude, rad.
    height : float or array
        Computed height, m.

    Returns
    -------
    (..., 3) ndarray
        ``[dr_E, dr_N, dr_U]``, m (longitude difference wrapped to [-pi, pi)).
    """
    out = np.empty(np.shape(lat) + (3,))
    # Wrap the longitude difference so a site near +-180 deg gives small errors.
    dlon = np.mod(np.asarray(lon) - site.lon + math.pi, 2.0 * math.pi) - math.pi
    out[..., 0] = dlon * site.r_n * math.cos(site.lat)
    out[..., 1] = (np.asarray(lat) - site.lat) * site.r_m
    out[..., 2] = np.asarray(height) - site.height
    return out
