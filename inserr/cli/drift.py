"""``inserr drift``: free-inertial drift of an IMU budget under an indexing scheme."""

from __future__ import annotations

import argparse

from inserr.cli.common import add_json_flag, emit, format_table
from inserr.scenario.flags import DRIFT, add_flags, scenario_from_args


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_flags(p, "drift", DRIFT)
    p.add_argument("--out", default=None, help="also write a report directory here")
    add_json_flag(p)


def run(args: argparse.Namespace) -> int:
    from inserr.drift.report import build_report
    from inserr.drift.study import run_scheme

    scen = scenario_from_args(args)
    r = run_scheme(scen)
    m = r.metrics()
    if args.out:
        build_report(scen, [r]).write(args.out)
    budget = list(m["error_budget"].items())[:8]
    human = (
        f"scheme {m['scheme']}, {m['hours']:g} h, {scen.motion.describe(scen.heading_convention)}\n"
        + format_table(
            ["metric", "value"],
            [
                ["max horizontal error (nmi)", m["max_horizontal_error_nmi"]],
                ["final horizontal error (nmi)", m["final_horizontal_error_nmi"]],
                ["final horizontal 1-sigma, noise (nmi)", m["final_horizontal_1sigma_nmi"]],
                ["RMS horizontal, unknown signs (nmi)", m["rms_horizontal_error_nmi"]],
                ["worst sign pattern (nmi)", m["worst_case_horizontal_error_nmi"]],
                ["final heading error (deg)", m["final_heading_error_deg"]],
                ["motor starts per hour", m["motor_starts_per_hour"]],
            ],
        )
        + "\n\nlargest error sources (RMS horizontal at the end, nmi)\n"
        + format_table(["source", "nmi"], [[k, v] for k, v in budget])
    )
    for w in m["warnings"]:
        human += f"\nwarning: {w}"
    emit(args, m, human)
    return 0
