"""``inserr cycle``: closed-form cycle integrals of a periodic scheme on a static base."""

from __future__ import annotations

import argparse

from inserr.cli.common import add_json_flag, emit, finite_float, format_table


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--scheme", required=True, help="periodic (open-loop) scheme name")
    p.add_argument("--rate", type=finite_float, default=6.0, help="table rate, deg/s (default 6)")
    p.add_argument("--stop", type=finite_float, default=300.0, help="stop time, s (default 300)")
    p.add_argument(
        "--reversal", type=finite_float, default=0.0, help="continuous: reversal period, s"
    )
    add_json_flag(p)


def run(args: argparse.Namespace) -> int:
    from inserr.cycle import cycle_integrals
    from inserr.schemes import build_scheme
    from inserr.units import DEG

    opts = {"reversal": args.reversal} if args.scheme == "continuous" else {}
    c = cycle_integrals(build_scheme(args.scheme, args.rate * DEG, args.stop, **opts))
    h = c.horizontal
    result = {
        "scheme": args.scheme,
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
        f"{args.scheme}: cycle {c.cycle_time:.3f} s, {c.motor_starts_per_hour:.2f} motor starts/h\n"
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
