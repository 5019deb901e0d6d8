"""``inserr cycle``: closed-form cycle integrals of a periodic scheme on a static base.

The scheme comes from ``--scheme NAME`` (with ``--rate``, ``--stop``, ``--reversal``) or
from a scenario file, ``inserr cycle SCENARIO.toml``: its ``[scheme]`` table, including
a ``custom`` table of ``[[scheme.steps]]``, and its vehicle attitude (heading, pitch and
roll at t = 0, held fixed: cycle integrals are defined on a static base). Flags given
with a file override its keys.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from inserr.cli.common import add_json_flag, emit, format_table
from inserr.scenario.flags import add_flags, scenario_from_args

#: The flags of ``inserr cycle``: the scheme and the (static) vehicle attitude.
FLAG_NAMES = (
    "scheme",
    "rate",
    "stop",
    "start",
    "reversal",
    "heading-convention",
    "heading",
    "pitch",
    "roll",
)


#: Relative size below which a cycle-integral entry is round-off of exactly cancelling
#: sums (double precision leaves ~1e-16 of the scale; 1e-12 keeps a wide margin while
#: any physical residue of a real scheme is many orders larger).
ROUND_OFF = 1e-12


def zero_round_off(values, scale: float) -> np.ndarray:
    """``values`` with entries smaller than ``ROUND_OFF * scale`` in magnitude set to 0.

    Parameters
    ----------
    values : array
    scale : float
        The magnitude the entries are built from (same unit).

    Returns
    -------
    ndarray
        A copy; printed as 0 rather than as ``-2.84217e-14``.
    """
    out = np.array(values, dtype=float)
    out[np.abs(out) < ROUND_OFF * scale] = 0.0
    return out + 0.0  # no "-0"


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_flags(p, "drift", FLAG_NAMES)
    add_json_flag(p)


def run(args: argparse.Namespace) -> int:
    from inserr.schemes.cycle_integrals import cycle_integrals, scenario_cycle

    scen = scenario_from_args(args)
    scheme, base, base_desc = scenario_cycle(scen)
    name = scen.scheme_name
    c = cycle_integrals(scheme, base)
    # Entries that cancel exactly (a symmetric cycle) come out as round-off of the
    # sums, ~1e-16 of their scale: the cycle time for the integrals in s, one full
    # turn for those in rad.
    t, turn = c.cycle_time, 2.0 * math.pi
    h = zero_round_off(c.horizontal, t)
    result = {
        "scheme": name,
        "static_base": base_desc,
        "cycle_time_s": c.cycle_time,
        "horizontal_cycle_integral_s": h.tolist(),
        "residual_drift_fraction": c.residual_drift_fraction,
        "motor_starts_per_hour": c.motor_starts_per_hour,
        "stops_integral_s": zero_round_off(c.stops, t).tolist(),
        "turns_integral_s": zero_round_off(c.turns, t).tolist(),
        "full_cycle_integral_s": zero_round_off(c.full, t).tolist(),
        "scale_factor_rate_integral_rad": zero_round_off(c.scale_factor, turn).tolist(),
        "misalignment_rate_integral_rad": zero_round_off(c.misalignment, turn).tolist(),
        "mean_excursion_s": zero_round_off(c.mean_excursion, t).tolist(),
        "mean_excursion_scale_factor_rad": zero_round_off(
            c.mean_excursion_scale_factor, turn
        ).tolist(),
        "mean_excursion_misalignment_rad": zero_round_off(
            c.mean_excursion_misalignment, turn
        ).tolist(),
    }
    sf = np.array(result["scale_factor_rate_integral_rad"])
    human = (
        f"{name}: cycle {c.cycle_time:.3f} s, {c.motor_starts_per_hour:.2f} motor starts/h\n"
        f"static base: {base_desc}\n"
        "horizontal block of the cycle integral of C_s^n (s):\n"
        + format_table(
            ["", "IMU x", "IMU y"], [["E", h[0, 0], h[0, 1]], ["N", h[1, 0], h[1, 1]]], "{:.6g}"
        )
        + f"\nresidual drift fraction: {c.residual_drift_fraction:.3e} of each horizontal bias\n"
        "scale-factor x table-rate integral (rad per unit SF error; rows E,N,U; columns x,y,z):\n"
        + format_table(["", "x", "y", "z"], [[r, *sf[i]] for i, r in enumerate("ENU")], "{:.4g}")
    )
    emit(args, result, human)
    return 0
