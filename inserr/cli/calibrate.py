"""``inserr calibrate``: multi-position gyro/accelerometer calibration study (P1).

Examples::

    inserr calibrate --method offaxis-four-position --runs 100 --seed 1 --json
    inserr calibrate --method six-position --stop 600 --arw 0.001
    inserr calibrate --method my_set.toml --lat 45
    inserr calibrate --design --design-sizes 4,6 --top 5
    inserr calibrate my_calibration.toml --runs 20

The inputs are a ``calibration`` scenario (file and/or flags; see
:mod:`inserr.calibration.inputs`): ``--stop`` is the dwell at every position,
``--rate`` the indexing rate, the ``[imu]`` flags the true errors and noise (P1's by
default). Output units (human and JSON): scale factors ppm, misalignments arcsec, gyro
biases deg/h, accelerometer biases ug, times s; sensitivities to the table's positioning
error in those units per arcsec (``positioning_sensitivity``). Every flag that takes a
quantity accepts a bare number in the unit given in its help, or the number with a unit
written (``--arw "0.03 deg/sqrt(h)"``).
"""

from __future__ import annotations

import argparse
import math

from inserr.cli.common import add_json_flag, emit, format_table, stamp
from inserr.core.units import DEG
from inserr.scenario.flags import add_flags, scenario_from_args

HELP = "Multi-position gyro/accelerometer calibration."

#: The flags of ``inserr calibrate``.
FLAG_NAMES = (
    "method",
    "lat",
    "height",
    "stop",
    "rate",
    "settle",
    "runs",
    "seed",
    "positioning-error",
    "positioning-model",
    "gyro-bias",
    "accel-bias",
    "gyro-sf",
    "accel-sf",
    "gyro-misalignment",
    "accel-misalignment",
    "arw",
    "vrw",
    "sample-rate",
    "per-sample",
    "design",
    "design-sizes",
    "design-sensors",
    "design-step",
    "top",
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the flags of ``inserr calibrate``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The sub-command's parser: the ``calibration`` scenario flags (a positional
        scenario file, overridden by the flags), ``--out`` and ``--json``.

    Returns
    -------
    None
    """
    add_flags(parser, "calibration", FLAG_NAMES)
    parser.add_argument(
        "--out",
        default=None,
        help="write a report directory (figures, report.md/html, results.json)",
    )
    add_json_flag(parser)


def _design(args: argparse.Namespace, inp) -> int:
    from inserr.calibration.position_sets import describe_candidate, design_sets, set_criterion
    from inserr.calibration.two_axis_table import offaxis_four_position, six_position

    site, dwell, rate, settle = inp.site, inp.dwell, inp.rate, inp.settle
    sensors = inp.design_sensors
    cands = design_sets(
        site, dwell, inp.design_sizes, sensors, inp.design_step, rate, settle, inp.top
    )
    refs = {
        name: set_criterion(fn(dwell, rate, settle), site, sensors)
        for name, fn in (
            ("offaxis_four_position", offaxis_four_position),
            ("six_position", six_position),
        )
    }
    best = cands[0].criterion if cands else math.nan
    rows = [describe_candidate(c, site, inp.truth.arw, best, refs) for c in cands]
    result = {
        "criterion": "det(FIM)^(1/12) per second of total time (dwell + indexing); "
        "relative_efficiency = criterion / best criterion",
        "sensors": sensors,
        "dwell_s": dwell,
        "table_rate_deg_s": rate / DEG,
        "reference_efficiency": {
            k: (v / best if v > 0 and best > 0 else None) for k, v in refs.items()
        },
        "candidates": rows,
    }
    lines = [
        "Candidate position sets ranked by D-optimal precision per unit time "
        f"({sensors}); "
        f"dwell {dwell:g} s per position, table {rate / DEG:g} deg/s.",
        "Efficiency 1 = best found; a set with efficiency e needs 1/e times as long for the same "
        "D-precision.",
        "",
        format_table(
            [
                "#",
                "mechanism",
                "n",
                "stops (outer,inner) deg",
                "time s",
                "gyro rk",
                "acc rk",
                "eff",
                "cond",
                "+eq",
            ],
            [
                [
                    k + 1,
                    r["mechanism"],
                    r["n_positions"],
                    " ".join(f"({o},{i})" for o, i in r["stops_outer_inner_deg"]),
                    f"{r['total_time_s']:.0f}",
                    r["gyro_rank"],
                    r["accel_rank"],
                    f"{r['relative_efficiency']:.3f}",
                    f"{r['gyro_condition_number']:.3g}",
                    r["equivalent_sets"],
                ]
                for k, r in enumerate(rows)
            ],
        ),
        "",
        "Reference sets: "
        + ", ".join(
            f"{k} efficiency {v:.3f}" if v is not None else f"{k}: not full rank"
            for k, v in result["reference_efficiency"].items()
        ),
    ]
    emit(args, result, "\n".join(lines))
    return 0


def run(args: argparse.Namespace) -> int:
    """Run ``inserr calibrate``: Monte Carlo study of one position set, or ``--design``.

    Prints the summary (human text, or JSON under ``--json``: ``positions``,
    ``total_time_s``, ``rank``, ``condition_number``, ``parameters``,
    ``positioning_sensitivity`` and the same blocks under ``accel``; engineering units,
    see the module) and writes the ``--out`` report directory if asked.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed flags of :func:`add_arguments`.

    Returns
    -------
    int
        Exit status, 0 on success (bad input raises :class:`InputError`, which the
        CLI reports with status 2).
    """
    from inserr.calibration.inputs import calibration_inputs

    scen = scenario_from_args(args, "calibration")
    inp = calibration_inputs(scen)
    if inp.design:
        return _design(args, inp)
    config = inp.config

    from inserr.calibration.report import build_report
    from inserr.calibration.summary import (
        PARAMETER_HEADER,
        SENSITIVITY_HEADER,
        calibration_summary,
        parameter_rows,
        sensitivity_axes_text,
        sensitivity_rows,
    )

    summary, results = calibration_summary(inp.position_set, inp.site, inp.truth, config)
    if args.out:
        stamp(build_report(summary, results), scen, args).write(args.out)
    lines = [
        f"{summary['method']}: {summary['n_positions']} positions at latitude "
        f"{summary['latitude_deg']:g} deg; "
        f"time {summary['total_time_s']:.0f} s (dwell {summary['dwell_time_s']:.0f} s + indexing "
        f"{summary['indexing_time_s']:.0f} s); {config.runs} runs, seed {config.seed}.",
        "",
        format_table(
            ["pos", "outer deg", "inner deg", "up", "dwell s", "gyro input deg/h"],
            [
                [
                    p["name"],
                    f"{p['outer_deg']:.0f}",
                    f"{p['inner_deg']:.0f}",
                    p["up_axis"],
                    f"{p['dwell_s']:g}",
                    " ".join(f"{v:+.3f}" for v in p["gyro_input_deg_h"]),
                ]
                for p in summary["positions"]
            ],
        ),
    ]
    for sensor, block in (("gyro", summary), ("accel", summary["accel"])):
        lines += [
            "",
            f"{sensor}: rank {block['rank']} of 12, condition number "
            f"{block['condition_number']:.4g} "
            "(dwell-weighted design, columns scaled to unit norm)",
            *block["identifiability_messages"],
            format_table(PARAMETER_HEADER, parameter_rows(block)),
            "",
            f"{sensor}: largest first-order sensitivity to one position's positioning error, "
            f"over all positions and about {sensitivity_axes_text(config.positioning_model)}; "
            "parameter unit per arcsec:",
            format_table(
                SENSITIVITY_HEADER, sensitivity_rows(block["positioning_sensitivity"]), "{:.3g}"
            ),
        ]
    if args.out:
        lines += ["", f"report written to {args.out}"]
    emit(args, summary, "\n".join(lines))
    return 0
