"""Rotation-modulation north finder (P3): Cramér-Rao lower bound on heading and latitude.

Assumptions of the bound (stated in ``docs/tutorials/northfinding.md``):

* Data: every raw sample of both sensors (angle and velocity increments at the
  sample rate), not the filter's period means, so it bounds *any* unbiased
  estimator using the sensors.
* Noise: white only (ARW, VRW), Gaussian. The constant biases are unknown nuisance
  parameters estimated jointly (they cost information only through their overlap
  with the sinusoids, which vanishes over whole table turns).
* Bias instability is not in the exact bound. :func:`bias_instability_psd` gives the
  Gauss-Markov PSD at the table frequency; for records of many turns the bound
  including it is the white bound scaled by ``sqrt(1 + S_gm(w) / ARW^2)``
  (``crlb(..., bias_instability=True)``), because the amplitudes are estimated at
  the table frequency only.
* Parameters: ``[heading, lat, pitch, roll, eps', nabla']`` (``lat`` dropped when it
  is known). ``eps'`` and ``nabla'`` are the total constants of each sensor, a
  one-to-one re-parametrisation of the biases.

Since the outputs are linear in the coefficients ``c = [A, B, C, D, eps', nabla']``,
the Fisher information is ``J = G^T (sum_j u_j u_j^T / sigma_j^2) G`` with
``u_j`` the sample's regressor and ``G = dc/dparameters``
(:func:`inserr.northfinder.instrument.coefficient_jacobian`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from inserr.core.errors import InputError
from inserr.northfinder.instrument import (
    Instrument,
    Pose,
    SensorGrade,
    coefficient_jacobian,
    n_filter_periods,
    table_angle_integrals,
)

#: Parameter names of the bound, in order.
PARAMETERS = ("heading", "lat", "pitch", "roll", "eps", "nabla")
#: Eigenvalues of a (Jacobi-scaled) information matrix below this fraction of the
#: largest count as zero: the parameters reaching into them get an infinite bound.
SINGULAR_RCOND = 1e-13


def bias_instability_psd(sigma: float, tau: float, omega: float) -> float:
    """Two-sided PSD of a first-order Gauss-Markov process at angular frequency omega.

    ``S(w) = 2 sigma^2 tau / (1 + w^2 tau^2)``, in units^2 s (the same convention as
    ``ARW^2``: a white process of PSD S has variance S / T when averaged over T).
    Its maximum over ``tau`` is ``sigma^2 / |w|`` at ``tau = 1 / |w|``.

    Parameters
    ----------
    sigma : float
        Steady-state 1 sigma of the process: rad/s (gyro) or m/s^2 (accelerometer).
    tau : float
        Correlation time, s.
    omega : float
        Angular frequency, rad/s (the table rate).

    Returns
    -------
    float
        PSD in (rad/s)^2 s = rad^2/s, or (m/s^2)^2 s.
    """
    return 2.0 * sigma**2 * tau / (1.0 + (omega * tau) ** 2)


def coefficient_information(
    instrument: Instrument, grade: SensorGrade, duration: float
) -> tuple[np.ndarray, np.ndarray]:
    """Cumulative Fisher information of the raw samples about ``[A, B, C, D, eps', nabla']``.

    Parameters
    ----------
    instrument : Instrument
        Table rate (rad/s), sample rate (Hz) and filter period (s).
    grade : SensorGrade
        White noise: gyro ARW (rad/sqrt(s)) and accelerometer VRW (m/s/sqrt(s)), both > 0.
    duration : float
        Record length, s (truncated to whole filter periods).

    Returns
    -------
    times : ndarray (n_periods,)
        End of each filter period, s.
    info : ndarray (n_periods, 6, 6)
        Information of all samples up to ``times[k]``, in 1/(rad/s)^2 (A, B, eps')
        and 1/(m/s^2)^2 (C, D, nabla'); gyro and accelerometer blocks do not couple.
    """
    if grade.gyro_arw <= 0 or grade.accel_vrw <= 0:
        raise InputError(
            "grade", "the bound is infinite without white noise", "give ARW and VRW > 0"
        )
    n_periods = n_filter_periods(instrument, duration)
    m = instrument.samples_per_period
    h = 1.0 / instrument.sample_rate
    t0 = np.arange(n_periods * m) * h
    ci, si = table_angle_integrals(instrument, t0, h)
    # Regressor of one increment on [cos-amplitude, sin-amplitude, constant].
    u = np.stack([ci, si, np.full_like(ci, h)], axis=-1).reshape(n_periods, m, 3)
    per_period = np.einsum("kmi,kmj->kij", u, u) / h
    cum = np.cumsum(per_period, axis=0)
    info = np.zeros((n_periods, 6, 6))
    for idx, psd in (([0, 1, 4], grade.gyro_arw**2), ([2, 3, 5], grade.accel_vrw**2)):
        rows, cols = np.ix_(idx, idx)
        info[:, rows, cols] = cum / psd
    times = (np.arange(n_periods) + 1) * instrument.filter_period
    return times, info


def _inverse(info: np.ndarray) -> np.ndarray:
    """Bound covariance from a stack of information matrices, allowing singular ones.

    Jacobi scaling first (the parameters differ by ~1e10 in natural size), then a
    pseudo-inverse from the eigen-decomposition. A parameter whose unit vector
    reaches into the null space (eigenvalues below ``SINGULAR_RCOND`` of the largest)
    is not identifiable: its variance is +inf and its covariances NaN. The others
    keep their bound, which is what the pseudo-inverse gives for an identifiable
    parameter (e.g. heading on a level table at the equator, where latitude is lost).
    """
    d = np.sqrt(np.einsum("...ii->...i", info))
    d = np.where(d > 0, d, 1.0)  # a parameter with no information: its row stays zero
    s = info / (d[..., :, None] * d[..., None, :])
    w, v = np.linalg.eigh(s)
    keep = w > SINGULAR_RCOND * w.max(axis=-1, keepdims=True)
    w_inv = np.where(keep, 1.0 / np.where(keep, w, 1.0), 0.0)
    cov = (v * w_inv[..., None, :]) @ np.swapaxes(v, -1, -2)
    cov = cov / (d[..., :, None] * d[..., None, :])
    leak = np.sum(v**2 * (~keep)[..., None, :], axis=-1)
    lost = leak > 1e-6
    cov = np.where(lost[..., :, None] | lost[..., None, :], np.nan, cov)
    diag = np.einsum("...ii->...i", cov)  # a writable view
    diag[lost] = np.inf
    return cov


@dataclass(frozen=True)
class Bound:
    """Cramér-Rao lower bounds (1 sigma) after each filter period.

    Attributes
    ----------
    times : ndarray (n,)
        End of each filter period, s.
    heading, lat, pitch, roll : ndarray (n,)
        1-sigma bounds, rad (heading of the base's ``b_y`` axis, clockwise from
        north; pitch and roll of the base b); ``lat`` is NaN when latitude is known;
        +inf where the data do not identify the parameter (e.g. latitude at the
        equator on a level table).
    covariance : ndarray (n, p, p)
        Inverse Fisher information over :attr:`parameters` (rad, rad/s, m/s^2).
    parameters : tuple of str
        Names of the p unknowns, a subset of :data:`PARAMETERS` in that order.
    """

    times: np.ndarray
    heading: np.ndarray
    lat: np.ndarray
    pitch: np.ndarray
    roll: np.ndarray
    covariance: np.ndarray
    parameters: tuple[str, ...]


def crlb(
    pose: Pose,
    instrument: Instrument,
    grade: SensorGrade,
    duration: float,
    *,
    latitude_known: bool = False,
    bias_instability: bool = False,
) -> Bound:
    """Cramér-Rao bound on heading, latitude, pitch and roll after each filter period.

    Parameters
    ----------
    pose : Pose
        Truth: latitude, heading, pitch and roll of the base (rad), height (m).
    instrument : Instrument
        Table and sensor geometry (rates rad/s and Hz, mounting angles rad).
    grade : SensorGrade
        Noise (ARW rad/sqrt(s) and VRW m/s/sqrt(s), both > 0); the Gauss-Markov
        terms are used only with ``bias_instability``.
    duration : float
        Record length, s (truncated to whole filter periods).
    latitude_known : bool
        Drop latitude from the unknowns.
    bias_instability : bool
        Inflate the white PSDs by the Gauss-Markov PSD at the table frequency (the
        asymptotic, many-turns bound; see the module docstring).

    Returns
    -------
    Bound
        1-sigma bounds (rad) and covariance after each filter period.
    """
    times, info_c = coefficient_information(instrument, grade, duration)
    if bias_instability:
        w = instrument.table_rate
        inflate_g = (
            1.0
            + bias_instability_psd(grade.gyro_bias_instability, grade.gyro_correlation_time, w)
            / grade.gyro_arw**2
        )
        inflate_a = (
            1.0
            + bias_instability_psd(grade.accel_bias_instability, grade.accel_correlation_time, w)
            / grade.accel_vrw**2
        )
        per_state = [inflate_g, inflate_g, inflate_a, inflate_a, inflate_g, inflate_a]
        scale = np.sqrt(np.array(per_state))
        info_c = info_c / (scale[:, None] * scale[None, :])
    g = np.eye(6)
    g[:4, :4] = coefficient_jacobian(pose, instrument)
    info = np.einsum("ji,kjl,lm->kim", g, info_c, g)
    keep = [i for i, name in enumerate(PARAMETERS) if not (latitude_known and name == "lat")]
    cov = _inverse(info[:, keep][:, :, keep])
    names = tuple(PARAMETERS[i] for i in keep)
    sig = np.sqrt(np.einsum("kii->ki", cov))

    def pick(name: str) -> np.ndarray:
        return sig[:, names.index(name)] if name in names else np.full(len(times), np.nan)

    return Bound(
        times=times,
        heading=pick("heading"),
        lat=pick("lat"),
        pitch=pick("pitch"),
        roll=pick("roll"),
        covariance=cov,
        parameters=names,
    )
