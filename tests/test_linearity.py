"""Helpers of the linear-vs-nonlinear study (inserr.reference.linearity) that need no pyins.

Truths: the static base keeps exactly the site, attitude and declared heading convention
of the scenario it comes from (a 15 deg heading read counter-clockwise is -15 deg
clockwise inside inserr), and the probe limit is picked by hand from labelled probes.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from inserr.reference.linearity import error_sizes, probe_limits, static_base
from inserr.scenario.schema import load_scenario

P0 = Path(__file__).resolve().parents[1] / "analyses" / "p0_swinging_base" / "scenario.toml"


def test_static_base_keeps_site_attitude_and_convention():
    scen = load_scenario(P0)
    base = static_base(scen, hours=2.0)
    assert base.duration == pytest.approx(7200.0, rel=1e-15)
    assert base.heading_convention == scen.heading_convention == "counter-clockwise-from-north"
    # P0's "15 deg" read counter-clockwise: inserr holds headings clockwise from north.
    assert base.motion.heading == pytest.approx(-math.radians(15.0), rel=1e-14)
    assert (base.motion.pitch, base.motion.roll) == pytest.approx(
        (math.radians(1.0), math.radians(-2.0)), rel=1e-14
    )
    assert base.site.lat == pytest.approx(scen.site.lat, rel=1e-15)
    assert not any(base.imu.gyro_bias) and not any(base.init.attitude)
    ccw = static_base(scen.with_changes({"motion.heading_convention": "clockwise-from-north"}))
    assert ccw.motion.heading == pytest.approx(math.radians(15.0), rel=1e-14)


def test_probe_limits_picks_the_largest_probe_within_one_percent():
    sizes = error_sizes(load_scenario(P0))
    assert sizes["heading_rad"] == pytest.approx(math.radians(1.0 / 60.0), rel=1e-12)  # 60"
    probes = [
        {"probe": "initial heading error 1 deg", "rms_difference_relative_to_max": 0.001},
        {"probe": "initial heading error 3 deg", "rms_difference_relative_to_max": 0.009},
        {"probe": "initial heading error 10 deg", "rms_difference_relative_to_max": 0.05},
        {"probe": "initial north position error 50 km", "rms_difference_relative_to_max": 0.02},
    ]
    lim = probe_limits(probes, sizes)
    assert lim["heading errors"]["text"] == "3 deg"
    # 3 deg against P0's 1 arcmin heading error: 180 times.
    assert lim["heading errors"]["ratio"] == pytest.approx(180.0, rel=1e-12)
    assert "north position errors" not in lim and "tilts" not in lim
