"""``inserr drift``: free-inertial drift of an IMU budget under an indexing scheme."""

from __future__ import annotations

import argparse

from inserr.cli.common import add_json_flag, emit, format_table, warn_empty_budget
from inserr.scenario.flags import DRIFT, add_flags, scenario_from_args


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_flags(p, "drift", DRIFT)
    p.add_argument("--out", default=None, help="also write a report directory here")
    add_json_flag(p)


def run(args: argparse.Namespace) -> int:
    from inserr.drift.budget import source_label
    from inserr.drift.report import build_report
    from inserr.drift.study import EMPTY_BUDGET, METRIC_COLUMNS, metric_values, run_scheme

    scen = scenario_from_args(args)
    r = run_scheme(scen)
    m = r.metrics()
    if args.out:
        build_report(scen, [r], source=getattr(args, "scenario", None)).write(args.out)
    warn_empty_budget(args, [r])
    budget = [(source_label(k), v) for k, v in list(m["error_budget"].items())[:8]]
    human = (
        f"scheme {m['scheme']}, {m['hours']:g} h, {scen.motion.describe(scen.heading_convention)}\n"
        + format_table(
            ["metric", "value"],
            [[label, value] for label, value in zip(METRIC_COLUMNS, metric_values(r), strict=True)],
        )
        + "\n\nlargest error sources (RMS horizontal at the end, nmi)\n"
        + format_table(["source", "nmi"], [[k, v] for k, v in budget])
    )
    for w in m["warnings"]:
        if w != EMPTY_BUDGET:  # said on stderr, with the flag to use
            human += f"\nwarning: {w}"
    emit(args, m, human)
    return 0
