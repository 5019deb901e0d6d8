"""The drift report (``inserr drift``, ``compare`` and ``run`` with ``--out``), for the one writer.

:func:`build_report` turns scheme runs on one scenario into a
:class:`~inserr.output.report.Report` — the scenario, the comparison table, the
horizontal-error and attitude figures, and the error budget of every run — that
:meth:`~inserr.output.report.Report.write` renders like every other inserr report.
"""

from __future__ import annotations

from inserr.drift.study import SchemeRun, describe, metrics_table
from inserr.output.report import Report
from inserr.scenario.schema import Scenario


def build_report(scen: Scenario, runs: list[SchemeRun], title: str | None = None) -> Report:
    """A report: scenario, comparison table, figures, per-source budget of every run."""
    from inserr.drift import figures as plots

    rep = Report(title or f"inserr drift report: {scen.name}")
    rep.heading("Scenario")
    rep.table(["item", "value"], [list(r) for r in describe(scen)])
    rep.heading("Results")
    header, rows = metrics_table(runs)
    rep.table(header, rows)
    for r in runs:
        for w in r.metrics()["warnings"]:
            rep.paragraph(f"Warning ({r.name}): {w}.")
    rep.paragraph(
        "Deterministic columns use every constant error with its sign as given. "
        "'RMS unknown signs' treats each constant error as a random constant whose "
        "1-sigma is its magnitude; 'worst signs' is the sign pattern that maximises the "
        "horizontal error (both maxima over the run). 'Noise 1-sigma' is the radial "
        "(DRMS) horizontal error from ARW/VRW/bias instability at the end."
    )
    results = {r.name: r.result for r in runs}
    rep.figure(
        plots.horizontal_error(results),
        "horizontal_error",
        "Horizontal position error, one panel per scheme: signs as given (solid), RMS over "
        "unknown signs (dashed), worst sign pattern (dotted), noise 1-sigma envelope (shaded)",
    )
    rep.figure(plots.attitude_errors(results), "attitude_errors", "Attitude errors (deterministic)")
    for r in runs:
        rep.heading(f"Error budget: {r.name}", 3)
        budget = r.result.metrics["error_budget"]
        rep.table(
            ["source", "RMS horizontal at end (nmi)"],
            [[k, v] for k, v in list(budget.items())[:12]],
        )
        rep.figure(
            plots.error_budget(budget, title=f"Error budget: {r.name}", scheme=r.name),
            f"budget_{r.name}",
        )
    rep.results = {
        "scenario": scen.name,
        "runs": [r.metrics() for r in runs],
    }
    return rep
