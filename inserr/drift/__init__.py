"""Drift: free-inertial drift of a scenario under its indexing schemes, and its report.

* ``analysis`` — deterministic errors, random constants of unknown sign, noise, budget
  (:func:`~inserr.drift.analysis.analyze_drift`).
* ``unknown_signs`` — RMS and exact worst case over the signs of the constant errors.
* ``study`` — a scenario run under a scheme (:func:`~inserr.drift.study.run_scheme`), tables.
* ``comparison`` — schemes compared on one scenario: figures per error set, motion grids.
* ``paper`` — a paper's published figures beside the model's: readings, sign ranges, claims.
* ``figures`` — horizontal error, attitude, error budget and table-angle figures.
* ``report`` — the drift report, for the one writer.
"""

from inserr.core.lazy import lazy_exports

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
    },
)

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
]
