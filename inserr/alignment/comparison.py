"""Alignment scheme comparison: static vs indexed fine alignment, and what indexing costs.

The study behind ``analyses/alignment_observability`` for any :class:`SchemeComparison`
(a base, an IMU budget, a prior and the schemes): the alignment filter
(:mod:`inserr.alignment.filter`) per scheme on a static base and on a swinging base
(final 1 sigma, convergence time, degree of observability, least reduced directions,
one simulated run, and the same run without the errors the filter does not model);
the piecewise-constant observability analysis (:mod:`inserr.alignment.observability`)
of each scheme's timeline, with and without position updates, and the classic
10-state picture; what indexing costs in time; and a sweep of one scheme's stop time.
:func:`compare_schemes` runs it all; the write-up is
:func:`inserr.alignment.comparison_report.build_report`.

Units: SI inside; the returned dicts are in engineering units as their keys say
(arcsec, arcmin, deg, deg/h, µg, ppm, s).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from inserr.alignment.filter import (
    STATES,
    UNITS,
    AlignmentResult,
    Prior,
    Settings,
    report_transform,
    static_floors,
)
from inserr.alignment.observability import alignment10, analyze, full_timeline
from inserr.alignment.study import (
    SHOWN,
    Base,
    alignment_timeline,
    run_schemes,
    time_to_reach,
    weakest_directions,
)
from inserr.core.earth import Site
from inserr.core.imu import ImuErrors
from inserr.core.units import (
    ARCMIN,
    ARCSEC,
    DEG_PER_HOUR,
    DEG_PER_SQRT_HOUR,
    MICRO_G,
    MICRO_G_PER_SQRT_HZ,
    PPM,
)
from inserr.model.psi_model import ErrorModel, Layout
from inserr.schemes.vehicle_motion import Motion, YawSwing

#: Degree of observability sqrt(P0)/sqrt(Pk) above which a state counts as well
#: estimated (sigma down by 10x), and below which as not estimated (down by < 20 %).
WELL, NOT = 10.0, 1.25


@dataclass(frozen=True)
class SchemeComparison:
    """Settings of the scheme comparison (SI).

    Attributes
    ----------
    site : Site
    motion : Motion
        The static base (heading, pitch, roll); the swinging base adds a yaw swing to it.
    schemes : tuple of str
        Scheme names (:func:`inserr.schemes.catalogue.build_scheme`); ``"none"`` is the
        static reference of the costs.
    rate : float
        Table rate, rad/s.
    stop : float
        Stop time, s.
    substep : float
        Sub-step of continuous base motion, s.
    duration : float
        Alignment time, s.
    imu : ImuErrors
        True errors of the simulated runs (biases also the prior 1 sigma of the filter).
    prior : Prior
        Prior 1 sigma of the filter (and initial errors of the simulated runs).
    settings : Settings
        Filter measurements (zero-velocity updates).
    sweep_scheme : str
        Scheme whose stop time is swept.
    sweep_stops : tuple of float
        Its stop times, s.
    swing_amplitude : float
        Peak heading rate of the swinging base, rad/s.
    swing_period : float
        Period of the swing, s.
    seed : int
        Seed of the simulated runs (echoed in the results).
    quick : bool
        A reduced run (echoed in the results and the write-up).
    """

    site: Site
    motion: Motion
    schemes: tuple[str, ...]
    rate: float
    stop: float
    substep: float
    duration: float
    imu: ImuErrors
    prior: Prior
    settings: Settings
    sweep_scheme: str
    sweep_stops: tuple[float, ...]
    swing_amplitude: float
    swing_period: float
    seed: int
    quick: bool = False


def compare_schemes(sc: SchemeComparison) -> tuple[dict, dict]:
    """Run the whole comparison.

    Parameters
    ----------
    sc : SchemeComparison

    Returns
    -------
    results : dict
        ``settings``, ``static_floors`` (with the attitude prior) and
        ``static_floors_diffuse``, ``classic``, ``observability``, ``static`` and
        ``swing`` (:func:`summarize`), ``static_bias_only_error`` and ``stop_sweep``.
    runs : dict
        The filter results for the figures: ``static``, ``swing`` (by scheme) and
        ``stop_sweep`` (by stop label).
    """
    site, motion, duration, names = sc.site, sc.motion, sc.duration, list(sc.schemes)
    imu, prior, settings = sc.imu, sc.prior, sc.settings
    base = Base(site, motion, sc.rate, sc.stop, sc.substep)
    # The same runs without the scale factors and misalignments the filter does not
    # model (same noise realization), to show what they cost.
    imu_bias_only = ImuErrors(
        gyro_bias=imu.gyro_bias, accel_bias=imu.accel_bias, arw=imu.arw, vrw=imu.vrw
    )
    tilt, head = prior.attitude[0], prior.attitude[2]
    sweep_scheme, stops = sc.sweep_scheme, sc.sweep_stops
    swing_amplitude, swing_period = sc.swing_amplitude, sc.swing_period
    floors = static_floors(
        site, imu.gyro_bias, imu.accel_bias, motion.attitude(0.0)[0], prior.attitude
    )
    diffuse = static_floors(site, imu.gyro_bias, imu.accel_bias, motion.attitude(0.0)[0])

    static = run_schemes(base, names, duration, imu, prior, settings)
    static_bias_only = run_schemes(base, names, duration, imu_bias_only, prior, settings)
    swing_motion = YawSwing(
        motion.heading,
        motion.pitch,
        motion.roll,
        amplitude=swing_amplitude,
        period=swing_period,
    )
    swing_base = Base(site, swing_motion, sc.rate, sc.stop, sc.substep)
    swing = run_schemes(swing_base, names, duration, imu, prior, settings)
    sweep_rows, sweep_runs = stop_sweep(
        site, motion, sc.rate, sweep_scheme, stops, duration, imu, prior, settings, floors
    )
    results = {
        "quick": sc.quick,
        "settings": {
            "lat_deg": math.degrees(site.lat),
            "g": site.g,
            "radius_m": site.mean_radius,
            "height_m": site.height,
            "heading_deg": math.degrees(motion.heading),
            "pitch_deg": math.degrees(motion.pitch),
            "roll_deg": math.degrees(motion.roll),
            "gyro_bias_deg_h": float(imu.gyro_bias[0] / DEG_PER_HOUR),
            "accel_bias_ug": float(imu.accel_bias[0] / MICRO_G),
            "arw_deg_rt_h": float(imu.arw / DEG_PER_SQRT_HOUR),
            "vrw_ug_rt_hz": float(imu.vrw / MICRO_G_PER_SQRT_HZ),
            "gyro_sf_ppm": float(imu.gyro_scale_factor[0] / PPM),
            "accel_sf_ppm": float(imu.accel_scale_factor[0] / PPM),
            "gyro_misalignment_arcsec": float(imu.gyro_misalignment[0] / ARCSEC),
            "accel_misalignment_arcsec": float(imu.accel_misalignment[0] / ARCSEC),
            "minutes": duration / 60.0,
            "zupt_rate_hz": settings.zupt_rate,
            "zupt_sigma_m_s": settings.zupt_sigma,
            "vertical": settings.vertical,
            "initial_tilt_arcsec": float(tilt / ARCSEC),
            "initial_heading_arcmin": float(head / ARCMIN),
            "initial_velocity_m_s": prior.velocity,
            "initial_position_m": prior.position,
            "rate_deg_s": math.degrees(sc.rate),
            "stop_s": sc.stop,
            "sweep_scheme": sweep_scheme,
            "swing_amplitude_deg_s": math.degrees(swing_amplitude),
            "swing_period_s": swing_period,
            "seed": sc.seed,
        },
        "static_floors": {
            "phi_e_arcsec": floors["phi_e"] / ARCSEC,
            "phi_n_arcsec": floors["phi_n"] / ARCSEC,
            "phi_u_arcmin": floors["phi_u"] / ARCMIN,
        },
        "static_floors_diffuse": {
            "phi_e_arcsec": diffuse["phi_e"] / ARCSEC,
            "phi_n_arcsec": diffuse["phi_n"] / ARCSEC,
            "phi_u_arcmin": diffuse["phi_u"] / ARCMIN,
        },
        "classic": classic(site, motion.heading),
        "observability": observability(site, base, names, duration, settings.vertical),
        "static": summarize(static, base, duration, floors, prior),
        "static_bias_only_error": {
            n: r.summary()["final_error"] for n, r in static_bias_only.items()
        },
        "swing": summarize(swing, swing_base, duration, floors, prior),
        "stop_sweep": sweep_rows,
    }
    runs = {"static": static, "swing": swing, "stop_sweep": sweep_runs}
    return results, runs


def eng(result: AlignmentResult, state: str, row: int = -1) -> float:
    """sigma of ``state`` at output ``row`` in its engineering unit."""
    return float(result.sigma[row, STATES.index(state)] / UNITS[state][1])


def classify(result: AlignmentResult) -> dict[str, list[str]]:
    """Shown states grouped by their degree of observability at the end."""
    deg = result.observability_degree()
    out: dict[str, list[str]] = {"well": [], "partly": [], "not": []}
    for s in SHOWN:
        d = deg[STATES.index(s)]
        out["well" if d >= WELL else "not" if d < NOT else "partly"].append(s)
    return out


def costs(
    result: AlignmentResult, timeline, floors: dict, prior_sigma: np.ndarray, static=None
) -> dict:
    """What a scheme costs and buys in time.

    ``static`` is the unindexed run on the same base (same output times): the time
    after which the scheme's heading sigma stays below the static one is what the
    scheme costs before it starts to pay.
    """
    dt = np.diff(timeline.times)
    moving = np.linalg.norm(timeline.omega_n, axis=1) > 0
    turning = float(dt[moving].sum())
    # Positions visited = stops (zero-rate intervals; a run of them is one stop).
    stops = int(np.sum(~moving & np.concatenate([[True], moving[:-1]])))
    t = result.t
    i_u = STATES.index("phi_u")
    ax = [STATES.index("accel_bias_x"), STATES.index("accel_bias_y")]
    t_acc = [time_to_reach(t, result.sigma[:, i], 0.1 * prior_sigma[i]) for i in ax]
    marks = {}
    for minutes in (2, 5, 10):
        k = np.searchsorted(t, minutes * 60.0)
        if k < len(t):
            marks[f"{minutes}"] = eng(result, "phi_u", int(k))
    better = math.nan
    if static is not None and static is not result:
        better = time_to_reach(t, result.sigma[:, i_u] / static.sigma[:, i_u], 1.0)
    return {
        "turning_s": turning,
        "turning_fraction": turning / timeline.duration,
        "stops": stops,
        "time_heading_better_than_static_s": better,
        "time_to_static_heading_floor_s": time_to_reach(t, result.sigma[:, i_u], floors["phi_u"]),
        "time_to_accel_xy_10pct_s": max(t_acc)
        if not any(math.isnan(v) for v in t_acc)
        else math.nan,
        "heading_sigma_arcmin_at_min": marks,
    }


def summarize(results: dict, base: Base, duration: float, floors: dict, prior: Prior) -> dict:
    """Per scheme: the filter's summary, degree-of-observability classes, costs and the
    least reduced directions (the unindexed run ``"none"``, if present, is the static
    reference of :func:`costs`)."""
    out = {}
    static = results.get("none")
    for name, r in results.items():
        tl = alignment_timeline(base, name, duration)
        d = r.summary()
        d["classes"] = classify(r)
        d["costs"] = costs(r, tl, floors, prior.sigma(), static)
        d["weakest_directions"] = [
            {"eigenvalue": lam, "direction": txt} for lam, txt in weakest_directions(r)
        ]
        out[name] = d
    return out


def observability(site, base: Base, names, duration: float, vertical: str) -> dict:
    """TOM rank and unobservable directions of every scheme's timeline."""
    model = ErrorModel(site, Layout(bias=True), vertical=vertical)
    out = {}
    for name in names:
        tl = alignment_timeline(base, name, duration)
        entry = {}
        for pos in (False, True):
            system = full_timeline(model, tl, position=pos)
            r = analyze(system)
            entry["zupt_position" if pos else "zupt"] = {
                "n_states": r.n_states,
                "rank": r.rank,
                "rank_gap": r.gap,
                "unobservable": list(r.unobservable),
                "smallest_singular_values": r.singular_values[-4:].tolist(),
                "separately_observable": separately_observable(model, system, r, tl.c_sn[0]),
            }
        out[name] = entry
    return out


def separately_observable(model, system, result, c_sn0) -> dict[str, bool]:
    """Which reported states (:data:`SHOWN`) the TOM determines on their own.

    A reported state ``y_i = m_i . x`` (attitude phi, IMU-frame biases at t = 0) is
    observable iff ``m_i`` is orthogonal to the TOM null space. Checked in the
    system's scaled units, where the null-space basis is orthonormal, with a cosine
    threshold of 1e-6 (the rank tolerance is far coarser, so this cannot flip on
    round-off). Attitude is judged as psi: phi = psi + dr/R also carries the position
    error, which zero-velocity updates never see, but that term is dr/R (0.3 arcsec
    for 10 m) and not what "is heading observable" asks.
    """
    m = report_transform(model, c_sn0)
    cols = [model.layout.names.index(nm) for nm in system.names]
    scale = np.asarray(system.scale, dtype=float)
    null = result.null_space / scale[:, None]
    out = {}
    for state in SHOWN:
        row = m[STATES.index(state), cols].copy()
        if state.startswith("phi_"):
            row[[k for k, nm in enumerate(system.names) if nm.startswith("dr_")]] = 0.0
        row *= scale
        if null.size == 0:
            out[state] = True
            continue
        cos = np.abs(row @ null) / (np.linalg.norm(row) * np.linalg.norm(null, axis=0))
        out[state] = bool(np.max(cos) < 1e-6)
    return out


def classic(site, heading: float) -> dict:
    """The 10-state textbook picture at the study's heading."""
    one = analyze(alignment10(site, [heading]))
    two = analyze(alignment10(site, [heading, heading + math.pi]))
    return {
        "one_heading": {
            "rank": one.rank,
            "n_states": one.n_states,
            "unobservable": list(one.unobservable),
        },
        "two_headings": {
            "rank": two.rank,
            "n_states": two.n_states,
            "unobservable": list(two.unobservable),
        },
    }


def stop_sweep(
    site, motion, rate, name, stops, duration, imu, prior, settings, floors
) -> tuple[list, dict]:
    """Run ``name`` on a static base for each stop time; rows of costs and the runs."""
    rows, runs = [], {}
    for stop in stops:
        base = Base(site, motion, rate, stop)
        r = run_schemes(base, [name], duration, imu, prior, settings)[name]
        tl = alignment_timeline(base, name, duration)
        c = costs(r, tl, floors, prior.sigma())
        rows.append(
            {
                "stop_s": stop,
                "stops_in_run": c["stops"],
                "turning_fraction": c["turning_fraction"],
                "final_sigma": r.summary()["final_sigma"],
                "time_to_static_heading_floor_s": c["time_to_static_heading_floor_s"],
                "time_to_accel_xy_10pct_s": c["time_to_accel_xy_10pct_s"],
            }
        )
        runs[f"{stop:g} s"] = r
    return rows, runs
