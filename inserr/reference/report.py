"""The validation report (``inserr validate --out``), handed to the one writer.

:func:`build_report` turns a :class:`~inserr.reference.validation.Validation` into a
:class:`~inserr.output.report.Report` — the comparison metrics, the linear and
nonlinear overlays, the Monte Carlo against the covariance — that
:meth:`~inserr.output.report.Report.write` renders like every other inserr report.
"""

from __future__ import annotations

from inserr.core.units import HOUR
from inserr.output.report import Report
from inserr.reference.validation import Validation


def build_report(v: Validation) -> Report:
    """The overlay figures, the metrics and the Monte Carlo test; ``results`` = the summary.

    Parameters
    ----------
    v : Validation
        What :func:`inserr.reference.validation.validate` computed.

    Returns
    -------
    Report
        Ready for :meth:`~inserr.output.report.Report.write`.
    """
    from inserr.reference.figures import attitude_overlay, horizontal_overlay, monte_carlo_figure

    rep = Report(f"inserr validate: {v.scenario.name}, scheme {v.scheme}")
    rep.paragraph(
        f"Linear prediction (psi-angle model) against the nonlinear reference (python-ins "
        f"strapdown navigation of ideal increments from inverse navigation, errors injected), "
        f"IMU rate {v.rate:g} Hz, {v.scenario.duration / HOUR:g} h."
    )
    rows = [[k, value] for k, value in v.metrics.items() if value is not None]
    rep.table(["metric", "value"], rows)
    rep.figure(
        horizontal_overlay(v.linear, v.nonlinear),
        "horizontal_overlay",
        "Horizontal position error: linear vs nonlinear",
    )
    rep.figure(
        attitude_overlay(v.linear, v.nonlinear),
        "attitude_overlay",
        "Attitude errors: linear vs nonlinear",
    )
    if v.monte_carlo is not None:
        mc = v.monte_carlo.summary()
        rep.heading("Monte Carlo")
        rep.table(["metric", "value"], [[k, str(val)] for k, val in mc.items() if k != "chi2"])
        if "chi2" in mc:
            rep.table(
                ["chi-square test", "value"], [[k, str(val)] for k, val in mc["chi2"].items()]
            )
        rep.figure(
            monte_carlo_figure(v.monte_carlo),
            "monte_carlo",
            "Monte Carlo spread vs covariance",
        )
    for note in v.notes:
        rep.paragraph(f"Note: {note}")
    rep.results = v.summary()
    return rep
