"""``inserr validate``: linear prediction against the nonlinear strapdown reference.

Same scenario flags as ``inserr drift`` plus the reference's own: ``--runs N``
(N > 1 adds a Monte Carlo compared with the covariance by a chi-square test),
``--seed K``, ``--sample-rate HZ`` (the reference's IMU rate, default 100 Hz, P0's),
``--chunk H``, ``--confidence C`` and ``--random-constants`` (scenario keys
``scenario.runs``, ``scenario.seed``, ``imu.sample_rate`` and ``[validate]``). Needs
the optional extra ``inserr[reference]`` (python-ins).
"""

from __future__ import annotations

import argparse

from inserr.cli.common import add_json_flag, emit, format_table, stamp
from inserr.scenario.flags import DRIFT, add_flags, scenario_from_args

#: The flags of ``inserr validate``: the drift scenario and the reference's settings.
FLAG_NAMES = (
    *DRIFT,
    "runs",
    "seed",
    "sample-rate",
    "chunk",
    "confidence",
    "random-constants",
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_flags(p, "drift", FLAG_NAMES)
    p.add_argument(
        "--out", default=None, help="also write a report directory with the overlay plots"
    )
    add_json_flag(p)


def run(args: argparse.Namespace) -> int:
    from inserr.reference.report import build_report
    from inserr.reference.strapdown import require_pyins
    from inserr.reference.validation import validate_scenario

    scen = scenario_from_args(args)
    require_pyins()
    v = validate_scenario(scen)
    if args.out:
        stamp(build_report(v), scen, args).write(args.out)
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
