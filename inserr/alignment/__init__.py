"""Alignment: fine alignment on a static, swinging or indexed base — filter and observability.

* ``filter`` — the alignment Kalman filter on the inserr error model
  (:func:`~inserr.alignment.filter.run_alignment`) and its figures of merit.
* ``inputs`` — what the alignment and observability studies read from a scenario.
* ``observability`` — observability of piecewise-constant systems: rank, null space, words.
* ``study`` — the filter per scheme on one base, and the tables.
* ``figures`` — σ(t) and estimation-error figures.
* ``report`` — the alignment report, for the one writer.
* ``api`` — the notebook front door: ``align`` from a scenario, file or dict.
* ``comparison`` — static vs indexed alignment: the filter per scheme on a static and a
  swinging base, observability per scheme, what indexing costs, a stop-time sweep (the
  study of ``analyses/alignment_observability``).
* ``comparison_report`` — its write-up, for the one writer.
"""

from inserr.core.lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "AlignmentResult": "inserr.alignment.filter",
        "Prior": "inserr.alignment.filter",
        "Settings": "inserr.alignment.filter",
        "run_alignment": "inserr.alignment.filter",
        "static_floors": "inserr.alignment.filter",
        "analyze": "inserr.alignment.observability",
        "full_timeline": "inserr.alignment.observability",
        "Base": "inserr.alignment.study",
        "run_schemes": "inserr.alignment.study",
        "build_report": "inserr.alignment.report",
        "AlignmentInputs": "inserr.alignment.inputs",
        "alignment_inputs": "inserr.alignment.inputs",
        "align": "inserr.alignment.api",
        "AlignmentStudy": "inserr.alignment.api",
        "SchemeComparison": "inserr.alignment.comparison",
        "compare_schemes": "inserr.alignment.comparison",
    },
)

__all__ = [
    "AlignmentResult",
    "Prior",
    "Settings",
    "run_alignment",
    "static_floors",
    "analyze",
    "full_timeline",
    "Base",
    "run_schemes",
    "build_report",
    "AlignmentInputs",
    "alignment_inputs",
    "align",
    "AlignmentStudy",
    "SchemeComparison",
    "compare_schemes",
]
