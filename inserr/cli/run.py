"""``inserr run SCENARIO.toml``: run a scenario file and write its report directory."""

from __future__ import annotations

import argparse
from pathlib import Path

from inserr.cli.common import add_json_flag, by_column, emit, format_table, warn_empty_budget
from inserr.output.progress import progress


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scenario", help="scenario TOML file")
    p.add_argument("--out", default=None, help="report directory (default: <scenario stem>_report)")
    add_json_flag(p)


def run(args: argparse.Namespace) -> int:
    from inserr.drift.report import build_report
    from inserr.drift.study import metrics_table, run_scheme
    from inserr.output.report import check_report_dir
    from inserr.scenario.schema import load_scenario

    scen = load_scenario(args.scenario)
    out = args.out
    if out is None:  # a given --out was checked by the CLI entry point already
        out = f"{Path(args.scenario).stem}_report"
        check_report_dir(out, inputs=[args.scenario])
    names = (scen.scheme_name,) + tuple(n for n in scen.compare if n != scen.scheme_name)
    runs = [run_scheme(scen, n) for n in progress(names, total=len(names), desc="schemes")]
    path = build_report(scen, runs, source=args.scenario).write(out)
    header, rows = by_column(*metrics_table(runs))
    warn_empty_budget(args, runs)
    emit(
        args,
        {"scenario": scen.name, "report": str(path), "runs": [r.metrics() for r in runs]},
        format_table(header, rows) + f"\n\nreport written to {out}/report.html",
    )
    return 0
