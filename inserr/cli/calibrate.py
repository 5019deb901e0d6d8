"""``inserr calibrate``: multi-position gyro/accelerometer calibration study (P1).

Examples::

    inserr calibrate --method offaxis-four-position --runs 100 --seed 1 --json
    inserr calibrate --method six-position --dwell 600 --arw 0.001
    inserr calibrate --method my_set.toml --lat 45
    inserr calibrate --design --design-sizes 4,6 --top 5

Output units (human and JSON): scale factors ppm, misalignments arcsec, gyro biases
deg/h, accelerometer biases micro-g, times s; sensitivities to the table's positioning
error in those units per arcsec (``positioning_sensitivity``). Every flag that takes a
quantity accepts a bare number in the unit given in its help, or the number with a unit
written (``--arw "0.03 deg/sqrt(h)"``).
"""

from __future__ import annotations

import argparse
import math
from dataclasses import replace
from pathlib import Path

from inserr.calibration.estimation import (
    DEFAULT_ARW,
    DEFAULT_VRW,
    P1_POSITIONING_ERROR,
    P1_SAMPLE_RATE,
    MonteCarloConfig,
    p1_truth,
)
from inserr.calibration.two_axis_table import (
    BUILTIN_SETS,
    DEFAULT_DWELL,
    DEFAULT_RATE,
    builtin_set,
    load_position_set,
)
from inserr.cli.common import add_json_flag, emit, format_table, parse_int
from inserr.core.earth import Site
from inserr.core.errors import InputError, require_latitude
from inserr.core.units import (
    ARCSEC,
    DEG,
    DEG_PER_SQRT_HOUR,
    MICRO_G_PER_SQRT_HZ,
    parse_quantity,
)

HELP = "Multi-position gyro/accelerometer calibration."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Register the flags of ``inserr calibrate``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The sub-command's parser. Quantities are stored as text and parsed (with
        units: deg, s, arcsec, deg/sqrt(h), ug/sqrt(Hz), deg/s, Hz) in :func:`run`.

    Returns
    -------
    None
    """
    # Quantities are read as text and parsed in run(), so bad values raise InputError
    # (one line, exit 2) instead of argparse's usage dump.
    parser.add_argument(
        "--method",
        default="offaxis-four-position",
        help=f"{' | '.join(BUILTIN_SETS)} | path to a TOML position-set file "
        "(default offaxis-four-position)",
    )
    parser.add_argument("--lat", default="34", help="latitude, deg (default 34, P1)")
    parser.add_argument(
        "--dwell",
        default=None,
        help=f"dwell per position, s (default {DEFAULT_DWELL:g}; for a FILE only the "
        "positions that give none)",
    )
    parser.add_argument("--runs", default="100", help="Monte Carlo runs (default 100)")
    parser.add_argument("--seed", default="1", help="random seed (default 1)")
    parser.add_argument(
        "--positioning-error",
        default=f"{P1_POSITIONING_ERROR / ARCSEC:g}",
        help="half-width of the uniform positioning error at every stop, arcsec (default 3, P1)",
    )
    parser.add_argument(
        "--positioning-model",
        default="three-axis",
        help="three-axis: small rotation about east, north and up, each uniform (default); "
        "gimbal: errors of the two gimbal angles only",
    )
    parser.add_argument(
        "--arw",
        default=f"{DEFAULT_ARW / DEG_PER_SQRT_HOUR:g}",
        help="gyro angle random walk, deg/sqrt(h) (default 0.0005)",
    )
    parser.add_argument(
        "--vrw",
        default=f"{DEFAULT_VRW / MICRO_G_PER_SQRT_HZ:g}",
        help="accelerometer velocity random walk, ug/sqrt(Hz) (default 5)",
    )
    parser.add_argument(
        "--rate", default=f"{DEFAULT_RATE / DEG:g}", help="table indexing rate, deg/s (default 6)"
    )
    parser.add_argument("--settle", default="0", help="settling time per move, s (default 0)")
    parser.add_argument(
        "--sample-rate",
        default=f"{P1_SAMPLE_RATE:g}",
        help="output rate, Hz (default 100; used only with --per-sample)",
    )
    parser.add_argument(
        "--per-sample",
        action="store_true",
        help="simulate every sample and average (default: draw the exact Gaussian dwell average)",
    )
    parser.add_argument(
        "--design",
        action="store_true",
        help="rank candidate position sets instead of a Monte Carlo",
    )
    parser.add_argument(
        "--design-sizes", default="4,5,6", help="numbers of positions to try (default 4,5,6)"
    )
    parser.add_argument(
        "--design-sensors",
        default="gyro",
        help="gyro (default) or gyro+accel: what must be identifiable",
    )
    parser.add_argument(
        "--design-step", default="90", help="gimbal step, deg (default 90: 90/180 deg moves)"
    )
    parser.add_argument("--top", default="10", help="number of candidate sets shown (default 10)")
    parser.add_argument(
        "--out",
        default=None,
        help="write a report directory (figures, report.md/html, results.json)",
    )
    add_json_flag(parser)


def _nonneg(text: str, kind: str, flag: str, unit: str) -> float:
    v = parse_quantity(text, kind, flag, default_unit=unit)
    if v < 0:
        raise InputError(flag, f"must be >= 0, got {text!r}")
    return v


def _positive(text: str, kind: str, flag: str, unit: str) -> float:
    v = parse_quantity(text, kind, flag, default_unit=unit)
    if v <= 0:
        raise InputError(flag, f"must be > 0, got {text!r}", f"give a positive value in {unit}")
    return v


def _position_set(args: argparse.Namespace, rate: float, settle: float):
    dwell = DEFAULT_DWELL if args.dwell is None else _positive(args.dwell, "time", "--dwell", "s")
    if args.method in BUILTIN_SETS:
        return builtin_set(args.method, dwell, rate, settle)
    path = Path(args.method)
    if path.suffix.lower() != ".toml" and not path.exists():
        raise InputError(
            "--method",
            f"unknown method {args.method!r}",
            f"use {', '.join(BUILTIN_SETS)} or the path of a .toml position-set file",
        )
    pset = load_position_set(path, dwell, rate)
    if settle and not pset.table.settle:
        pset = replace(pset, table=replace(pset.table, settle=settle))
    return pset


def _design(args: argparse.Namespace, site: Site, rate: float, settle: float, arw: float) -> int:
    from inserr.calibration.position_sets import describe_candidate, design_sets, set_criterion
    from inserr.calibration.two_axis_table import offaxis_four_position, six_position

    dwell = DEFAULT_DWELL if args.dwell is None else _positive(args.dwell, "time", "--dwell", "s")
    try:
        sizes = tuple(int(s) for s in str(args.design_sizes).split(","))
    except ValueError:
        raise InputError(
            "--design-sizes", f"cannot read {args.design_sizes!r}", "give e.g. 4,5,6"
        ) from None
    step = _positive(args.design_step, "angle", "--design-step", "deg")
    top = parse_int(args.top, "--top", 1)
    cands = design_sets(site, dwell, sizes, args.design_sensors, step, rate, settle, top)
    refs = {
        name: set_criterion(fn(dwell, rate, settle), site, args.design_sensors)
        for name, fn in (
            ("offaxis_four_position", offaxis_four_position),
            ("six_position", six_position),
        )
    }
    best = cands[0].criterion if cands else math.nan
    rows = [describe_candidate(c, site, arw, best, refs) for c in cands]
    result = {
        "criterion": "det(FIM)^(1/12) per second of total time (dwell + indexing); "
        "relative_efficiency = criterion / best criterion",
        "sensors": args.design_sensors,
        "dwell_s": dwell,
        "table_rate_deg_s": rate / DEG,
        "reference_efficiency": {
            k: (v / best if v > 0 and best > 0 else None) for k, v in refs.items()
        },
        "candidates": rows,
    }
    lines = [
        "Candidate position sets ranked by D-optimal precision per unit time "
        f"({args.design_sensors}); "
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
    lat = require_latitude(parse_quantity(args.lat, "angle", "--lat", default_unit="deg"), "--lat")
    site = Site(lat)
    rate = _positive(args.rate, "angular_rate", "--rate", "deg/s")
    settle = _nonneg(args.settle, "time", "--settle", "s")
    arw = _nonneg(args.arw, "arw", "--arw", "deg/sqrt(h)")
    vrw = _nonneg(args.vrw, "vrw", "--vrw", "ug/sqrt(Hz)")
    if args.design:
        return _design(args, site, rate, settle, arw)
    config = MonteCarloConfig(
        runs=parse_int(args.runs, "--runs", 2),
        seed=parse_int(args.seed, "--seed", 0),
        positioning_error=_nonneg(args.positioning_error, "angle", "--positioning-error", "arcsec"),
        positioning_model=args.positioning_model,
        per_sample=args.per_sample,
        sample_rate=_positive(args.sample_rate, "frequency", "--sample-rate", "Hz"),
    )
    pset = _position_set(args, rate, settle)

    from inserr.calibration.report import build_report
    from inserr.calibration.summary import (
        PARAMETER_HEADER,
        SENSITIVITY_HEADER,
        calibration_summary,
        parameter_rows,
        sensitivity_axes_text,
        sensitivity_rows,
    )

    summary, results = calibration_summary(pset, site, p1_truth(arw, vrw), config)
    if args.out:
        build_report(summary, results).write(args.out)
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
