"""Published north-finder repeatability beside the model, and the sensor grade it implies.

P3 (Li Haijun et al. 2016) reports prototype tests: heading repeatability better than
0.5 mil (1 sigma) after about 3 minutes, and a latitude error of 0.0538 deg (1 sigma),
with no initial latitude and no precise levelling. :func:`against_published` sets such
numbers beside the filter's Monte Carlo and the Cramér-Rao bound of an
:class:`~inserr.northfinder.accuracy.AccuracyStudy`'s base case, and inverts the bound
(with the bias instability) for the gyro grade each number implies.

Physics used: on a table whose normal is near the vertical, heading comes from the
horizontal Earth rate ``Omega cos L`` and latitude from the magnitude of the same
horizontal component, so both bounds are set by the same amplitude noise and
``sigma_L / sigma_psi ~ cot L`` (:func:`consistent_latitude` solves the exact bound
ratio). Every gyro error scaled by ``f`` scales both bounds by ``f`` (up to the small
accelerometer share), so a published sigma implies the grade ``f`` times the
default's (:func:`~inserr.northfinder.accuracy.required_factor`).

Which mil P3 means is not stated: inserr's mil is the NATO mil (2 pi / 6400 rad); the
circle of 6000 mils used in Chinese and Russian practice and the milliradian are read
too, and every answer is given under each.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from inserr.core.units import DEG, DEG_PER_HOUR, DEG_PER_SQRT_HOUR, MIL
from inserr.northfinder.accuracy import AccuracyStudy, required_factor, scaled_gyro
from inserr.northfinder.bounds import crlb
from inserr.northfinder.instrument import Pose
from inserr.northfinder.study import monte_carlo

#: One mil in rad under each reading of the word.
MIL_READINGS = {
    "NATO mil (2π/6400)": MIL,
    "6000-mil circle (2π/6000)": 2.0 * math.pi / 6000.0,
    "milliradian": 1e-3,
}


#: Rough gyro classes by angle random walk, deg/sqrt(h) (upper limits; the usual ranges of
#: navigation-grade and tactical-grade gyros, e.g. P. D. Groves, *Principles of GNSS,
#: Inertial, and Multisensor Integrated Navigation Systems*, 2nd ed., 2013, ch. 4).
GYRO_CLASSES = (("navigation-grade", 0.003), ("tactical-grade", 0.1))


def gyro_class(arw_deg_sqrt_h: float) -> str:
    """Rough class of a gyro by its ARW in deg/sqrt(h) (:data:`GYRO_CLASSES`)."""
    for name, limit in GYRO_CLASSES:
        if arw_deg_sqrt_h <= limit:
            return name
    return "below tactical-grade"


@dataclass(frozen=True)
class PublishedRepeatability:
    """Published 1-sigma repeatability of a north finder.

    Parameters
    ----------
    heading : float
        Heading 1 sigma, rad (a value in mils read as NATO mils; see
        :data:`MIL_READINGS` for the other readings).
    time : float
        After this time, s.
    latitude : float
        Latitude 1 sigma, rad.
    """

    heading: float
    time: float
    latitude: float


def _ratio(pose: Pose, sc: AccuracyStudy, duration: float) -> float:
    b = crlb(pose, sc.instrument, sc.grade, duration, bias_instability=True)
    return float(b.lat[-1] / b.heading[-1])


def consistent_latitude(
    sc: AccuracyStudy, duration: float, ratio: float, limits: tuple[float, float] = (1.0, 89.0)
) -> float | None:
    """Latitude (rad) at which the bounds' latitude/heading ratio equals ``ratio``.

    Bisection on the bound ratio (with bias instability) at the base case's heading,
    tilt and grade; the ratio falls monotonically from the equator to the pole
    (about cot L).

    Parameters
    ----------
    sc : AccuracyStudy
    duration : float
        s.
    ratio : float
        sigma_latitude / sigma_heading (rad / rad).
    limits : (float, float)
        Latitude search range, deg.

    Returns
    -------
    float or None
        rad (in the base case's hemisphere); None if ``ratio`` is outside the range.
    """
    sign = 1.0 if sc.pose.lat >= 0 else -1.0
    lo, hi = (math.radians(v) for v in limits)

    def f(lat: float) -> float:
        return _ratio(replace(sc.pose, lat=sign * lat), sc, duration) - ratio

    f_lo = f(lo)
    if f_lo * f(hi) > 0:
        return None
    for _ in range(40):  # 2^-40 of 88 deg, 1e-12 rad: far below any printed digit
        mid = 0.5 * (lo + hi)
        f_mid = f(mid)
        if f_lo * f_mid > 0:
            lo, f_lo = mid, f_mid
        else:
            hi = mid
    return sign * 0.5 * (lo + hi)


def _grade(sc: AccuracyStudy, factor: float) -> dict:
    g = scaled_gyro(sc.grade, factor)
    return {
        "factor": factor,
        "arw_deg_sqrt_h": g.gyro_arw / DEG_PER_SQRT_HOUR,
        "bias_instability_deg_h": g.gyro_bias_instability / DEG_PER_HOUR,
    }


def against_published(sc: AccuracyStudy, results: dict, paper: PublishedRepeatability) -> dict:
    """The published numbers beside the base case, and the grades they imply.

    Parameters
    ----------
    sc : AccuracyStudy
        The study (base case, default grade, runs and seed: the Monte Carlo at the
        latitude figure's grade uses ``runs`` runs and seed ``seed + 3``).
    results : dict
        :func:`~inserr.northfinder.accuracy.accuracy_study`'s results (its time history
        must reach ``paper.time``; its grade sweep's answer is quoted, and then needed,
        only when the study's requirement is the paper's heading number at its time).
    paper : PublishedRepeatability

    Returns
    -------
    dict
        ``paper`` (mil, deg, s), ``model`` (Monte Carlo and bounds at the paper's time,
        mil and deg; convergence time), ``heading_grade`` per mil reading (bound
        answer; the Monte Carlo answer for the NATO reading when the study solved it),
        ``latitude_grade`` (bound answer and a Monte Carlo at that grade) and
        ``consistent_latitude_deg`` per mil reading (where both numbers imply one grade,
        with that grade).
    """
    pose, ins, grade, t = sc.pose, sc.instrument, sc.grade, paper.time
    th = results["time_history"]
    k = int(np.argmin(np.abs(np.asarray(th["time_s"]) - t)))
    bi = crlb(pose, ins, grade, t, bias_instability=True)
    model = {
        "time_s": float(th["time_s"][k]),
        "heading_sigma_mil": float(th["heading_sigma_mil"][k]),
        "crlb_heading_mil": float(th["crlb_heading_mil"][k]),
        "crlb_bi_heading_mil": float(bi.heading[-1] / MIL),
        "latitude_sigma_deg": float(th["latitude_sigma_deg"][k]),
        "crlb_latitude_deg": float(th["crlb_latitude_deg"][k]),
        "crlb_bi_latitude_deg": float(bi.lat[-1] / DEG),
        "convergence_time_s": th["summary"]["convergence_time_s"],
        "pitch_sigma_deg": th["summary"]["pitch_error_1sigma_deg"],
        "roll_sigma_deg": th["summary"]["roll_error_1sigma_deg"],
    }
    mils = paper.heading / MIL
    heading, consistent = {}, {}
    for name, mil in MIL_READINGS.items():
        target = mils * mil
        heading[name] = {
            "heading_deg": target / DEG,
            "crlb": _grade(sc, required_factor(pose, ins, grade, t, target)),
        }
        lat = consistent_latitude(sc, t, paper.latitude / target)
        consistent[name] = None
        if lat is not None:
            f = required_factor(replace(pose, lat=lat), ins, grade, t, target)
            consistent[name] = {"latitude_deg": lat / DEG, **_grade(sc, f)}
    if math.isclose(sc.requirement, paper.heading, rel_tol=1e-12) and sc.time == t:
        need = results["grade_sweep"]["required"]["monte_carlo"]
        heading[next(iter(MIL_READINGS))]["monte_carlo"] = {
            **_grade(sc, need["factor"]),
            "mc_sigma_mil": need["mc_sigma_mil"],
            "runs": results["grade_sweep"]["required"]["runs"],
        }
    f_lat = required_factor(pose, ins, grade, t, paper.latitude, quantity="lat")
    check = monte_carlo(
        pose,
        ins,
        scaled_gyro(grade, f_lat),
        t,
        n_runs=sc.runs,
        seed=sc.seed + 3,
        hemisphere=sc.hemisphere,
        desc="latitude grade",
    )
    latitude = {
        "crlb": _grade(sc, f_lat),
        "runs": sc.runs,
        "seed": sc.seed + 3,
        "mc_latitude_sigma_deg": float(check.lat_sigma()[-1] / DEG),
        "mc_heading_sigma_mil": float(check.heading_sigma()[-1] / MIL),
        "crlb_heading_mil": float(check.bound_bi.heading[-1] / MIL),
    }
    return {
        "paper": {
            "heading_mil": mils,
            "time_s": t,
            "latitude_deg": paper.latitude / DEG,
            "latitude_over_heading": paper.latitude / paper.heading,
        },
        "model": model,
        "heading_grade": heading,
        "latitude_grade": latitude,
        "consistent_latitude": consistent,
        "base_latitude_deg": pose.lat / DEG,
        "base_ratio": _ratio(pose, sc, t),
    }
