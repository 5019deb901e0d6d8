"""The drift report (``inserr drift``, ``compare`` and ``run`` with ``--out``), for the one writer.

:func:`build_report` turns scheme runs on one scenario into a
:class:`~inserr.output.report.Report` that an engineer reads at a glance:

* the provenance (inserr version, scenario file, SHA-256 of the resolved scenario);
* the set-up: the whole scenario, initial errors included (:func:`~inserr.drift.study.describe`);
* the comparison table, every column an error with its unit;
* the horizontal-error figure (one panel per scheme, scheme colours, RMS dashed
  black and worst signs dotted grey in every panel) and the attitude-error figure
  (one row per scheme, tilts in arcsec and heading in arcmin, as in the tables);
* the error budget of every scheme as one table and one figure with the same rows
  (readable source names, the rest gathered, the root-sum-square total);
* the data: ``timeseries.csv`` (the series at ``output.export_step``) and
  ``budget.csv`` (every source of every scheme), and ``results.json`` with the
  version, the resolved scenario (units as written) and its digest.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from inserr.drift.budget import budget_table
from inserr.drift.study import (
    SchemeRun,
    budget_csv,
    describe,
    export_step,
    metrics_table,
    timeseries_csv,
)
from inserr.output.report import Report
from inserr.scenario.schema import Scenario, resolved_scenario, scenario_digest

#: Sources shown one by one in a budget table and figure (the rest are gathered).
BUDGET_TOP = 12


def provenance(scen: Scenario, source: str | Path | None = None) -> dict:
    """Which inserr and which inputs produced a report (for ``results.json`` and its header).

    Parameters
    ----------
    scen : Scenario
    source : str or Path, optional
        The scenario file, when the run read one (its SHA-256 is recorded too).

    Returns
    -------
    dict
        ``inserr_version``, ``scenario_sha256`` (of the resolved scenario, see
        :func:`~inserr.scenario.schema.scenario_digest`), and with a file
        ``scenario_file`` and ``scenario_file_sha256`` (of its bytes).
    """
    from inserr import __version__

    out = {"inserr_version": __version__, "scenario_sha256": scenario_digest(scen)}
    if source is not None and Path(source).is_file():
        out["scenario_file"] = str(source)
        out["scenario_file_sha256"] = hashlib.sha256(Path(source).read_bytes()).hexdigest()
    return out


def build_report(
    scen: Scenario,
    runs: list[SchemeRun],
    title: str | None = None,
    source: str | Path | None = None,
) -> Report:
    """A report: provenance, set-up, comparison table, figures, budgets and data files.

    Parameters
    ----------
    scen : Scenario
        The scenario every run ran.
    runs : list of SchemeRun
        One per scheme, in the order shown.
    title : str, optional
        Report title (default ``"inserr drift report: <scenario name>"``).
    source : str or Path, optional
        The scenario file, when there is one (named and hashed in the report).

    Returns
    -------
    Report
        Ready for :meth:`~inserr.output.report.Report.write`.
    """
    from inserr.drift import figures as plots

    prov = provenance(scen, source)
    rep = Report(title or f"inserr drift report: {scen.name}")
    where = f"scenario file `{prov['scenario_file']}`, " if "scenario_file" in prov else ""
    rep.paragraph(
        f"Written by inserr {prov['inserr_version']} from {where}resolved scenario "
        f"SHA-256 `{prov['scenario_sha256'][:16]}…` (full digest in results.json)."
    )
    rep.heading("Set-up")
    rep.table(["item", "value"], [list(r) for r in describe(scen)])
    rep.heading("Results")
    header, rows = metrics_table(runs)
    rep.table(header, rows)
    for r in runs:
        for w in r.metrics()["warnings"]:
            rep.paragraph(f"Warning ({r.name}): {w}.")
    rep.paragraph(
        "Signs as given: every constant error with its sign as written. 'RMS, unknown "
        "signs' treats each constant error as a random constant whose 1-sigma is its "
        "magnitude; 'worst signs' is the sign pattern that maximises the horizontal "
        "error (both are maxima over the run). 'Noise 1-sigma' is the radial (DRMS) "
        "horizontal error from ARW, VRW and bias instability at the end. Heading error "
        "in arcmin, tilts in arcsec, positions in nautical miles, throughout."
    )
    results = {r.name: r.result for r in runs}
    rep.figure(
        plots.horizontal_error(results),
        "horizontal_error",
        "Horizontal position error, one panel per scheme (its colour): signs as given "
        "(solid), RMS over unknown signs (black, dashed), worst sign pattern (grey, "
        "dotted), noise 1-sigma envelope (shaded).",
        crop=False,
    )
    rep.figure(
        plots.attitude_errors(results),
        "attitude_errors",
        "Attitude errors with the signs as given, one row per scheme: east and north "
        "tilt errors (arcsec), heading error (arcmin).",
        crop=False,
    )
    rep.heading("Error budget")
    table = budget_table({r.name: r.result.metrics["error_budget"] for r in runs}, BUDGET_TOP)
    if len(table.rows) == 1:  # the total alone: no error source at all
        rep.paragraph("No error source is set: the budget is empty and every error is zero.")
    else:
        rep.paragraph(
            "RMS horizontal position error at the end of the run per error source, nmi: "
            f"the {BUDGET_TOP} largest (by their largest contribution over the schemes), "
            "the others gathered, and the root-sum-square total of each scheme (the "
            "sources are independent: constant errors of unknown sign, and noise). The "
            "figure below shows the same rows."
        )
        rep.table(
            ["source", "type", *(f"{name} (nmi)" for name in table.schemes)],
            [
                [row.label, row.kind, *vals]
                for row, vals in zip(table.rows, table.values, strict=True)
            ],
        )
        rep.figure(
            plots.budget_figure(table, "Error budget at the end of the run"),
            "error_budget",
            "RMS horizontal position error at the end per source, one bar per scheme (its "
            "colour); the root-sum-square total hatched, at the bottom.",
            crop=False,
        )
    step = export_step(runs[0]) if runs else scen.value("output.export_step")
    rep.heading("Data")
    rep.attach(
        "timeseries.csv",
        timeseries_csv(runs),
        f"the errors of every scheme every {step:g} s (output.export_step), units in "
        "the column names",
    )
    rep.attach("budget.csv", budget_csv(runs), "every error source of every scheme, with totals")
    rep.results = {
        **prov,
        "scenario_name": scen.name,
        "scenario": resolved_scenario(scen),
        "runs": [r.metrics() for r in runs],
    }
    return rep
