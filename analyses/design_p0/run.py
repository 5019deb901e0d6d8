"""Design for P0's vehicle (issue 17): the schedule robust to its swing, and for a static base.

Reads ``scenario.toml`` beside this file: P0's site, IMU budget, initial errors,
tilted vehicle and table; its ``[design]`` section is the single-axis family, P0's
36-case swing grid (12 periods x 3 peak yaw rates) and 36 held-out swings. Two
designs run through ``inserr.design.study.run_design`` (the code of ``inserr
design``):

* **P0 vehicle**: the design of the scenario as it is; the output directory is that
  design's directory (resumable: rerun to resume, nothing is recomputed);
* **closed-loop rule**: the same motions, the nulling rule's parameters designed
  (``design.family = nulling``), its lengthening of a stop allowed to reach one to two
  periods of the longest swing of the range (1200 to 2400 s), so that it can shift the
  turn phase by a whole swing at any period (the catalogue rule lengthens by at most
  its stop), in ``nulling/``;
* **static base**: the same vehicle at rest (``motion.type = static``), designed for
  that one motion, in ``static/``.

The write-up ``REPORT.md`` (generated, with ``results.json`` and the figures) holds
the P0 design's report, the verdicts of issue 17 and the static-base design.

    python analyses/design_p0/run.py [--quick] [--out DIR] [--workers N] [--scheduler ADDR]

``--quick`` designs for 6 h runs, three swings and a small budget, into
``results/quick/``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from inserr.design import figures
from inserr.design.motions import build_motion
from inserr.design.study import DesignOutcome, build_report, run_design
from inserr.output.report import write_text_atomic
from inserr.scenario.schema import Scenario, load_scenario, scenario_from_dict

HERE = Path(__file__).resolve().parent
QUICK = {
    "scenario.duration": "6 h",
    "design.periods": "30, 120, 660 s",
    "design.amplitudes": "6 deg/s",
    "design.held_out": 3,
    "design.budget": 20,
    "design.population": 10,
    "design.verify": 3,
    "design.screen_duration": "6 h",
}
STATIC = {"design.motions": "scenario", "design.held_out": 0}
#: The closed-loop design: three variables, so a smaller population and budget (its
#: candidates plan a closed-loop rule on every motion: the costly part).
NULLING = {
    "design.family": "nulling",
    "design.extension_range": "1200, 2400 s",
    "design.budget": 60,
    "design.population": 10,
}


def at_rest(scen: Scenario) -> Scenario:
    """The same vehicle at rest: a static motion at its heading, pitch and roll (the
    swing's amplitude and period dropped, as a static motion reads neither)."""
    raw = json.loads(json.dumps(scen.raw))
    raw["motion"] = {
        k: v for k, v in raw["motion"].items() if k in ("heading", "pitch", "roll")
    } | {"type": "static"}
    return scenario_from_dict(raw, scen.base_dir)


def _below(ch: dict, cat: list[dict], key: str, where: str) -> str:
    """The sentence comparing the designed schedule's ``key`` with every catalogue scheme's."""
    best = min(cat, key=lambda c: c[key])
    beaten = [c["label"] for c in cat if c[key] <= ch[key]]
    text = (
        f"{where} the designed schedule's worst RMS is {ch[key]:.4g} nmi; the best catalogue "
        f"scheme's is {best[key]:.4g} nmi ({best['label']}). "
    )
    if beaten:
        return text + f"It is NOT below: {', '.join(beaten)} do as well or better."
    tie = ch[key] > 0.99 * best[key]
    return (
        text
        + "The designed schedule is below every catalogue scheme"
        + (" (by less than 1 %: a tie in practice)." if tie else ".")
    )


def verdicts(o: DesignOutcome) -> list[str]:
    """Issue 17's done-when, as sentences computed from the results."""
    r = o.results
    ch = r["chosen"]
    cat = r["catalogue"]
    trad = next(c for c in cat if c["label"] == "two-position")
    grid = o.settings.grid
    out = []
    if grid:
        out.append(_below(ch, cat, "grid_worst_nmi", f"On P0's {grid}-case grid"))
        out.append(
            _below(
                ch,
                cat,
                "worst_nmi",
                f"On the whole motion set the search saw (the grid and "
                f"{len(o.settings.motions) - grid} training draws)",
            )
        )
    else:
        out.append(_below(ch, cat, "worst_nmi", "On the motion set"))
    out.append(
        f"Motor starts: {ch['starts_per_hour']:.4g} per hour against the traditional cycle's "
        f"{trad['starts_per_hour']:.4g} "
        + ("(no more)." if ch["starts_per_hour"] <= trad["starts_per_hour"] else "(MORE).")
    )
    if "held_out_worst_nmi" in ch:
        hbest = min(
            (c for c in cat if "held_out_worst_nmi" in c), key=lambda c: c["held_out_worst_nmi"]
        )
        ok = [c for c in cat if "held_out_worst_nmi" in c and c["meets_constraints"]]
        hok = min(ok, key=lambda c: c["held_out_worst_nmi"]) if ok else None
        held_beaten = [
            c["label"] + ("" if c["meets_constraints"] else " (which breaks the constraints)")
            for c in cat
            if c.get("held_out_worst_nmi", 1e9) <= ch["held_out_worst_nmi"]
        ]
        out.append(
            f"On the {len(ch['held_out_rms_nmi'])} held-out motions the designed schedule's "
            f"worst RMS is {ch['held_out_worst_nmi']:.4g} nmi (at "
            f"{ch['held_out_worst_motion']}); the best catalogue scheme's is "
            f"{hbest['held_out_worst_nmi']:.4g} nmi ({hbest['label']})"
            + (
                f", of those that meet the constraints {hok['held_out_worst_nmi']:.4g} nmi "
                f"({hok['label']}). "
                if hok is not None and hok is not hbest
                else ". "
            )
            + (
                "The design holds on motions it never saw."
                if not held_beaten
                else f"It does NOT hold there: {', '.join(held_beaten)} do as well or better."
            )
        )
    if "held_out_worst_nmi" in ch:
        # An open-loop cycle repeats its turn times: a swing whose period divides the cycle
        # (near enough) meets every turn at the same phase, and the error grows cycle after
        # cycle. Say how close the held-out worst case is to such a period.
        worst = next(m for m in o.settings.held_out if m.label == ch["held_out_worst_motion"])
        for name, length in cycle_lengths(o):
            if worst.period is None:
                break
            ratio = length / worst.period
            out.append(
                f"The designed {name} lasts {length:.1f} s; the held-out worst swing's "
                f"period is {worst.period:.1f} s, {ratio:.3f} of which fit in it (nearest "
                f"whole number {round(ratio)}"
                + (": a resonance of the repeated cycle)." if abs(ratio - round(ratio)) < 0.05
                   else ")."),
            )  # fmt: skip
    if r["motion_evaluations_computed"] == 0:
        out.append(
            f"Every evaluation of this write-up came from the design's cache "
            f"({r['evaluations_in_cache_at_start']} evaluations, computed by an earlier run "
            "of the same design; run times in docs/design.md)."
        )
    else:
        out.append(
            f"Run time of the design: {r['seconds']:.0f} s ({r['engine']}; "
            f"{r['motion_evaluations_computed']} motion evaluations computed, "
            f"{r['evaluations_in_cache_at_start']} taken from the cache)."
        )
    return out


def meets_issue_17(o: DesignOutcome) -> bool:
    """Whether a design meets issue 17's done-when: its worst on the grid strictly below
    every catalogue scheme's, no more motor starts per hour than the traditional cycle,
    and its held-out worst strictly below every catalogue scheme's."""
    r = o.results
    ch, cat = r["chosen"], r["catalogue"]
    trad = next(c for c in cat if c["label"] == "two-position")
    held = [c["held_out_worst_nmi"] for c in cat if "held_out_worst_nmi" in c]
    return (
        bool(o.settings.grid)
        and all(ch["grid_worst_nmi"] < c["grid_worst_nmi"] for c in cat)
        and ch["starts_per_hour"] <= trad["starts_per_hour"]
        and "held_out_worst_nmi" in ch
        and all(ch["held_out_worst_nmi"] < h for h in held)
    )


def summary(designs: list[tuple[str, DesignOutcome]]) -> str:
    """One sentence: which of the designs meets issue 17's done-when (:func:`meets_issue_17`)."""
    met = [name for name, o in designs if meets_issue_17(o)]
    missed = [name for name, o in designs if not meets_issue_17(o)]
    if not met:
        return (
            "No design here meets issue 17's done-when (below every catalogue scheme on the "
            "grid and on the held-out swings, at no more motor starts than the traditional "
            "cycle); the sentences below say where each falls short."
        )
    return (
        f"Issue 17's done-when (below every catalogue scheme on the grid and on the held-out "
        f"swings, at no more motor starts than the traditional cycle) is met by the "
        f"{' and the '.join(met)}"
        + (f", not by the {' or the '.join(missed)}" if missed else "")
        + ". The sentences below give each design's figures."
    )


def cycle_lengths(o: DesignOutcome) -> list[tuple[str, float]]:
    """The chosen open-loop schedule's cycle lengths (s): one for a repeated cycle, A and B
    for the golden order (a closed-loop rule has none)."""
    from inserr.design.families import SingleAxis

    fam = o.settings.family
    if not isinstance(fam, SingleAxis) or o.chosen is None:
        return []
    sch = fam.decode(o.chosen.desc["vars"]).scheme
    if fam.name == "single-axis":
        return [("cycle", sch.cycle_time)]
    # golden: the cycle starts are the starts of every m-th stop at position 0
    m = len(fam._cycle(o.chosen.desc["vars"][:-1])[0])
    table = sch.plan(build_motion(o.settings.motions[0].spec), 4 * 3600.0)
    stops = [k for k in range(len(table)) if table.kind[k] == "stop"]
    lengths = sorted(set(np.round(np.diff([table.t0[k] for k in stops[::m]]), 6)))
    return [("cycle A", lengths[0]), ("cycle B", lengths[-1])]


def held_out_budgets(scen: Scenario, o: DesignOutcome) -> list[list]:
    """Per-source budget of the held-out worst cases: of the designed schedule and of the
    best catalogue scheme that meets the constraints, each on both worst motions.

    Rows: scheme, motion, RMS (nmi), time of the peak (h), the four largest sources.
    """
    from inserr.design.objective import ErrorBudget, candidate_scheme

    st = o.settings
    if o.chosen is None or o.chosen.held is None:
        return []
    ok = [c for c in o.catalogue if c.outcome.feasible and c.held is not None]
    if not ok:
        return []
    best = min(ok, key=lambda c: max(c.held.rms.values()))
    budget = ErrorBudget(scen, st.full.exclude)
    worst = [st.held_out[max(s.held.rms, key=s.held.rms.get)] for s in (o.chosen, best)]
    rows = []
    for s in (o.chosen, best):
        sch = candidate_scheme(s.desc, scen)
        for m in dict.fromkeys(worst, None):
            motion = build_motion(m.spec)
            t, rms, src = budget.breakdown(sch.plan(motion, st.full.duration), motion, st.full)
            top = ", ".join(f"{n} {v:.3g}" for n, v in src[:4])
            name = "designed" if s is o.chosen else s.label
            rows.append([name, m.label, rms, t / 3600.0, top])
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="6 h runs, 3 swings, results/quick/")
    ap.add_argument("--out", default=None, help="output directory (default results/)")
    ap.add_argument("--workers", type=int, default=None, help="local worker processes")
    ap.add_argument("--scheduler", default=None, help="Dask scheduler (tcp://HOST:PORT)")
    args = ap.parse_args(argv)
    out = Path(args.out) if args.out else HERE / "results" / ("quick" if args.quick else "")
    scen = load_scenario(HERE / "scenario.toml")
    if args.quick:
        scen = scen.with_changes(QUICK)
    engine = {"scheduler": args.scheduler, "workers": args.workers}
    p0 = run_design(scen, out_dir=out, markdown_name="REPORT.md", **engine)
    print(f"P0 vehicle: chosen {p0.results['chosen']['label']}", file=sys.stderr)
    nul_scen = scen.with_changes(QUICK | NULLING if args.quick else NULLING)
    nul = run_design(nul_scen, out_dir=out / "nulling", markdown_name="REPORT.md", **engine)
    print(f"closed-loop rule: chosen {nul.results['chosen']['label']}", file=sys.stderr)
    static_scen = at_rest(scen).with_changes(STATIC)
    static = run_design(static_scen, out_dir=out / "static", markdown_name="REPORT.md", **engine)
    print(f"static base: chosen {static.results['chosen']['label']}", file=sys.stderr)

    rep = build_report(scen, p0, "Designing the indexing schedule for P0's vehicle (issue 17)")
    rep.heading("Verdicts (issue 17)")
    rep.paragraph(
        summary(
            [
                ("designed open-loop single-axis cycle", p0),
                ("designed closed-loop single-axis rule (nulling family, next section)", nul),
            ]
        )
    )
    rep.paragraph("The designed open-loop single-axis cycle:")
    for line in verdicts(p0):
        rep.paragraph(line)
    rows = held_out_budgets(scen, p0)
    if rows:
        rep.heading("What makes the held-out worst cases")
        rep.paragraph(
            "The per-source budget (nmi, each source's horizontal error at the peak of the "
            "RMS; their root sum of squares is the RMS) of the designed schedule and of the "
            "best catalogue scheme that meets the constraints, each on both schedules' "
            "held-out worst motions, at the full horizon."
        )
        rep.table(["scheme", "motion", "RMS (nmi)", "peak at (h)", "largest sources (nmi)"], rows)
    rep.heading("A closed-loop rule designed for the same motions")
    nr = nul.results
    ext = nr["settings"]["family"]["settings"]["extension_range"]
    rep.paragraph(
        f"The nulling rule's parameters designed for the same grid (minimum stop, longest "
        f"lengthening of a stop from {ext[0]:g} to {ext[1]:g} s, rate; full "
        f"report in `nulling/REPORT.md`): chosen {nr['chosen']['label']}."
    )
    for line in verdicts(nul):
        rep.paragraph(line)
    rep.heading("A static base")
    st = static.results
    rep.paragraph(
        f"The same vehicle at rest, designed for that one motion (same family, budget and "
        f"constraints; full report in `static/REPORT.md`): chosen "
        f"{st['chosen']['label']}, RMS {st['chosen']['worst_nmi']:.4g} nmi at "
        f"{st['chosen']['starts_per_hour']:.4g} motor starts per hour."
    )
    rows = [st["chosen"]] + st["catalogue"]
    rep.table(
        ["scheme", "RMS (nmi)", "starts/h", "meets constraints"],
        [
            [
                ("designed: " if c is st["chosen"] else "") + c["label"][:60],
                c["worst_nmi"],
                c["starts_per_hour"],
                "yes" if c["meets_constraints"] else "no",
            ]
            for c in sorted(rows, key=lambda c: c["worst_nmi"])
        ],  # fmt: skip
    )
    rep.figure(
        figures.comparison(
            [
                {
                    "label": "designed" if c is st["chosen"] else c["label"],
                    "values": c["rms_nmi"],
                    "designed": c is st["chosen"],
                    "feasible": c["meets_constraints"],
                }
                for c in rows
            ],  # fmt: skip
            "Static base",
        ),
        "compare_static",
        "Static base: the designed schedule and every catalogue scheme",
    )
    rep.results = {
        "p0_vehicle": p0.results,
        "p0_vehicle_nulling": nul.results,
        "static_base": static.results,
    }
    rep.write_into(out, markdown_name="REPORT.md")
    write_text_atomic(out / "report.html", rep.html())
    print(out / "REPORT.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
