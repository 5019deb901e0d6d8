"""``inserr modes``: Schuler, Foucault and Earth periods read off the model's eigenvalues."""

from __future__ import annotations

import argparse
import math

from inserr.cli.common import add_json_flag, emit, finite_float, format_table
from inserr.core.earth import Site
from inserr.model.psi_model import ErrorModel, modes


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--lat", type=finite_float, required=True, help="latitude, deg")
    p.add_argument("--height", type=finite_float, default=0.0, help="height, m (default 0)")
    p.add_argument(
        "--earth",
        choices=("ellipsoid", "spherical"),
        default="ellipsoid",
        help="Earth shape (default WGS84 ellipsoid)",
    )
    p.add_argument(
        "--vertical",
        choices=("clamped", "free"),
        default="clamped",
        help="vertical channel (default clamped)",
    )
    add_json_flag(p)


def run(args: argparse.Namespace) -> int:
    site = Site.from_degrees(args.lat, height=args.height, spherical=args.earth == "spherical")
    m = modes(ErrorModel(site, vertical=args.vertical))
    result = {
        "latitude_deg": args.lat,
        "schuler_period_min": m.schuler_period_s / 60.0,
        "foucault_period_h": m.foucault_period_s / 3600.0
        if math.isfinite(m.foucault_period_s)
        else None,
        "earth_period_h": m.earth_period_s / 3600.0,
        "eigenvalues_per_s": [[float(e.real), float(e.imag)] for e in m.eigenvalues],
        "earth_model": args.earth,
        "gravity_m_s2": site.g,
        "vertical_time_constant_s": m.vertical_time_constant_s,
    }
    rows = [
        ["Schuler", f"{result['schuler_period_min']:.3f} min"],
        [
            "Foucault",
            "infinite (no split)"
            if result["foucault_period_h"] is None
            else f"{result['foucault_period_h']:.3f} h",
        ],
        ["Earth (sidereal)", f"{result['earth_period_h']:.4f} h"],
    ]
    if m.vertical_time_constant_s:
        rows.append(["vertical divergence", f"{m.vertical_time_constant_s:.1f} s time constant"])
    emit(
        args,
        result,
        f"Eigen-periods at latitude {args.lat:g} deg ({args.earth} Earth, g = {site.g:.5f})\n"
        + format_table(["mode", "period"], rows),
    )
    return 0
