"""P2 reproduction: none vs four-position vs modified four-position on a static base.

Runs ``scenario.toml``'s schemes with the full error budget and without the up-gyro bias,
opening with a stop and with the first turn (as P2 writes its cycle), adds the closed-form
cycle integrals (:mod:`inserr.drift.comparison`) and writes ``results/`` (figures,
``results.json``, ``REPORT.md``, every number taken from the results).

    python analyses/p2_four_position/run.py [--scenario FILE] [--out DIR]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from inserr.core.errors import InputError
from inserr.core.units import DEG, DEG_PER_HOUR, G0, MICRO_G
from inserr.drift import figures as plots
from inserr.drift.comparison import cycle_summary, drift_summary, heading_figure
from inserr.drift.study import describe, run_scheme
from inserr.output.report import Report, check_report_dir
from inserr.scenario.schema import load_scenario

HERE = Path(__file__).resolve().parent
VARIANTS = {"full": "full budget", "no_up_gyro": "up-gyro bias removed"}
STARTS = {"stop": "stop first", "turn": "turn first"}
FOUR, MOD = "four-position", "four-position-modified"
COLUMNS = {  # column -> key of drift_summary
    "max horiz (nmi)": "max_horizontal_nmi", "final horiz (nmi)": "final_horizontal_nmi",
    "RMS unknown signs (nmi)": "rms_unknown_signs_nmi", "worst signs (nmi)": "worst_signs_nmi",
    "max abs heading (arcmin)": "max_abs_heading_error_arcmin",
    "motor starts/h": "motor_starts_per_hour",
}  # fmt: skip


def azimuth_verdict(full: dict) -> tuple[bool | None, str]:
    """P2's azimuth claim on one opening's full-budget runs: (holds?, evidence). Holds if the
    modification halves the largest heading error; fails if they differ by under 10 % and the
    up-gyro bias dominates the modified heading; else 'partly' (None)."""
    a4, am = (full[n]["max_abs_heading_error_arcmin"] for n in (FOUR, MOD))
    dominant = next(iter(full[MOD]["heading_budget_arcmin"]))
    gap = abs(am - a4) / max(a4, 1e-12)
    holds = True if am < 0.5 * a4 else (False if gap < 0.1 and dominant == "gyro_bias_z" else None)
    return holds, f"max |heading| {a4:.2f} vs {am:.2f} arcmin ({100 * gap:.1f} % apart), " + (
        f"{dominant} dominates"
    )


def claims(s: dict, cyc: dict, rate: float) -> list[dict]:
    """P2's claims, each with the model's verdict and evidence under each opening phase."""
    out = []
    closed = 2.0 * math.sqrt(2.0) / rate  # the traditional cycle's residual, s
    for start in STARTS:
        c4, cm = cyc[start][FOUR], cyc[start][MOD]
        h4 = np.asarray(c4["horizontal_cycle_integral_s"])
        hm = float(np.max(np.abs(np.asarray(cm["horizontal_cycle_integral_s"]))))
        stops4 = float(np.max(np.abs(np.asarray(c4["stops_horizontal_s"]))))
        noz, full = s[start]["no_up_gyro"], s[start]["full"]
        out += [
            (start, "the traditional cycle leaves a horizontal drift residual on a static base, "
             "from the turns", abs(h4[0, 0] - closed) <= 1e-9 * closed and stops4 <= 1e-9 * closed,
             f"cycle integral {h4[0, 0]:.3f} s (2 sqrt(2) / omega = {closed:.3f} s), stops "
             f"{stops4:.1e} s"),
            (start, "stops of Ts + 2/omega at A and D cancel it", hm <= 1e-9 * closed,
             f"modified cycle integral {hm:.1e} s, residual "
             f"{100 * c4['residual_drift_fraction']:.2f} % -> "
             f"{100 * cm['residual_drift_fraction']:.1e} % of the bias"),
            (start, "the modification lowers the horizontal error",
             noz[MOD]["max_horizontal_nmi"] < noz[FOUR]["max_horizontal_nmi"],
             f"72 h max without the up-gyro bias {noz[FOUR]['max_horizontal_nmi']:.3f} -> "
             f"{noz[MOD]['max_horizontal_nmi']:.3f} nmi; full budget "
             f"{full[FOUR]['max_horizontal_nmi']:.2f} -> {full[MOD]['max_horizontal_nmi']:.2f}"),
            (start, "the modification removes the azimuth-axis error growth",
             *azimuth_verdict(full)),
        ]  # fmt: skip
    return [{"start": a, "claim": b, "holds": c, "evidence": d} for a, b, c, d in out]


def build(scen, runs, s: dict, cyc: dict, timing: dict) -> Report:
    """The write-up: set-up and choices, against the paper, results, cycle integrals."""
    rep = Report("P2 reproduction: four-position indexing on a static base")
    rep.heading("Set-up")
    rep.table(["item", "value"], [list(r) for r in describe(scen)])
    ug = scen.imu.accel_bias[0] / MICRO_G
    rep.paragraph(
        f"Choices P2 does not make: latitude {math.degrees(scen.site.lat):g} deg (the project's "
        "reference site; P1 and P3 use 34 deg, P0's site is at 34.246 deg) and stop time "
        f"{scen.scheme_stop:g} s (P0's; the {cyc['stop'][FOUR]['cycle_time_s']:g} s cycle is "
        f"inside the 84.4 min Schuler period). Units: 1e-4 g is {ug:g} ug (inserr's ug is 1e-6 g0, "
        f"g0 = {G0} m/s^2). The base is level at heading {scen.motion.heading / DEG:g} deg (the "
        "same under both heading conventions); no initial errors and no noise, so every number "
        f"below is the propagation of the constant sensor errors (vertical channel "
        f"{scen.vertical}). Each scheme runs opening with a stop (the built-in schemes) and "
        "with its first turn (P2 writes its cycle turn first: A -> C, stop, ...)."
    )
    cl = claims(s, cyc, scen.scheme_rate)
    rep.heading("Against the paper")
    rep.paragraph(
        "P2 gives no table of results, only claims. Each claim, the model's verdict under "
        "each opening phase, and the evidence (stop first; the turn-first evidence is in "
        "results.json):"
    )
    word = {True: "holds", False: "fails", None: "partly"}
    by = {(c["start"], c["claim"]): c for c in cl}
    rows = [[c["claim"], *(word[by[(st, c["claim"])]["holds"]] for st in STARTS), c["evidence"]]
            for c in cl if c["start"] == "stop"]  # fmt: skip
    rep.table(["P2's claim", *STARTS.values(), "model (stop first)"], rows)
    az = {st: by[(st, cl[-1]["claim"])] for st in STARTS}
    rep.paragraph(
        "**Azimuth-axis claim: "
        + "; ".join(f"{STARTS[st]} the model says it {word[a['holds']]}" for st, a in az.items())
        + ".** Rotation about the up axis leaves the up gyro's bias unmodulated (its cycle "
        f"integral is the whole cycle, {cyc['stop'][MOD]['up_axis_cycle_integral_s']:.1f} s per "
        f"{cyc['stop'][MOD]['cycle_time_s']:.1f} s); "
        + "; ".join(f"{STARTS[st]}: {a['evidence']}" for st, a in az.items())
        + ". Without the up-gyro bias the largest heading error is "
        + "; ".join(
            f"{STARTS[st]} {s[st]['no_up_gyro'][FOUR]['max_abs_heading_error_arcmin']:.3f}"
            f" -> {s[st]['no_up_gyro'][MOD]['max_abs_heading_error_arcmin']:.3f} arcmin"
            for st in STARTS
        )  # fmt: skip
        + ": the modification removes only the part the horizontal residual feeds into heading."
    )
    rep.heading("Results (72 h, every error as given)")
    rows = [[STARTS[st], VARIANTS[k], n, *(v[c] for c in COLUMNS.values())]
            for st in STARTS for k in VARIANTS for n, v in s[st][k].items()]  # fmt: skip
    rep.table(["opening", "budget", "scheme", *COLUMNS], rows)
    for k, label in VARIANTS.items():
        results = {n: r.result for n, r in runs["stop"][k].items()}
        fig = plots.horizontal_error(results, title=f"Horizontal position error, {label}")
        rep.figure(fig, f"horizontal_{k}", f"Horizontal error (stop first), {label}")
    rep.heading("Cycle integrals (closed form, one cycle, static base)")
    rep.table(
        ["opening", "scheme", "cycle (s)", "E,x (s)", "N,y (s)", "turns E,x (s)",
         "residual (% of bias)", "equivalent drift (deg/h)", "motor starts/h"],
        [
            [STARTS[st], n, c["cycle_time_s"], c["horizontal_cycle_integral_s"][0][0],
             c["horizontal_cycle_integral_s"][1][1], c["turns_horizontal_s"][0][0],
             100 * c["residual_drift_fraction"], c["equivalent_horizontal_drift_deg_h"],
             c["motor_starts_per_hour"]]
            for st in STARTS
            for n, c in cyc[st].items()
        ],
    )  # fmt: skip
    rep.heading("Heading error")
    panels = {f"{VARIANTS[k]}, stop first": runs["stop"][k] for k in VARIANTS}
    rep.figure(heading_figure(panels), "heading_error", "Heading error of the three schemes")
    budget = runs["stop"]["full"][MOD].metrics()["error_budget"]
    fig = plots.error_budget(budget, title=f"Horizontal budget: {MOD}, full", scheme=MOD)
    rep.figure(fig, "budget_modified_full", "Per-source RMS horizontal error at 72 h, modified")
    rep.paragraph("Run time: " + ", ".join(f"{k} {v:.1f} s" for k, v in timing.items()) + ".")
    choices = {"latitude_deg": math.degrees(scen.site.lat), "stop_s": scen.scheme_stop,
               "g0_m_s2": G0, "accel_bias_ug": ug, "accel_bias_g": scen.imu.accel_bias[0] / G0,
               "heading_convention": scen.heading_convention}  # fmt: skip
    rep.results = {
        "scenario": scen.name,
        "choices": choices,
        "runs": s,
        "cycle_integrals": cyc,
        "claims": cl,
        "timing_s": timing,
    }
    return rep


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenario", default=str(HERE / "scenario.toml"))
    ap.add_argument("--out", default=str(HERE / "results"))
    args = ap.parse_args(argv)
    try:
        check_report_dir(args.out, "--out")  # before any work: never replace a user's directory
    except InputError as exc:
        print(f"run.py: error: {exc}", file=sys.stderr)
        return 2
    base = load_scenario(args.scenario)
    bx, by, _ = base.imu.gyro_bias / DEG_PER_HOUR
    runs, s, cyc, timing = {}, {}, {}, {}
    for st in STARTS:
        scen = base.with_changes({"scheme.start": st})
        no_z = scen.with_changes({"imu.gyro_bias": f"{bx},{by},0 deg/h"})
        cyc[st] = cycle_summary(scen, [n for n in scen.compare if n != "none"])
        runs[st], s[st] = {"full": {}, "no_up_gyro": {}}, {}
        for k, sc in {"full": scen, "no_up_gyro": no_z}.items():
            for n in scen.compare:
                t0 = time.perf_counter()
                runs[st][k][n] = run_scheme(sc, n)
                timing[f"{n} ({k}, {STARTS[st]})"] = time.perf_counter() - t0
            s[st][k] = {n: drift_summary(r) for n, r in runs[st][k].items()}
    print(build(base, runs, s, cyc, timing).write(args.out, markdown_name="REPORT.md"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
