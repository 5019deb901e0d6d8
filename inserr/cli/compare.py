"""``inserr compare``: several indexing schemes on one scenario, one table, overlaid plots."""

from __future__ import annotations

import argparse

from inserr.cli.common import add_json_flag, by_column, emit, format_table, warn_empty_budget
from inserr.output.progress import progress
from inserr.scenario.flags import DRIFT, add_flags, scenario_from_args


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_flags(p, "drift", (*DRIFT, "schemes"))
    p.add_argument("--out", default=None, help="write a report directory here")
    add_json_flag(p)


def run(args: argparse.Namespace) -> int:
    from inserr.drift.report import build_report
    from inserr.drift.study import compared_schemes, metrics_table, run_scheme

    scen = scenario_from_args(args)
    names = compared_schemes(scen)
    runs = [run_scheme(scen, n) for n in progress(names, total=len(names), desc="schemes")]
    if args.out:
        build_report(
            scen, runs, f"inserr scheme comparison: {scen.name}", getattr(args, "scenario", None)
        ).write(args.out)
    header, rows = by_column(*metrics_table(runs))
    warn_empty_budget(args, runs)
    emit(
        args,
        {"scenario": scen.name, "runs": [r.metrics() for r in runs]},
        format_table(header, rows),
    )
    return 0
