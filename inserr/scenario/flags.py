"""The scenario flags shared by ``drift``, ``compare``, ``validate``, ``align`` and ``sweep``.

Each flag maps to one dotted scenario key and has a documented unit; values may
also carry an explicit unit (``--gyro-bias "0.02 deg/h"``). The flags are turned
into the same nested table a scenario file gives, so both are validated by
:func:`inserr.scenario.schema.scenario_from_dict`.
"""

from __future__ import annotations

import argparse

from inserr.core.errors import InputError
from inserr.scenario.schema import Scenario, load_scenario, scenario_from_dict

#: flag name (without --) -> (dotted scenario key, unit appended to bare numbers, help)
FLAGS: dict[str, tuple[str, str | None, str]] = {
    "lat": ("site.latitude", "deg", "latitude, deg (default 34)"),
    "lon": ("site.longitude", "deg", "longitude, deg"),
    "height": ("site.height", "m", "height above the ellipsoid, m"),
    "hours": ("scenario.duration", "h", "duration, h (default 72)"),
    "gyro-bias": ("imu.gyro_bias", "deg/h", "gyro bias, deg/h: one value or x,y,z"),
    "accel-bias": ("imu.accel_bias", "ug", "accelerometer bias, micro-g: one value or x,y,z"),
    "gyro-sf": ("imu.gyro_scale_factor", "ppm", "gyro scale-factor error, ppm: one value or x,y,z"),
    "accel-sf": ("imu.accel_scale_factor", "ppm", "accelerometer scale-factor error, ppm"),
    "gyro-misalignment": (
        "imu.gyro_misalignment",
        "arcsec",
        "gyro misalignment, arcsec (all six, or xy,xz,yx,yz,zx,zy)",
    ),
    "accel-misalignment": (
        "imu.accel_misalignment",
        "arcsec",
        "accelerometer misalignment, arcsec",
    ),
    "arw": ("imu.arw", "deg/sqrt(h)", "angle random walk, deg/sqrt(h)"),
    "vrw": ("imu.vrw", "ug/sqrt(Hz)", "velocity random walk, micro-g/sqrt(Hz)"),
    "gyro-bias-instability": (
        "imu.gyro_bias_instability",
        "deg/h",
        "Gauss-Markov gyro bias 1 sigma, deg/h",
    ),
    "accel-bias-instability": (
        "imu.accel_bias_instability",
        "ug",
        "Gauss-Markov accel bias 1 sigma, micro-g",
    ),
    "correlation-time": (
        "imu.gyro_correlation_time",
        "s",
        "Gauss-Markov correlation time, s (gyro and accel)",
    ),
    "initial-attitude": (
        "initial.attitude",
        "arcsec",
        "initial attitude error E,N,U (tilts, heading), arcsec",
    ),
    "initial-velocity": ("initial.velocity", "m/s", "initial velocity error, m/s"),
    "initial-position": ("initial.position", "m", "initial position error, m"),
    "heading": ("motion.heading", "deg", "vehicle heading, deg (clockwise from north)"),
    "pitch": ("motion.pitch", "deg", "vehicle pitch, deg"),
    "roll": ("motion.roll", "deg", "vehicle roll, deg"),
    "turn-rate": ("motion.rate", "deg/s", "constant heading rate (turn on the spot), deg/s"),
    "scheme": ("scheme.name", None, "indexing scheme (default none)"),
    "rate": ("scheme.rate", "deg/s", "table rate, deg/s (default 6)"),
    "stop": ("scheme.stop", "s", "stop time, s (default 300)"),
    "reversal": ("scheme.reversal", "s", "continuous scheme: reversal period, s (0 = none)"),
    "delta": ("scheme.delta", None, "flexible scheme: stop threshold (default 0.01)"),
    "variant": ("scheme.variant", None, "flexible scheme: threshold or crossing"),
    "step": ("output.step", "s", "output step of the deterministic run, s (default 1)"),
    "covariance-step": (
        "output.covariance_step",
        "s",
        "output step of covariance results, s (default 60)",
    ),
    "substep": ("output.substep", "s", "sub-step of continuous motion, s (default 1)"),
    "vertical": ("output.vertical", None, "vertical channel: clamped (default) or free"),
}

#: Flags whose value is a pair handled specially.
YAW_SWING = "yaw-swing"


def add_scenario_flags(parser: argparse.ArgumentParser, scenario_file: bool = True) -> None:
    """Add the scenario flags (all optional) and, if asked, a positional scenario file."""
    if scenario_file:
        parser.add_argument("scenario", nargs="?", help="scenario TOML file (flags override it)")
    for name, (_, _, help_) in FLAGS.items():
        parser.add_argument(
            f"--{name}", dest=name.replace("-", "_"), default=None, metavar="X", help=help_
        )
    parser.add_argument(
        f"--{YAW_SWING}",
        dest="yaw_swing",
        default=None,
        metavar="AMP,PERIOD",
        help="yaw swing: peak rate deg/s, period s (heading rate AMP cos(2 pi t / PERIOD))",
    )


def _with_unit(flag: str, text: str, unit: str | None) -> str:
    """Append the flag's unit to bare numbers (``"0.02"``, ``"1,2,3"``, ``"nan"``)."""
    text = text.strip()
    if unit is None:
        return text
    try:
        [float(v) for v in text.split(",")]
    except ValueError:
        return text  # the user wrote a unit (or garbage, which the parser will name)
    return f"{text} {unit}"


def flags_to_dict(args: argparse.Namespace) -> dict:
    """Nested scenario table of the flags that were given."""
    d: dict[str, dict] = {}
    for name, (key, unit, _) in FLAGS.items():
        value = getattr(args, name.replace("-", "_"), None)
        if value is None:
            continue
        section, _, k = key.partition(".")
        if key in ("scheme.delta",):
            try:
                d.setdefault(section, {})[k] = float(value)
            except ValueError:
                raise InputError(f"--{name}", f"{value!r} is not a number") from None
            continue
        d.setdefault(section, {})[k] = _with_unit(name, value, unit)
        if name == "correlation-time":
            d["imu"]["accel_correlation_time"] = d["imu"][k]
    if getattr(args, "turn_rate", None) is not None:
        d.setdefault("motion", {})["type"] = "turn"
    swing = getattr(args, "yaw_swing", None)
    if swing is not None:
        parts = swing.split(",")
        if len(parts) != 2:
            raise InputError(
                "--yaw-swing", f"expected AMP,PERIOD, got {swing!r}", "e.g. --yaw-swing 6,120"
            )
        m = d.setdefault("motion", {})
        if m.get("type") == "turn":
            raise InputError("--yaw-swing", "cannot be combined with --turn-rate")
        m["type"] = "yaw-swing"
        m["amplitude"] = _with_unit("yaw-swing", parts[0], "deg/s")
        m["period"] = _with_unit("yaw-swing", parts[1], "s")
    return d


def merge(base: dict, over: dict) -> dict:
    """Section-wise merge of two nested scenario tables (``over`` wins)."""
    out = {k: dict(v) for k, v in base.items()}
    for section, table in over.items():
        out.setdefault(section, {}).update(table)
    return out


def scenario_from_args(args: argparse.Namespace) -> Scenario:
    """Scenario from the optional file argument overlaid with the flags."""
    over = flags_to_dict(args)
    path = getattr(args, "scenario", None)
    base = load_scenario(path) if path else None
    try:
        if base is None:
            return scenario_from_dict(over)
        return scenario_from_dict(merge(base.raw, over), base.base_dir) if over else base
    except InputError as exc:
        # Name the flag the user typed, not the scenario key it was translated to.
        given = {
            key: f"--{name}"
            for name, (key, _, _) in FLAGS.items()
            if getattr(args, name.replace("-", "_"), None) is not None
        }
        if exc.field in given:
            raise InputError(f"{given[exc.field]} ({exc.field})", exc.problem, exc.fix) from None
        raise
