"""Drift: free-inertial drift of a scenario under its indexing schemes, and its report.

The package is callable: ``inserr.drift(scenario, "two-position")`` runs
:func:`inserr.drift.api.drift` (and ``inserr.compare`` compares schemes).

* ``analysis`` — deterministic errors, random constants of unknown sign, noise, budget
  (:func:`~inserr.drift.analysis.analyze_drift`).
* ``unknown_signs`` — RMS and exact worst case over the signs of the constant errors.
* ``study`` — a scenario run under a scheme (:func:`~inserr.drift.study.run_scheme`), tables.
* ``comparison`` — schemes compared on one scenario: figures per error set, motion grids.
* ``paper`` — a paper's published figures beside the model's: readings, sign ranges, claims.
* ``validity`` — where a result can be trusted: finiteness, the free vertical channel,
  the linear model's range, Schuler resonance of the indexing cycle.
* ``figures`` — horizontal error, attitude, error budget and table-angle figures.
* ``report`` — the drift report, for the one writer.
* ``budget`` — readable source names and the rows every budget table and figure shows.
* ``api`` — the notebook front door: ``drift`` and ``compare`` from a scenario, file or dict.
"""

from inserr.core.lazy import callable_package, lazy_exports

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "DriftResult": "inserr.drift.analysis",
        "analyze_drift": "inserr.drift.analysis",
        "rms_norm": "inserr.drift.unknown_signs",
        "worst_case_norm": "inserr.drift.unknown_signs",
        "SchemeRun": "inserr.drift.study",
        "describe": "inserr.drift.study",
        "metrics_table": "inserr.drift.study",
        "run_scheme": "inserr.drift.study",
        "build_report": "inserr.drift.report",
        "source_label": "inserr.drift.budget",
        "budget_rows": "inserr.drift.budget",
        "drift": "inserr.drift.api",
        "compare": "inserr.drift.api",
        "Comparison": "inserr.drift.api",
    },
)
callable_package(__name__, "inserr.drift.api", "drift")

__all__ = [
    "DriftResult",
    "analyze_drift",
    "rms_norm",
    "worst_case_norm",
    "SchemeRun",
    "describe",
    "metrics_table",
    "run_scheme",
    "build_report",
    "source_label",
    "budget_rows",
    "drift",
    "compare",
    "Comparison",
]
