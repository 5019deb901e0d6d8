"""Measure where the linear psi model parts from the nonlinear strapdown reference.

The linear-validity monitor of ``inserr drift`` (:mod:`inserr.drift.validity`) warns
when a run leaves the range where the linear model holds. Its thresholds come from
this measurement: each family below grows one error until the linear prediction and
the nonlinear reference (:mod:`inserr.reference`, python-ins) part, and records the
*departure* at each magnitude,

* position: ``max_t |dr_nl - dr_lin| / max_t |dr_lin|`` (horizontal error vectors),
* attitude: ``max_t |phi_nl - phi_lin| / max_t |phi_lin|`` (all three components),

beside the quantities the monitor watches in the linear result: the largest attitude
error ``max |phi|`` and the fixed-site measure ``max |dr_h| max(1, |tan L|) / R``.
The tables in ``docs/theory.md`` (section 7) are this script's output.

    python tools/linear_validity.py            # all families (about 15 minutes)
    python tools/linear_validity.py --only heading

Needs the optional extra ``inserr[reference]``.
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from inserr.core.units import ARCSEC
from inserr.reference.validation import interpolate, validate
from inserr.scenario.schema import scenario_from_dict

#: The reference's IMU rate, Hz: the cases are static (no coning to resolve).
RATE = 10.0

#: family -> (description, base scenario, key varied, values, how to print a value)
FAMILIES: dict[str, tuple[str, dict, str, list, str]] = {
    "heading": (
        "initial heading error, static, 2 h, lat 34 deg",
        {"scenario": {"duration": "2 h"}},
        "initial.attitude",
        [
            "0, 0, 0.1 deg",
            "0, 0, 0.3 deg",
            "0, 0, 1 deg",
            "0, 0, 2 deg",
            "0, 0, 5 deg",
            "0, 0, 10 deg",
        ],  # fmt: skip
        "phi_U0",
    ),
    "tilt": (
        "initial east tilt, static, 2 h, lat 34 deg",
        {"scenario": {"duration": "2 h"}},
        "initial.attitude",
        ["0.1, 0, 0 deg", "0.3, 0, 0 deg", "1, 0, 0 deg", "2, 0, 0 deg", "5, 0, 0 deg"],
        "phi_E0",
    ),
    "gyro": (
        "heading gyro bias (IMU z), static, 4 h, lat 34 deg",
        {"scenario": {"duration": "4 h"}},
        "imu.gyro_bias",
        [
            "0, 0, 0.3 deg/h",
            "0, 0, 1 deg/h",
            "0, 0, 3 deg/h",
            "0, 0, 10 deg/h",
            "0, 0, 30 deg/h",
        ],  # fmt: skip
        "b_z",
    ),
    "velocity": (
        "initial north velocity error, static, 2 h, lat 34 deg",
        {"scenario": {"duration": "2 h"}},
        "initial.velocity",
        ["0, 1, 0 m/s", "0, 3, 0 m/s", "0, 10, 0 m/s", "0, 30, 0 m/s", "0, 100, 0 m/s"],
        "dv_N0",
    ),
    "velocity80": (
        "initial north velocity error, static, 2 h, lat 80 deg",
        {"scenario": {"duration": "2 h"}, "site": {"latitude": "80 deg"}},
        "initial.velocity",
        ["0, 0.3, 0 m/s", "0, 1, 0 m/s", "0, 3, 0 m/s", "0, 10, 0 m/s", "0, 30, 0 m/s"],
        "dv_N0",
    ),
    "pole": (
        "gyro 0.1 deg/h and accelerometer 100 ug biases, static, 6 h, by latitude",
        {
            "scenario": {"duration": "6 h"},
            "imu": {"gyro_bias": "0.1 deg/h", "accel_bias": "100 ug"},
        },
        "site.latitude",
        [
            "45 deg",
            "60 deg",
            "70 deg",
            "75 deg",
            "80 deg",
            "85 deg",
            "88 deg",
            "89 deg",
            "89.5 deg",
            "89.9 deg",
        ],
        "lat",
    ),
}


def measure(base: dict, key: str, value: str) -> dict:
    """One linear/nonlinear pair: the departures and the monitored quantities."""
    section, _, name = key.partition(".")
    data = {s: dict(t) for s, t in base.items()}
    data.setdefault(section, {})[name] = value
    scen = scenario_from_dict(data)
    v = validate(scen, rate=RATE, chunk=3600.0)
    lin, nl = v.linear, v.nonlinear
    dr_lin = interpolate(lin.t, lin.nav[:, 6:8], nl.t)
    phi_lin = interpolate(lin.t, lin.attitude, nl.t)
    pos_dep = np.linalg.norm(nl.dr[:, :2] - dr_lin, axis=1).max() / max(
        np.linalg.norm(dr_lin, axis=1).max(), 1e-12
    )
    att_dep = np.abs(nl.phi - phi_lin).max() / max(np.abs(phi_lin).max(), 1e-15)
    lat = scen.site.lat
    r = scen.site.mean_radius
    max_h = float(lin.horizontal.max())
    return {
        "value": value,
        "max_phi_deg": math.degrees(float(np.abs(lin.attitude).max())),
        "max_tilt_arcsec": float(np.abs(lin.attitude[:, :2]).max() / ARCSEC),
        "max_horizontal_km": max_h / 1000.0,
        "fixed_site_measure": max_h * max(1.0, abs(math.tan(lat))) / r,
        "position_departure": float(pos_dep),
        "attitude_departure": float(att_dep),
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", choices=list(FAMILIES), action="append", help="one family")
    args = ap.parse_args(argv)
    for fam in args.only or list(FAMILIES):
        text, base, key, values, label = FAMILIES[fam]
        print(f"\n**{fam}**: {text}\n")
        print(
            f"| {label} | max abs(phi) (deg) | max horizontal (km) | "
            "max abs(dr_h) max(1, abs(tan L)) / R | position departure | attitude departure |"
        )
        print("|---|---|---|---|---|---|")
        for value in values:
            m = measure(base, key, value)
            print(
                f"| {value} | {m['max_phi_deg']:.3g} | {m['max_horizontal_km']:.3g} | "
                f"{m['fixed_site_measure']:.2e} | {100 * m['position_departure']:.2g} % | "
                f"{100 * m['attitude_departure']:.2g} % |",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
