"""Free-inertial drift analysis: deterministic errors, random constants, noise, budget.

:func:`analyze_drift` runs the three computations the ``inserr drift`` command and
the report need, all on the same IMU attitude history (a composed schedule or a
:class:`~inserr.model.timeline.Timeline`):

1. the deterministic response to every constant error with its sign as given
   (one column, fine output grid);
2. the unit response of each constant error source (N columns, coarse grid), from
   which the random-constant RMS, the worst sign combination and the per-source
   budget follow by superposition;
3. the covariance due to white noise (ARW, VRW) and Gauss-Markov bias instability,
   one propagation per noise source so that each has its own budget line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.core.imu import ImuErrors, InitialErrors
from inserr.core.units import NMI
from inserr.drift.unknown_signs import rms_norm, worst_case_norm
from inserr.drift.validity import all_finite, attitude_extent
from inserr.model.attitude_history import AttitudeHistory, TimelineHistory
from inserr.model.discretization import discretizer_for
from inserr.model.error_sources import (
    Source,
    constant_sources,
    layout_for,
    source_matrix,
    source_set,
)
from inserr.model.exact_propagation import Output, propagate_covariance, propagate_outputs
from inserr.model.fast_propagation import (
    constant_error_response,
    gauss_markov_covariance,
    run_blocks,
    single_thread_blas,
    white_noise_covariance,
)
from inserr.model.psi_model import DR, ErrorModel, Layout, attitude_error
from inserr.model.timeline import Timeline


@dataclass
class DriftResult:
    """Everything :func:`analyze_drift` computes (SI units, ENU).

    Attributes
    ----------
    t : (M,) s
        Fine output grid of the deterministic run.
    nav : (M, 9)
        Deterministic navigation errors with the signs as given: psi (rad),
        dv (m/s), dr (m), ENU.
    attitude : (M, 3) rad
        True attitude error phi = psi + dtheta (E, N tilt; U heading error).
    t_cov : (Mc,) s
        Coarse grid of the random-constant and noise results.
    sources : list of Source
        The non-zero constant error sources, in the order of the N columns below.
    source_horizontal : (Mc, N, 2) m
        Horizontal position error (E, N) per source, scaled by its magnitude.
    source_heading : (Mc, N) rad
        Heading error per source, scaled by its magnitude.
    noise_cov : dict name -> (Mc, 9, 9)
        Navigation-error covariance (rad^2, (m/s)^2, m^2, ENU) due to each noise
        source (``arw``, ``vrw``, ``gyro_bias_instability``,
        ``accel_bias_instability``; only the non-zero ones).
    metrics : dict
        Headline numbers (see :func:`headline`).
    engine : dict
        How the results were computed. The fast engine's constant errors: ``windows``
        (quadrature windows by kind, lifted periods, lift period and phase step;
        :class:`~inserr.model.fast_propagation.ConstantErrorResponse`), ``paths`` (the
        faster ways taken, sorted) and ``nodes`` (attitude evaluations). Each noise
        source (when there is noise): ``noise[name]`` is ``"white"`` (closed form),
        ``"gauss-markov"`` (the fast engine's modal form) or ``"steps"`` (the
        step-by-step covariance propagation).

    The derived curves (:attr:`horizontal`, :attr:`rms_horizontal`,
    :attr:`worst_horizontal`, :attr:`noise_horizontal_sigma`) are computed on first
    use and kept: the metrics, the figures and the exports all read them.
    """

    t: np.ndarray
    nav: np.ndarray
    attitude: np.ndarray
    t_cov: np.ndarray
    sources: list[Source]
    source_horizontal: np.ndarray
    source_heading: np.ndarray
    noise_cov: dict[str, np.ndarray]
    metrics: dict = field(default_factory=dict)
    engine: dict = field(default_factory=dict)

    @cached_property
    def horizontal(self) -> np.ndarray:
        """Deterministic horizontal position error magnitude, m, on the fine grid."""
        return _horizontal(self.nav)

    @cached_property
    def noise_horizontal_sigma(self) -> np.ndarray:
        """1-sigma radial (DRMS) horizontal error from all noise sources, m, coarse grid."""
        tot = sum(
            (p[:, 6, 6] + p[:, 7, 7] for p in self.noise_cov.values()), np.zeros(len(self.t_cov))
        )
        return np.sqrt(np.maximum(tot, 0.0))

    @cached_property
    def rms_horizontal(self) -> np.ndarray:
        """RMS horizontal error of the constant errors taken as random constants, m."""
        return rms_norm(self.source_horizontal)

    @cached_property
    def worst_horizontal(self) -> np.ndarray:
        """Horizontal error of the worst sign combination at each coarse time, m."""
        return _worst_horizontal(self.source_horizontal)

    @cached_property
    def attitude_extent(self) -> tuple[float, float]:
        """Largest tilt (E, N) and heading error magnitudes over the run, rad."""
        return attitude_extent(self.attitude)

    @cached_property
    def finite(self) -> bool:
        """True if every number of the result is finite (nav, attitude, per-source, noise)."""
        return all_finite(self.nav, self.attitude) and all_finite(
            self.source_horizontal, self.source_heading, *self.noise_cov.values()
        )


def _horizontal(nav: np.ndarray) -> np.ndarray:
    """Horizontal position error magnitude, m, of navigation states (M, 9)."""
    return np.hypot(nav[:, 6], nav[:, 7])


def _worst_horizontal(source_horizontal: np.ndarray) -> np.ndarray:
    """Horizontal error of the worst sign combination, m, per row of (M, N, 2)."""
    return worst_case_norm(source_horizontal, signs=False)[0]


def output_grid(duration: float, step: float) -> np.ndarray:
    """Output times 0, step, 2 step, ..., and the final time (always included).

    Parameters
    ----------
    duration : float
        Final time, s.
    step : float
        Grid step, s.

    Returns
    -------
    ndarray, shape (M,)
        Increasing times, s; ``duration`` is appended when the last multiple of
        ``step`` falls more than 1 us short of it.
    """
    n = int(math.floor(duration / step + 1e-9))
    t = np.arange(n + 1) * step
    if duration - t[-1] > 1e-6:
        t = np.append(t, duration)
    return t


def _noise_runs(imu: ImuErrors) -> dict[str, tuple[float, float, float, float]]:
    runs = {}
    if imu.arw > 0:
        runs["arw"] = (imu.arw, 0.0, 0.0, 0.0)
    if imu.vrw > 0:
        runs["vrw"] = (0.0, imu.vrw, 0.0, 0.0)
    if imu.gyro_bias_instability > 0:
        runs["gyro_bias_instability"] = (0.0, 0.0, imu.gyro_bias_instability, 0.0)
    if imu.accel_bias_instability > 0:
        runs["accel_bias_instability"] = (0.0, 0.0, 0.0, imu.accel_bias_instability)
    return runs


ENGINES = ("fast", "exact")


def analyze_drift(
    site: Site,
    imu: ImuErrors,
    init: InitialErrors,
    history: AttitudeHistory | Timeline,
    *,
    dt_out: float = 1.0,
    dt_cov: float = 60.0,
    vertical: str = "clamped",
    engine: str = "fast",
    substep: float = 1.0,
) -> DriftResult:
    """Drift of a free-inertial INS over an IMU attitude history for the IMU budget ``imu``.

    Parameters
    ----------
    site : Site
        Location, Earth model and gravity.
    imu : ImuErrors
        IMU error budget, SI, IMU frame s.
    init : InitialErrors
        Initial attitude (rad), velocity (m/s) and position (m) errors, ENU.
    history : AttitudeHistory or Timeline
        IMU attitude ``C_s^n(t)``: a composed schedule
        (:class:`~inserr.schemes.composition.ScheduleHistory`, the exact continuous
        motion) or a :class:`~inserr.model.timeline.Timeline` (piecewise-constant rates).
    dt_out : float, s
        Output step of the deterministic run.
    dt_cov : float, s
        Output step of the random-constant and covariance results.
    vertical : {"clamped", "free"}
        Vertical-channel mode of :class:`~inserr.model.psi_model.ErrorModel`.
    engine : {"fast", "exact"}
        ``"fast"`` (default): :mod:`inserr.model.fast_propagation` (modal, quadrature
        over smooth windows, white noise in closed form). ``"exact"``: the step-by-step
        engine :mod:`inserr.model.exact_propagation` on a timeline (a schedule is cut
        into ``substep`` sub-steps of constant rate first); kept as the reference.
    substep : float, s
        Sub-step of continuous motion when a timeline must be built from a schedule.

    Returns
    -------
    DriftResult
        Time histories and :func:`headline` metrics.
    """
    if engine not in ENGINES:
        raise InputError("output.engine", f"unknown engine {engine!r}", "use fast or exact")
    # The whole analysis on one BLAS thread: its products are small or medium, where
    # threads cost more than they save (see single_thread_blas).
    with single_thread_blas():
        return _analyze_drift(site, imu, init, history, dt_out, dt_cov, vertical, engine, substep)


def _analyze_drift(site, imu, init, history, dt_out, dt_cov, vertical, engine, substep):
    duration = history.duration
    t = output_grid(duration, dt_out)
    t_cov = output_grid(duration, dt_cov)
    sources = constant_sources(imu, init, vertical)
    model = ErrorModel(site, layout_for(imu.without_noise()), vertical=vertical)
    engine_info: dict = {}

    def timeline() -> Timeline:
        if isinstance(history, Timeline):
            return history
        return history.timeline(substep)

    def constants() -> tuple[np.ndarray, np.ndarray]:
        if engine == "fast":
            hist = TimelineHistory(history) if isinstance(history, Timeline) else history
            resp = constant_error_response(model, hist, source_set(model, sources), t, t_cov)
            engine_info.update(windows=resp.windows, paths=sorted(resp.paths), nodes=resp.nodes)
            return resp.fine, resp.coarse
        tl = timeline()
        disc = discretizer_for(model)
        cols = source_matrix(model, sources, tl.c_sn[0])
        values = np.array([s.value for s in sources])
        x0 = cols @ values if sources else np.zeros(model.layout.n)
        # One pass: column 0 is the signed sum (fine grid), the others one source each.
        fine, coarse = propagate_outputs(
            disc,
            tl,
            np.column_stack([x0, cols * values]),
            [Output(t, slice(0, 9), slice(0, 1)), Output(t_cov, slice(0, 9), slice(1, None))],
        )
        return fine[..., 0], coarse

    def noise() -> dict[str, np.ndarray]:
        noise_cov: dict[str, np.ndarray] = {}
        how: dict[str, str] = {}
        for name, (arw, vrw, gbi, abi) in _noise_runs(imu).items():
            nmodel = ErrorModel(
                site,
                Layout(bias=False, bias_instability=(gbi > 0 or abi > 0)),
                vertical=vertical,
                gyro_correlation_time=imu.gyro_correlation_time,
                accel_correlation_time=imu.accel_correlation_time,
            )
            if engine == "fast" and not nmodel.layout.bias_instability:
                # White noise is isotropic: its covariance does not depend on the attitude.
                noise_cov[name] = white_noise_covariance(nmodel, arw, vrw, t_cov)
                how[name] = "white"
                continue
            if engine == "fast":
                # A Gauss-Markov bias is seen through the attitude history.
                hist = TimelineHistory(history) if isinstance(history, Timeline) else history
                sensor, sigma, tau = (
                    ("gyro", gbi, imu.gyro_correlation_time)
                    if gbi > 0
                    else ("accel", abi, imu.accel_correlation_time)
                )
                nav_model = ErrorModel(site, Layout(bias=False), vertical=vertical)
                noise_cov[name] = gauss_markov_covariance(
                    nav_model, hist, sigma, tau, sensor, t_cov
                )
                how[name] = "gauss-markov"
                continue
            ndisc = discretizer_for(nmodel, nmodel.noise_intensity(arw, vrw, gbi, abi))
            p0 = np.zeros((nmodel.layout.n,) * 2)
            if nmodel.layout.bias_instability:
                p0[nmodel.layout["bg"], nmodel.layout["bg"]] = gbi**2 * np.eye(3)
                p0[nmodel.layout["ba"], nmodel.layout["ba"]] = abi**2 * np.eye(3)
            noise_cov[name] = propagate_covariance(ndisc, timeline(), p0, t_cov)[:, :9, :9]
            how[name] = "steps"
        if how:
            engine_info["noise"] = how
        return noise_cov

    if engine == "fast":
        # Independent of each other: on up to two threads (run_blocks).
        (nav, coarse), noise_cov = run_blocks([constants, noise])
    else:
        (nav, coarse), noise_cov = constants(), noise()
    if sources:
        src_h = np.moveaxis(coarse[:, DR, :][:, :2, :], 1, 2)  # (Mc, N, 2)
    else:
        src_h = np.zeros((len(t_cov), 0, 2))

    # The derived curves are independent of each other: those of the fine grid beside
    # those of the per-source responses, on up to two threads, with the worst case over
    # unknown signs (the longest; its rows are independent) split between the two. The
    # cached curves are computed as DriftResult's properties compute them.
    cut = len(t_cov) // 4

    def fine_curves() -> tuple:
        att = attitude_error(site, nav)
        worst = _worst_horizontal(src_h[:cut])
        return att, _horizontal(nav), worst, all_finite(nav, att), attitude_extent(att)

    def source_curves() -> tuple:
        head = (
            attitude_error(site, np.moveaxis(coarse, 1, 2))[..., 2]
            if sources
            else np.zeros((len(t_cov), 0))
        )
        worst = _worst_horizontal(src_h[cut:])
        return head, rms_norm(src_h), worst, all_finite(src_h, head, *noise_cov.values())

    (att, horizontal, worst_a, fine_ok, extent), (src_head, rms, worst_b, source_ok) = run_blocks(
        [fine_curves, source_curves]
    )
    res = DriftResult(t, nav, att, t_cov, sources, src_h, src_head, noise_cov)
    vars(res).update(
        horizontal=horizontal,
        rms_horizontal=rms,
        worst_horizontal=np.concatenate([worst_a, worst_b]),
        finite=fine_ok and source_ok,
        attitude_extent=extent,
    )
    res.engine = engine_info
    res.metrics = headline(res)
    return res


def headline(res: DriftResult) -> dict:
    """Headline metrics of a drift result (nautical miles and degrees at the edge).

    Keys: ``hours``, ``max_horizontal_error_nmi``, ``final_horizontal_error_nmi``
    (deterministic, signs as given), ``final_horizontal_1sigma_nmi`` (noise, DRMS),
    ``final_heading_error_deg`` (deterministic), ``rms_horizontal_error_nmi`` and
    ``worst_case_horizontal_error_nmi`` (maximum over the run, constant errors of
    unknown sign), ``rms_total_horizontal_error_nmi`` (maximum over the run of the
    RMS including noise), and ``error_budget`` (source -> RMS horizontal error at
    the end, nmi).

    Parameters
    ----------
    res : DriftResult
        A drift result (SI).

    Returns
    -------
    dict
        The keys above; horizontal errors in nmi, heading error in deg, duration in h.
    """
    h = res.horizontal
    rms = res.rms_horizontal
    noise = res.noise_horizontal_sigma
    budget = {}
    for j, s in enumerate(res.sources):
        budget[s.name] = float(np.linalg.norm(res.source_horizontal[-1, j]) / NMI)
    for name, p in res.noise_cov.items():
        budget[name] = float(math.sqrt(max(p[-1, 6, 6] + p[-1, 7, 7], 0.0)) / NMI)
    return {
        "hours": float(res.t[-1] / 3600.0),
        "max_horizontal_error_nmi": float(h.max() / NMI),
        "final_horizontal_error_nmi": float(h[-1] / NMI),
        "final_horizontal_1sigma_nmi": float(noise[-1] / NMI),
        "final_heading_error_deg": float(math.degrees(res.attitude[-1, 2])),
        "rms_horizontal_error_nmi": float(rms.max() / NMI),
        "worst_case_horizontal_error_nmi": float(res.worst_horizontal.max() / NMI),
        "rms_total_horizontal_error_nmi": float(np.sqrt(rms**2 + noise**2).max() / NMI),
        "error_budget": dict(sorted(budget.items(), key=lambda kv: -kv[1])),
    }
