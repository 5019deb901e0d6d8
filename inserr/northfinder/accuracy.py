"""North-finder accuracy study: heading σ vs time, table rate, gyro grade, heading × latitude.

The study behind ``analyses/p3_northfinder`` for any :class:`AccuracyStudy` (a base
case and the grids to sweep): Monte Carlo of the filter beside the Cramér-Rao bound
(:mod:`inserr.northfinder.study`, :mod:`inserr.northfinder.bounds`) over time, table
rate and gyro grade; the gyro grade that meets a heading requirement, solved on the
bound and on the Monte Carlo; the bound's inflation by the bias instability; a map
over heading and latitude; and P3's small-angle mounting model against the exact
inversion. :func:`accuracy_study` runs them all; the write-up is
:func:`inserr.northfinder.accuracy_report.build_report`.

Units: SI inside (rad, rad/s, s); the returned dicts are in engineering units (mil,
deg, deg/s, deg/h, deg/sqrt(h)) as their keys say. Headings are clockwise from north.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from inserr.core.units import DEG, DEG_PER_HOUR, DEG_PER_S, DEG_PER_SQRT_HOUR, MIL
from inserr.northfinder.bounds import bias_instability_psd, crlb
from inserr.northfinder.filter import (
    hemisphere_name,
    period_measurements,
    run_filter,
    solve,
    wrap_angle,
)
from inserr.northfinder.instrument import Instrument, Pose, SensorGrade, simulate
from inserr.northfinder.study import MonteCarloResult, monte_carlo
from inserr.output.progress import progress

#: The quantities :func:`required_factor` can hold to a target: a :class:`Bound` field.
BOUND_QUANTITIES = ("heading", "lat")


@dataclass(frozen=True)
class AccuracyStudy:
    """Base case and grids of the accuracy study (SI).

    Attributes
    ----------
    pose : Pose
        The base case's truth.
    instrument : Instrument
    grade : SensorGrade
        The default grade; sweeps scale its gyro errors.
    hemisphere : int
        Declared to the estimator at the base case, +1 north or -1 south (map cells
        and latitude rows declare their own latitude's).
    runs : int
        Runs of every Monte Carlo but the map's and the required-grade check's.
    check_runs : int
        Runs of the Monte Carlo that solves and verifies the required grade.
    seed : int
        Master seed (checks use seed + 1 and + 2, map cells seed + 1000 + k).
    requirement : float
        Heading 1 sigma to meet, rad.
    time : float
        In this time, s (the time of every sweep).
    history_duration : float
        Length of the time history, s.
    rates : tuple of float
        Table rates, rad/s.
    stress_bi, stress_tau : float
        Harsher gyro bias instability (rad/s) and its correlation time (s).
    factors : tuple of float
        Gyro-error scale factors of the grade sweep.
    grade_latitudes : tuple of float
        Latitudes (rad) at which the required grade is solved.
    bi_taus : tuple of float
        Gauss-Markov correlation times, s.
    map_heading_step, map_lat_step, map_lat_limit : float
        Bound map grid, rad.
    mc_headings, mc_latitudes : tuple of float
        Monte Carlo map cells, rad.
    mc_map_runs : int
        Runs per map cell.
    gyro_tilts, accel_azimuths, accel_tilts : tuple of float
        Mounting angles of the small-angle table, rad.
    """

    pose: Pose
    instrument: Instrument
    grade: SensorGrade
    hemisphere: int
    runs: int
    check_runs: int
    seed: int
    requirement: float
    time: float
    history_duration: float
    rates: tuple[float, ...]
    stress_bi: float
    stress_tau: float
    factors: tuple[float, ...]
    grade_latitudes: tuple[float, ...]
    bi_taus: tuple[float, ...]
    map_heading_step: float
    map_lat_step: float
    map_lat_limit: float
    mc_headings: tuple[float, ...]
    mc_latitudes: tuple[float, ...]
    mc_map_runs: int
    gyro_tilts: tuple[float, ...]
    accel_azimuths: tuple[float, ...]
    accel_tilts: tuple[float, ...]


def accuracy_study(sc: AccuracyStudy) -> tuple[dict, MonteCarloResult]:
    """Run every part of the study.

    Returns
    -------
    results : dict
        ``time_history``, ``rate_sweep``, ``grade_sweep``, ``bias_instability``,
        ``map``, ``small_angle`` (the functions below).
    history : MonteCarloResult
        The time history's Monte Carlo, for its figures.
    """
    results: dict = {}
    results["time_history"], history = time_history(sc)
    results["rate_sweep"] = rate_sweep(sc)
    results["grade_sweep"] = grade_sweep(sc)
    results["bias_instability"] = bias_instability_table(sc)
    results["map"] = heading_latitude_map(sc)
    results["small_angle"] = small_angle_table(sc)
    return results, history


def scaled_gyro(grade: SensorGrade, factor: float) -> SensorGrade:
    """A grade with every gyro error (ARW, bias, bias instability) times ``factor``.

    Parameters
    ----------
    grade : SensorGrade
        Reference grade (SI).
    factor : float
        Dimensionless scale factor, > 0.

    Returns
    -------
    SensorGrade
    """
    return grade.replace(
        gyro_arw=grade.gyro_arw * factor,
        gyro_bias=grade.gyro_bias * factor,
        gyro_bias_instability=grade.gyro_bias_instability * factor,
    )


def time_history(sc: AccuracyStudy) -> tuple[dict, MonteCarloResult]:
    """Heading and latitude error vs time at the base case.

    Parameters
    ----------
    sc : AccuracyStudy
        The study's settings.

    Returns
    -------
    results : dict
        Summary, figures at the requirement time and histories (s, mil, deg).
    result : MonteCarloResult
        For the figures.
    """
    res = monte_carlo(
        sc.pose,
        sc.instrument,
        sc.grade,
        sc.history_duration,
        n_runs=sc.runs,
        seed=sc.seed,
        hemisphere=sc.hemisphere,
        desc="time history",
    )
    k3 = int(np.argmin(np.abs(res.times - sc.time)))
    out = {
        "summary": res.summary(),
        "at_requirement_time": {
            "time_s": float(res.times[k3]),
            "heading_sigma_mil": float(res.heading_sigma()[k3] / MIL),
            "heading_bias_mil": float(res.heading_bias()[k3] / MIL),
            "crlb_heading_mil": float(res.bound.heading[k3] / MIL),
            "latitude_sigma_deg": float(res.lat_sigma()[k3] / DEG),
            "crlb_latitude_deg": float(res.bound.lat[k3] / DEG),
        },
        "time_s": res.times,
        "heading_sigma_mil": res.heading_sigma() / MIL,
        "heading_bias_mil": res.heading_bias() / MIL,
        "crlb_heading_mil": res.bound.heading / MIL,
        "latitude_sigma_deg": res.lat_sigma() / DEG,
        "crlb_latitude_deg": res.bound.lat / DEG,
    }
    return out, res


def rate_sweep(sc: AccuracyStudy) -> dict:
    """Monte Carlo heading sigma and bounds vs table rate, default and stress grades.

    Parameters
    ----------
    sc : AccuracyStudy
        The study's settings.

    Returns
    -------
    dict
        ``rows``: rate (deg/s), Monte Carlo sigma, CRLB and CRLB with bias
        instability (mil) for each grade.
    """
    stress = sc.grade.replace(
        gyro_bias_instability=sc.stress_bi, gyro_correlation_time=sc.stress_tau
    )
    rows = []
    for rate in progress(sc.rates, total=len(sc.rates), desc="rate sweep"):
        ins = replace(sc.instrument, table_rate=rate)
        row = {"rate_deg_s": rate / DEG_PER_S}
        for label, grade in (("default", sc.grade), ("stress", stress)):
            res = monte_carlo(
                sc.pose,
                ins,
                grade,
                sc.time,
                n_runs=sc.runs,
                seed=sc.seed,
                hemisphere=sc.hemisphere,
                desc=label,
            )
            row[f"{label}_mc_sigma_mil"] = float(res.heading_sigma()[-1] / MIL)
            row[f"{label}_crlb_mil"] = float(res.bound.heading[-1] / MIL)
            row[f"{label}_crlb_bi_mil"] = float(res.bound_bi.heading[-1] / MIL)
        rows.append(row)
    return {"rows": rows}


def _bound_at(pose, ins, grade, duration, quantity: str = "heading") -> float:
    """Bound of ``quantity`` with bias instability at the end of ``duration``, rad."""
    return float(getattr(crlb(pose, ins, grade, duration, bias_instability=True), quantity)[-1])


def required_factor(pose, ins, grade, duration, target, quantity: str = "heading") -> float:
    """Largest gyro-error scale factor whose bound (with bias instability) meets ``target``.

    The bound is monotonic in the factor (it scales every gyro noise), so bisection on
    log(factor) converges; 40 halvings give 1e-12 relative.

    Parameters
    ----------
    pose, ins, grade
        Base case (SI).
    duration : float
        s.
    target : float
        1 sigma to meet, rad.
    quantity : str
        ``"heading"`` or ``"lat"`` (latitude, unknown to the estimator).

    Returns
    -------
    float
        Scale factor on every gyro error (dimensionless).
    """
    if quantity not in BOUND_QUANTITIES:
        raise ValueError(f"quantity must be one of {BOUND_QUANTITIES}, got {quantity!r}")
    lo, hi = 1e-3, 1e3
    for _ in range(40):
        mid = math.sqrt(lo * hi)
        bound = _bound_at(pose, ins, scaled_gyro(grade, mid), duration, quantity)
        lo, hi = (mid, hi) if bound <= target else (lo, mid)
    return lo


def required_factor_mc(
    pose: Pose,
    ins: Instrument,
    grade: SensorGrade,
    duration: float,
    target: float,
    *,
    start: float,
    n_runs: int,
    seed: int,
    hemisphere: int,
    tolerance: float = 1e-3,
    max_iterations: int = 5,
) -> dict:
    """Gyro-error scale factor at which the filter's Monte Carlo sigma meets ``target``.

    With the seed fixed, every gyro noise sample scales with the factor and the
    filter's gain does not depend on it (R and Q scale together, the prior is
    diffuse), so the Monte Carlo heading sigma is proportional to the factor up to
    the small accelerometer share and the second-order terms of the heading solution.
    The fixed-point step ``f <- f * target / sigma(f)`` therefore lands in one step
    and the next evaluation confirms it.

    Parameters
    ----------
    pose, ins, grade
        Base case (SI).
    duration : float
        s.
    target : float
        Heading 1 sigma to meet, rad.
    start : float
        First factor to try (the bound's answer).
    n_runs, seed, hemisphere
        Monte Carlo runs, seed and the declared hemisphere (+1 or -1).
    tolerance : float
        Relative tolerance on sigma / target.
    max_iterations : int
        Monte Carlo evaluations at most.

    Returns
    -------
    dict
        ``factor``; ``mc_sigma_mil`` and ``crlb_mil`` at it; ``iterations``: the
        (factor, sigma in mil) pairs evaluated.
    """
    f, steps = start, []
    for _ in range(max_iterations):
        res = monte_carlo(
            pose,
            ins,
            scaled_gyro(grade, f),
            duration,
            n_runs=n_runs,
            seed=seed,
            hemisphere=hemisphere,
            desc=f"x{f:.4g}",
        )
        sigma = float(res.heading_sigma()[-1])
        steps.append({"factor": f, "mc_sigma_mil": sigma / MIL})
        if abs(sigma / target - 1.0) <= tolerance:
            break
        f *= target / sigma
    return {
        "factor": f,
        "mc_sigma_mil": sigma / MIL,
        "crlb_mil": float(res.bound.heading[-1] / MIL),
        "iterations": steps,
    }


def grade_sweep(sc: AccuracyStudy) -> dict:
    """Heading sigma vs gyro grade, and the grade that meets the requirement.

    The required grade is solved on the filter's Monte Carlo
    (:func:`required_factor_mc`, ``check_runs`` runs, starting from the bound's
    answer of :func:`required_factor`) and verified with independent seeds; the
    bound's answer is kept beside it.

    Parameters
    ----------
    sc : AccuracyStudy
        The study's settings.

    Returns
    -------
    dict
        ``rows`` (ARW deg/sqrt(h), bias instability deg/h, sigma/bias/bound in mil),
        ``required`` (``crlb``, ``monte_carlo`` and ``verification`` answers) and
        ``required_by_latitude``.
    """
    pose, ins, grade, t = sc.pose, sc.instrument, sc.grade, sc.time
    hemi, target, n_check = sc.hemisphere, sc.requirement, sc.check_runs
    rows = []
    for f in progress(sc.factors, total=len(sc.factors), desc="grade sweep"):
        g = scaled_gyro(grade, f)
        res = monte_carlo(
            pose, ins, g, t, n_runs=sc.runs, seed=sc.seed, hemisphere=hemi, desc=f"x{f:g}"
        )
        rows.append(
            {
                "factor": f,
                "arw_deg_sqrt_h": g.gyro_arw / DEG_PER_SQRT_HOUR,
                "bias_instability_deg_h": g.gyro_bias_instability / DEG_PER_HOUR,
                "mc_sigma_mil": float(res.heading_sigma()[-1] / MIL),
                "mc_bias_mil": float(res.heading_bias()[-1] / MIL),
                "crlb_mil": float(res.bound.heading[-1] / MIL),
            }
        )

    def _grade_of(f: float) -> dict:
        g = scaled_gyro(grade, f)
        return {
            "factor": f,
            "arw_deg_sqrt_h": g.gyro_arw / DEG_PER_SQRT_HOUR,
            "bias_deg_h": g.gyro_bias / DEG_PER_HOUR,
            "bias_instability_deg_h": g.gyro_bias_instability / DEG_PER_HOUR,
        }

    f_bound = required_factor(pose, ins, grade, t, target)
    solved = required_factor_mc(
        pose,
        ins,
        grade,
        t,
        target,
        start=f_bound,
        n_runs=n_check,
        seed=sc.seed + 1,
        hemisphere=hemi,
    )
    at_bound = solved["iterations"][0]
    check = monte_carlo(
        pose,
        ins,
        scaled_gyro(grade, solved["factor"]),
        t,
        n_runs=n_check,
        seed=sc.seed + 2,
        hemisphere=hemi,
        desc="verification",
    )
    by_lat = []
    for lat in progress(sc.grade_latitudes, total=len(sc.grade_latitudes), desc="latitudes"):
        p = replace(pose, lat=lat)
        f_b = required_factor(p, ins, grade, t, target)
        mc = required_factor_mc(
            p,
            ins,
            grade,
            t,
            target,
            start=f_b,
            n_runs=n_check,
            seed=sc.seed + 1,
            hemisphere=1 if lat > 0 else -1,  # declared as a user there would
        )
        by_lat.append(
            {
                "latitude_deg": lat / DEG,
                "crlb_factor": f_b,
                "crlb_arw_deg_sqrt_h": grade.gyro_arw * f_b / DEG_PER_SQRT_HOUR,
                "factor": mc["factor"],
                "arw_deg_sqrt_h": grade.gyro_arw * mc["factor"] / DEG_PER_SQRT_HOUR,
                "bias_instability_deg_h": grade.gyro_bias_instability * mc["factor"] / DEG_PER_HOUR,
                "mc_sigma_at_crlb_grade_mil": mc["iterations"][0]["mc_sigma_mil"],
                "mc_sigma_mil": mc["mc_sigma_mil"],
                "crlb_mil": mc["crlb_mil"],
            }
        )
    return {
        "rows": rows,
        "required": {
            "runs": n_check,
            "sampling_spread": 1.0 / math.sqrt(2.0 * (n_check - 1)),
            "crlb": {
                **_grade_of(f_bound),
                "crlb_mil": target / MIL,
                "mc_sigma_mil": at_bound["mc_sigma_mil"],
            },
            "monte_carlo": {
                **_grade_of(solved["factor"]),
                "mc_sigma_mil": solved["mc_sigma_mil"],
                "crlb_mil": solved["crlb_mil"],
                "seed": sc.seed + 1,
                "iterations": solved["iterations"],
            },
            "verification": {
                "seed": sc.seed + 2,
                "mc_sigma_mil": float(check.heading_sigma()[-1] / MIL),
                "mc_bias_mil": float(check.heading_bias()[-1] / MIL),
                "crlb_mil": float(check.bound.heading[-1] / MIL),
            },
        },
        "required_by_latitude": by_lat,
    }


def bias_instability_table(sc: AccuracyStudy) -> dict:
    """Inflation of the heading bound by the gyro bias instability vs correlation time.

    Parameters
    ----------
    sc : AccuracyStudy
        The study's settings.

    Returns
    -------
    dict
        ``rows``: tau (s), Gauss-Markov PSD / ARW^2 at the table frequency and the
        sigma inflation (dimensionless); ``worst_case_inflation`` over tau.
    """
    g, w = sc.grade, sc.instrument.table_rate
    rows = []
    for tau in sc.bi_taus:
        s = bias_instability_psd(g.gyro_bias_instability, tau, w)
        rows.append(
            {
                "tau_s": tau,
                "psd_ratio": s / g.gyro_arw**2,
                "sigma_inflation": math.sqrt(1.0 + s / g.gyro_arw**2),
            }
        )
    worst = math.sqrt(1.0 + g.gyro_bias_instability**2 / abs(w) / g.gyro_arw**2)
    return {"rows": rows, "worst_case_inflation": worst}


def heading_latitude_map(sc: AccuracyStudy) -> dict:
    """Bounds over heading x latitude and Monte Carlo cells beside them.

    Each Monte Carlo cell declares the hemisphere of its own latitude, as a user
    standing there would.

    Parameters
    ----------
    sc : AccuracyStudy
        The study's settings.

    Returns
    -------
    dict
        Grids (deg), heading bounds (mil) with latitude unknown and known, latitude
        bound (deg), and ``mc_cells`` (sigma, bias and bound in mil, ratio, ambiguous
        fraction, and the warnings of :func:`inserr.northfinder.study.diagnose`).
    """
    pose, ins, grade, t = sc.pose, sc.instrument, sc.grade, sc.time
    headings = np.arange(0.0, 2 * math.pi - 1e-9, sc.map_heading_step)
    lim, step = sc.map_lat_limit, sc.map_lat_step
    # Whole degrees: arange's round-off would otherwise print as 1e-13 deg.
    lats = np.radians(np.round(np.degrees(np.arange(-lim, lim + 1e-9, step)), 9))
    bound_h = np.empty((len(lats), len(headings)))
    bound_l = np.empty_like(bound_h)
    bound_known = np.empty_like(bound_h)
    for i, lat in enumerate(progress(lats, total=len(lats), desc="bound map")):
        for j, h in enumerate(headings):
            here = replace(pose, lat=lat, heading=h)
            b = crlb(here, ins, grade, t)
            bound_h[i, j], bound_l[i, j] = b.heading[-1], b.lat[-1]
            bound_known[i, j] = crlb(here, ins, grade, t, latitude_known=True).heading[-1]
    cells = []
    grid = [(lat, h) for lat in sc.mc_latitudes for h in sc.mc_headings]
    for k, (lat, h) in enumerate(progress(grid, total=len(grid), desc="Monte Carlo map")):
        # Independent seeds per cell, so the spread over cells shows the sampling error.
        res = monte_carlo(
            replace(pose, lat=lat, heading=h),
            ins,
            grade,
            t,
            n_runs=sc.mc_map_runs,
            seed=sc.seed + 1000 + k,
            hemisphere=1 if lat > 0 else -1,  # declared as a user there would
            desc="cell",
        )
        sigma, bias = res.heading_sigma()[-1], res.heading_bias()[-1]
        cells.append(
            {
                "latitude_deg": lat / DEG,
                "heading_deg": h / DEG,
                "mc_sigma_mil": float(sigma / MIL),
                "mc_bias_mil": float(bias / MIL),
                "crlb_mil": float(res.bound.heading[-1] / MIL),
                "ratio": float(sigma / res.bound.heading[-1]),
                "bias_in_sigma": float(abs(bias) / sigma),
                "ambiguous_fraction": float(res.ambiguous[-1].mean()),
                "hemisphere_declared": hemisphere_name(res.hemisphere),
                "warnings": list(res.warnings),
            }
        )
    return {
        "headings_deg": headings / DEG,
        "latitudes_deg": lats / DEG,
        "crlb_heading_mil": bound_h / MIL,
        "crlb_latitude_deg": bound_l / DEG,
        "crlb_heading_latitude_known_mil": bound_known / MIL,
        "mc_cells": cells,
        "mc_runs": sc.mc_map_runs,
    }


def small_angle_table(sc: AccuracyStudy) -> dict:
    """Noise-free errors of P3's small-angle mounting model and of the exact inversion.

    Parameters
    ----------
    sc : AccuracyStudy
        The study's settings.

    Returns
    -------
    dict
        ``rows``: mounting angle (deg) and the heading (mil), latitude (deg), pitch
        and roll (microrad) errors of both models.
    """
    pose, grade = sc.pose, sc.grade
    base = replace(sc.instrument, sample_rate=10.0)  # noise-free: increments are exact
    cases = [("gyro_tilt", v) for v in sc.gyro_tilts]
    cases += [("accel_azimuth", v) for v in sc.accel_azimuths]
    cases += [("accel_tilt", v) for v in sc.accel_tilts]
    rows = []
    for name, value in cases:
        ins = replace(base, **{name: value})
        data = simulate(pose, ins, grade.without_noise(), sc.time)
        x = run_filter(period_measurements(data, ins), ins, grade).x[-1, :, 0]
        row = {"mounting": name, "angle_deg": value / DEG}
        for model in ("p3", "exact"):
            s = solve(x, ins, hemisphere=sc.hemisphere, model=model)
            row[f"{model}_heading_mil"] = float(wrap_angle(s.heading - pose.heading) / MIL)
            row[f"{model}_latitude_deg"] = float((s.lat - pose.lat) / DEG)
            row[f"{model}_pitch_urad"] = float((s.pitch - pose.pitch) * 1e6)
            row[f"{model}_roll_urad"] = float((s.roll - pose.roll) * 1e6)
        rows.append(row)
    return {"rows": rows}
