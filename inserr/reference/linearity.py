"""How far the linear error model holds: linear vs nonlinear on long runs, and where it breaks.

:func:`inserr.reference.validation.validate` compares one scenario's linear prediction
with the nonlinear reference. A reproduction that leans on the linear model for long
runs (P0's 72 h, ``analyses/p0_swinging_base/nonlinear.py``) also needs:

* :func:`linear_and_nonlinear` — one scheme of a scenario through both, deterministic
  errors and one noisy realisation, with the arrays for figures;
* :func:`case_row` — the metrics of such a case in nautical miles, for tables;
* :func:`linearity_probes` — single errors pushed past their size one at a time, to
  show where the linearisation stops holding, and :func:`probe_limits`, the largest
  probe of each family that still agrees within 1 %;
* :func:`rate_dependence` — the same case at several IMU rates, which separates the
  reference's own discretisation (falls with the rate) from the linearisation (does not);
* :func:`pseudo_drift_check` — how much of a large heading error's difference is the
  small-angle form of the attitude error alone;
* :func:`comparison_figure` — linear (solid) vs nonlinear (dashed), and their difference.

A linear-vs-nonlinear agreement validates the linearisation of the scenario it runs,
not the scenario's reading of a paper: both sides share the reading.
"""

from __future__ import annotations

import math
import time

import numpy as np

from inserr.core.earth import OMEGA_IE
from inserr.core.units import HOUR, NMI
from inserr.scenario.schema import Scenario


def linear_and_nonlinear(scen: Scenario, scheme: str, rate: float) -> tuple[dict, dict]:
    """One scheme of ``scen``: linear drift analysis and two nonlinear runs on the same history.

    Parameters
    ----------
    scen : Scenario
    scheme : str
        Scheme name.
    rate : float
        IMU sample rate of the reference, Hz.

    Returns
    -------
    info : dict
        ``metrics`` (:func:`inserr.reference.validation.compare` of the deterministic
        runs, plus the noisy run's maximum and final horizontal error, the linear noise
        1 sigma and RMS over unknown signs, m; motor starts per hour), ``experiment``,
        ``scheme``, ``hours``, ``imu_rate_hz``, ``yaw_period_s``, ``heading_convention``
        and the wall times (s).
    arrays : dict
        ``lin_t``, ``lin_dr`` (E, N, m), ``lin_phi``, ``nl_t``, ``nl_dr``, ``nl_phi`` and
        ``noisy_dr``.
    """
    from inserr.drift.study import run_scheme
    from inserr.reference.strapdown import RunSpec, attitude_history, deterministic_run, simulate
    from inserr.reference.validation import compare

    t0 = time.perf_counter()
    lin_run = run_scheme(scen, scheme)
    t_lin = time.perf_counter() - t0
    lin = lin_run.result
    specs = [
        deterministic_run(scen.imu, scen.init, scen.dt_out),
        RunSpec(scen.imu, scen.init, np.random.SeedSequence(scen.seed), True, scen.dt_out),
    ]
    t0 = time.perf_counter()
    det, noisy = simulate(
        scen.site,
        attitude_history(lin_run.timeline),
        scen.duration,
        specs,
        rate=rate,
        vertical=scen.vertical,
        desc=f"{scen.name} {scheme}",
    )
    t_nl = time.perf_counter() - t0
    metrics = compare(lin, det)
    metrics["noisy_nonlinear_max_horizontal_error_m"] = float(noisy.horizontal.max())
    metrics["noisy_nonlinear_final_horizontal_error_m"] = float(noisy.horizontal[-1])
    metrics["linear_noise_1sigma_final_m"] = float(lin.noise_horizontal_sigma[-1])
    metrics["linear_rms_unknown_signs_max_m"] = float(lin.rms_horizontal.max())
    metrics["motor_starts_per_hour"] = lin_run.motor_starts_per_hour
    info = {
        "metrics": metrics,
        "experiment": scen.name,
        "scheme": scheme,
        "hours": scen.duration / HOUR,
        "imu_rate_hz": rate,
        "yaw_period_s": getattr(scen.motion, "period", None),
        "heading_convention": scen.heading_convention,
        "wall_time_linear_s": t_lin,
        "wall_time_nonlinear_s": t_nl,
    }
    arrays = {
        "lin_t": lin.t,
        "lin_dr": lin.nav[:, 6:8],
        "lin_phi": lin.attitude,
        "nl_t": det.t,
        "nl_dr": det.dr[:, :2],
        "nl_phi": det.phi,
        "noisy_dr": noisy.dr[:, :2],
    }
    return info, arrays


#: Metrics of :func:`linear_and_nonlinear` converted to nautical miles by :func:`case_row`.
NMI_METRICS = (
    "linear_max_horizontal_error",
    "nonlinear_max_horizontal_error",
    "linear_final_horizontal_error",
    "nonlinear_final_horizontal_error",
    "rms_difference",
    "max_difference",
    "noisy_nonlinear_max_horizontal_error",
    "noisy_nonlinear_final_horizontal_error",
    "linear_noise_1sigma_final",
)


def case_row(info: dict) -> dict:
    """A table row of one case of :func:`linear_and_nonlinear` (nautical miles, relative)."""
    m = info["metrics"]
    row = {k: info.get(k) for k in ("experiment", "scenario_file", "yaw_period_s", "scheme")}
    row["status"] = "ok"
    row.update({f"{k}_nmi": m[f"{k}_m"] / NMI for k in NMI_METRICS})
    lin_f, nl_f = m["linear_final_horizontal_error_m"], m["nonlinear_final_horizontal_error_m"]
    row["relative_difference"] = m["relative_difference"]
    row["final_relative_difference"] = abs(nl_f - lin_f) / lin_f if lin_f > 0 else None
    row["rms_difference_relative_to_max"] = (
        m["rms_difference_m"] / m["linear_max_horizontal_error_m"]
    )
    for k in (
        "linear_final_heading_error_arcsec",
        "nonlinear_final_heading_error_arcsec",
        "max_attitude_difference_arcsec",
        "motor_starts_per_hour",
    ):
        row[k] = m[k]
    for k in ("wall_time_linear_s", "wall_time_nonlinear_s", "code_fingerprint"):
        row[k] = info.get(k)
    return row


def static_base(scen: Scenario, hours: float = 4.0) -> Scenario:
    """The scenario's site and vehicle attitude, static, no indexing, no errors, ``hours`` long."""
    from inserr.scenario.schema import scenario_from_dict

    raw = {k: dict(v) for k, v in scen.raw.items() if k in ("site", "motion")}
    keep = ("heading", "pitch", "roll", "heading_convention")
    raw["motion"] = {k: v for k, v in raw.get("motion", {}).items() if k in keep}
    raw.update({"scenario": {"duration": f"{hours} h"}, "scheme": {"name": "none"}})
    return scenario_from_dict(raw)


#: Single errors pushed past a navigation-grade size (label, scenario changes), one at a time.
PROBES: tuple[tuple[str, dict], ...] = (
    *(
        (f"initial heading error {v}", {"initial.attitude": f"0,0,{v}"})
        for v in ("1 deg", "3 deg", "10 deg")
    ),
    *(
        (f"initial tilt errors E,N {v} deg", {"initial.attitude": f"{v},{v},0 deg"})
        for v in ("0.5", "2")
    ),
    *(
        (f"initial north position error {v} km", {"initial.position": f"0,{v},0 km"})
        for v in ("50", "200")
    ),
    *(
        (
            f"free vertical channel, P0 biases, {v}",
            {
                "output.vertical": "free",
                "scenario.duration": v,
                "imu.gyro_bias": "0.003 deg/h",
                "imu.accel_bias": "30 ug",
            },
        )
        for v in ("0.5 h", "1 h", "1.5 h")
    ),
)


def linearity_probes(base: Scenario, probes=PROBES, rate: float = 2.0) -> list[dict]:
    """Linear vs nonlinear for each probe on ``base`` (:func:`static_base`; an IMU at rest, so
    a 2 Hz reference has no sampling error).

    Returns
    -------
    list of dict
        ``probe``, ``linear_max_horizontal_error_m``, ``relative_difference``,
        ``rms_difference_m``, ``rms_difference_relative_to_max``,
        ``max_attitude_difference_arcsec``, ``final_vertical_error_m``.
    """
    from inserr.reference.validation import validate

    rows = []
    for label, changes in probes:
        v = validate(base.with_changes(changes), rate=rate)
        m = v.metrics
        rows.append(
            {
                "probe": label,
                "linear_max_horizontal_error_m": m["linear_max_horizontal_error_m"],
                "relative_difference": m["relative_difference"],
                "rms_difference_m": m["rms_difference_m"],
                "rms_difference_relative_to_max": m["rms_difference_m"]
                / m["linear_max_horizontal_error_m"],
                "max_attitude_difference_arcsec": m["max_attitude_difference_arcsec"],
                "final_vertical_error_m": float(v.nonlinear.dr[-1, 2]),
            }
        )
    return rows


#: Probe families: (name, label prefix, unit of the label's number in rad or m, size key).
FAMILIES = (
    ("heading errors", "initial heading error ", math.radians(1.0), "heading_rad"),
    ("tilts", "initial tilt errors E,N ", math.radians(1.0), "tilt_rad"),
    ("north position errors", "initial north position error ", 1000.0, "horizontal_position_m"),
)


def error_sizes(scen: Scenario) -> dict:
    """The initial errors of ``scen`` that :func:`probe_limits` compares with, SI."""
    a, r = scen.init.attitude, scen.init.position
    return {
        "tilt_rad": float(max(abs(a[0]), abs(a[1]))),
        "heading_rad": float(abs(a[2])),
        "horizontal_position_m": float(np.hypot(r[0], r[1])),
        "latitude_rad": float(scen.site.lat),
        "radius_m": float(scen.site.mean_radius),
    }


def probe_limits(probes: list[dict], sizes: dict) -> dict:
    """Per family, the largest probe whose RMS difference stays within 1 % of the maximum.

    Returns
    -------
    dict
        Family -> ``text`` (the probe's size as labelled), ``value`` (SI) and ``ratio``
        (value over the scenario's own error of that kind; None if it has none).
    """
    out = {}
    for name, prefix, unit, key in FAMILIES:
        good = [
            p
            for p in probes
            if p["probe"].startswith(prefix) and p["rms_difference_relative_to_max"] < 0.01
        ]
        if good:
            best = max(good, key=lambda p: float(p["probe"][len(prefix) :].split()[0]))
            text = best["probe"][len(prefix) :]
            value = float(text.split()[0]) * unit
            ratio = value / sizes[key] if sizes.get(key, 0) > 0 else None
            out[name] = {"text": text, "value": value, "ratio": ratio}
    return out


def rate_dependence(scen: Scenario, rates=(5.0, 20.0, 100.0), hours: float = 1.0) -> list[dict]:
    """Linear vs nonlinear of ``scen`` (``hours`` long) at several IMU rates (Hz).

    The reference's own discretisation (two-sample coning/sculling, the rotation spline
    of the inverse navigation around table starts and stops) shrinks as the rate grows;
    the linearisation error does not. The trend separates the two.
    """
    from inserr.reference.validation import validate

    scen = scen.with_changes({"scenario.duration": f"{hours} h", "compare.schemes": []})
    out = []
    for rate in rates:
        m = validate(scen, rate=rate).metrics
        out.append(
            {
                "imu_rate_hz": rate,
                "hours": hours,
                "relative_difference": m["relative_difference"],
                "rms_difference_m": m["rms_difference_m"],
            }
        )
    return out


def pseudo_drift_check(base: Scenario, heading_deg: float = 3.0) -> dict:
    """How much of a large heading error's nonlinear-minus-linear difference is a pseudo drift.

    With a heading error psi_U the exact Earth rate seen by the platform differs from
    the linear model's ``(I - [psi x]) Omega`` by ``Omega_N (cos psi_U - 1)`` along north
    (to second order): a pseudo gyro drift. Its linear response is subtracted from the
    difference; what remains comes from the other second-order terms.

    Parameters
    ----------
    base : Scenario
        A static base (:func:`static_base`).
    heading_deg : float
        Initial heading error, deg.

    Returns
    -------
    dict
        ``initial_heading_error_deg``, ``rms_difference_m``,
        ``rms_difference_after_removing_pseudo_drift_m`` and ``share_explained``.
    """
    from inserr.drift.study import run_scheme
    from inserr.reference.validation import interpolate, validate

    v = validate(base.with_changes({"initial.attitude": f"0,0,{heading_deg} deg"}), rate=2.0)
    nl = v.nonlinear
    diff = nl.dr[:, :2] - interpolate(v.linear.t, v.linear.nav[:, 6:8], nl.t)
    psi = math.radians(heading_deg)
    eps_n = np.array([0.0, -OMEGA_IE * math.cos(base.site.lat) * (1.0 - math.cos(psi)), 0.0])
    eps_s = base.timeline().c_sn[0].T @ eps_n
    drift = base.with_changes({"imu.gyro_bias": ",".join(f"{x:.17e}" for x in eps_s) + " rad/s"})
    r = run_scheme(drift).result
    rest = diff - interpolate(r.t, r.nav[:, 6:8], nl.t)
    rms = float(np.sqrt(np.mean(np.sum(diff**2, axis=1))))
    rms_rest = float(np.sqrt(np.mean(np.sum(rest**2, axis=1))))
    return {
        "initial_heading_error_deg": heading_deg,
        "rms_difference_m": rms,
        "rms_difference_after_removing_pseudo_drift_m": rms_rest,
        "share_explained": 1.0 - rms_rest / rms,
    }


def comparison_figure(cases: list[tuple[dict, dict]], title: str):
    """Linear (solid) vs nonlinear (dashed) horizontal error per scheme; their difference below.

    Parameters
    ----------
    cases : list of (info, arrays)
        As returned by :func:`linear_and_nonlinear`.
    title : str

    Returns
    -------
    matplotlib.figure.Figure
    """
    from inserr.output import figure_style as style

    fig, (ax, axd) = style.subplots(
        2, 1, height=7.0, sharex=True, gridspec_kw={"height_ratios": [2, 1]}
    )
    for i, (info, d) in enumerate(cases):
        name = info["scheme"]
        c = style.scheme_color(name, i)
        ax.plot(
            d["lin_t"] / HOUR,
            np.hypot(*d["lin_dr"].T) / NMI,
            color=c,
            lw=1.2,
            label=f"{name} linear",
        )
        ax.plot(
            d["nl_t"] / HOUR,
            np.hypot(*d["nl_dr"].T) / NMI,
            color=c,
            lw=1.0,
            ls="--",
            label=f"{name} nonlinear",
        )
        lin_on = np.column_stack(
            [np.interp(d["nl_t"], d["lin_t"], d["lin_dr"][:, k]) for k in range(2)]
        )
        axd.plot(
            d["nl_t"] / HOUR,
            np.linalg.norm(d["nl_dr"] - lin_on, axis=1),
            color=c,
            lw=0.8,
            label=name,
        )
    ax.set(ylabel="horizontal error (nmi)", title=title)
    ax.legend(ncol=2)
    axd.set(ylabel="|dr_nl - dr_lin| (m)", xlabel="time (h)")
    axd.legend()
    for a in (ax, axd):
        style.grid(a)
    return style.finish(fig)


def case_table(rows: list[dict]) -> tuple[list[str], list[list]]:
    """Header and rows of :func:`case_row` rows (nmi; RMS difference in m); others by status."""
    keys = (
        "linear_max_horizontal_error_nmi",
        "nonlinear_max_horizontal_error_nmi",
        "relative_difference",
        "final_relative_difference",
    )
    header = ["experiment", "scheme", "linear max", "nonlinear max", "rel. diff (max)"]
    header += ["rel. diff (final)", "RMS diff (m)", "noisy run max", "noise 1-sigma (end)"]
    body = []
    for r in rows:
        head = [r.get("scenario_file") or r.get("experiment"), r["scheme"]]
        if r.get("status") != "ok":
            body.append([*head, r.get("status", "?"), *[""] * 6])
            continue
        body.append(
            [
                *head,
                *(r[k] for k in keys),
                r["rms_difference_nmi"] * NMI,
                r["noisy_nonlinear_max_horizontal_error_nmi"],
                r["linear_noise_1sigma_final_nmi"],
            ]
        )
    return header, body


def probe_table(probes: list[dict]) -> tuple[list[str], list[list]]:
    """Header and rows of :func:`linearity_probes` results (km, relative, arcsec, m)."""
    header = ["probe", "linear max (km)", "rel. diff (max)", "RMS diff / max"]
    header += ["max attitude diff (arcsec)", "final height error (m)"]
    body = [
        [
            p["probe"],
            p["linear_max_horizontal_error_m"] / 1000.0,
            p["relative_difference"],
            p["rms_difference_relative_to_max"],
            p["max_attitude_difference_arcsec"],
            p["final_vertical_error_m"],
        ]
        for p in probes
    ]
    return header, body
