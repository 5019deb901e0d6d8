"""``inserr align``: Kalman-filter alignment on a static, swinging or indexed base.

The inputs are an ``alignment`` scenario (file and/or flags; see
:mod:`inserr.alignment.inputs`): the bias flags are both the prior 1 sigma of the
bias states and the true biases of the simulated run, ``--initial-attitude`` the
attitude prior 1 sigma. White noise (``--arw``, ``--vrw``) is off unless given, so
that ``inserr align --scheme none`` shows the classic static floors
(tilt = nabla / g, heading = eps_E / (Omega cos L)). ``--schemes a,b`` runs several
schemes on the same base.
"""

from __future__ import annotations

import argparse
import math

from inserr.cli.common import add_json_flag, emit, format_table, stamp
from inserr.scenario.flags import INITIAL, MOTION, add_flags, scenario_from_args

#: The flags of ``inserr align``.
FLAG_NAMES = (
    "scheme",
    "schemes",
    "duration",
    "lat",
    "lon",
    "height",
    "gyro-bias",
    "accel-bias",
    "gyro-sf",
    "accel-sf",
    "gyro-misalignment",
    "accel-misalignment",
    "arw",
    "vrw",
    "rate",
    "stop",
    *MOTION,
    "zupt-rate",
    "zupt-sigma",
    "position-sigma",
    *INITIAL,
    "vertical",
    "seed",
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_flags(p, "alignment", FLAG_NAMES)
    p.add_argument("--out", default=None, help="write a report directory here")
    add_json_flag(p)


def run(args: argparse.Namespace) -> int:
    from inserr.alignment.filter import static_floors
    from inserr.alignment.inputs import alignment_inputs
    from inserr.alignment.report import build_report
    from inserr.alignment.study import SHOWN, run_schemes, weakest_directions
    from inserr.core.units import ARCMIN, ARCSEC

    scen = scenario_from_args(args, "alignment")
    inp = alignment_inputs(scen)
    names, base, duration, prior, settings = (
        list(inp.schemes),
        inp.base,
        inp.duration,
        inp.prior,
        inp.settings,
    )
    results = run_schemes(base, names, duration, inp.imu, prior, settings)
    # Floors of the unindexed IMU (table at its zero) on this base at t = 0: the
    # textbook ones (diffuse attitude prior) and the ones this filter can reach,
    # which also carry the attitude prior's information.
    c0 = base.motion.attitude(0.0)[0]

    def in_units(f: dict) -> dict:
        return {
            "phi_e_arcsec": f["phi_e"] / ARCSEC,
            "phi_n_arcsec": f["phi_n"] / ARCSEC,
            "phi_u_arcmin": f["phi_u"] / ARCMIN,
        }

    floor = in_units(
        static_floors(base.site, prior.gyro_bias, prior.accel_bias, c0, prior.attitude)
    )
    floor_diffuse = in_units(static_floors(base.site, prior.gyro_bias, prior.accel_bias, c0))
    runs = {}
    for name, r in results.items():
        d = {"scheme": name, **r.summary()}
        d["weakest_directions"] = [
            {"eigenvalue": lam, "direction": text} for lam, text in weakest_directions(r)
        ]
        runs[name] = d
    common = {
        "minutes": duration / 60.0,
        "lat_deg": math.degrees(base.site.lat),
        "base": base.motion.describe(scen.heading_convention),
        "static_floor": floor,
        "static_floor_diffuse_prior": floor_diffuse,
        "settings": r.meta,
    }
    payload = {**common, **runs[names[0]]} if len(names) == 1 else {**common, "runs": runs}
    if args.out:
        rep = build_report(
            results,
            payload,
            base=base,
            duration=duration,
            settings=settings,
            floor=floor,
            floor_diffuse=floor_diffuse,
        )
        stamp(rep, scen, args).write(args.out)
    keys = [_key(s) for s in SHOWN]
    header = (
        ["state"]
        + [f"{n} σ" for n in names]
        + [f"{n} t_conv s" for n in names]
        + [f"{n} √P0/√Pk" for n in names]
    )
    rows = []
    for k in keys:
        row: list = [k]
        row += [runs[n]["final_sigma"][k] for n in names]
        row += [runs[n]["convergence_time_s"][k] for n in names]
        row += [runs[n]["observability_degree"][k] for n in names]
        rows.append(row)
    human = (
        f"alignment {duration / 60:g} min at lat {math.degrees(base.site.lat):g} deg, "
        f"{base.motion.describe(scen.heading_convention)}\n"
        f"static floors with this prior: phi_e {floor['phi_e_arcsec']:.4g} arcsec, "
        f"phi_n {floor['phi_n_arcsec']:.4g} arcsec, "
        f"heading {floor['phi_u_arcmin']:.4g} arcmin "
        f"(diffuse prior: {floor_diffuse['phi_e_arcsec']:.4g} arcsec, "
        f"{floor_diffuse['phi_u_arcmin']:.4g} arcmin)\n"
        + format_table(header, rows)
        + (f"\n\nreport written to {args.out}" if args.out else "")
    )
    emit(args, payload, human)
    return 0


def _key(state: str) -> str:
    from inserr.alignment.filter import UNITS

    return UNITS[state][0]
