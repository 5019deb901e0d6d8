"""``inserr northfind``: Monte Carlo of the rotation-modulation north finder beside its bound.

Example::

    inserr northfind --lat 34 --heading 30 --pitch 1 --roll -2 --minutes 3 \\
        --runs 50 --seed 1 --json

Every value flag takes a bare number in its documented unit or a number with a
unit (``--arw "0.001 deg/sqrt(h)"``, ``--minutes "180 s"``). ``--lat`` is the
simulated truth and is never given to the estimator unless ``--latitude-known``. The
estimator is told only the hemisphere the user declares with ``--hemisphere`` (default
north), never the one of ``--lat``: one gyro and one accelerometer cannot tell the
hemispheres apart (see ``docs/tutorials/northfinding.md``). The JSON echoes the
declaration (``hemisphere_declared``) and lists ``warnings`` for the polar and
equatorial bands, an unresolved latitude, the mirror root, and a Monte Carlo sigma
outside 0.8-1.2 times the bound.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from inserr.cli.common import add_json_flag, emit, format_table, parse_int
from inserr.core.errors import InputError
from inserr.core.units import parse_quantity

HELP = "Rotation-modulation north finder (1 gyro, 1 accel)."

#: flag -> (physical kind, default unit, default value, help)
_VALUE_FLAGS: dict[str, tuple[str, str, str | None, str]] = {
    "--lat": ("angle", "deg", None, "true latitude, deg (simulation only; hidden from the filter)"),
    "--heading": ("angle", "deg", None, "true heading, deg clockwise from north"),
    "--pitch": ("angle", "deg", "0", "pitch of the base, deg"),
    "--roll": ("angle", "deg", "0", "roll of the base, deg"),
    "--minutes": ("time", "min", "3", "duration of each run, min"),
    "--rate": ("angular_rate", "deg/s", "6", "table rate, deg/s (sign = direction)"),
    "--sample-rate": ("frequency", "Hz", "100", "sensor sample rate, Hz"),
    "--filter-period": ("time", "s", "1", "Kalman filter period, s"),
    "--arw": ("arw", "deg/sqrt(h)", "0.001", "gyro angle random walk, deg/sqrt(h)"),
    "--gyro-bias": ("angular_rate", "deg/h", "0.05", "gyro bias, deg/h"),
    "--gyro-bi": ("angular_rate", "deg/h", "0.005", "gyro bias instability (GM 1σ), deg/h"),
    "--gyro-bi-tau": ("time", "s", "300", "gyro bias-instability correlation time, s"),
    "--vrw": ("vrw", "ug/sqrt(Hz)", "10", "accelerometer velocity random walk, µg/√Hz"),
    "--accel-bias": ("acceleration", "ug", "100", "accelerometer bias, µg"),
    "--accel-bi": ("acceleration", "ug", "0", "accelerometer bias instability (1σ), µg"),
    "--accel-bi-tau": ("time", "s", "300", "accelerometer bias-instability correlation time, s"),
    "--gyro-tilt": ("angle", "deg", "0", "gyro tilt toward the rotation axis, deg"),
    "--accel-azimuth": ("angle", "deg", "0", "accelerometer azimuth from the gyro axis, deg"),
    "--accel-tilt": ("angle", "deg", "0", "accelerometer tilt toward the rotation axis, deg"),
}

#: Field names of the north-finder dataclasses -> the flag a user types.
_FIELD_TO_FLAG = {
    "lat": "--lat",
    "heading": "--heading",
    "pitch": "--pitch",
    "roll": "--roll",
    "duration": "--minutes",
    "table_rate": "--rate",
    "sample_rate": "--sample-rate",
    "filter_period": "--filter-period",
    "gyro_arw": "--arw",
    "gyro_bias": "--gyro-bias",
    "gyro_bias_instability": "--gyro-bi",
    "gyro_correlation_time": "--gyro-bi-tau",
    "accel_vrw": "--vrw",
    "accel_bias": "--accel-bias",
    "accel_bias_instability": "--accel-bi",
    "accel_correlation_time": "--accel-bi-tau",
    "gyro_tilt": "--gyro-tilt",
    "accel_azimuth": "--accel-azimuth",
    "accel_tilt": "--accel-tilt",
    "runs": "--runs",
    "seed": "--seed",
    "grade": "--arw/--vrw",
}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Add the ``northfind`` flags to a parser.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The ``northfind`` sub-command parser; modified in place.

    Returns
    -------
    None
    """
    for flag, (_, unit, default, help_) in _VALUE_FLAGS.items():
        required = default is None
        parser.add_argument(
            flag,
            required=required,
            default=default,
            metavar=unit.upper().replace("/", "_").replace("(", "").replace(")", ""),
            help=help_ + ("" if required else f" (default {default})"),
        )
    parser.add_argument("--runs", default="50", help="Monte Carlo runs (default 50)")
    parser.add_argument("--seed", default="0", help="random seed, integer >= 0 (default 0)")
    parser.add_argument(
        "--latitude-known",
        action="store_true",
        help="give the estimator the true latitude (--hemisphere is then not used)",
    )
    parser.add_argument(
        "--hemisphere",
        choices=("north", "south"),
        default="north",
        help="hemisphere the user declares to the estimator (default north; the "
        "instrument cannot tell the hemispheres apart, and it is not taken from --lat)",
    )
    parser.add_argument("--out", default=None, metavar="DIR", help="write a report directory")
    add_json_flag(parser)


def _with_flag_names(exc: InputError) -> InputError:
    """Re-label an error raised by the library with the flag the user typed."""
    return InputError(_FIELD_TO_FLAG.get(exc.field, exc.field), exc.problem, exc.fix)


def _setup(args: argparse.Namespace):
    """Parse and validate every input; raises InputError before any work is done.

    Returns pose, instrument, grade (SI), duration (s), runs, seed and the declared
    hemisphere (+1 north, -1 south).
    """
    from inserr.northfinder.instrument import Instrument, Pose, SensorGrade, n_filter_periods

    v = {
        flag: parse_quantity(
            getattr(args, flag[2:].replace("-", "_")), kind, flag, default_unit=unit
        )
        for flag, (kind, unit, _, _) in _VALUE_FLAGS.items()
    }
    if v["--minutes"] <= 0:
        minutes = v["--minutes"] / 60.0
        raise InputError("--minutes", f"must be positive, got {minutes:g} min", "give e.g. 3")
    runs = parse_int(args.runs, "--runs", 1)
    seed = parse_int(args.seed, "--seed", 0)
    if args.out is not None and Path(args.out).exists() and not Path(args.out).is_dir():
        raise InputError("--out", f"{args.out!r} exists and is not a directory", "give a directory")
    try:
        pose = Pose(v["--lat"], v["--heading"], v["--pitch"], v["--roll"])
        instrument = Instrument(
            table_rate=v["--rate"],
            sample_rate=v["--sample-rate"],
            filter_period=v["--filter-period"],
            gyro_tilt=v["--gyro-tilt"],
            accel_azimuth=v["--accel-azimuth"],
            accel_tilt=v["--accel-tilt"],
        )
        grade = SensorGrade(
            gyro_arw=v["--arw"],
            gyro_bias=v["--gyro-bias"],
            gyro_bias_instability=v["--gyro-bi"],
            gyro_correlation_time=v["--gyro-bi-tau"],
            accel_vrw=v["--vrw"],
            accel_bias=v["--accel-bias"],
            accel_bias_instability=v["--accel-bi"],
            accel_correlation_time=v["--accel-bi-tau"],
        )
        if grade.gyro_arw <= 0 or grade.accel_vrw <= 0:
            raise InputError(
                "--arw" if grade.gyro_arw <= 0 else "--vrw",
                "the filter and the bound need non-zero white noise",
                "give a positive noise density",
            )
        n_filter_periods(instrument, v["--minutes"])
    except InputError as exc:
        raise _with_flag_names(exc) from None
    # The user's declaration, never the hemisphere of the simulated --lat.
    hemisphere = 1 if args.hemisphere == "north" else -1
    return pose, instrument, grade, v["--minutes"], runs, seed, hemisphere


def run(args: argparse.Namespace) -> int:
    """Run the Monte Carlo study, print the summary and optionally write a report.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed ``northfind`` flags (see :func:`add_arguments`).

    Returns
    -------
    int
        Exit status, 0 (bad input raises InputError, which the CLI turns into 2).
    """
    pose, instrument, grade, duration, runs, seed, hemisphere = _setup(args)
    from inserr.northfinder.study import monte_carlo

    result = monte_carlo(
        pose,
        instrument,
        grade,
        duration,
        n_runs=runs,
        seed=seed,
        latitude_known=args.latitude_known,
        hemisphere=hemisphere,
    )
    summary = {
        **result.summary(),
        "latitude_known": bool(args.latitude_known),
        "seed": seed,
    }
    if args.out is not None:
        from inserr.northfinder.report import build_report

        summary["report"] = str(build_report(result, summary, pose, instrument).write(args.out))
    emit(args, summary, _human(summary))
    return 0


def _fmt(v, spec: str = "{:.4g}") -> str:
    return "n/a" if v is None else spec.format(v)


def _human(s: dict) -> str:
    conv = s["convergence_time_s"]
    rows = [
        ["heading 1σ [mil]", _fmt(s["heading_error_1sigma_mil"]), _fmt(s["crlb_heading_mil"])],
        ["heading bias [mil]", _fmt(s["heading_bias_mil"]), ""],
        ["latitude 1σ [deg]", _fmt(s["latitude_error_1sigma_deg"]), _fmt(s["crlb_latitude_deg"])],
        ["latitude bias [deg]", _fmt(s["latitude_bias_deg"]), ""],
    ]
    lines = [
        f"North finder, {s['runs']} runs of {s['duration_s']:g} s "
        + (
            "(latitude known)"
            if s["latitude_known"]
            else f"(latitude unknown, {s['hemisphere_declared']}ern hemisphere declared)"
        ),
        "",
        format_table(["quantity", "Monte Carlo", "CRLB"], rows),
        "",
        f"heading σ / CRLB: {s['heading_sigma_over_crlb']:.3f}",
        "convergence (|error| <= 0.5 mil in >= 68 % of runs from then on): "
        + ("not reached within the run" if conv is None else f"{conv:g} s"),
    ]
    if s["warnings"]:
        lines += ["", "warnings:"] + [f"  - {w}" for w in s["warnings"]]
    if s.get("report"):
        lines.append(f"report: {s['report']}")
    return "\n".join(lines)
