"""A published Monte Carlo table of two calibration methods, set beside the model.

P1 (Miao et al. 2018) prints, for its static six-position and off-axis four-position
methods, the *mean* of 100 simulated calibrations of each of the 12 gyro parameters,
and claims deviations "at the 1e-7 level", the four-position method better on 9 of
the 12, and a third less time. :func:`against_published` puts such a table beside
:func:`inserr.calibration.comparison.compare_sets`'s Monte Carlo and says what the
model makes of each claim.

The statistics used (least squares is unbiased, so a mean of ``N`` runs deviates from
the truth only by Monte Carlo noise):

* the mean of ``N`` runs with per-run sigma ``s`` deviates by ``N(0, s^2 / N)``, whose
  expected magnitude is ``s sqrt(2 / (pi N))`` (:func:`expected_abs_mean`);
* of two independent zero-mean normal deviations with sigmas ``a`` and ``b``, the first
  is the smaller in magnitude with probability ``(2/pi) atan(b/a)``
  (:func:`better_probability`); the count of such wins over 12 parameters is
  Poisson-binomial (:func:`count_distribution`);
* with the noise-free (positioning-error-only) sigma ``p_i`` and the CRLB per unit ARW
  ``c_i``, the predicted sigma at ARW ``w`` is ``sqrt(w^2 c_i^2 + p_i^2)``; the paper's
  deviations divided by ``p_i / sqrt(N)`` (z-scores) have RMS ``sqrt(1 + w^2 k)`` with
  ``k = mean(c_i^2 / p_i^2)``, which gives the noise level the table implies
  (:func:`implied_arw`), and the RMS expected deviation of a class falls below a
  threshold only for ARW below a closed-form value (:func:`max_arw_for_level`).

Units: SI inside; the table's own units (e.g. 1e-4, 1e-5 rad, deg/h) at the edges.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from inserr.calibration.comparison import Comparison, class_rms, predicted_sigma
from inserr.calibration.estimation import (
    PARAMETER_NAMES,
    CalibrationDesign,
    MonteCarloConfig,
    positioning_sigma,
)
from inserr.calibration.position_sets import design_sets, set_criterion
from inserr.calibration.two_axis_table import PositionSet, pointing
from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.core.imu import ImuErrors
from inserr.core.units import DEG_PER_HOUR, DEG_PER_SQRT_HOUR

#: Every IMU axis once up and once down.
EVERY_AXIS_UP_AND_DOWN = ("+x", "-x", "+y", "-y", "+z", "-z")
#: Names of the designed six-position sets of :func:`six_position_sets`.
EVERY_NAME, BEST_NAME = "every-axis-up-down-best", "six-best"
#: Parameters whose deviation the "1e-7 level" speaks of: dimensionless or rad.
SF_AND_MIS = slice(0, 9)


@dataclass(frozen=True)
class PublishedTable:
    """A published table of Monte Carlo means and the claims made from it.

    Parameters
    ----------
    means : dict
        Set name -> ``{parameter name: mean estimate}``, SI (as printed, misprints kept).
    runs : int
        Monte Carlo runs behind each mean.
    printed_units : dict
        Class (``sf``, ``mis``, ``bias``) -> (label, SI value of one printed unit).
    misprint : tuple or None
        ``(set name, parameter, SI value)``: the reading used instead of a printed value
        that is evidently a misprint; both readings are reported.
    better_count : int
        Claimed number of parameters on which the first set is better.
    time_saving : float
        Claimed fraction of the time saved by the first set.
    deviation_level : float
        Claimed order of magnitude of the mean deviations (SI, dimensionless/rad).
    """

    means: dict[str, dict[str, float]]
    runs: int
    printed_units: dict[str, tuple[str, float]]
    misprint: tuple[str, str, float] | None
    better_count: int
    time_saving: float
    deviation_level: float

    def read(self, name: str, corrected: bool = True) -> np.ndarray:
        """Means of set ``name`` in parameter order (SI), with or without the correction."""
        v = np.array([self.means[name][p] for p in PARAMETER_NAMES], dtype=float)
        if corrected and self.misprint and self.misprint[0] == name:
            v[PARAMETER_NAMES.index(self.misprint[1])] = self.misprint[2]
        return v

    def unit(self, j: int) -> tuple[str, float]:
        """Printed unit of parameter ``j``: (label, SI value)."""
        return self.printed_units[PARAMETER_NAMES[j].split("_")[0]]


def _power_label(v: float) -> str:
    """``1e-4`` -> ``"1e-4"``, ``1.0`` -> ``""``, ``2.5`` -> ``"2.5"``: a printed unit's factor."""
    if v == 1.0:
        return ""
    m, e = f"{v:.6e}".split("e")
    if float(m) == 1.0:
        return f"1e{int(e)}"
    return f"{v:g}"


def published_table(
    set_names: tuple[str, str],
    rows: Sequence[str],
    means: tuple[Sequence[float], Sequence[float]],
    units: dict[str, float],
    *,
    runs: int,
    misprint: tuple[str, float] | None,
    better_count: int,
    time_saving: float,
    deviation_level: float,
    field: str = "paper",
) -> PublishedTable:
    """A :class:`PublishedTable` from the printed rows, checked.

    Parameters
    ----------
    set_names : (str, str)
        Candidate and reference set names.
    rows : sequence of str
        Parameter name of each printed row (:data:`PARAMETER_NAMES`, any order).
    means : (sequence, sequence)
        Printed means of the candidate and the reference set, row by row, printed units.
    units : dict
        SI value of one printed unit of ``scale_factor`` (dimensionless),
        ``misalignment`` (rad) and ``bias`` (rad/s).
    runs, better_count, time_saving, deviation_level
        As :class:`PublishedTable`.
    misprint : (str, float) or None
        Parameter of the candidate set printed wrongly, and its reading (printed unit).
    field : str
        Scenario table the values come from, for error messages.

    Returns
    -------
    PublishedTable
        SI values.

    Raises
    ------
    InputError
        Naming ``<field>.<key>``: rows not the 12 parameters, a row count mismatch, an
        unknown misprint parameter.
    """
    if sorted(rows) != sorted(PARAMETER_NAMES):
        raise InputError(
            f"{field}.rows",
            "must name each of the 12 parameters once",
            f"use {', '.join(PARAMETER_NAMES)} in the printed order",
        )
    printed = {
        "sf": (_power_label(units["scale_factor"]) or "1", units["scale_factor"]),
        "mis": (f"{_power_label(units['misalignment'])} rad".strip(), units["misalignment"]),
        "bias": (f"{_power_label(units['bias'] / DEG_PER_HOUR)} deg/h".strip(), units["bias"]),
    }
    table = {}
    for name, values, key in zip(
        set_names, means, ("candidate_means", "reference_means"), strict=True
    ):
        if len(values) != len(rows):
            raise InputError(f"{field}.{key}", f"{len(values)} values for {len(rows)} rows")
        table[name] = {
            p: float(v) * printed[p.split("_")[0]][1] for p, v in zip(rows, values, strict=True)
        }
    fix = None
    if misprint is not None:
        param, reading = misprint
        if param not in PARAMETER_NAMES:
            raise InputError(f"{field}.misprint", f"unknown parameter {param!r}")
        fix = (set_names[0], param, reading * printed[param.split("_")[0]][1])
    return PublishedTable(table, runs, printed, fix, better_count, time_saving, deviation_level)


def expected_abs_mean(sigma: np.ndarray | float, runs: int) -> np.ndarray:
    """Expected |mean of ``runs`` zero-mean normal deviations| with per-run ``sigma``."""
    return np.asarray(sigma) * math.sqrt(2.0 / (math.pi * runs))


def better_probability(sigma_a: np.ndarray, sigma_b: np.ndarray) -> np.ndarray:
    """P(|X| < |Y|) for independent X ~ N(0, a^2), Y ~ N(0, b^2): ``(2/pi) atan(b/a)``."""
    return 2.0 / math.pi * np.arctan2(np.asarray(sigma_b), np.asarray(sigma_a))


def count_distribution(p: np.ndarray) -> np.ndarray:
    """Poisson-binomial pmf of the number of successes of independent trials ``p``.

    Returns
    -------
    (len(p) + 1,) ndarray
        ``pmf[k]`` = probability of exactly ``k`` successes.
    """
    pmf = np.zeros(len(p) + 1)
    pmf[0] = 1.0
    for q in p:
        pmf[1:] = pmf[1:] * (1.0 - q) + pmf[:-1] * q
        pmf[0] *= 1.0 - q
    return pmf


def max_arw_for_level(
    crlb_per_arw: np.ndarray, positioning: np.ndarray, threshold: float, runs: int
) -> float | None:
    """Largest ARW whose RMS expected |mean deviation| stays at or below ``threshold``.

    Solves ``mean(w^2 c_i^2 + p_i^2) = threshold^2 pi runs / 2`` for ``w``.

    Parameters
    ----------
    crlb_per_arw : array
        CRLB sigma per unit ARW of each parameter (SI per rad/sqrt(s)).
    positioning : array
        Positioning-error sigma of each parameter, SI.
    threshold : float
        RMS expected |mean deviation|, SI.
    runs : int

    Returns
    -------
    float or None
        rad/sqrt(s); None when the positioning error alone exceeds the threshold.
    """
    budget = threshold**2 * math.pi * runs / 2.0 - float(np.mean(np.square(positioning)))
    if budget <= 0:
        return None
    return math.sqrt(budget / float(np.mean(np.square(crlb_per_arw))))


def implied_arw(z: np.ndarray, crlb_per_arw: np.ndarray, positioning: np.ndarray) -> float | None:
    """ARW at which the noise-free-normalised deviations ``z`` have their expected RMS.

    ``z_i`` = deviation / (``p_i`` / sqrt(runs)); at ARW ``w`` their mean square is
    ``1 + w^2 mean(c_i^2 / p_i^2)``. None when ``RMS(z) <= 1`` (no noise needed).
    """
    excess = float(np.mean(np.square(z))) - 1.0
    if excess <= 0:
        return None
    k = float(np.mean(np.square(np.asarray(crlb_per_arw) / np.asarray(positioning))))
    return math.sqrt(excess / k)


def positions_pointing(pset: PositionSet, site: Site) -> list[dict[str, Any]]:
    """Per stop: gimbal angles (deg), the IMU axis along east/north/up, gyro input (deg/h)."""
    rows = []
    for p, c in zip(pset.positions, pset.attitudes, strict=True):
        u = c.T @ site.earth_rate_n / DEG_PER_HOUR
        u[np.abs(u) < 1e-9] = 0.0  # exact zeros, as the paper prints them
        rows.append(
            {
                "name": p.name,
                "outer_deg": round(math.degrees(p.outer), 6),
                "inner_deg": round(math.degrees(p.inner), 6),
                **pointing(c),
                "gyro_input_deg_h": u,
            }
        )
    return rows


def _noise_parts(pset: PositionSet, site: Site, config: MonteCarloConfig):
    """CRLB per unit ARW (at 1 rad/sqrt(s)) and positioning sigma of the gyro parameters, SI."""
    d = CalibrationDesign.from_position_set(pset, site, "gyro", 1.0)
    pos = positioning_sigma(d, pset, config.positioning_error, config.positioning_model)
    return d.crlb_sigma(), pos


def against_published(
    comparison: Comparison,
    paper: PublishedTable,
    sets: dict[str, PositionSet],
    site: Site,
    imu: ImuErrors,
    config: MonteCarloConfig,
    dwells: tuple[float, ...],
) -> dict[str, Any]:
    """The published table and claims beside the model (JSON-ready).

    Parameters
    ----------
    comparison : Comparison
        :func:`compare_sets` of the same two sets (its baseline and noise-free runs).
    paper : PublishedTable
        Means and claims; its set names are those of ``comparison``.
    sets : dict
        The two sets at the baseline dwell, candidate first.
    site, imu, config
        The comparison's site, truth and noise, Monte Carlo settings.
    dwells : tuple of float
        Dwells (s) at which the time saving is quoted.

    Returns
    -------
    dict
        ``runs`` (behind each published mean); ``rows`` (per set and parameter:
        printed and model numbers in the printed unit, z-score); ``better`` (count
        claim); ``level`` (deviation-level claim, ARW thresholds); ``implied`` (noise
        the table implies); ``time`` (saving per dwell); ``six_position_sets`` (which
        axes point where, and how a set with every axis up and down compares).
    """
    names = comparison.names
    runs = paper.runs
    truth = comparison.baseline[names[0]]["gyro"].truth
    parts = {n: _noise_parts(ps, site, config) for n, ps in sets.items()}
    sigma_nf = {n: parts[n][1] for n in names}
    rows, z_all = {}, []
    for n in names:
        printed, used = paper.read(n, corrected=False), paper.read(n)
        nf, base = comparison.noise_free[n]["gyro"], comparison.baseline[n]["gyro"]
        z = (used - truth) / (sigma_nf[n] / math.sqrt(runs))
        z_all.append(z)
        rows[n] = []
        for j, p in enumerate(PARAMETER_NAMES):
            label, f = paper.unit(j)
            rows[n].append(
                {
                    "parameter": p,
                    "unit": label,
                    "true": truth[j] / f,
                    "printed_mean": printed[j] / f,
                    "mean": used[j] / f,
                    "deviation": (used[j] - truth[j]) / f,
                    "noise_free_mean": (truth[j] + nf.mean_deviation[j]) / f,
                    "noise_free_std": nf.std[j] / f,
                    "baseline_mean": (truth[j] + base.mean_deviation[j]) / f,
                    "baseline_std": base.std[j] / f,
                    "z_noise_free": z[j],
                    "z_printed": (printed[j] - truth[j]) / (sigma_nf[n][j] / math.sqrt(runs)),
                }
            )
    z_all = np.concatenate(z_all)
    c_all = np.concatenate([parts[n][0] for n in names])
    p_all = np.concatenate([sigma_nf[n] for n in names])

    # Claim: first set better on `better_count` of 12 (smaller |mean deviation|).
    dev = {n: {c: np.abs(paper.read(n, corrected=c) - truth) for c in (True, False)} for n in names}
    a, b = names
    better: dict[str, Any] = {
        "claimed": paper.better_count,
        "in_table": int(np.sum(dev[a][True] < dev[b][True])),
        "in_table_as_printed": int(np.sum(dev[a][False] < dev[b][False])),
    }
    pred_base = {n: predicted_sigma(sets[n], site, imu, config) for n in names}
    for label, sig in (("noise_free", sigma_nf), ("baseline", pred_base)):
        pmf = count_distribution(better_probability(sig[a], sig[b]))
        better[label] = {
            "expected": float(np.arange(13) @ pmf),
            "p_at_least_claimed": float(pmf[paper.better_count :].sum()),
            "most_likely": int(np.argmax(pmf)),
            "sigma_better": int(np.sum(sig[a] < sig[b])),
        }

    # Claim: deviations at the `deviation_level` level (order of magnitude: below 10x).
    threshold = 10.0 * paper.deviation_level
    level: dict[str, Any] = {"claimed": paper.deviation_level, "threshold": threshold}
    for n in names:
        sl = SF_AND_MIS
        c, p = parts[n][0][sl], parts[n][1][sl]
        w = max_arw_for_level(c, p, threshold, runs)
        exp_base = expected_abs_mean(pred_base[n][sl], runs)
        level[n] = {
            "table_rms": float(np.sqrt(np.mean((paper.read(n) - truth)[sl] ** 2))),
            "noise_free_rms": float(np.sqrt(np.mean(expected_abs_mean(p, runs) ** 2))),
            "baseline_rms": float(np.sqrt(np.mean(exp_base**2))),
            "max_arw_deg_per_sqrt_h": None if w is None else w / DEG_PER_SQRT_HOUR,
        }
    arw = implied_arw(z_all, c_all, p_all)
    implied = {
        "rms_z": float(np.sqrt(np.mean(z_all**2))),
        "n": int(len(z_all)),
        "arw_deg_per_sqrt_h": None if arw is None else arw / DEG_PER_SQRT_HOUR,
        "dwell_s": float(sets[a].positions[0].dwell),
    }

    # Claim: about `time_saving` faster.
    t_a, t_b = sets[a], sets[b]
    timing = {
        "claimed": paper.time_saving,
        "dwell_limit": 1.0 - len(t_a) / len(t_b),
        "by_dwell": [
            {
                "dwell_s": d,
                "saving": 1.0
                - (len(t_a) * d + t_a.indexing_time) / (len(t_b) * d + t_b.indexing_time),
            }
            for d in dwells
        ],
    }
    return {
        "runs": runs,
        "rows": rows,
        "better": better,
        "level": level,
        "implied": implied,
        "time": timing,
        "six_position_sets": six_position_sets(sets, site, imu, config),
    }


def six_position_sets(
    sets: dict[str, PositionSet], site: Site, imu: ImuErrors, config: MonteCarloConfig
) -> dict[str, Any]:
    """Which axes the reference six-position set points where, beside other six-position sets.

    Compares the two sets of ``sets`` with the best six-position set whose stops point
    every IMU axis up once and down once, and with the best six-position set of any
    kind (:func:`~inserr.calibration.position_sets.design_sets`, 90 deg steps, gyro
    criterion), all at the same dwell: D-efficiency relative to the reference set and
    the class RMS of the predicted gyro sigma with and without sensor noise.

    Returns
    -------
    dict
        ``positions`` (per set: :func:`positions_pointing`) and ``rows`` (per set:
        ``name``, ``total_time_s``, ``d_efficiency``, ``predicted``, ``noise_free``).
    """
    four, six = sets
    dwell, rate = sets[six].positions[0].dwell, sets[six].table.rate
    every = design_sets(site, dwell, (6,), "gyro", rate=rate, top=1, up_axes=EVERY_AXIS_UP_AND_DOWN)
    best = design_sets(site, dwell, (6,), "gyro", rate=rate, top=1)
    named = dict(sets)
    named[EVERY_NAME] = every[0].position_set()
    named[BEST_NAME] = best[0].position_set()
    quiet = imu.replace(arw=0.0)
    ref = set_criterion(sets[six], site)
    return {
        "positions": {n: positions_pointing(ps, site) for n, ps in named.items()},
        "rows": [
            {
                "name": n,
                "total_time_s": ps.total_time,
                "d_efficiency": set_criterion(ps, site) / ref,
                "predicted": class_rms(predicted_sigma(ps, site, imu, config)),
                "noise_free": class_rms(predicted_sigma(ps, site, quiet, config)),
            }
            for n, ps in named.items()
        ],
    }
