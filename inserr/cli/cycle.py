"""``inserr cycle``: closed-form cycle integrals of a periodic scheme on a static base.

The scheme comes from ``--scheme NAME`` (with ``--rate``, ``--stop``, ``--reversal``) or
from a scenario file, ``inserr cycle SCENARIO.toml``: its ``[scheme]`` table, including
a ``custom`` table of ``[[scheme.steps]]``, and its vehicle attitude (heading, pitch and
roll at t = 0, held fixed: cycle integrals are defined on a static base). Flags given
with a file override its ``[scheme]`` keys.
"""

from __future__ import annotations

import argparse
import math

from inserr.cli.common import add_json_flag, emit, finite_float, format_table


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "scenario",
        nargs="?",
        help="scenario TOML file: use its [scheme] table (and vehicle attitude)",
    )
    p.add_argument("--scheme", default=None, help="periodic (open-loop) scheme name")
    p.add_argument("--rate", type=finite_float, default=None, help="table rate, deg/s (default 6)")
    p.add_argument("--stop", type=finite_float, default=None, help="stop time, s (default 300)")
    p.add_argument(
        "--reversal", type=finite_float, default=None, help="continuous: reversal period, s"
    )
    add_json_flag(p)


def _scheme_and_base(args: argparse.Namespace):
    """(scheme name, scheme object, static base Motion, base description)."""
    from inserr.core.errors import InputError
    from inserr.core.units import DEG
    from inserr.schemes.catalogue import build_scheme
    from inserr.schemes.vehicle_motion import Motion

    if args.scenario is None:
        if args.scheme is None:
            raise InputError(
                "--scheme",
                "no scheme given",
                "give --scheme NAME or a scenario file (inserr cycle SCENARIO.toml)",
            )
        rate = 6.0 if args.rate is None else args.rate
        stop = 300.0 if args.stop is None else args.stop
        reversal = 0.0 if args.reversal is None else args.reversal
        opts = {"reversal": reversal} if args.scheme == "continuous" else {}
        scheme = build_scheme(args.scheme, rate * DEG, stop, **opts)
        return args.scheme, scheme, Motion(), "level, heading 0 (body = ENU)"

    from inserr.scenario.flags import merge
    from inserr.scenario.schema import load_scenario, scenario_from_dict

    scen = load_scenario(args.scenario)
    over = {
        key: value
        for key, value in (
            ("name", args.scheme),
            ("rate", None if args.rate is None else f"{args.rate!r} deg/s"),
            ("stop", None if args.stop is None else f"{args.stop!r} s"),
            ("reversal", None if args.reversal is None else f"{args.reversal!r} s"),
        )
        if value is not None
    }
    if over:
        scen = scenario_from_dict(merge(scen.raw, {"scheme": over}), scen.base_dir)
    m = scen.motion
    h0 = float(m.heading_at(0.0))
    base = Motion(heading=h0, pitch=m.pitch, roll=m.roll)
    desc = (
        f"heading {math.degrees(h0):g} deg, pitch {math.degrees(m.pitch):g} deg, "
        f"roll {math.degrees(m.roll):g} deg"
    )
    if type(m) is not Motion:
        desc += f" (the scenario's {m.name} motion held at its t = 0 attitude)"
    return scen.scheme_name, scen.scheme(), base, desc


def run(args: argparse.Namespace) -> int:
    from inserr.schemes.cycle_integrals import cycle_integrals

    name, scheme, base, base_desc = _scheme_and_base(args)
    c = cycle_integrals(scheme, base)
    h = c.horizontal
    result = {
        "scheme": name,
        "static_base": base_desc,
        "cycle_time_s": c.cycle_time,
        "horizontal_cycle_integral_s": h.tolist(),
        "residual_drift_fraction": c.residual_drift_fraction,
        "motor_starts_per_hour": c.motor_starts_per_hour,
        "stops_integral_s": c.stops.tolist(),
        "turns_integral_s": c.turns.tolist(),
        "full_cycle_integral_s": c.full.tolist(),
        "scale_factor_rate_integral_rad": c.scale_factor.tolist(),
        "misalignment_rate_integral_rad": c.misalignment.tolist(),
        "mean_excursion_s": c.mean_excursion.tolist(),
        "mean_excursion_scale_factor_rad": c.mean_excursion_scale_factor.tolist(),
        "mean_excursion_misalignment_rad": c.mean_excursion_misalignment.tolist(),
    }
    human = (
        f"{name}: cycle {c.cycle_time:.3f} s, {c.motor_starts_per_hour:.2f} motor starts/h\n"
        f"static base: {base_desc}\n"
        "horizontal block of the cycle integral of C_s^n (s):\n"
        + format_table(
            ["", "IMU x", "IMU y"], [["E", h[0, 0], h[0, 1]], ["N", h[1, 0], h[1, 1]]], "{:.6g}"
        )
        + f"\nresidual drift fraction: {c.residual_drift_fraction:.3e} of each horizontal bias\n"
        "scale-factor x table-rate integral (rad per unit SF error; rows E,N,U; columns x,y,z):\n"
        + format_table(
            ["", "x", "y", "z"], [[r, *c.scale_factor[i]] for i, r in enumerate("ENU")], "{:.4g}"
        )
    )
    emit(args, result, human)
    return 0
