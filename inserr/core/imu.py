"""The IMU error budget: deterministic errors, noise, bias instability, initial errors.

Sensor model (the same for gyros and accelerometers, IMU frame s)::

    measured = (I + K) @ true + bias + noise,   K = S + M,

``S = diag(sx, sy, sz)`` holds the scale-factor errors and ``M`` the six
misalignments ``M[x, y] = Mxy`` (sensitivity of the x sensor to the y input),
``Mxz, Myx, Myz, Mzx, Mzy``. This is P1's ``N_x = (1 + dKx) w_x + Kxy w_y + Kxz w_z + Dx``.

All fields are SI: rad/s, m/s^2, dimensionless, rad/sqrt(s), m/s/sqrt(s), s.
Engineering units live at the edges (:mod:`inserr.core.units`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace

import numpy as np

from inserr.core.errors import InputError

#: IMU axis names, in order.
AXES = ("x", "y", "z")
#: Misalignment names, in P1's order, and their (row, column) in K.
MISALIGNMENTS = ("xy", "xz", "yx", "yz", "zx", "zy")
MISALIGNMENT_INDEX = {
    "xy": (0, 1),
    "xz": (0, 2),
    "yx": (1, 0),
    "yz": (1, 2),
    "zx": (2, 0),
    "zy": (2, 1),
}


def error_matrix(scale_factor: np.ndarray, misalignment: np.ndarray) -> np.ndarray:
    """Sensor error matrix ``K = S + M`` from scale-factor errors and misalignments.

    Parameters
    ----------
    scale_factor : (3,) array
        Scale-factor errors of the x, y, z sensors, dimensionless (the diagonal S).
    misalignment : (6,) array
        Misalignments, rad (dimensionless entries of K), in the order of
        :data:`MISALIGNMENTS`: ``M[x, y] = Mxy`` is the x sensor's sensitivity to y.

    Returns
    -------
    ndarray, shape (3, 3)
        ``K``, IMU frame s, dimensionless.
    """
    k = np.diag(np.asarray(scale_factor, dtype=float))
    for value, name in zip(np.asarray(misalignment, dtype=float), MISALIGNMENTS, strict=True):
        k[MISALIGNMENT_INDEX[name]] = value
    return k


def _vec(value, n: int, name: str) -> np.ndarray:
    if (
        value is None
        or isinstance(value, (str, bytes))
        or (isinstance(value, (list, tuple)) and any(isinstance(v, (str, bytes)) for v in value))
    ):
        raise TypeError(f"{name}: expected a number or {n} numbers in SI units, got {value!r}")
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{name}: expected a number or {n} numbers, got {value!r}") from None
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.shape != (n,):
        raise InputError(name, f"expected {n} values, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise InputError(name, "contains a non-finite value", "give finite numbers")
    return a


@dataclass(frozen=True)
class ImuErrors:
    """Error budget of a three-axis IMU, SI units, IMU frame.

    Parameters
    ----------
    gyro_bias : (3,) rad/s
        Constant gyro bias per IMU axis (a scalar is used for all three).
    accel_bias : (3,) m/s^2
        Constant accelerometer bias per IMU axis.
    gyro_scale_factor, accel_scale_factor : (3,) dimensionless
        Scale-factor errors per IMU axis (diagonal of K).
    gyro_misalignment, accel_misalignment : (6,) rad
        Misalignments (off-diagonal of K), order ``xy, xz, yx, yz, zx, zy``.
    arw : float, rad/sqrt(s)
        Gyro angle random walk (white rate noise, same on the three axes).
    vrw : float, m/s/sqrt(s)
        Accelerometer velocity random walk (white specific-force noise, same on
        the three axes).
    gyro_bias_instability : float, rad/s
        Steady-state 1 sigma of a first-order Gauss-Markov gyro bias (0 = none).
    accel_bias_instability : float, m/s^2
        Same for the accelerometers.
    gyro_correlation_time, accel_correlation_time : float, s
        Correlation times of the Gauss-Markov processes.

    Notes
    -----
    Noise and bias instability are isotropic (one value for the three axes). That
    is what datasheets give, and it makes their navigation-frame statistics
    independent of the IMU attitude, so covariance propagation under any indexing
    scheme is exact (see ``docs/theory.md``).
    """

    gyro_bias: np.ndarray = field(default_factory=lambda: np.zeros(3))
    accel_bias: np.ndarray = field(default_factory=lambda: np.zeros(3))
    gyro_scale_factor: np.ndarray = field(default_factory=lambda: np.zeros(3))
    accel_scale_factor: np.ndarray = field(default_factory=lambda: np.zeros(3))
    gyro_misalignment: np.ndarray = field(default_factory=lambda: np.zeros(6))
    accel_misalignment: np.ndarray = field(default_factory=lambda: np.zeros(6))
    arw: float = 0.0
    vrw: float = 0.0
    gyro_bias_instability: float = 0.0
    accel_bias_instability: float = 0.0
    gyro_correlation_time: float = 3600.0
    accel_correlation_time: float = 3600.0

    def __post_init__(self) -> None:
        for name, n in (
            ("gyro_bias", 3),
            ("accel_bias", 3),
            ("gyro_scale_factor", 3),
            ("accel_scale_factor", 3),
            ("gyro_misalignment", 6),
            ("accel_misalignment", 6),
        ):
            object.__setattr__(self, name, _vec(getattr(self, name), n, name))
        for name in ("arw", "vrw", "gyro_bias_instability", "accel_bias_instability"):
            v = float(getattr(self, name))
            if not math.isfinite(v) or v < 0:
                what = "negative" if v < 0 else "not finite"
                example = {
                    "arw": "0.001 deg/sqrt(h)",
                    "vrw": "10 ug/sqrt(Hz)",
                    "gyro_bias_instability": "0.005 deg/h",
                    "accel_bias_instability": "10 ug",
                }[name]
                raise InputError(
                    name,
                    f"a 1-sigma magnitude must be finite and >= 0; this one is {what}",
                    f"give its magnitude, e.g. {example}",
                )
            object.__setattr__(self, name, v)
        for name in ("gyro_correlation_time", "accel_correlation_time"):
            v = float(getattr(self, name))
            if not math.isfinite(v) or v <= 0:
                raise InputError(name, f"must be a finite time > 0, got {v!r}")
            object.__setattr__(self, name, v)

    @property
    def gyro_error_matrix(self) -> np.ndarray:
        """``K_g = S_g + M_g`` (3x3, dimensionless)."""
        return error_matrix(self.gyro_scale_factor, self.gyro_misalignment)

    @property
    def accel_error_matrix(self) -> np.ndarray:
        """``K_a = S_a + M_a`` (3x3, dimensionless)."""
        return error_matrix(self.accel_scale_factor, self.accel_misalignment)

    @property
    def has_scale_misalignment(self) -> bool:
        """True if any scale-factor or misalignment error is non-zero."""
        return bool(
            np.any(self.gyro_scale_factor)
            or np.any(self.accel_scale_factor)
            or np.any(self.gyro_misalignment)
            or np.any(self.accel_misalignment)
        )

    @property
    def has_bias_instability(self) -> bool:
        """True if either Gauss-Markov bias instability is non-zero."""
        return self.gyro_bias_instability > 0 or self.accel_bias_instability > 0

    def replace(self, **changes) -> ImuErrors:
        """A copy with some fields changed (``dataclasses.replace``).

        Parameters
        ----------
        **changes
            Field names and new values, SI units as in the class parameters.

        Returns
        -------
        ImuErrors
            The validated copy.
        """
        return replace(self, **changes)

    def without_noise(self) -> ImuErrors:
        """The deterministic part only (noise and bias instability removed)."""
        return replace(
            self, arw=0.0, vrw=0.0, gyro_bias_instability=0.0, accel_bias_instability=0.0
        )

    def scaled(self, factor: float) -> ImuErrors:
        """A copy with every error (not the correlation times) multiplied by ``factor``.

        Parameters
        ----------
        factor : float
            Dimensionless multiplier (>= 0 keeps the noise terms valid).

        Returns
        -------
        ImuErrors
            The scaled copy.
        """
        kw = {}
        for f in fields(self):
            if f.name.endswith("correlation_time"):
                continue
            kw[f.name] = getattr(self, f.name) * factor
        return replace(self, **kw)


@dataclass(frozen=True)
class InitialErrors:
    """Initial navigation errors at t = 0 (ENU, SI).

    Parameters
    ----------
    attitude : (3,) rad
        True attitude error phi (E, N, U): phi_E, phi_N level tilts, phi_U heading
        error (positive = indicated heading too large, see ``docs/theory.md``).
    velocity : (3,) m/s
        Velocity error (E, N, U).
    position : (3,) m
        Position error (E, N, U).
    """

    attitude: np.ndarray = field(default_factory=lambda: np.zeros(3))
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    position: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        for name in ("attitude", "velocity", "position"):
            object.__setattr__(self, name, _vec(getattr(self, name), 3, name))
