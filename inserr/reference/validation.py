"""Linear prediction against the nonlinear reference; Monte Carlo against covariance.

:func:`validate` runs, on one scenario, the linear drift analysis
(:func:`inserr.drift.study.run_scheme`) and the nonlinear reference
(:mod:`inserr.reference.strapdown`), and compares them in two ways.

1. **Deterministic errors.** One nonlinear run with the budget's constant errors
   as given and no noise, against the linear deterministic response. Reported:
   the maxima of the horizontal error over the run, their relative difference
   ``|max_nl - max_lin| / max_lin``, and the RMS over the time history of the
   horizontal error *vector* difference ``|dr_nl - dr_lin|`` (E, N), which also
   catches a direction error that equal magnitudes would hide.
2. **Monte Carlo** (``runs > 1``). ``runs`` further nonlinear runs with independent
   noise (ARW, VRW, bias instability) and, optionally, the constant errors drawn
   as zero-mean random constants with 1 sigma = their magnitude. Their horizontal
   error at the final time is compared with the linear 2x2 horizontal covariance
   ``P`` (noise covariance, plus the random-constant covariance
   ``sum_j h_j h_j^T`` when constants are drawn).

Consistency test (:func:`chi2_consistency`). With ``N`` independent Gaussian
samples ``x_i`` of covariance ``P`` and their sample mean ``xbar``,
``q = sum_i (x_i - xbar)^T P^-1 (x_i - xbar)`` is chi-square with ``2 (N - 1)``
degrees of freedom. The covariance is declared consistent with the Monte Carlo
at confidence ``c`` (default 0.99) when ``q`` lies inside the two-sided interval
``[chi2_{(1-c)/2}, chi2_{(1+c)/2}]``: too small a spread and too large a spread
both fail. Subtracting the sample mean makes the test about the spread only; the
mean is what part 1 checks. The test is made once, at the final time, so its
confidence level is exact (per-time tests would be strongly correlated).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from inserr.core.errors import InputError
from inserr.core.units import ARCSEC, HOUR
from inserr.drift.analysis import DriftResult
from inserr.reference.injection import child_seed, draw_constants
from inserr.reference.strapdown import (
    DEFAULT_CHUNK,
    DEFAULT_RATE,
    ErrorHistory,
    RunSpec,
    attitude_history,
    deterministic_run,
    require_pyins,
    simulate,
)
from inserr.scenario.schema import Scenario

#: Default confidence of the chi-square consistency test.
DEFAULT_CONFIDENCE = 0.99


def interpolate(t_from: np.ndarray, values: np.ndarray, t_to: np.ndarray) -> np.ndarray:
    """Interpolate (M, k) ``values`` linearly from ``t_from`` to ``t_to`` (exact at shared t)."""
    values = np.asarray(values, dtype=float)
    return np.column_stack([np.interp(t_to, t_from, values[:, j]) for j in range(values.shape[1])])


def compare(linear: DriftResult, nonlinear: ErrorHistory) -> dict:
    """Deterministic linear response against one nonlinear run (metres, arcsec).

    Returns
    -------
    dict
        ``linear_max_horizontal_error_m``, ``nonlinear_max_horizontal_error_m``,
        ``relative_difference`` (of the maxima; None if the linear maximum is 0),
        ``rms_difference_m`` and ``max_difference_m`` (of the horizontal error vector
        over the nonlinear output times), final horizontal errors, final heading
        errors (arcsec) and the largest attitude-error difference (arcsec).
    """
    dr_lin = interpolate(linear.t, linear.nav[:, 6:8], nonlinear.t)
    diff = np.linalg.norm(nonlinear.dr[:, :2] - dr_lin, axis=1)
    phi_lin = interpolate(linear.t, linear.attitude, nonlinear.t)
    lin_max = float(linear.horizontal.max())
    nl_max = float(nonlinear.horizontal.max())
    return {
        "linear_max_horizontal_error_m": lin_max,
        "nonlinear_max_horizontal_error_m": nl_max,
        "relative_difference": abs(nl_max - lin_max) / lin_max if lin_max > 0 else None,
        "rms_difference_m": float(np.sqrt(np.mean(diff**2))),
        "max_difference_m": float(diff.max()),
        "linear_final_horizontal_error_m": float(linear.horizontal[-1]),
        "nonlinear_final_horizontal_error_m": float(nonlinear.horizontal[-1]),
        "linear_final_heading_error_arcsec": float(linear.attitude[-1, 2] / ARCSEC),
        "nonlinear_final_heading_error_arcsec": float(nonlinear.phi[-1, 2] / ARCSEC),
        "max_attitude_difference_arcsec": float(np.abs(nonlinear.phi - phi_lin).max() / ARCSEC),
    }


@dataclass(frozen=True)
class ConsistencyTest:
    """Result of :func:`chi2_consistency` (see the module notes)."""

    statistic: float
    dof: int
    lower: float
    upper: float
    p_value: float
    confidence: float

    @property
    def consistent(self) -> bool:
        """True when the statistic is inside the two-sided acceptance interval."""
        return self.lower <= self.statistic <= self.upper

    @property
    def accepted_sigma_ratio(self) -> tuple[float, float]:
        """Range of (sample spread / covariance 1-sigma) the test accepts: its resolution."""
        return (math.sqrt(self.lower / self.dof), math.sqrt(self.upper / self.dof))

    def as_dict(self) -> dict:
        """The test as plain JSON: statistic, bounds, p-value, verdict and its resolution.

        Returns
        -------
        dict
            ``accepted_sigma_ratio`` is the range of spread/covariance ratios the test
            cannot tell from 1 at this confidence; with few runs it is wide (0.35 to 1.7
            for 3 runs in 2-D at 95 %), and ``note`` says so.
        """
        lo, hi = self.accepted_sigma_ratio
        note = (
            f"with {self.dof} degrees of freedom the test accepts any spread from {lo:.2f} to "
            f"{hi:.2f} times the covariance 1-sigma; more runs resolve finer"
            if hi - lo > 0.4
            else ""
        )
        return {
            "test": "two-sided chi-square on sum_i (x_i - xbar)^T P^-1 (x_i - xbar), final time",
            "accepted_sigma_ratio": [lo, hi],
            "note": note,
            "statistic": self.statistic,
            "dof": self.dof,
            "lower": self.lower,
            "upper": self.upper,
            "p_value": self.p_value,
            "confidence": self.confidence,
            "verdict": "consistent" if self.consistent else "inconsistent",
        }


def chi2_consistency(
    samples: np.ndarray, cov: np.ndarray, confidence: float = DEFAULT_CONFIDENCE
) -> ConsistencyTest:
    """Are ``samples`` (N, d) consistent with covariance ``cov`` (d, d)? Two-sided chi-square test.

    Parameters
    ----------
    samples : (N, d)
        Independent samples (N >= 2).
    cov : (d, d)
        Predicted covariance (positive definite).
    confidence : float
        Probability that a correct covariance passes, in (0, 1).
    """
    from scipy.stats import chi2

    x = np.asarray(samples, dtype=float)
    n, d = x.shape
    if n < 2:
        raise InputError(
            "scenario.runs", f"the consistency test needs at least 2 runs, got {n}", "give e.g. 20"
        )
    if not 0.0 < confidence < 1.0:
        raise InputError(
            "validate.confidence", f"must be in (0, 1), got {confidence!r}", "give e.g. 0.99"
        )
    dev = x - x.mean(axis=0)
    q = float(np.einsum("ni,ij,nj->", dev, np.linalg.inv(cov), dev))
    dof = d * (n - 1)
    lo, hi = chi2.ppf([(1.0 - confidence) / 2.0, (1.0 + confidence) / 2.0], dof)
    p = float(min(1.0, 2.0 * min(chi2.cdf(q, dof), chi2.sf(q, dof))))
    return ConsistencyTest(q, dof, float(lo), float(hi), p, confidence)


def horizontal_covariance(linear: DriftResult, random_constants: bool) -> np.ndarray:
    """Predicted (Mc, 2, 2) covariance of the horizontal error (E, N), m^2, on ``linear.t_cov``.

    Noise covariances, plus ``sum_j h_j h_j^T`` of the per-source responses when the
    constant errors are read as random constants.
    """
    p = np.zeros((len(linear.t_cov), 2, 2))
    for cov in linear.noise_cov.values():
        p += cov[:, 6:8, 6:8]
    if random_constants:
        h = linear.source_horizontal  # (Mc, N, 2), already scaled by the magnitudes
        p += np.einsum("tni,tnj->tij", h, h)
    return p


@dataclass
class MonteCarlo:
    """Monte Carlo runs and their comparison with the covariance."""

    runs: list[ErrorHistory]
    t: np.ndarray
    samples: np.ndarray  # (R, Mc, 2) horizontal errors E, N on t
    cov: np.ndarray  # (Mc, 2, 2)
    test: ConsistencyTest | None
    random_constants: bool

    @property
    def sample_std(self) -> np.ndarray:
        """Radial (DRMS) sample standard deviation sqrt(tr S), m, per time (N - 1 denominator)."""
        return np.sqrt(np.sum(np.var(self.samples, axis=0, ddof=1), axis=-1))

    @property
    def sigma(self) -> np.ndarray:
        """Radial (DRMS) covariance 1 sigma sqrt(tr P), m, per time."""
        return np.sqrt(np.maximum(np.trace(self.cov, axis1=1, axis2=2), 0.0))

    def summary(self) -> dict:
        std, sig = float(self.sample_std[-1]), float(self.sigma[-1])
        out = {
            "runs": len(self.runs),
            "random_constants": self.random_constants,
            "time_s": float(self.t[-1]),
            "sample_std_horizontal_m": std,
            "covariance_sigma_horizontal_m": sig,
            "std_ratio": std / sig if sig > 0 else None,
            "sample_mean_horizontal_m": self.samples[:, -1, :].mean(axis=0),
        }
        if self.test is None:
            out["verdict"] = (
                "not applicable: the predicted covariance is singular at the final time"
            )
        else:
            out["chi2"] = self.test.as_dict()
            out["verdict"] = self.test.as_dict()["verdict"]
        return out


@dataclass
class Validation:
    """Everything :func:`validate` computes."""

    scenario: Scenario
    scheme: str
    linear: DriftResult
    nonlinear: ErrorHistory
    metrics: dict
    monte_carlo: MonteCarlo | None
    rate: float
    seed: int
    notes: list[str] = field(default_factory=list)

    def summary(self) -> dict:
        """JSON-ready summary (SI units, arcsec for attitude)."""
        out = {
            "scenario": self.scenario.name,
            "scheme": self.scheme,
            "hours": self.scenario.duration / HOUR,
            "imu_rate_hz": self.rate,
            "vertical": self.scenario.vertical,
            **self.metrics,
            "runs": 1 if self.monte_carlo is None else len(self.monte_carlo.runs),
            "seed": self.seed,
        }
        if self.monte_carlo is not None:
            out["monte_carlo"] = self.monte_carlo.summary()
        out["notes"] = list(self.notes)
        return out


def _mc_specs(
    scen: Scenario, runs: int, seed: int, random_constants: bool, record_step: float
) -> list[RunSpec]:
    specs = []
    root = np.random.SeedSequence(seed)
    for r in range(runs):
        child = child_seed(root, r)
        noise_seed, const_seed = child_seed(child, 0), child_seed(child, 1)
        imu, init = scen.imu, scen.init
        if random_constants:
            imu, init = draw_constants(imu, init, np.random.default_rng(const_seed))
        specs.append(RunSpec(imu, init, noise_seed, noise=True, record_step=record_step))
    return specs


def validate(
    scen: Scenario,
    *,
    runs: int = 1,
    seed: int | None = None,
    rate: float = DEFAULT_RATE,
    chunk: float = DEFAULT_CHUNK,
    confidence: float = DEFAULT_CONFIDENCE,
    random_constants: bool = False,
    scheme: str | None = None,
) -> Validation:
    """Linear analysis and nonlinear reference of ``scen``; comparison and Monte Carlo.

    Parameters
    ----------
    scen : Scenario
    runs : int
        1: the deterministic comparison only. N > 1: also N Monte Carlo runs.
    seed : int, optional
        Seed of the Monte Carlo (default: the scenario's ``scenario.seed``).
    rate : float, Hz
        IMU sample rate of the reference.
    chunk : float, s
        Chunk length of the reference (memory bound; results do not depend on it).
    confidence : float
        Confidence of the chi-square consistency test.
    random_constants : bool
        Monte Carlo draws the constant errors too (zero mean, 1 sigma = magnitude).
    scheme : str, optional
        Scheme name (default: the scenario's).
    """
    from inserr.drift.study import run_scheme

    require_pyins()  # fail before the linear work when the extra is missing
    if runs < 1:
        raise InputError("scenario.runs", f"must be >= 1, got {runs}")
    seed = scen.seed if seed is None else int(seed)
    noisy = scen.imu.arw > 0 or scen.imu.vrw > 0 or scen.imu.has_bias_instability
    if runs > 1 and not (noisy or random_constants):
        raise InputError(
            "scenario.runs",
            "a Monte Carlo needs a random error, but the budget has no noise or bias instability",
            "give imu.arw, imu.vrw or a bias instability, or set validate.random_constants",
        )
    notes = []
    if scen.site.spherical:
        notes.append(
            "the scenario uses a spherical Earth; the reference always uses the WGS84 ellipsoid"
        )

    lin_run = run_scheme(scen, scheme)
    lin = lin_run.result
    specs = [deterministic_run(scen.imu, scen.init, scen.dt_out)]
    if runs > 1:
        specs += _mc_specs(scen, runs, seed, random_constants, scen.dt_cov)
    histories = simulate(
        scen.site,
        attitude_history(lin_run.timeline),
        scen.duration,
        specs,
        rate=rate,
        chunk=chunk,
        vertical=scen.vertical,
        desc=f"reference {lin_run.name}",
    )
    det = histories[0]
    mc = None
    if runs > 1:
        t_end = det.t[-1]
        t = lin.t_cov[lin.t_cov <= t_end + 1e-9]
        samples = np.stack([interpolate(h.t, h.dr[:, :2], t) for h in histories[1:]])
        cov = horizontal_covariance(lin, random_constants)[: len(t)]
        if t[-1] < t_end - 1e-9:
            notes.append(
                f"Monte Carlo compared at {t[-1]:g} s, the last covariance time before the end"
            )
        test = None
        if np.linalg.matrix_rank(cov[-1]) == 2 and np.linalg.cond(cov[-1]) < 1e12:
            test = chi2_consistency(samples[:, -1, :], cov[-1], confidence)
        mc = MonteCarlo(histories[1:], t, samples, cov, test, random_constants)
    return Validation(scen, lin_run.name, lin, det, compare(lin, det), mc, rate, seed, notes)


def validate_scenario(scen) -> Validation:
    """:func:`validate` with its settings read from the scenario.

    Reads ``scenario.runs``, ``scenario.seed``, ``imu.sample_rate`` (the reference's
    IMU rate), ``validate.chunk``, ``validate.confidence`` and
    ``validate.random_constants``; the scheme is the scenario's.

    Parameters
    ----------
    scen : Scenario

    Returns
    -------
    Validation
    """
    return validate(
        scen,
        runs=scen.value("scenario.runs"),
        seed=scen.seed,
        rate=scen.value("imu.sample_rate"),
        chunk=scen.value("validate.chunk"),
        confidence=scen.value("validate.confidence"),
        random_constants=scen.value("validate.random_constants"),
    )
