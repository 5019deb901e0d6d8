"""Calibration results for people: JSON-ready summaries and P1-style figures.

Engineering units throughout (this is an edge of the package): scale factors in ppm,
misalignments in arcsec, gyro biases in deg/h, accelerometer biases in micro-g, inputs
in deg/h and g, times in s. Figures are built on :class:`matplotlib.figure.Figure`
(no pyplot state, no display needed).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from inserr.calibration import (
    PARAMETER_NAMES,
    MonteCarloConfig,
    SensorResult,
    monte_carlo,
    parameter_unit,
)
from inserr.earth import Site
from inserr.imu import ImuErrors
from inserr.mechanism import PositionSet
from inserr.report import Report
from inserr.units import ARCSEC, DEG_PER_HOUR, DEG_PER_SQRT_HOUR, G0, MICRO_G_PER_SQRT_HZ


def positions_summary(pset: PositionSet, site: Site) -> list[dict[str, Any]]:
    """Per stop: name, gimbal angles (deg), dwell (s), up axis, ideal inputs (deg/h and g)."""
    rows = pset.describe()
    for row, c in zip(rows, pset.attitudes, strict=True):
        for key, ref, unit in (
            ("gyro_input_deg_h", site.earth_rate_n, DEG_PER_HOUR),
            ("accel_input_g", site.specific_force_n, G0),
        ):
            u = c.T @ ref
            # Nominal zeros come out of the DCM products as ~1e-16 of the reference;
            # shown as exact zeros so the table reads like P1's.
            u[np.abs(u) < 1e-12 * np.linalg.norm(ref)] = 0.0
            row[key] = u / unit
    return rows


def sensor_summary(result: SensorResult) -> dict[str, Any]:
    """Rank, condition number, identifiability messages and the per-parameter table of one triad."""
    ident = result.identifiability
    return {
        "rank": ident.rank,
        "condition_number": ident.condition_number,
        "unidentifiable": ident.unidentifiable,
        "identifiability_messages": list(ident.messages),
        "parameters": result.table(),
    }


def calibration_summary(
    pset: PositionSet, site: Site, imu: ImuErrors, config: MonteCarloConfig
) -> tuple[dict[str, Any], dict[str, SensorResult]]:
    """Run the Monte Carlo of a position set and summarise it.

    Returns
    -------
    summary : dict
        Keys ``method``, ``positions``, ``n_positions``, ``dwell_time_s``,
        ``indexing_time_s``, ``total_time_s``, ``rank``, ``condition_number``,
        ``unidentifiable``, ``identifiability_messages``, ``parameters`` (gyro), ``accel``
        (the same keys for the accelerometers), ``units`` and ``settings``.
    results : dict
        The raw :class:`SensorResult` per sensor (SI), for figures.
    """
    results = monte_carlo(pset, site, imu, config)
    summary: dict[str, Any] = {
        "method": pset.name,
        "latitude_deg": math.degrees(site.lat),
        "positions": positions_summary(pset, site),
        "n_positions": len(pset),
        "dwell_time_s": pset.dwell_time,
        "indexing_time_s": pset.indexing_time,
        "total_time_s": pset.total_time,
    }
    summary.update(sensor_summary(results["gyro"]))
    summary["accel"] = sensor_summary(results["accel"])
    summary["units"] = {
        "sf": "ppm",
        "mis": "arcsec",
        "gyro bias": "deg/h",
        "accel bias": "ug (micro-g)",
        "inputs": "deg/h (gyro), g (accel)",
        "time": "s",
    }
    summary["settings"] = {
        "runs": config.runs,
        "seed": config.seed,
        "positioning_error_arcsec": config.positioning_error / ARCSEC,
        "positioning_model": config.positioning_model,
        "per_sample": config.per_sample,
        "sample_rate_hz": config.sample_rate,
        "arw_deg_per_sqrt_h": imu.arw / DEG_PER_SQRT_HOUR,
        "vrw_ug_per_sqrt_hz": imu.vrw / MICRO_G_PER_SQRT_HZ,
        "table_rate_deg_s": math.degrees(pset.table.rate),
        "table": pset.table.name,
    }
    return summary, results


def deviation_figure(result: SensorResult, title: str) -> Figure:
    """P1-style figure: estimate minus truth for every run, one panel per parameter.

    The dashed lines mark +-1 predicted sigma (CRLB and positioning error combined).
    """
    fig = Figure(figsize=(12, 8))
    axes = fig.subplots(4, 3, sharex=True)
    dev = result.deviations
    runs = np.arange(1, dev.shape[0] + 1)
    for j, name in enumerate(PARAMETER_NAMES):
        ax = axes.flat[j]
        unit, f = parameter_unit(name, result.sensor)
        if result.identifiability.identifiable[j]:
            ax.plot(runs, dev[:, j] / f, ".", ms=3)
            s = result.predicted_std[j] / f
            ax.axhline(s, ls="--", lw=0.8, color="k")
            ax.axhline(-s, ls="--", lw=0.8, color="k")
            ax.axhline(0.0, lw=0.5, color="0.5")
        else:
            ax.text(0.5, 0.5, "not identifiable", ha="center", va="center", transform=ax.transAxes)
        ax.set_title(f"{name} [{unit}]", fontsize=9)
        ax.tick_params(labelsize=7)
    for ax in axes[-1]:
        ax.set_xlabel("run", fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def std_figure(results: dict[str, SensorResult], sensor: str, title: str) -> Figure:
    """Bar chart per parameter: Monte Carlo std of each method beside its CRLB and prediction.

    Values are relative to the predicted std of the first method, so the three units
    (ppm, arcsec, deg/h) share one axis.
    """
    fig = Figure(figsize=(12, 4.5))
    ax = fig.subplots()
    names = list(PARAMETER_NAMES)
    x = np.arange(len(names))
    first = next(iter(results.values()))[sensor]
    ref = np.where(np.isfinite(first.predicted_std), first.predicted_std, np.nan)
    width = 0.8 / max(1, len(results))
    for k, (label, res) in enumerate(results.items()):
        r = res[sensor]
        off = (k - (len(results) - 1) / 2) * width
        ax.bar(x + off, r.std / ref, width, label=f"{label}: MC std")
        ax.plot(x + off, r.crlb_sigma / ref, "k_", ms=12)
        ax.plot(x + off, r.predicted_std / ref, "r_", ms=12)
    ax.plot([], [], "k_", label="CRLB (noise only)")
    ax.plot([], [], "r_", label="CRLB + positioning error")
    ax.set_xticks(x, names, rotation=45, fontsize=8)
    ax.set_ylabel(f"std / predicted std of {next(iter(results))}")
    ax.set_title(title)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def parameter_rows(summary: dict[str, Any]) -> list[list[Any]]:
    """Table rows (parameter, unit, true, mean deviation, std, CRLB, positioning, predicted)."""
    rows = []
    for name, p in summary["parameters"].items():
        vals = [
            p[k]
            for k in (
                "true",
                "mean_deviation",
                "std",
                "crlb_sigma",
                "positioning_sigma",
                "predicted_std",
            )
        ]
        rows.append([name, p["unit"], *[("n/a" if v is None else float(v)) for v in vals]])
    return rows


PARAMETER_HEADER = [
    "parameter",
    "unit",
    "true",
    "mean dev",
    "std",
    "CRLB",
    "pos. sigma",
    "predicted",
]


def build_report(summary: dict[str, Any], results: dict[str, SensorResult]) -> Report:
    """A report with the position table, the parameter tables and the P1-style figures."""
    rep = Report(f"Multi-position calibration: {summary['method']}")
    s = summary["settings"]
    rep.paragraph(
        f"Latitude {summary['latitude_deg']:.4g} deg; {summary['n_positions']} positions; dwell "
        f"{summary['dwell_time_s']:.0f} s + indexing {summary['indexing_time_s']:.0f} s = "
        f"{summary['total_time_s']:.0f} s. {s['runs']} runs, seed {s['seed']}, ARW "
        f"{s['arw_deg_per_sqrt_h']:.4g} deg/sqrt(h), VRW "
        f"{s['vrw_ug_per_sqrt_hz']:.4g} ug/sqrt(Hz), positioning error uniform "
        f"+-{s['positioning_error_arcsec']:.4g} arcsec ({s['positioning_model']})."
    )
    rep.heading("Positions")
    rep.table(
        ["name", "outer deg", "inner deg", "up", "dwell s", "gyro input deg/h", "accel input g"],
        [
            [
                p["name"],
                p["outer_deg"],
                p["inner_deg"],
                p["up_axis"],
                p["dwell_s"],
                ", ".join(f"{v:+.3f}" for v in p["gyro_input_deg_h"]),
                ", ".join(f"{v:+.3f}" for v in p["accel_input_g"]),
            ]
            for p in summary["positions"]
        ],
    )
    for sensor, block in (("gyro", summary), ("accel", summary["accel"])):
        rep.heading(
            f"{sensor}: rank {block['rank']}, condition number {block['condition_number']:.4g}"
        )
        for msg in block["identifiability_messages"]:
            rep.paragraph(msg)
        rep.table(PARAMETER_HEADER, parameter_rows(block))
        rep.figure(
            deviation_figure(results[sensor], f"{summary['method']}: {sensor} estimate - truth"),
            f"{sensor}_deviation",
            "Estimate minus truth per run; dashed: +-1 predicted sigma.",
        )
        rep.figure(
            std_figure({summary["method"]: results}, sensor, f"{sensor}: std vs CRLB"),
            f"{sensor}_std",
            "Monte Carlo std beside the CRLB and the CRLB combined with the positioning error.",
        )
    rep.results = summary
    return rep
