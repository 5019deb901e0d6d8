"""``inserr northfind``: Monte Carlo of the rotation-modulation north finder beside its bound.

Example::

    inserr northfind --lat 34 --heading 30 --pitch 1 --roll -2 --duration 3min \\
        --runs 50 --seed 1 --json

The inputs are a ``northfinder`` scenario (file and/or flags; see
:mod:`inserr.northfinder.inputs`). Every value flag takes a bare number in its
documented unit or a number with a unit (``--arw "0.001 deg/sqrt(h)"``);
``--duration`` always carries its unit (``3min``). ``--lat`` is the simulated truth
and is never given to the estimator unless ``--latitude-known``. The
estimator is told only the hemisphere the user declares with ``--hemisphere`` (default
north), never the one of ``--lat``: one gyro and one accelerometer cannot tell the
hemispheres apart (see ``docs/tutorials/northfinding.md``). The JSON echoes the
declaration (``hemisphere_declared``) and lists ``warnings`` for the polar and
equatorial bands, an unresolved latitude, the mirror root, and a Monte Carlo sigma
outside 0.8-1.2 times the bound.
"""

from __future__ import annotations

import argparse

from inserr.cli.common import add_json_flag, emit, format_table, stamp
from inserr.scenario.flags import add_flags, scenario_from_args

HELP = "Rotation-modulation north finder (1 gyro, 1 accel)."

#: The flags of ``inserr northfind``.
FLAG_NAMES = (
    "lat",
    "height",
    "heading",
    "pitch",
    "roll",
    "duration",
    "rate",
    "sample-rate",
    "filter-period",
    "arw",
    "gyro-bias",
    "gyro-bias-instability",
    "gyro-correlation-time",
    "vrw",
    "accel-bias",
    "accel-bias-instability",
    "accel-correlation-time",
    "gyro-tilt",
    "accel-azimuth",
    "accel-tilt",
    "runs",
    "seed",
    "latitude-known",
    "hemisphere",
)


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
    add_flags(parser, "northfinder", FLAG_NAMES)
    parser.add_argument("--out", default=None, metavar="DIR", help="write a report directory")
    add_json_flag(parser)


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
    from inserr.northfinder.api import northfind

    scen = scenario_from_args(args, "northfinder")
    study = northfind(scen)  # the notebook front door: one path for both
    inp, result = study.inputs, study.result
    summary = {
        **result.summary(),
        "latitude_known": bool(inp.latitude_known),
        "seed": inp.seed,
    }
    if args.out is not None:
        from inserr.northfinder.report import build_report

        summary["report"] = str(
            stamp(build_report(result, summary, inp.pose, inp.instrument), scen, args).write(
                args.out
            )
        )
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
