"""The calibration study's report (``inserr calibrate --out``), handed to the one writer.

:func:`build_report` turns :func:`inserr.calibration.summary.calibration_summary`'s
summary and raw results into a :class:`~inserr.output.report.Report` — positions,
parameter and sensitivity tables, the P1-style figures of both triads — that
:meth:`~inserr.output.report.Report.write` renders like every other inserr report.
"""

from __future__ import annotations

from typing import Any

from inserr.calibration.estimation import SensorResult
from inserr.calibration.summary import (
    PARAMETER_HEADER,
    parameter_rows,
    sensitivity_axes_text,
    sensitivity_table,
)
from inserr.output.report import Report


def build_report(summary: dict[str, Any], results: dict[str, SensorResult]) -> Report:
    """A report with the position table, the parameter and sensitivity tables and figures.

    Parameters
    ----------
    summary : dict
        :func:`calibration_summary`'s summary (engineering units).
    results : dict
        :func:`calibration_summary`'s raw results (SI), for the figures.

    Returns
    -------
    Report
        Ready to :meth:`~inserr.output.report.Report.write`; ``results`` holds ``summary``.
    """
    from inserr.calibration.figures import deviation_figure, std_figure

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
        rep.paragraph(
            f"{sensor}: first-order sensitivity of each estimate to the positioning error at "
            "one position (the others exact), in the parameter's unit per arcsec, about "
            + sensitivity_axes_text(s["positioning_model"])
            + "; max abs = largest magnitude, at = where it occurs."
        )
        rep.table(*sensitivity_table(block["positioning_sensitivity"], s["positioning_model"]))
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


def build_noise_report(fit) -> Report:
    """The report of ``inserr imu-budget --out``: terms per axis, the figure, ``[imu]``.

    Parameters
    ----------
    fit : inserr.calibration.allan.NoiseFit
        The fitted recording.

    Returns
    -------
    Report
        Ready to :meth:`~inserr.output.report.Report.write`; ``results`` holds
        :func:`inserr.calibration.allan.summary` and the inserr version.
    """
    from inserr import __version__
    from inserr.calibration.allan import (
        AXES,
        SENSORS,
        TERM_POWERS,
        TERMS,
        imu_section,
        in_units,
        summary,
    )
    from inserr.calibration.figures import allan_figure

    rec = fit.recording
    pct = f"{fit.confidence:.0%}"
    rep = Report(f"IMU noise budget: {rec.source}")
    rep.paragraph(
        f"Written by inserr {__version__}. Static recording `{rec.source}`: {rec.samples} "
        f"samples at {rec.rate:g} Hz ({rec.duration / 3600:.3g} h). Overlapping Allan "
        "deviation per axis at octave-spaced averaging times; the standard terms fitted by "
        "their IEEE Std 952 slopes (random walk -1/2, bias instability 0 with the 0.664 "
        f"factor, rate random walk +1/2, rate ramp +1), with {pct} intervals from the "
        "number of independent clusters behind each point. A term whose interval reaches "
        "0 is not resolved by the recording (shown as an upper bound)."
    )
    for sensor in SENSORS:
        rep.heading("Gyro" if sensor == "gyro" else "Accelerometer")
        rows = []
        for name in TERM_POWERS:
            label, unit, _ = TERMS[sensor][name]
            row: list = [label, unit]
            for axis in AXES:
                t = fit.term(sensor, axis, name)
                lo, val, hi = (in_units(sensor, name, v) for v in (t.low, t.value, t.high))
                row.append(f"{val:.3g} [{lo:.3g}, {hi:.3g}]" if t.resolved else f"< {hi:.3g}")
            rows.append(row)
        rep.table(["term", "unit", *(f"{a} ({pct} interval)" for a in AXES)], rows)
    rep.figure(
        allan_figure(fit),
        "allan_deviation",
        "Allan deviation per axis: data with 1-sigma error bars from the cluster counts, "
        f"the fitted sum with its {pct} band, and the slope line of each resolved term.",
        crop=False,
    )
    rep.heading("Scenario section")
    rep.paragraph(
        "Ready for a scenario file (`inserr run` reads it as it is): inserr's noise is "
        "isotropic, so each key takes the largest axis; the bias instability becomes the "
        "first-order Gauss-Markov process whose Allan-deviation peak equals the measured "
        "floor. Rate random walk and ramp have no scenario key (listed as comments)."
    )
    rep.markdown_text("```toml\n" + imu_section(fit) + "```")
    rep.results = {"inserr_version": __version__, **summary(fit)}
    return rep
