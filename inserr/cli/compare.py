"""``inserr compare``: several indexing schemes on one scenario, one table, overlaid plots."""

from __future__ import annotations

import argparse

from inserr.cli.common import add_json_flag, emit, format_table
from inserr.core.errors import InputError
from inserr.output.progress import progress
from inserr.scenario.flags import add_scenario_flags, scenario_from_args


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_scenario_flags(p)
    p.add_argument(
        "--schemes",
        default=None,
        help="comma-separated scheme names (default: the scenario's [compare] list)",
    )
    p.add_argument("--out", default=None, help="write a report directory here")
    add_json_flag(p)


def run(args: argparse.Namespace) -> int:
    from inserr.drift.report import build_report
    from inserr.drift.study import metrics_table, run_scheme

    scen = scenario_from_args(args)
    names = tuple(s.strip() for s in args.schemes.split(",")) if args.schemes else scen.compare
    if not names:
        raise InputError(
            "--schemes", "no schemes to compare", "give --schemes a,b,c or a [compare] list"
        )
    for n in names:
        scen.scheme(n)  # validate every name before any work
    runs = [run_scheme(scen, n) for n in progress(names, total=len(names), desc="schemes")]
    if args.out:
        build_report(scen, runs, f"inserr scheme comparison: {scen.name}").write(args.out)
    header, rows = metrics_table(runs)
    emit(
        args,
        {"scenario": scen.name, "runs": [r.metrics() for r in runs]},
        format_table(header, rows),
    )
    return 0
