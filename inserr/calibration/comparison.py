"""Two position sets side by side: precision, time, noise and positioning-error sweeps.

The study behind ``analyses/p1_calibration`` (P1's off-axis four-position set against
the static six-position set), for any two sets: :func:`compare_sets` runs the Monte
Carlo of both at a baseline, without sensor noise (positioning error only), at equal
total time, sweeps dwell, gyro noise and positioning error, checks the dwell-average
shortcut against a per-sample simulation, and ranks designed sets beside the two.
Its write-up is :func:`inserr.calibration.comparison_report.build_report`.

Units: everything SI inside; the returned ``results`` dict is in engineering units
(ppm, arcsec, deg/h, s) as :meth:`~inserr.calibration.estimation.SensorResult.table`
gives them. "Predicted" sigma is the Cramer-Rao bound of the sensor noise combined
with the first-order effect of the positioning error (independent sources).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from dataclasses import replace as dataclass_replace
from typing import Any

import numpy as np

from inserr.calibration.estimation import (
    PARAMETER_NAMES,
    CalibrationDesign,
    MonteCarloConfig,
    SensorResult,
    monte_carlo,
    parameter_unit,
    positioning_sigma,
)
from inserr.calibration.position_sets import (
    candidate_tables,
    describe_candidate,
    design_sets,
    set_criterion,
)
from inserr.calibration.summary import calibration_summary
from inserr.calibration.two_axis_table import PositionSet
from inserr.core.earth import Site
from inserr.core.imu import ImuErrors
from inserr.core.units import ARCSEC, DEG_PER_SQRT_HOUR
from inserr.output.progress import progress

#: Parameter classes: slices of the parameter vector (:data:`PARAMETER_NAMES`).
CLASSES = {"sf": slice(0, 3), "mis": slice(3, 9), "bias": slice(9, 12)}

#: ``make_set(name, dwell)``: the named set with this dwell per position (s).
SetFactory = Callable[[str, float], PositionSet]


def class_rms(values: Sequence[float] | np.ndarray, sensor: str = "gyro") -> dict[str, float]:
    """RMS over each parameter class, in engineering units.

    Parameters
    ----------
    values : (12,) array
        One value per parameter (SI, order of :data:`PARAMETER_NAMES`), e.g. sigmas.
    sensor : str
        "gyro" (ppm, arcsec, deg/h) or "accel" (ppm, arcsec, micro-g).

    Returns
    -------
    dict
        ``{"sf": ..., "mis": ..., "bias": ...}``.
    """
    out = {}
    for cls, sl in CLASSES.items():
        f = parameter_unit(PARAMETER_NAMES[sl.start], sensor)[1]
        out[cls] = float(np.sqrt(np.mean((np.asarray(values)[sl] / f) ** 2)))
    return out


def predicted_sigma(
    pset: PositionSet, site: Site, imu: ImuErrors, config: MonteCarloConfig
) -> np.ndarray:
    """Predicted gyro 1-sigma per parameter: CRLB (ARW) and positioning error combined.

    Parameters
    ----------
    pset : PositionSet
    site : Site
    imu : ImuErrors
        Only ``arw`` (rad/sqrt(s)) is used.
    config : MonteCarloConfig
        Positioning error half-width (rad) and model.

    Returns
    -------
    (12,) ndarray
        SI (dimensionless, rad, rad/s).
    """
    d = CalibrationDesign.from_position_set(pset, site, "gyro", imu.arw)
    pos = positioning_sigma(d, pset, config.positioning_error, config.positioning_model)
    return np.hypot(d.crlb_sigma(), pos)


def compare_sigmas(first: np.ndarray, second: np.ndarray, tolerance: float) -> dict[str, Any]:
    """Per-parameter ratio first / second of two sigma vectors, and who is outside 1 +- tol.

    Parameters
    ----------
    first, second : (12,) array
        Sigmas in the same units.
    tolerance : float
        Relative difference counted as "the same".

    Returns
    -------
    dict
        ``ratio`` by parameter; ``worse`` (ratio > 1 + tol) and ``better``
        (ratio < 1 - tol) parameter names; ``max_ratio``/``argmax``,
        ``min_ratio``/``argmin``.
    """
    r = np.asarray(first) / np.asarray(second)
    return {
        "ratio": {n: float(v) for n, v in zip(PARAMETER_NAMES, r, strict=True)},
        "worse": [n for n, v in zip(PARAMETER_NAMES, r, strict=True) if v > 1 + tolerance],
        "better": [n for n, v in zip(PARAMETER_NAMES, r, strict=True) if v < 1 - tolerance],
        "max_ratio": float(np.max(r)),
        "argmax": PARAMETER_NAMES[int(np.argmax(r))],
        "min_ratio": float(np.min(r)),
        "argmin": PARAMETER_NAMES[int(np.argmin(r))],
    }


def equal_time_dwell(pset: PositionSet, total_time: float) -> float:
    """Dwell per position (s) at which ``pset`` takes ``total_time`` (s) in all.

    The indexing time does not depend on the dwell, so the dwell fills the rest
    equally: ``(total - indexing) / n``.
    """
    return (total_time - pset.indexing_time) / len(pset)


def crossover_dwell(
    pset: PositionSet, dwell: float, site: Site, imu: ImuErrors, config: MonteCarloConfig
) -> dict[str, float]:
    """Dwell (s) at which the gyro noise equals the positioning error, per class.

    The CRLB scales as ``1 / sqrt(dwell)`` when every dwell of the set scales alike,
    and the positioning error does not depend on the dwell, so the two class RMS
    values are equal at ``dwell * (crlb / positioning)^2``.

    Parameters
    ----------
    pset : PositionSet
        The set, every stop dwelling ``dwell``.
    dwell : float
        Its dwell per position, s.
    site, imu, config
        Site, ARW (rad/sqrt(s)) and positioning error of the comparison.

    Returns
    -------
    dict
        ``{"sf": s, "mis": s, "bias": s}``.
    """
    d = CalibrationDesign.from_position_set(pset, site, "gyro", imu.arw)
    pos = positioning_sigma(d, pset, config.positioning_error, config.positioning_model)
    out = {}
    for cls, sl in CLASSES.items():
        ratio = np.sqrt(np.mean(d.crlb_sigma()[sl] ** 2)) / np.sqrt(np.mean(pos[sl] ** 2))
        out[cls] = float(dwell * ratio**2)
    return out


@dataclass(frozen=True)
class ComparisonSettings:
    """What :func:`compare_sets` sweeps and how it judges.

    Parameters
    ----------
    tolerance : float
        Relative sigma difference counted as "the same".
    dwells : tuple of float
        Dwell sweep, s per position.
    arws : tuple of float
        Gyro ARW sweep, rad/sqrt(s).
    positioning_errors : tuple of float
        Positioning-error half-width sweep, rad.
    per_sample_check : bool
        Cross-check the dwell-average shortcut with a per-sample Monte Carlo (slow).
    design_sizes : tuple of int
        Set sizes the designer ranks.
    """

    tolerance: float = 0.10
    dwells: tuple[float, ...] = ()
    arws: tuple[float, ...] = ()
    positioning_errors: tuple[float, ...] = ()
    per_sample_check: bool = True
    design_sizes: tuple[int, ...] = (4, 5, 6)


@dataclass(frozen=True)
class Comparison:
    """What :func:`compare_sets` returns.

    Attributes
    ----------
    names : tuple of str
        The two sets, the candidate (e.g. four-position) first.
    results : dict
        JSON-ready numbers (engineering units; see :func:`compare_sets`).
    baseline, noise_free : dict
        Raw Monte Carlo results per set name (``{"gyro": SensorResult, "accel": ...}``),
        with and without sensor noise, for figures.
    """

    names: tuple[str, str]
    results: dict[str, Any]
    baseline: dict[str, dict[str, SensorResult]]
    noise_free: dict[str, dict[str, SensorResult]]


def _sweep(names, values, make, site) -> dict[str, dict[str, list]]:
    """Class-RMS Monte Carlo std and prediction of both sets over one swept value."""
    out: dict[str, dict[str, list]] = {n: {"mc": [], "pred": [], "x": []} for n in names}
    for v in progress(values, total=len(values), desc="sweep"):
        for n in names:
            ps, im, cf = make(n, v)
            r = monte_carlo(ps, site, im, cf)["gyro"]
            out[n]["mc"].append(class_rms(r.std))
            out[n]["pred"].append(class_rms(r.predicted_std))
            out[n]["x"].append(ps.total_time)
    return out


def compare_sets(
    names: tuple[str, str],
    make_set: SetFactory,
    dwell: float,
    rate: float,
    site: Site,
    imu: ImuErrors,
    config: MonteCarloConfig,
    settings: ComparisonSettings,
) -> Comparison:
    """Compare a candidate position set with a reference set (gyro calibration).

    Parameters
    ----------
    names : (str, str)
        Candidate and reference set names, as ``make_set`` knows them.
    make_set : callable
        ``make_set(name, dwell) -> PositionSet`` (dwell per position, s).
    dwell : float
        Baseline dwell per position, s.
    rate : float
        Indexing rate of the designed sets, rad/s.
    site : Site
        Latitude and gravity.
    imu : ImuErrors
        True errors and noise (SI).
    config : MonteCarloConfig
        Runs, seed, positioning error of every Monte Carlo.
    settings : ComparisonSettings
        Sweeps and tolerance.

    Returns
    -------
    Comparison
        ``results`` keys: ``baseline`` (per set, :func:`calibration_summary`),
        ``noise_free`` (per set, gyro table without sensor noise), ``equal_time``,
        ``verdict`` (times, sigma ratios at equal dwell / noise-free / equal time, and
        against the best six-position set a two-axis table reaches), ``sweeps``,
        ``positioning_models``, ``noise_positioning_crossover_dwell_s``,
        ``per_sample_check`` (if asked) and ``design``.
    """
    four, six = names
    tol = settings.tolerance
    sets = {n: make_set(n, dwell) for n in names}
    results: dict[str, Any] = {}

    # 1. Baseline Monte Carlo of both sets.
    base: dict[str, dict[str, SensorResult]] = {}
    results["baseline"] = {}
    for n, ps in sets.items():
        summary, res = calibration_summary(ps, site, imu, config)
        base[n] = res
        results["baseline"][n] = summary

    # 2. No sensor noise: positioning error only.
    quiet = imu.replace(arw=0.0, vrw=0.0)
    noise_free = {n: monte_carlo(ps, site, quiet, config) for n, ps in sets.items()}
    results["noise_free"] = {n: r["gyro"].table() for n, r in noise_free.items()}

    # 3. Equal total time: the candidate dwells longer.
    t6 = sets[six].total_time
    four_eq = make_set(four, equal_time_dwell(sets[four], t6))
    eq_res = monte_carlo(four_eq, site, imu, config)
    results["equal_time"] = {
        "dwell_four_s": equal_time_dwell(sets[four], t6),
        "total_time_s": four_eq.total_time,
        "gyro": eq_res["gyro"].table(),
    }

    # 4. Verdict numbers (predictions; the Monte Carlo beside them).
    pred = {n: predicted_sigma(ps, site, imu, config) for n, ps in sets.items()}
    pred_nf = {n: predicted_sigma(ps, site, quiet, config) for n, ps in sets.items()}
    pred_eq = predicted_sigma(four_eq, site, imu, config)
    verdict: dict[str, Any] = {
        "time_four_s": sets[four].total_time,
        "time_six_s": t6,
        "time_saving": 1.0 - sets[four].total_time / t6,
        "dwell_only_saving": 1.0 - sets[four].dwell_time / sets[six].dwell_time,
        "equal_dwell": compare_sigmas(pred[four], pred[six], tol),
        "noise_free": compare_sigmas(pred_nf[four], pred_nf[six], tol),
        "equal_time": compare_sigmas(pred_eq, pred[six], tol),
        "mc_equal_dwell_ratio": {
            n: float(v)
            for n, v in zip(
                PARAMETER_NAMES, base[four]["gyro"].std / base[six]["gyro"].std, strict=True
            )
        },
        "d_efficiency_four_over_six": set_criterion(sets[four], site)
        / set_criterion(sets[six], site),
    }
    # The classical six-position set is weak on the x scale factor (x only ever sees the
    # vertical Earth rate); compare with the best six-position set a two-axis table reaches.
    best6 = design_sets(site, dwell, (6,), "gyro", rate=rate, top=1)[0]
    best6_set = best6.position_set()
    pred_b6 = predicted_sigma(best6_set, site, imu, config)
    four_eq_b6 = make_set(four, equal_time_dwell(sets[four], best6_set.total_time))
    verdict["best_six"] = {
        "mechanism": best6.mechanism,
        "stops_outer_inner_deg": best6.stops_deg(),
        "total_time_s": best6_set.total_time,
        "equal_dwell": compare_sigmas(pred[four], pred_b6, tol),
        "equal_time": compare_sigmas(predicted_sigma(four_eq_b6, site, imu, config), pred_b6, tol),
        "noise_free": compare_sigmas(
            pred_nf[four], predicted_sigma(best6_set, site, quiet, config), tol
        ),
    }
    results["verdict"] = verdict

    # 5. Sweeps of dwell, gyro noise and positioning error (with and without noise).
    def pos_cfg(v: float) -> MonteCarloConfig:
        return MonteCarloConfig(
            runs=config.runs,
            seed=config.seed,
            positioning_error=v,
            positioning_model=config.positioning_model,
        )

    dwells, arws, pes = settings.dwells, settings.arws, settings.positioning_errors
    results["sweeps"] = {
        "dwell_s": list(dwells),
        "dwell": _sweep(names, dwells, lambda n, v: (make_set(n, v), imu, config), site),
        "arw_deg_per_sqrt_h": [v / DEG_PER_SQRT_HOUR for v in arws],
        "arw": _sweep(names, arws, lambda n, v: (sets[n], imu.replace(arw=v), config), site),
        "positioning_error_arcsec": [v / ARCSEC for v in pes],
        "positioning": _sweep(names, pes, lambda n, v: (sets[n], imu, pos_cfg(v)), site),
        "positioning_noise_free": _sweep(
            names, pes, lambda n, v: (sets[n], quiet, pos_cfg(v)), site
        ),
    }

    # Positioning-error models: three-axis vs gimbal angles only, noise-free.
    models = {}
    for model in ("three-axis", "gimbal"):
        c = dataclass_replace(pos_cfg(config.positioning_error), positioning_model=model)
        models[model] = {
            n: class_rms(monte_carlo(ps, site, quiet, c)["gyro"].std) for n, ps in sets.items()
        }
    results["positioning_models"] = models
    results["noise_positioning_crossover_dwell_s"] = crossover_dwell(
        sets[four], dwell, site, imu, config
    )

    # 6. Per-sample cross-check of the dwell-average shortcut.
    if settings.per_sample_check:
        ps_cfg = MonteCarloConfig(
            runs=config.runs,
            seed=config.seed,
            positioning_error=0.0,
            per_sample=True,
            sample_rate=config.sample_rate,
        )
        sh_cfg = MonteCarloConfig(runs=config.runs, seed=config.seed, positioning_error=0.0)
        results["per_sample_check"] = {
            n: {
                "per_sample": class_rms(monte_carlo(ps, site, imu, ps_cfg)["gyro"].std),
                "shortcut": class_rms(monte_carlo(ps, site, imu, sh_cfg)["gyro"].std),
                "crlb": class_rms(
                    CalibrationDesign.from_position_set(ps, site, "gyro", imu.arw).crlb_sigma()
                ),
            }
            for n, ps in sets.items()
        }

    # 7. Designed sets beside the two.
    results["design"] = design_comparison(sets, site, dwell, rate, imu.arw, settings.design_sizes)
    return Comparison(names, results, base, noise_free)


def design_comparison(
    sets: dict[str, PositionSet],
    site: Site,
    dwell: float,
    rate: float,
    arw: float,
    sizes: tuple[int, ...],
) -> dict[str, Any]:
    """The designer's best sets beside ``sets``, for three choices of sensors and steps.

    Returns
    -------
    dict
        Per ``"<sensors>, <step> deg steps"``: ``candidates``
        (:func:`describe_candidate`), ``reference_efficiency`` of ``sets`` and the
        ``best_four_position_efficiency`` of every mechanism (None: no full-rank set),
        all relative to the best candidate.
    """
    design = {}
    for sensors, step_deg in (("gyro", 90), ("gyro+accel", 90), ("gyro", 180)):
        step = math.radians(step_deg)
        cands = design_sets(site, dwell, sizes, sensors, step, rate, top=5)
        refs = {n: set_criterion(ps, site, sensors) for n, ps in sets.items()}
        best4 = {}
        for mech, table in candidate_tables(rate).items():
            fours = design_sets(site, dwell, (4,), sensors, step, rate, top=1, tables={mech: table})
            best4[mech] = fours[0].criterion / cands[0].criterion if fours else None
        design[f"{sensors}, {step_deg} deg steps"] = {
            "candidates": [
                describe_candidate(c, site, arw, cands[0].criterion, refs) for c in cands
            ],
            "reference_efficiency": {n: v / cands[0].criterion for n, v in refs.items()},
            "best_four_position_efficiency": best4,
        }
    return design


def settings_summary(
    site: Site,
    imu: ImuErrors,
    dwell: float,
    rate: float,
    config: MonteCarloConfig,
    *,
    tolerance: float,
    quick: bool,
) -> dict[str, Any]:
    """The comparison's set-up in engineering units (the ``scenario`` block of its results).

    Returns
    -------
    dict
        Latitude (deg), dwell (s), table rate (deg/s), ARW (deg/sqrt(h)), positioning
        error (arcsec) and model, runs, seed, ``quick`` and ``tolerance``.
    """
    return {
        "latitude_deg": math.degrees(site.lat),
        "dwell_s": dwell,
        "table_rate_deg_s": math.degrees(rate),
        "arw_deg_per_sqrt_h": imu.arw / DEG_PER_SQRT_HOUR,
        "positioning_error_arcsec": config.positioning_error / ARCSEC,
        "positioning_model": config.positioning_model,
        "runs": config.runs,
        "seed": config.seed,
        "quick": quick,
        "tolerance": tolerance,
    }
