"""Output: how results leave inserr — the one report writer, the one figure style, progress.

* ``report`` — :class:`~inserr.output.report.Report` and its writer (``report.md``,
  ``report.html``, PNGs, ``results.json``; atomic, never over a user's directory);
  strict JSON.
* ``outdir`` — output directories that cannot hurt anyone: ownership manifests, write
  probes, atomic file writes, leftovers of killed runs.
* ``figure_style`` — sizes, resolution, fonts, grid and a colour per scheme; figures on
  :class:`matplotlib.figure.Figure`, never pyplot.
* ``progress`` — progress bars on a terminal, silent otherwise.
* ``results`` — the interface every study result offers a notebook (``metrics``,
  ``to_dataframe``, ``budget``, ``plot``, Jupyter HTML) and its helpers.
"""

from inserr.core.lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "Report": "inserr.output.report",
        "check_output_dir": "inserr.output.outdir",
        "check_report_dir": "inserr.output.report",
        "dumps": "inserr.output.report",
        "write_bytes_atomic": "inserr.output.outdir",
        "write_text_atomic": "inserr.output.report",
        "progress": "inserr.output.progress",
        "set_quiet": "inserr.output.progress",
        "StudyResult": "inserr.output.results",
        "budget_frame": "inserr.output.results",
    },
)

__all__ = [
    "Report",
    "check_output_dir",
    "check_report_dir",
    "dumps",
    "write_bytes_atomic",
    "write_text_atomic",
    "progress",
    "set_quiet",
    "StudyResult",
    "budget_frame",
]
