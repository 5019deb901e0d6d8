"""Write-up of a two-set comparison (:mod:`inserr.calibration.comparison`), for the one writer.

:func:`build_report` turns :func:`~inserr.calibration.comparison.compare_sets`'s
results (and, when given, :func:`~inserr.calibration.published.against_published`'s)
into a :class:`~inserr.output.report.Report`: the answer on the candidate set's claim,
the published table beside the model, accuracy and repeatability at the baseline,
accelerometers, sweeps, positioning-error sensitivity and designed sets. Every
number in the text comes from the results; the verdicts follow the numbers.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from inserr.calibration.comparison import CLASSES, Comparison
from inserr.calibration.estimation import PARAMETER_NAMES
from inserr.calibration.summary import (
    PARAMETER_HEADER,
    parameter_rows,
    sensitivity_axes_text,
    sensitivity_rows,
    sensitivity_table,
)
from inserr.output.report import Report

CLASS_WORDS = {"sf": "scale factors", "mis": "misalignments", "bias": "biases"}


def _fmt(v: float, digits: int = 3) -> str:
    return f"{v:.{digits}g}"


def _and(items: list[str]) -> str:
    """``["a", "b", "c"]`` -> ``"a, b and c"``."""
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + f" and {items[-1]}"


def verdict_text(v: dict[str, Any], sc: dict[str, Any], four: str, six: str) -> list[str]:
    """The plain statements on the candidate set's claim, generated from the numbers.

    Parameters
    ----------
    v : dict
        ``results["verdict"]`` of :func:`~inserr.calibration.comparison.compare_sets`.
    sc : dict
        ``results["scenario"]`` (:func:`~inserr.calibration.comparison.settings_summary`).
    four, six : str
        Candidate and reference set names.

    Returns
    -------
    list of str
        One paragraph each.
    """
    tol = sc["tolerance"]
    ed, nf, et = v["equal_dwell"], v["noise_free"], v["equal_time"]

    def side(c):
        worse = ", ".join(f"{n} (x{c['ratio'][n]:.2f})" for n in c["worse"]) or "none"
        better = ", ".join(f"{n} (x{c['ratio'][n]:.2f})" for n in c["better"]) or "none"
        return worse, better

    def span(c):
        return f"x{c['min_ratio']:.2f} ({c['argmin']}) to x{c['max_ratio']:.2f} ({c['argmax']})"

    w_ed, b_ed = side(ed)
    w_nf, b_nf = side(nf)
    w_et, b_et = side(et)
    out = [
        f"**Time.** {four} takes {v['time_four_s']:.0f} s and {six} {v['time_six_s']:.0f} s at "
        f"{sc['dwell_s']:.0f} s dwell and {sc['table_rate_deg_s']:.3g} deg/s: a saving of "
        f"{100 * v['time_saving']:.1f} % (the dwell alone saves "
        f"{100 * v['dwell_only_saving']:.1f} %; indexing moves change the rest).",
        f"**Equal dwell per position, ARW {sc['arw_deg_per_sqrt_h']:.3g} deg/sqrt(h), positioning "
        f"+-{sc['positioning_error_arcsec']:.3g} arcsec.** Predicted sigma of {four} relative "
        f"to {six} (more than {100 * tol:.0f} % worse): {w_ed}; better: {b_ed}. Range "
        f"{span(ed)}.",
        f"**Noise-free (P1's apparent regime, positioning error only).** Worse: {w_nf}; better: "
        f"{b_nf}. Range {span(nf)}.",
        f"**Equal total time** ({four} dwelling longer). Worse: {w_et}; better: {b_et}. Range "
        f"{span(et)}.",
        f"**Precision per unit time** (D-criterion, dwell and indexing charged): {four} / {six} = "
        f"{v['d_efficiency_four_over_six']:.3f}.",
    ]
    b6 = v["best_six"]
    stops = " ".join(f"({o},{i})" for o, i in b6["stops_outer_inner_deg"])
    out.append(
        f"**Against the best six-position set** the designer finds ({b6['mechanism']} table, "
        f"stops {stops} deg, {b6['total_time_s']:.0f} s): ratio range at equal dwell "
        f"x{b6['equal_dwell']['min_ratio']:.2f} to x{b6['equal_dwell']['max_ratio']:.2f} "
        f"({len(b6['equal_dwell']['worse'])} parameters worse by more than {100 * tol:.0f} %); "
        f"at equal total time x{b6['equal_time']['min_ratio']:.2f} to "
        f"x{b6['equal_time']['max_ratio']:.2f}; noise-free x{b6['noise_free']['min_ratio']:.2f} "
        f"to x{b6['noise_free']['max_ratio']:.2f}."
    )
    if not ed["worse"]:
        claim = (
            f"**Verdict: P1's claim holds.** With noise and dwell accounted for, {four} is within "
            f"{100 * tol:.0f} % of {six} on every gyro parameter while saving "
            f"{100 * v['time_saving']:.0f} % of the time."
        )
    else:
        claim = (
            f"**Verdict: P1's claim does not hold as stated.** At equal dwell per position the "
            f"{100 * v['time_saving']:.0f} % time saving costs accuracy on {len(ed['worse'])} "
            f"of 12 gyro parameters (up to x{ed['max_ratio']:.2f}): fewer positions average "
            "less noise."
        )
        if not et["worse"]:
            claim += (
                f" Given the same total time, {four} matches or beats {six} on every parameter, "
                "so the honest form of the claim is *equal or better precision for the same time*, "
                "not the same accuracy in a third less time."
            )
        else:
            claim += (
                f" Even with the same total time it is worse on {len(et['worse'])} parameters "
                f"(up to x{et['max_ratio']:.2f})."
            )
    claim += " In the noise-free limit (positioning error only) it is " + (
        f"within {100 * tol:.0f} % on every parameter."
        if not nf["worse"]
        else f"worse on {len(nf['worse'])} parameters (up to x{nf['max_ratio']:.2f}) and "
        f"better on {len(nf['better'])}."
    )
    return [*out, claim]


def _where(at: list[dict[str, str]], n_positions: int) -> str:
    """``[{p4, about_east}, {p5, about_east}]`` -> ``"about east at p4 and p5"``."""
    groups: dict[str, list[str]] = {}
    for e in at:
        axis = e["axis"].removeprefix("about_").replace("_", " ")
        groups.setdefault(axis, []).append(e["position"])
    out = []
    for axis, ps in groups.items():
        where = "every position" if len(ps) == n_positions else _and(ps)
        out.append(f"about {axis} at {where}")
    return "; ".join(out)


def sensitivity_sentence(name: str, block: dict[str, Any], half_width_arcsec: float) -> str:
    """One sentence: the most sensitive parameter(s) of each class and what the table does.

    ``block`` is a ``positioning_sensitivity`` block of
    :func:`inserr.calibration.summary.calibration_summary` (parameter unit per arcsec);
    classes are compared separately because their units differ. Parameters within 1e-6
    of the class maximum are named together.
    """
    rows = {r[0]: r for r in sensitivity_rows(block)}
    n_pos = len(next(iter(block.values()))["positions"])
    parts, effects = [], []
    for cls, sl in CLASSES.items():
        # identifiable parameters only
        vals = {n: float(rows[n][2]) for n in PARAMETER_NAMES[sl] if rows[n][2] != "n/a"}
        top = max(vals.values())
        group = [n for n, v in vals.items() if v >= top * (1.0 - 1e-6)]
        unit = block[group[0]]["unit"]
        if len(group) == 1:
            where = f", {_where(block[group[0]]['largest']['at'], n_pos)}" if top > 0 else ""
            parts.append(f"{group[0]} among the {CLASS_WORDS[cls]} ({top:.3g} {unit}{where})")
        elif len(group) == len(vals):
            parts.append(f"all {len(group)} {CLASS_WORDS[cls]} equally ({top:.3g} {unit})")
        else:
            parts.append(f"{_and(group)} among the {CLASS_WORDS[cls]} ({top:.3g} {unit})")
        effects.append(f"{top * half_width_arcsec:.2g} {unit.removesuffix('/arcsec').strip('()')}")
    return (
        f"**{name}.** Most sensitive to the positioning error: {parts[0]}; {parts[1]}; "
        f"{parts[2]} - so a +-{half_width_arcsec:.3g} arcsec error at one position moves a "
        f"parameter by at most {effects[0]}, {effects[1]} and {effects[2]} respectively."
    )


def build_report(
    comparison: Comparison,
    results: dict[str, Any],
    title: str,
    published: dict[str, Any] | None = None,
    paper: str = "the paper",
) -> Report:
    """The comparison's write-up.

    Parameters
    ----------
    comparison : Comparison
        Set names and the raw Monte Carlo results (figures).
    results : dict
        Everything ``results.json`` holds: ``scenario``
        (:func:`~inserr.calibration.comparison.settings_summary`) and
        :attr:`Comparison.results`' keys.
    title : str
        Report title.
    published : dict, optional
        :func:`~inserr.calibration.published.against_published`'s block: adds the
        "Against the paper" section.
    paper : str
        How the text names the publication (e.g. "P1").

    Returns
    -------
    Report
        ``results`` attached.
    """
    from inserr.calibration.figures import deviation_figure, std_figure
    from inserr.calibration.published_report import published_section

    names = list(comparison.names)
    base, noise_free = comparison.baseline, comparison.noise_free
    sc = results["scenario"]
    four, six = names
    v = results["verdict"]
    rep = Report(title)
    rep.paragraph(
        f"Latitude {sc['latitude_deg']:.4g} deg; {paper}'s true gyro errors; dwell "
        f"{sc['dwell_s']:.0f} s per position; table {sc['table_rate_deg_s']:.3g} deg/s; gyro ARW "
        f"{sc['arw_deg_per_sqrt_h']:.3g} deg/sqrt(h); positioning error uniform "
        f"+-{sc['positioning_error_arcsec']:.3g} arcsec ({sc['positioning_model']}: a small "
        f"rotation about each of east, north, up); {sc['runs']} Monte Carlo runs, seed "
        f"{sc['seed']}. Dwell averages of white noise are drawn exactly as N(0, ARW^2/T)."
        + (" QUICK RUN: fewer runs and sweep points." if sc["quick"] else "")
    )
    rep.heading("Answer")
    for line in verdict_text(v, sc, four, six):
        rep.paragraph(line)
    if published is not None:
        published_section(rep, published, results, names, paper)

    rep.heading("Accuracy and repeatability at the baseline")
    rep.paragraph(
        "Accuracy = mean deviation of the estimates from the truth; repeatability = their "
        f"standard deviation ({paper} reports the variance, the square). 'predicted' combines "
        "the CRLB (sensor noise) with the first-order effect of the positioning error. Units: "
        "ppm, arcsec, deg/h."
    )
    for n in names:
        s = results["baseline"][n]
        rep.heading(
            f"{n}: {s['n_positions']} positions, {s['total_time_s']:.0f} s, gyro rank {s['rank']}, "
            f"condition number {s['condition_number']:.3g}",
            level=3,
        )
        rep.table(PARAMETER_HEADER, parameter_rows(s))
        z = np.array(
            [
                abs(p["mean_deviation"]) / (p["std"] / math.sqrt(sc["runs"]))
                for p in s["parameters"].values()
            ]
        )
        rep.paragraph(
            f"Largest |mean deviation| / (std / sqrt(runs)) = {z.max():.2f}: least squares is "
            "unbiased, so the mean deviations are Monte Carlo noise, not a property of the method."
        )
        rep.figure(
            deviation_figure(base[n]["gyro"], f"{n}: gyro estimate - truth ({sc['runs']} runs)"),
            f"gyro_deviation_{n}",
            f"Per-run deviation ({paper}'s figure style); dashed: +-1 predicted sigma.",
        )
    rep.figure(
        std_figure(base, "gyro", "Gyro repeatability at equal dwell: MC std vs CRLB"),
        "gyro_std_compare",
        "Bars: Monte Carlo std; marks: CRLB and CRLB with positioning error; "
        f"normalised by {four}'s prediction.",
    )
    rep.figure(
        std_figure(noise_free, "gyro", "Noise-free: positioning error only"),
        "gyro_std_noise_free",
        f"Gyro scatter from the +-{sc['positioning_error_arcsec']:.3g} arcsec positioning error "
        f"alone ({paper}'s apparent regime).",
    )

    rep.heading("Accelerometers")
    for n in names:
        a = results["baseline"][n]["accel"]
        rep.paragraph(
            f"{n}: accelerometer rank {a['rank']} of 12. "
            + ("; ".join(a["identifiability_messages"]) or "All 12 parameters identifiable.")
        )
        rep.table(PARAMETER_HEADER, parameter_rows(a))

    _sweep_section(rep, results, four)
    rep.heading("Sensitivity to each position's positioning error")
    rep.paragraph(
        "First-order change of each gyro estimate per arcsec of positioning error at one "
        "position (the others exact), about "
        + sensitivity_axes_text(sc["positioning_model"])
        + ", in the parameter's unit per arcsec; max abs = largest magnitude, at = where it "
        "occurs. This is the linear map behind the 'pos. sigma' column above "
        "(CalibrationDesign.positioning_sensitivity, checked against finite differences)."
    )
    for n in names:
        block = results["baseline"][n]["positioning_sensitivity"]
        rep.paragraph(sensitivity_sentence(n, block, sc["positioning_error_arcsec"]))
        rep.table(*sensitivity_table(block, sc["positioning_model"]))
    _design_section(rep, results["design"], paper)
    rep.results = results
    return rep


def _sweep_section(rep: Report, results: dict[str, Any], four: str) -> None:
    from inserr.calibration.figures import class_sweep_figure

    sc, sw = results["scenario"], results["sweeps"]
    rep.heading("Dwell time, gyro noise and positioning error")
    rep.figure(
        class_sweep_figure(
            sw["dwell"], "total calibration time [s]", "Dwell sweep (x = total time)"
        ),
        "sweep_dwell",
        f"Dwell {', '.join(_fmt(d) for d in sw['dwell_s'])} s per position; RMS over each class.",
    )
    arw_series = {n: {**s, "x": sw["arw_deg_per_sqrt_h"]} for n, s in sw["arw"].items()}
    rep.figure(
        class_sweep_figure(arw_series, "ARW [deg/sqrt(h)]", "Gyro noise sweep"),
        "sweep_arw",
        "At equal dwell; below ~1e-4 deg/sqrt(h) the positioning error takes over.",
    )
    x = sw["positioning_error_arcsec"]
    pos_series = {
        **{n: {**s, "x": x} for n, s in sw["positioning"].items()},
        **{f"{n} noise-free": {**s, "x": x} for n, s in sw["positioning_noise_free"].items()},
    }
    rep.figure(
        class_sweep_figure(
            pos_series, "positioning error half-width [arcsec]", "Positioning error sweep"
        ),
        "sweep_positioning",
        "With the baseline noise and without noise.",
    )
    cross = results["noise_positioning_crossover_dwell_s"]
    rep.paragraph(
        f"For {four}, the +-{sc['positioning_error_arcsec']:.3g} arcsec positioning error equals "
        f"the ARW noise only at a dwell of {cross['sf'] / 3600:.3g} h (scale factors), "
        f"{cross['mis'] / 3600:.3g} h (misalignments) and {cross['bias'] / 3600:.3g} h "
        "(biases) per position: at any practical dwell the sensor noise dominates, and the "
        "positioning error matters only for gyros far quieter than this one."
    )
    m = results["positioning_models"]
    rep.paragraph("Positioning-error model, noise-free, RMS std per class (ppm, arcsec, deg/h):")
    rep.table(
        ["model", "set", "sf", "mis", "bias"],
        [[mo, n, r["sf"], r["mis"], r["bias"]] for mo, per in m.items() for n, r in per.items()],
    )
    if "per_sample_check" in results:
        rep.paragraph(
            "Cross-check of the dwell-average shortcut: the same Monte Carlo with every 100 Hz "
            "sample simulated (no positioning error). RMS std per class:"
        )
        rep.table(
            ["set", "class", "per-sample MC", "shortcut MC", "CRLB"],
            [
                [n, cls, r["per_sample"][cls], r["shortcut"][cls], r["crlb"][cls]]
                for n, r in results["per_sample_check"].items()
                for cls in CLASSES
            ],
        )


def _design_section(rep: Report, design: dict[str, Any], paper: str) -> None:
    rep.heading(f"Beyond {paper}: designed position sets")
    for sensors, d in design.items():
        rep.paragraph(
            f"Ranked by det(FIM)^(1/12) per second of total time; must identify, and moves: "
            f"{sensors}. Efficiency 1 = best found. Reference sets: "
            + ", ".join(
                f"{n} {e:.3f}" if e > 0 else f"{n} not full rank"
                for n, e in d["reference_efficiency"].items()
            )
            + "."
        )
        rep.table(
            ["mechanism", "n", "stops (outer, inner) deg", "time s", "gyro rank", "accel rank"]
            + ["efficiency"],
            [
                [
                    c["mechanism"],
                    c["n_positions"],
                    " ".join(f"({o},{i})" for o, i in c["stops_outer_inner_deg"]),
                    c["total_time_s"],
                    c["gyro_rank"],
                    c["accel_rank"],
                    c["relative_efficiency"],
                ]
                for c in d["candidates"]
            ],
        )
        best4 = d["best_four_position_efficiency"]
        rep.paragraph(
            f"Best full-rank four-position set per mechanism ({sensors}), efficiency: "
            + "; ".join(f"{m} {e:.3f}" if e is not None else f"{m}: none" for m, e in best4.items())
            + "."
        )
