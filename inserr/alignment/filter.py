"""Fine-alignment Kalman filter on the inserr error model (static, swinging or indexed base).

The filter is a filterpy :class:`~filterpy.kalman.KalmanFilter` whose state is the core
error model (:class:`~inserr.model.psi_model.ErrorModel` with constant biases): psi-angle,
velocity and position errors (ENU) and the gyro and accelerometer biases resolved in
n. Between measurements it predicts with the exact segment transitions of the IMU
attitude timeline (:class:`~inserr.model.discretization.Discretizer`: ``Phi(w, dt)`` and the Van
Loan ``Qd(w, dt)``), so stops, table turns and a yawing base are all handled by the
same code; the steps come from :func:`inserr.model.exact_propagation.make_steps`.

Measurements (choices stated once):

* **Zero-velocity updates** at ``zupt_rate`` Hz: ``z = dv + v``, ``v ~ N(0, zupt_sigma^2)``
  per axis. With the default *free* vertical channel all three velocity components
  are measured (a real alignment sees vertical velocity too, and that makes the z
  accelerometer bias observable); with a clamped vertical channel the model holds
  ``dv_U = 0`` and only E and N are measured.
  The IMU is assumed to sit at the centre of rotation, so a swinging or indexed base
  has zero true velocity (a lever arm would have to be removed first).
* **Position updates** (optional, ``position_sigma``): ``z = dr + v`` at the same rate.
* **Update form.** filterpy 2.0.0's ``KalmanFilter.update`` already uses the Joseph
  form ``P = (I - K H) P (I - K H)^T + K R K^T`` (checked in
  ``tests/test_alignment.py``); the result is symmetrised after every update. Every
  measurement is passed as a ``(dim_z, 1)`` column together with its ``H`` and ``R``:
  filterpy 2.0.0 skips its reshaping when ``H`` is given, and a 1-D ``z`` then
  broadcasts ``z - H x`` into a wrong ``(dim_z, dim_z)`` residual without an error.

Reported states (SI) are the ones a user asks about: the true attitude error
``phi = psi + dtheta(dr)``, velocity and position errors, and the biases *in the IMU
frame* (``b = C_n^s eps^n``), through the time-varying linear map
:func:`report_transform`. Covariances are mapped with it too.

Figures of merit (all computed from the reported covariance):

* **Convergence time** of a state: the first time after which its sigma stays within
  10 % of its final value. A state whose sigma fell by less than 10 % over the run
  (or grew) is not estimated at all and gets NaN.
* **Degree of observability** (PSINS style): ``sigma(0) / sigma(t)``; about 1 means
  the measurements taught the filter nothing about that state.
* **Normalised eigen-analysis**: the eigen-decomposition of
  ``D0^-1 P(t) D0^-1`` with ``D0 = diag(sigma(0))``, i.e. the covariance in units of
  the prior 1 sigma of every state. Eigenvalues near 1 are combinations the
  measurements did not reach; small ones are well estimated (Ham & Brown 1983).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from inserr.alignment.observability import measurement_matrix
from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.core.imu import ImuErrors
from inserr.core.units import ARCMIN, ARCSEC, DEG_PER_HOUR, MICRO_G
from inserr.model.discretization import Discretizer
from inserr.model.exact_propagation import make_steps
from inserr.model.psi_model import DR, PSI, ErrorModel, Layout, position_angle
from inserr.model.timeline import Timeline

#: Reported states, SI, in this order.
STATES = (
    "phi_e", "phi_n", "phi_u",
    "dv_e", "dv_n", "dv_u",
    "dr_e", "dr_n", "dr_u",
    "gyro_bias_x", "gyro_bias_y", "gyro_bias_z",
    "accel_bias_x", "accel_bias_y", "accel_bias_z",
)  # fmt: skip
#: Engineering key and unit factor of every reported state (value_SI / factor).
UNITS = {
    "phi_e": ("phi_e_arcsec", ARCSEC),
    "phi_n": ("phi_n_arcsec", ARCSEC),
    "phi_u": ("phi_u_arcmin", ARCMIN),
    "dv_e": ("dv_e_mm_s", 1e-3),
    "dv_n": ("dv_n_mm_s", 1e-3),
    "dv_u": ("dv_u_mm_s", 1e-3),
    "dr_e": ("dr_e_m", 1.0),
    "dr_n": ("dr_n_m", 1.0),
    "dr_u": ("dr_u_m", 1.0),
    "gyro_bias_x": ("gyro_bias_x_deg_h", DEG_PER_HOUR),
    "gyro_bias_y": ("gyro_bias_y_deg_h", DEG_PER_HOUR),
    "gyro_bias_z": ("gyro_bias_z_deg_h", DEG_PER_HOUR),
    "accel_bias_x": ("accel_bias_x_ug", MICRO_G),
    "accel_bias_y": ("accel_bias_y_ug", MICRO_G),
    "accel_bias_z": ("accel_bias_z_ug", MICRO_G),
}
#: Fraction of the final sigma that defines convergence, and of the prior sigma a
#: state must lose to count as estimated at all.
CONVERGENCE_FRACTION = 0.1


@dataclass(frozen=True)
class Prior:
    """Prior 1 sigma of the alignment filter (SI), also the true errors of a simulated run.

    Parameters
    ----------
    attitude : (3,) rad
        ``phi_E, phi_N`` (tilts) and ``phi_U`` (heading). Default 60 arcsec, 60 arcsec,
        60 arcmin: the output of a coarse alignment, ten times the tilt floor of a
        30 micro-g accelerometer and seventy times the heading floor of a 0.003 deg/h gyro,
        so the prior moves those floors by less than 1 %.
    velocity : float, m/s
    position : float, m
        Default 10 m (P0's initial position error).
    gyro_bias : (3,) rad/s, IMU frame
    accel_bias : (3,) m/s^2, IMU frame
    """

    attitude: np.ndarray = field(
        default_factory=lambda: np.array([60 * ARCSEC, 60 * ARCSEC, 60 * ARCMIN])
    )
    velocity: float = 0.01
    position: float = 10.0
    gyro_bias: np.ndarray = field(default_factory=lambda: np.full(3, 0.003 * DEG_PER_HOUR))
    accel_bias: np.ndarray = field(default_factory=lambda: np.full(3, 30 * MICRO_G))

    def __post_init__(self) -> None:
        for name in ("attitude", "gyro_bias", "accel_bias"):
            v = np.broadcast_to(np.asarray(getattr(self, name), dtype=float), (3,)).copy()
            if not np.all(np.isfinite(v)) or np.any(v < 0):
                raise InputError(f"prior.{name}", "must be finite and >= 0")
            object.__setattr__(self, name, v)
        for name in ("velocity", "position"):
            v = float(getattr(self, name))
            if not math.isfinite(v) or v < 0:
                raise InputError(f"prior.{name}", "must be finite and >= 0")
            object.__setattr__(self, name, v)

    def sigma(self) -> np.ndarray:
        """The 15 prior sigmas in :data:`STATES` order."""
        return np.concatenate(
            [
                self.attitude,
                np.full(3, self.velocity),
                np.full(3, self.position),
                self.gyro_bias,
                self.accel_bias,
            ]
        )


@dataclass(frozen=True)
class Settings:
    """Measurement and model choices of the alignment filter.

    Parameters
    ----------
    zupt_rate : float, Hz
        Zero-velocity update rate (default 1 Hz: the Schuler, Earth-rate and table
        dynamics are all far slower, so faster updates only add correlated samples
        of the same base disturbance).
    zupt_sigma : float, m/s
        1 sigma of a zero-velocity measurement (default 1 mm/s: residual motion of a
        parked vehicle or a test stand).
    position_sigma : float or None, m
        1 sigma of a position update at the ZUPT rate; None = no position updates.
    vertical : {"free", "clamped"}
        Vertical channel of the error model (see the module docstring).
    seed : int
        Seed of the simulated run (process and measurement noise).
    """

    zupt_rate: float = 1.0
    zupt_sigma: float = 1e-3
    position_sigma: float | None = None
    vertical: str = "free"
    seed: int = 0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.zupt_rate) and self.zupt_rate > 0):
            raise InputError("alignment.zupt_rate", f"must be > 0 Hz, got {self.zupt_rate!r}")
        if not (math.isfinite(self.zupt_sigma) and self.zupt_sigma > 0):
            raise InputError("alignment.zupt_sigma", f"must be > 0 m/s, got {self.zupt_sigma!r}")
        ps = self.position_sigma
        if ps is not None and not (math.isfinite(ps) and ps > 0):
            raise InputError("alignment.position_sigma", f"must be > 0 m, got {ps!r}")


@dataclass(frozen=True)
class AlignmentResult:
    """Output of :func:`run_alignment`, reported states (:data:`STATES`, SI).

    Attributes
    ----------
    t : (M,) s
        0 and every measurement time.
    estimate, sigma, truth : (M, 15)
        Filter estimate, its 1 sigma, and the simulated true error.
    p0, p_final : (15, 15)
        Reported covariance at the start and at the end.
    label : str
        Scheme (or case) name.
    """

    t: np.ndarray
    estimate: np.ndarray
    sigma: np.ndarray
    truth: np.ndarray
    p0: np.ndarray
    p_final: np.ndarray
    label: str = ""
    meta: dict = field(default_factory=dict, compare=False)

    @property
    def final_sigma(self) -> np.ndarray:
        """1 sigma of every reported state at the end, SI."""
        return self.sigma[-1]

    def convergence_time(self, fraction: float = CONVERGENCE_FRACTION) -> np.ndarray:
        """Per-state convergence time, s (NaN if not estimated); see :func:`convergence_time`."""
        return convergence_time(self.t, self.sigma, fraction)

    def observability_degree(self) -> np.ndarray:
        """Per-state ``sigma(0) / sigma(end)`` (PSINS degree of observability)."""
        return observability_degree(self.sigma[0], self.sigma[-1])

    def eigen(self, states=STATES) -> tuple[np.ndarray, np.ndarray]:
        """Normalised eigen-analysis of the final covariance of ``states``.

        See :func:`normalized_eigen`. Restricting to a subset (e.g. attitude and
        biases) takes the marginal covariance of those states, so unrelated
        unestimated states (position) do not crowd the list of weak directions.
        """
        idx = [STATES.index(s) for s in states]
        return normalized_eigen(self.p0[np.ix_(idx, idx)], self.p_final[np.ix_(idx, idx)])

    def summary(self) -> dict:
        """Final sigma, convergence time, observability degree and the simulated run's error.

        Returns
        -------
        dict
            ``final_sigma``, ``convergence_time_s``, ``observability_degree`` and
            ``final_error`` (estimate minus truth of the one simulated run at the end),
            each keyed by engineering name (``phi_e_arcsec``, ``gyro_bias_x_deg_h``, ...).
        """
        conv = self.convergence_time()
        deg = self.observability_degree()
        err = self.estimate[-1] - self.truth[-1]
        out: dict = {
            "final_sigma": {},
            "convergence_time_s": {},
            "observability_degree": {},
            "final_error": {},
        }
        for i, name in enumerate(STATES):
            key, factor = UNITS[name]
            out["final_sigma"][key] = float(self.final_sigma[i] / factor)
            out["convergence_time_s"][key] = float(conv[i])
            out["observability_degree"][key] = float(deg[i])
            out["final_error"][key] = float(err[i] / factor)
        return out


# ---------------------------------------------------------------------------------------
# Figures of merit (pure functions)
# ---------------------------------------------------------------------------------------
def convergence_time(
    t: np.ndarray, sigma: np.ndarray, fraction: float = CONVERGENCE_FRACTION
) -> np.ndarray:
    """Time after which each sigma stays within ``fraction`` of its final value.

    Parameters
    ----------
    t : (M,) s
    sigma : (M, n)
    fraction : float
        0.1 = within 10 %.

    Returns
    -------
    (n,) s; NaN for a state whose sigma did not fall by at least ``fraction`` of its
    initial value (not estimated: "within 10 % of the final sigma" would hold at t = 0).
    """
    sigma = np.asarray(sigma, dtype=float)
    out = np.full(sigma.shape[1], np.nan)
    for i in range(sigma.shape[1]):
        s = sigma[:, i]
        if not s[0] > 0 or s[-1] > (1.0 - fraction) * s[0]:
            continue
        bad = np.flatnonzero(s > (1.0 + fraction) * s[-1])
        out[i] = t[0] if len(bad) == 0 else t[min(bad[-1] + 1, len(t) - 1)]
    return out


def observability_degree(sigma0: np.ndarray, sigma_k: np.ndarray) -> np.ndarray:
    """PSINS-style degree of observability ``sqrt(P0_ii) / sqrt(Pk_ii)`` (NaN where P0_ii = 0)."""
    s0 = np.asarray(sigma0, dtype=float)
    sk = np.asarray(sigma_k, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(s0 > 0, s0 / np.where(sk > 0, sk, np.nan), np.nan)


def normalized_eigen(p0: np.ndarray, pk: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigen-analysis of ``D0^-1 Pk D0^-1``, ``D0 = diag(sqrt(P0_ii))``.

    States with zero prior variance are left out (their rows are zero).

    Returns
    -------
    eigenvalues : (n,) ascending
        Remaining variance of each eigen-direction as a fraction of the prior
        (1 = not reduced at all).
    eigenvectors : (n, n)
        Columns, in prior-sigma units of the states.
    """
    d = np.sqrt(np.clip(np.diag(p0), 0.0, None))
    inv = np.where(d > 0, 1.0 / np.where(d > 0, d, 1.0), 0.0)
    pn = pk * inv[:, None] * inv[None, :]
    w, v = np.linalg.eigh(0.5 * (pn + pn.T))
    return w, v


def describe_eigenvector(v: np.ndarray, names=STATES, threshold: float = 0.3) -> str:
    """Dominant components of a normalised eigenvector: ``+0.71 phi_n -0.70 accel_bias_x``."""
    order = np.argsort(-np.abs(v))
    parts = [f"{v[i]:+.2f} {names[i]}" for i in order if abs(v[i]) >= threshold * np.max(np.abs(v))]
    return " ".join(parts)


# ---------------------------------------------------------------------------------------
# The filter
# ---------------------------------------------------------------------------------------
def report_transform(model: ErrorModel, c_sn: np.ndarray) -> np.ndarray:
    """Linear map from the filter state to :data:`STATES` at IMU attitude ``c_sn``.

    ``phi = psi + dtheta(dr)`` (``dtheta`` linear in ``dr``,
    :func:`~inserr.model.psi_model.position_angle`),
    velocity and position unchanged, biases to the IMU frame
    (:meth:`~inserr.model.psi_model.ErrorModel.imu_transform`).
    """
    m = model.imu_transform(c_sn)
    m[PSI, DR] = position_angle(model.site, np.eye(3)).T
    return m


def _noise_factor(qd: np.ndarray) -> np.ndarray:
    """A square root ``L`` with ``L L^T = Qd`` (Qd may be singular: bias rows are zero)."""
    w, v = np.linalg.eigh(0.5 * (qd + qd.T))
    return v * np.sqrt(np.clip(w, 0.0, None))[None, :]


def run_alignment(
    site: Site,
    timeline: Timeline,
    imu: ImuErrors,
    prior: Prior | None = None,
    settings: Settings | None = None,
    truth0: np.ndarray | None = None,
    label: str = "",
) -> AlignmentResult:
    """Run the alignment filter over ``timeline`` and simulate one run alongside it.

    Parameters
    ----------
    site : Site
    timeline : Timeline
        IMU attitude history during alignment (scheme x base motion).
    imu : ImuErrors
        ``arw``, ``vrw`` set the process noise of the filter and of the simulated run;
        ``gyro_bias`` and ``accel_bias`` are the true biases of the simulated run.
        Scale-factor errors and misalignments (IMU frame) act on the simulated run
        only: the filter does not model them, so table turns kick the true attitude
        (``K`` x table rate) and the estimate errors show what that costs. The
        covariance (sigma, convergence, observability degree) does not depend on them.
        Bias instability is not supported.
    prior : Prior, optional
    settings : Settings, optional
    truth0 : (15,) SI, optional
        True reported state of the simulated run at t = 0 (:data:`STATES`). Default:
        every navigation error at its prior 1 sigma and the biases of ``imu``.
    label : str

    Returns
    -------
    AlignmentResult
    """
    from filterpy.kalman import KalmanFilter

    prior = prior or Prior()
    settings = settings or Settings()
    if imu.has_bias_instability:
        raise InputError(
            "imu",
            "the alignment filter models constant biases and white noise only",
            "set the bias instability to zero",
        )
    model = ErrorModel(site, Layout(bias=True), vertical=settings.vertical)
    n = model.layout.n
    disc = Discretizer(model, model.noise_intensity(imu.arw, imu.vrw))
    # The simulated run: the filter's model, plus (when given) the scale-factor and
    # misalignment matrices K as constant states the filter does not carry. The first
    # n states of both models have the same meaning, so z = H x_true[:n].
    if imu.has_scale_misalignment:
        model_t = ErrorModel(
            site, Layout(bias=True, scale_misalignment=True), vertical=settings.vertical
        )
        disc_t = Discretizer(model_t, model_t.noise_intensity(imu.arw, imu.vrw))
    else:
        model_t, disc_t = model, disc

    n_meas = int(math.floor(timeline.duration * settings.zupt_rate + 1e-9))
    if n_meas < 1:
        raise InputError(
            "scenario.duration", "the alignment is shorter than one measurement interval"
        )
    t_meas = np.arange(1, n_meas + 1) / settings.zupt_rate
    steps = make_steps(timeline, t_meas, use_omega=True)
    phis = disc.transitions(steps.unique_omega, steps.unique_dt)
    phis_t = phis if disc_t is disc else disc_t.transitions(steps.unique_omega, steps.unique_dt)

    h = measurement_matrix(model, settings.position_sigma is not None)
    r_diag = np.full(h.shape[0], settings.zupt_sigma**2)
    if settings.position_sigma is not None:
        r_diag[h.shape[0] // 2 :] = settings.position_sigma**2
    r = np.diag(r_diag)

    # Prior: independent reported states (phi, dv, dr, IMU-frame biases) mapped back to
    # the filter state. With a clamped vertical channel dv_U and dr_U are exactly zero.
    sig0 = prior.sigma()
    if truth0 is None:
        true0 = np.concatenate([sig0[:9], imu.gyro_bias, imu.accel_bias])
    else:
        true0 = np.array(truth0, dtype=float).reshape(len(STATES))
    if settings.vertical == "clamped":
        sig0[[5, 8]] = 0.0
        true0[[5, 8]] = 0.0
    m0 = report_transform(model, timeline.c_sn[0])
    m0_inv = np.linalg.inv(m0)
    p0 = m0_inv @ np.diag(sig0**2) @ m0_inv.T

    kf = KalmanFilter(dim_x=n, dim_z=h.shape[0])
    kf.x = np.zeros((n, 1))
    kf.P = p0.copy()

    rng = np.random.default_rng(settings.seed)
    if model_t is model:
        x_true = m0_inv @ true0
    else:
        # m0_inv has already resolved the biases in n; only K is still IMU-frame:
        # K^n = C_s^n K^s C_n^s, i.e. vec_row(K^n) = kron(C_s^n, C_s^n) vec_row(K^s).
        c0 = np.asarray(timeline.c_sn[0])
        k_n = [np.kron(c0, c0) @ k.ravel() for k in (imu.gyro_error_matrix, imu.accel_error_matrix)]
        x_true = np.concatenate([m0_inv @ true0, *k_n])
    attitudes = timeline.attitude_at(t_meas)
    t_all = np.concatenate([[0.0], t_meas])
    est = np.zeros((len(t_all), n))
    sig = np.zeros((len(t_all), n))
    tru = np.zeros((len(t_all), n))
    sig[0] = sig0
    tru[0] = true0
    factors: dict[int, np.ndarray] = {}
    p_rep = np.diag(sig0**2)
    for i in range(len(steps.dt)):
        k = int(steps.key[i])
        phi = phis[k]
        qd = disc.noise(steps.unique_omega[k], steps.unique_dt[k])
        if k not in factors:
            factors[k] = _noise_factor(qd)
        kf.predict(F=phi, Q=qd)
        # Noise drives the navigation states only, whose transition block is the same
        # in both models: one draw of n normals serves both, so a run with K and one
        # without see the same noise realization and differ only by K's response.
        x_true = phis_t[k] @ x_true
        x_true[:n] += factors[k] @ rng.standard_normal(n)
        rec = int(steps.record[i])
        if rec < 0:
            continue
        z = h @ x_true[:n] + np.sqrt(r_diag) * rng.standard_normal(h.shape[0])
        kf.update(z.reshape(-1, 1), R=r, H=h)
        kf.P = 0.5 * (kf.P + kf.P.T)
        m = report_transform(model, attitudes[rec])
        p_rep = m @ kf.P @ m.T
        est[rec + 1] = m @ kf.x[:, 0]
        sig[rec + 1] = np.sqrt(np.clip(np.diag(p_rep), 0.0, None))
        tru[rec + 1] = m @ x_true[:n]
    return AlignmentResult(
        t=t_all,
        estimate=est,
        sigma=sig,
        truth=tru,
        p0=np.diag(sig0**2),
        p_final=p_rep,
        label=label,
        meta={
            "zupt_rate_hz": settings.zupt_rate,
            "zupt_sigma_m_s": settings.zupt_sigma,
            "position_sigma_m": settings.position_sigma,
            "vertical": settings.vertical,
        },
    )


def static_floors(
    site: Site,
    gyro_sigma,
    accel_sigma,
    c_sn: np.ndarray | None = None,
    prior_attitude=None,
) -> dict[str, float]:
    """Classic static-alignment limits (rad): tilt ``nabla / g``, heading ``eps_E / Omega cos L``.

    On a static base zero-velocity updates cannot separate ``nabla_E`` from ``g phi_N``,
    ``nabla_N`` from ``-g phi_E`` and ``eps_E`` from ``-Omega cos L phi_U`` (plus a small
    ``Omega sin L phi_N`` term), so with a diffuse attitude prior the attitude sigmas
    settle at these values.  A finite attitude prior is independent information on the
    same combination: once the combination itself is known exactly, the posterior of the
    angle obeys ``1/sigma^2 = 1/sigma_prior^2 + 1/floor^2``.

    Parameters
    ----------
    site : Site
        Latitude (sets ``Omega cos L``) and gravity.
    gyro_sigma, accel_sigma : float or (3,)
        1 sigma of the IMU-frame biases, rad/s and m/s^2.
    c_sn : (3, 3), optional
        IMU attitude (default level, y north), to resolve the biases in n.
    prior_attitude : float or (3,), optional
        1 sigma of the attitude prior (phi_E, phi_N, phi_U), rad; default diffuse.

    Returns
    -------
    dict with ``phi_e``, ``phi_n``, ``phi_u`` (rad, ENU psi-angle components).
    """
    c = np.eye(3) if c_sn is None else np.asarray(c_sn, dtype=float)
    sg = np.sqrt((c**2) @ np.broadcast_to(np.asarray(gyro_sigma, dtype=float), (3,)) ** 2)
    sa = np.sqrt((c**2) @ np.broadcast_to(np.asarray(accel_sigma, dtype=float), (3,)) ** 2)
    om_n = float(site.earth_rate_n[1])
    floor = np.array([sa[1] / site.g, sa[0] / site.g, sg[0] / om_n])
    if prior_attitude is not None:
        p0 = np.broadcast_to(np.asarray(prior_attitude, dtype=float), (3,))
        with np.errstate(divide="ignore"):
            info = np.where(floor > 0, 1.0 / floor**2, np.inf) + 1.0 / p0**2
        floor = 1.0 / np.sqrt(info)
    return {"phi_e": float(floor[0]), "phi_n": float(floor[1]), "phi_u": float(floor[2])}
