"""The north finder's report (``inserr northfind --out``), handed to the one writer.

:func:`build_report` turns a Monte Carlo study
(:func:`inserr.northfinder.study.monte_carlo`) and its summary into a
:class:`~inserr.output.report.Report` — the set-up, the warnings, the summary table,
the heading, convergence and latitude figures, and the histories in
``results.json`` — that :meth:`~inserr.output.report.Report.write` renders like
every other inserr report.
"""

from __future__ import annotations

import math
from typing import Any

from inserr.core.units import MIL
from inserr.northfinder.instrument import Instrument, Pose
from inserr.northfinder.study import MonteCarloResult
from inserr.output.report import Report


def build_report(
    result: MonteCarloResult, summary: dict[str, Any], pose: Pose, instrument: Instrument
) -> Report:
    """Report of a north-finder Monte Carlo against the Cramér-Rao bound.

    Parameters
    ----------
    result : MonteCarloResult
        Error histories and bounds (SI).
    summary : dict
        :meth:`MonteCarloResult.summary` with ``latitude_known`` and ``seed`` (the
        JSON the command prints); written to ``results.json`` with the histories.
    pose : Pose
        The simulated truth: latitude, heading, pitch and roll (rad).
    instrument : Instrument
        The table (rate, rad/s) and the sensor mounting.

    Returns
    -------
    Report
        Ready for :meth:`~inserr.output.report.Report.write`.
    """
    from inserr.northfinder.figures import (
        convergence_figure,
        heading_history_figure,
        latitude_history_figure,
    )

    rep = Report("North finder: Monte Carlo against the Cramér-Rao bound")
    rep.paragraph(
        f"Site latitude {math.degrees(pose.lat):g} deg, heading {math.degrees(pose.heading):g} "
        f"deg, pitch {math.degrees(pose.pitch):g} deg, roll {math.degrees(pose.roll):g} deg; "
        f"table {math.degrees(instrument.table_rate):g} deg/s; {summary['runs']} runs of "
        f"{summary['duration_s']:g} s, seed {summary['seed']}. Latitude "
        + (
            "given to the estimator."
            if summary["latitude_known"]
            else "not given to the estimator; hemisphere declared: "
            f"{summary['hemisphere_declared']}."
        )
    )
    for warning in summary["warnings"]:
        rep.paragraph(f"**Warning** — {warning}.")
    rep.table(
        ["quantity", "value"],
        [
            [k, "n/a" if v is None else v]
            for k, v in summary.items()
            if k not in ("report", "warnings")
        ],
    )
    rep.figure(heading_history_figure(result), "heading_error", "Heading error vs time")
    rep.figure(convergence_figure(result), "convergence", "Runs within 0.5 mil vs time")
    if not result.latitude_known:
        rep.figure(latitude_history_figure(result), "latitude_error", "Latitude error vs time")
    rep.results.update(summary)
    rep.results["history"] = {
        "time_s": result.times,
        "heading_sigma_mil": result.heading_sigma() / MIL,
        "heading_bias_mil": result.heading_bias() / MIL,
        "crlb_heading_mil": result.bound.heading / MIL,
        "fraction_within_0p5_mil": result.fraction_within(),
    }
    return rep
