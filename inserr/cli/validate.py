"""``inserr validate``: linear prediction against the nonlinear strapdown reference.

Same scenario flags as ``inserr drift`` plus the reference's own: ``--runs N``
(N > 1 adds a Monte Carlo compared with the covariance by a chi-square test),
``--seed K``, ``--imu-rate HZ`` (default 100 Hz, P0's), ``--chunk H``,
``--confidence C`` and ``--random-constants``. Needs the optional extra
``inserr[reference]`` (python-ins).
"""

from __future__ import annotations

import argparse

from inserr.cli.common import (
    add_json_flag,
    emit,
    finite_float,
    format_table,
    positive_float,
    positive_int,
)
from inserr.scenario.flags import add_scenario_flags, scenario_from_args


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_scenario_flags(p)
    p.add_argument(
        "--runs",
        type=positive_int,
        default=1,
        help="1: deterministic comparison only (default); N > 1: also N Monte Carlo runs",
    )
    p.add_argument(
        "--seed", type=int, default=None, help="Monte Carlo seed (default: the scenario's, 0)"
    )
    p.add_argument(
        "--imu-rate",
        type=positive_float,
        default=100.0,
        metavar="HZ",
        help="IMU sample rate of the nonlinear reference, Hz (default 100)",
    )
    p.add_argument(
        "--chunk",
        type=positive_float,
        default=1.0,
        metavar="H",
        help="reference chunk length, h (bounds memory; default 1)",
    )
    p.add_argument(
        "--confidence",
        type=finite_float,
        default=0.99,
        help="confidence of the two-sided chi-square consistency test (default 0.99)",
    )
    p.add_argument(
        "--random-constants",
        action="store_true",
        help="Monte Carlo also draws the constant errors (zero mean, 1 sigma = magnitude)",
    )
    p.add_argument(
        "--out", default=None, help="also write a report directory with the overlay plots"
    )
    add_json_flag(p)


def run(args: argparse.Namespace) -> int:
    from inserr.core.units import HOUR
    from inserr.reference.report import build_report
    from inserr.reference.strapdown import require_pyins
    from inserr.reference.validation import validate

    scen = scenario_from_args(args)
    require_pyins()
    v = validate(
        scen,
        runs=args.runs,
        seed=args.seed,
        rate=args.imu_rate,
        chunk=args.chunk * HOUR,
        confidence=args.confidence,
        random_constants=args.random_constants,
    )
    if args.out:
        build_report(v).write(args.out)
    s = v.summary()
    rows = [
        [k, v_]
        for k, v_ in s.items()
        if k not in ("monte_carlo", "notes", "scenario") and v_ is not None
    ]
    human = f"scheme {s['scheme']}, {s['hours']:g} h, IMU {s['imu_rate_hz']:g} Hz\n" + format_table(
        ["metric", "value"], rows
    )
    if "monte_carlo" in s:
        mc = s["monte_carlo"]
        mrows = [
            [k, val]
            for k, val in mc.items()
            if k not in ("chi2", "sample_mean_horizontal_m") and val is not None
        ]
        if "chi2" in mc:
            c = mc["chi2"]
            mrows.append(
                [
                    "chi-square",
                    f"{c['statistic']:.4g} in [{c['lower']:.4g}, {c['upper']:.4g}] "
                    f"({c['dof']} dof, "
                    f"{100 * c['confidence']:g} % two-sided), p = {c['p_value']:.3g}",
                ]
            )
        human += "\n\nMonte Carlo vs covariance (final time)\n" + format_table(
            ["metric", "value"], mrows
        )
    for note in s["notes"]:
        human += f"\nnote: {note}"
    emit(args, s, human)
    return 0
