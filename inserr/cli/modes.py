"""``inserr modes``: Schuler, Foucault and Earth periods read off the model's eigenvalues."""

from __future__ import annotations

import argparse
import math

from inserr.cli.common import add_json_flag, emit, format_table
from inserr.scenario.flags import add_flags, scenario_from_args

#: The flags of ``inserr modes``: the site and the vertical channel.
FLAG_NAMES = ("lat", "height", "earth", "vertical")


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_flags(p, "drift", FLAG_NAMES)
    add_json_flag(p)


def run(args: argparse.Namespace) -> int:
    from inserr.model.psi_model import ErrorModel, modes

    scen = scenario_from_args(args)
    site, earth = scen.site, scen.value("site.earth")
    lat_deg = math.degrees(site.lat)
    m = modes(ErrorModel(site, vertical=scen.vertical))
    result = {
        "latitude_deg": lat_deg,
        "schuler_period_min": m.schuler_period_s / 60.0,
        "foucault_period_h": m.foucault_period_s / 3600.0
        if math.isfinite(m.foucault_period_s)
        else None,
        "earth_period_h": m.earth_period_s / 3600.0,
        "eigenvalues_per_s": [[float(e.real), float(e.imag)] for e in m.eigenvalues],
        "earth_model": earth,
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
        f"Eigen-periods at latitude {lat_deg:g} deg ({earth} Earth, g = {site.g:.5f})\n"
        + format_table(["mode", "period"], rows),
    )
    return 0
