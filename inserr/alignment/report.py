"""The alignment study's report (``inserr align --out``), handed to the one writer.

:func:`build_report` turns the filter results of several schemes on one base into a
:class:`~inserr.output.report.Report` — settings, final σ and convergence time,
degree of observability, least reduced directions, σ(t) and estimation-error
figures — that :meth:`~inserr.output.report.Report.write` renders like every other
inserr report.
"""

from __future__ import annotations

import math
from typing import Any

from inserr.alignment.filter import STATES, UNITS, AlignmentResult, Settings
from inserr.alignment.study import SHOWN, Base, summary_rows, weakest_directions
from inserr.output.report import Report


def settings_lines(
    base: Base,
    duration: float,
    settings: Settings,
    floor: dict[str, float],
    floor_diffuse: dict[str, float],
) -> list[str]:
    """The report's "Settings" paragraphs.

    Parameters
    ----------
    base : Base
        Site, base motion and the indexing table (SI).
    duration : float, s
        Alignment time.
    settings : Settings
        Measurement choices of the filter (SI).
    floor, floor_diffuse : dict
        Static floors with the attitude prior and with a diffuse one:
        ``phi_e_arcsec``, ``phi_n_arcsec``, ``phi_u_arcmin``.

    Returns
    -------
    list of str
        One paragraph per item.
    """
    ps = settings.position_sigma
    position = "none" if ps is None else f"{ps:g} m"
    return [
        f"Site: latitude {math.degrees(base.site.lat):.4g} deg, height {base.site.height:g} m. "
        f"Base: {base.motion.describe()}.",
        f"Alignment {duration / 60:g} min; table {math.degrees(base.rate):g} deg/s, "
        f"stops {base.stop:g} s.",
        f"Zero-velocity updates {settings.zupt_rate:g} Hz, 1σ {settings.zupt_sigma:g} m/s; "
        f"position updates: {position}; "
        f"vertical channel {settings.vertical}.",
        f"Static floors for this budget with this attitude prior: φE "
        f"{floor['phi_e_arcsec']:.3g} arcsec, φN {floor['phi_n_arcsec']:.3g} arcsec, heading "
        f"{floor['phi_u_arcmin']:.3g} arcmin (1/σ² = 1/σ_prior² + 1/floor²; with a diffuse "
        f"prior ∇/g = {floor_diffuse['phi_e_arcsec']:.3g} arcsec and ε_E/(Ω cos L) = "
        f"{floor_diffuse['phi_u_arcmin']:.3g} arcmin).",
    ]


def build_report(
    results: dict[str, AlignmentResult],
    payload: dict[str, Any],
    *,
    base: Base,
    duration: float,
    settings: Settings,
    floor: dict[str, float],
    floor_diffuse: dict[str, float],
    title: str = "Alignment study",
) -> Report:
    """Report: settings, summary table, weakest directions, figures, ``results.json``.

    Parameters
    ----------
    results : dict
        Scheme name -> alignment result, all on ``base``.
    payload : dict
        The study's JSON summary, written as ``results.json``.
    base, duration, settings, floor, floor_diffuse
        As in :func:`settings_lines`.
    title : str
        Report title.

    Returns
    -------
    Report
        Ready for :meth:`~inserr.output.report.Report.write`.
    """
    from inserr.alignment.figures import error_figure, sigma_figure

    rep = Report(title)
    rep.results = payload
    rep.heading("Settings")
    for line in settings_lines(base, duration, settings, floor, floor_diffuse):
        rep.paragraph(line)
    rep.heading("Final 1σ and convergence time")
    rep.paragraph(
        "Convergence time: first time after which σ stays within 10 % of its final value; "
        "'—' = the state was not estimated (σ fell by less than 10 % of its prior)."
    )
    header, rows = summary_rows(results)
    rep.table(header, rows)
    rep.heading("Degree of observability √P0/√Pk at the end")
    deg_rows = []
    for s in SHOWN:
        i = STATES.index(s)
        deg_rows.append(
            [UNITS[s][0]] + [float(r.observability_degree()[i]) for r in results.values()]
        )
    rep.table(["state", *results], deg_rows, fmt="{:.3g}")
    rep.heading("Least reduced directions (normalised eigen-analysis of P)")
    rep.paragraph(
        "Eigen-decomposition of D0⁻¹ P D0⁻¹ with D0 = diag(prior σ): an eigenvalue of 1 is a "
        "combination of states the alignment did not improve at all."
    )
    eig_rows = []
    for name, r in results.items():
        for lam, text in weakest_directions(r):
            eig_rows.append([name, lam, text])
    rep.table(["scheme", "eigenvalue", "direction (prior-σ units)"], eig_rows, fmt="{:.3g}")
    rep.figure(
        sigma_figure(results), "sigma", "1σ of attitude and IMU-frame biases during alignment"
    )
    rep.figure(
        error_figure(results),
        "attitude_error",
        "Attitude estimation error of one simulated run and ±1σ",
    )
    return rep
