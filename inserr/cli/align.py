"""``inserr align``: Kalman-filter alignment on a static, swinging or indexed base.

Bias flags are both the prior 1 sigma of the bias states and the true biases of the
simulated run. White noise (``--arw``, ``--vrw``) is off unless given, so that
``inserr align --scheme none`` shows the classic static floors
(tilt = nabla / g, heading = eps_E / (Omega cos L)).
"""

from __future__ import annotations

import argparse
import math

from inserr.cli.common import add_json_flag, axes, emit, format_table, require
from inserr.core.units import parse_quantity


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--scheme",
        default="none",
        help="indexing scheme(s) during alignment, comma-separated (default none)",
    )
    p.add_argument("--lat", default="34", help="latitude, deg (default 34)")
    p.add_argument("--lon", default="0", help="longitude, deg")
    p.add_argument("--height", default="0", help="height, m")
    p.add_argument("--minutes", default="10", help="alignment duration, min (default 10)")
    p.add_argument(
        "--gyro-bias",
        default="0.003",
        help="gyro bias prior 1σ and true value, deg/h: x or x,y,z (default 0.003)",
    )
    p.add_argument(
        "--accel-bias",
        default="30",
        help="accelerometer bias prior 1σ and true value, µg: x or x,y,z (default 30)",
    )
    for flag, what, unit in (
        ("--gyro-sf", "gyro scale-factor errors", "ppm: x or x,y,z"),
        ("--accel-sf", "accelerometer scale-factor errors", "ppm: x or x,y,z"),
        ("--gyro-misalignment", "gyro misalignments", "arcsec: one or xy,xz,yx,yz,zx,zy"),
        ("--accel-misalignment", "accelerometer misalignments", "arcsec: one or 6 values"),
    ):
        p.add_argument(
            flag,
            default=None,
            help=f"{what} of the simulated run, {unit}; not modelled by the filter "
            "(they move the true attitude during table turns), default 0",
        )
    p.add_argument("--arw", default="0", help="angle random walk, deg/sqrt(h) (default 0)")
    p.add_argument("--vrw", default="0", help="velocity random walk, µg/sqrt(Hz) (default 0)")
    p.add_argument("--rate", default="6", help="table rate, deg/s (default 6)")
    p.add_argument(
        "--stop",
        default="60",
        help="stop time of the scheme, s (default 60: several positions in 10 min)",
    )
    add_motion_flags(p)
    p.add_argument("--zupt-rate", default="1", help="zero-velocity update rate, Hz (default 1)")
    p.add_argument(
        "--zupt-sigma", default="0.001", help="zero-velocity measurement 1σ, m/s (default 0.001)"
    )
    p.add_argument(
        "--position-sigma", default=None, help="position updates with this 1σ, m (default: none)"
    )
    p.add_argument(
        "--initial-tilt", default="60", help="prior 1σ of the tilts, arcsec (default 60)"
    )
    p.add_argument(
        "--initial-heading", default="60", help="prior 1σ of the heading, arcmin (default 60)"
    )
    p.add_argument(
        "--initial-velocity", default="0.01", help="prior 1σ of velocity errors, m/s (default 0.01)"
    )
    p.add_argument(
        "--initial-position", default="10", help="prior 1σ of position errors, m (default 10)"
    )
    p.add_argument(
        "--vertical",
        default="free",
        choices=("free", "clamped"),
        help="vertical channel (default free)",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the simulated run")
    p.add_argument("--out", default=None, help="write a report directory here")
    add_json_flag(p)


def add_motion_flags(p: argparse.ArgumentParser, note: str = "") -> None:
    """``--heading/--pitch/--roll`` (deg) and ``--yaw-swing AMP,PERIOD`` of the vehicle."""
    p.add_argument("--heading", default="0", help=f"{note}vehicle heading, deg")
    p.add_argument("--pitch", default="0", help=f"{note}vehicle pitch, deg")
    p.add_argument("--roll", default="0", help=f"{note}vehicle roll, deg")
    p.add_argument(
        "--yaw-swing",
        default=None,
        metavar="AMP,PERIOD",
        help=f"{note}swinging base: peak yaw rate deg/s, period s",
    )


def quantity_flag(text: str, kind: str, flag: str, unit: str) -> float:
    """A flag value in SI; bare numbers are in the flag's documented ``unit``."""
    return float(parse_quantity(text, kind, flag, default_unit=unit))


def motion_from_args(args: argparse.Namespace):
    """The base motion of ``--heading/--pitch/--roll`` and ``--yaw-swing AMP,PERIOD``."""
    from inserr.core.errors import InputError
    from inserr.schemes.vehicle_motion import Motion, YawSwing

    heading = quantity_flag(args.heading, "angle", "--heading", "deg")
    pitch = quantity_flag(args.pitch, "angle", "--pitch", "deg")
    roll = quantity_flag(args.roll, "angle", "--roll", "deg")
    if not args.yaw_swing:
        return Motion(heading, pitch, roll)
    parts = args.yaw_swing.split(",")
    if len(parts) != 2:
        raise InputError(
            "--yaw-swing", f"expected AMP,PERIOD, got {args.yaw_swing!r}", "e.g. --yaw-swing 6,120"
        )
    return YawSwing(
        heading,
        pitch,
        roll,
        amplitude=quantity_flag(parts[0], "angular_rate", "--yaw-swing", "deg/s"),
        period=quantity_flag(parts[1], "time", "--yaw-swing", "s"),
    )


def _setup(args: argparse.Namespace):
    """Validated inputs: (names, base, duration, imu, prior, settings)."""
    import numpy as np

    from inserr.alignment.filter import Prior, Settings
    from inserr.alignment.study import Base
    from inserr.core.earth import Site
    from inserr.core.imu import ImuErrors
    from inserr.schemes.catalogue import SCHEMES

    names = [s.strip() for s in args.scheme.split(",") if s.strip()]
    require(bool(names), "--scheme", "no scheme given", "e.g. --scheme none,two-position")
    for n in names:
        require(
            n in SCHEMES, "--scheme", f"unknown scheme {n!r}", f"use one of: {', '.join(SCHEMES)}"
        )
    site = Site(
        quantity_flag(args.lat, "angle", "--lat", "deg"),
        quantity_flag(args.lon, "angle", "--lon", "deg"),
        quantity_flag(args.height, "length", "--height", "m"),
    )
    minutes = quantity_flag(args.minutes, "time", "--minutes", "min")
    require(minutes > 0, "--minutes", "must be > 0", "e.g. --minutes 10")
    gyro = axes(args.gyro_bias, "angular_rate", "--gyro-bias", "deg/h")
    accel = axes(args.accel_bias, "acceleration", "--accel-bias", "ug")
    require(
        bool(np.all(gyro >= 0) and np.all(accel >= 0)),
        "--gyro-bias/--accel-bias",
        "bias 1σ must be >= 0",
        "give magnitudes",
    )
    from inserr.core.units import parse_quantity

    def truth_only(text, kind, flag, unit, size):
        if text is None:
            return np.zeros(size)
        return parse_quantity(text, kind, flag, default_unit=unit, size=size)

    imu = ImuErrors(
        gyro_bias=gyro,
        accel_bias=accel,
        gyro_scale_factor=truth_only(args.gyro_sf, "ratio", "--gyro-sf", "ppm", 3),
        accel_scale_factor=truth_only(args.accel_sf, "ratio", "--accel-sf", "ppm", 3),
        gyro_misalignment=truth_only(
            args.gyro_misalignment, "angle", "--gyro-misalignment", "arcsec", 6
        ),
        accel_misalignment=truth_only(
            args.accel_misalignment, "angle", "--accel-misalignment", "arcsec", 6
        ),
        arw=quantity_flag(args.arw, "arw", "--arw", "deg/sqrt(h)"),
        vrw=quantity_flag(args.vrw, "vrw", "--vrw", "ug/sqrt(Hz)"),
    )
    motion = motion_from_args(args)
    rate = quantity_flag(args.rate, "angular_rate", "--rate", "deg/s")
    stop = quantity_flag(args.stop, "time", "--stop", "s")
    require(rate > 0, "--rate", "table rate must be > 0 deg/s")
    require(stop > 0, "--stop", "stop time must be > 0 s")
    base = Base(site, motion, rate, stop)
    tilt = quantity_flag(args.initial_tilt, "angle", "--initial-tilt", "arcsec")
    head = quantity_flag(args.initial_heading, "angle", "--initial-heading", "arcmin")
    prior = Prior(
        attitude=np.array([tilt, tilt, head]),
        velocity=quantity_flag(args.initial_velocity, "velocity", "--initial-velocity", "m/s"),
        position=quantity_flag(args.initial_position, "length", "--initial-position", "m"),
        gyro_bias=gyro,
        accel_bias=accel,
    )
    ps = (
        None
        if args.position_sigma is None
        else quantity_flag(args.position_sigma, "length", "--position-sigma", "m")
    )
    settings = Settings(
        zupt_rate=quantity_flag(args.zupt_rate, "frequency", "--zupt-rate", "Hz"),
        zupt_sigma=quantity_flag(args.zupt_sigma, "velocity", "--zupt-sigma", "m/s"),
        position_sigma=ps,
        vertical=args.vertical,
        seed=args.seed,
    )
    return names, base, minutes, imu, prior, settings


def run(args: argparse.Namespace) -> int:
    from inserr.alignment.filter import static_floors
    from inserr.alignment.report import build_report
    from inserr.alignment.study import SHOWN, run_schemes, weakest_directions
    from inserr.core.units import ARCMIN, ARCSEC

    names, base, duration, imu, prior, settings = _setup(args)
    results = run_schemes(base, names, duration, imu, prior, settings)
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
        "base": base.motion.describe(),
        "static_floor": floor,
        "static_floor_diffuse_prior": floor_diffuse,
        "settings": r.meta,
    }
    payload = {**common, **runs[names[0]]} if len(names) == 1 else {**common, "runs": runs}
    if args.out:
        build_report(
            results,
            payload,
            base=base,
            duration=duration,
            settings=settings,
            floor=floor,
            floor_diffuse=floor_diffuse,
        ).write(args.out)
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
        f"{base.motion.describe()}\n"
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
