"""Scenario files: the documented examples load, units convert, flags and keys agree."""

import math
import re
from pathlib import Path

import numpy as np
import pytest

from inserr.core.errors import InputError
from inserr.core.units import (
    ARCSEC,
    DEG,
    DEG_PER_HOUR,
    DEG_PER_SQRT_HOUR,
    G0,
    MICRO_G,
    PPM,
    parse_quantity,
)
from inserr.scenario.flags import FLAGS
from inserr.scenario.schema import SCHEMA, STUDY_DEFAULTS, load_scenario, scenario_from_dict

DOCS = Path(__file__).resolve().parents[1] / "docs" / "scenarios.md"


def _toml_blocks():
    return re.findall(r"```toml\n(.*?)```", DOCS.read_text(), re.S)


@pytest.mark.parametrize("index", range(len(_toml_blocks())))
def test_documented_examples_load(index, tmp_path):
    block = _toml_blocks()[index]
    path = tmp_path / "s.toml"
    path.write_text(block)
    scen = load_scenario(path)
    for study in STUDY_DEFAULTS:  # every study accepts every section
        load_scenario(path, study=study)
    if index == 0:
        assert scen.site.lat == pytest.approx(34.246 * DEG)
        assert np.allclose(scen.imu.gyro_bias, 0.003 * DEG_PER_HOUR)
        assert np.allclose(scen.imu.accel_bias, 30e-6 * G0)
        assert np.allclose(scen.imu.gyro_misalignment, 10 * ARCSEC)
        assert scen.imu.arw == pytest.approx(0.0005 * DEG_PER_SQRT_HOUR)
        assert scen.motion.name == "yaw-swing" and scen.motion.period == 120.0
        assert scen.compare == ("none", "flexible-two-position", "heading-isolation")
    elif "[[scheme.steps]]" in block:  # the custom scheme
        steps = scen.scheme_options["steps"]
        assert [s.angle for s in steps] == pytest.approx([math.pi, -math.pi])
        assert steps[0].rotation_time == 18.0
    elif "[alignment]" in block:  # the study sections
        assert scen.value("alignment.position_sigma") == 1.0
        assert scen.value("observability.headings") == pytest.approx((0.0, math.pi))
        assert scen.value("calibration.design_sizes") == (4, 5, 6)
        assert scen.value("calibration.positioning_error") == pytest.approx(3 * ARCSEC)
        assert scen.value("northfinder.hemisphere") == "north"
        assert scen.value("validate.chunk") == 3600.0
        assert scen.value("sweep.parameters") == ("stop=60,300", "rate=3,6")


def test_unit_conversions_against_definitions():
    assert parse_quantity("15 deg/h", "angular_rate", "f") == pytest.approx(math.radians(15) / 3600)
    assert parse_quantity("1 g", "acceleration", "f") == G0
    assert parse_quantity("100 ug", "acceleration", "f") == pytest.approx(100e-6 * 9.80665)
    assert parse_quantity("1 deg/sqrt(h)", "arw", "f") == pytest.approx(math.radians(1) / 60)
    assert parse_quantity("10 ppm", "ratio", "f") == pytest.approx(1e-5)
    assert parse_quantity("6400 mil", "angle", "f") == pytest.approx(2 * math.pi)
    assert parse_quantity("1 nmi", "length", "f") == 1852.0
    assert np.allclose(
        parse_quantity("1, 2, 3 arcsec", "angle", "f", size=3), np.array([1, 2, 3]) * ARCSEC
    )
    assert np.allclose(parse_quantity("5 ppm", "ratio", "f", size=3), 5 * PPM)
    with pytest.raises(InputError, match="f: unknown unit"):
        parse_quantity("3 deg/fortnight", "angular_rate", "f")
    with pytest.raises(InputError, match="no unit"):
        parse_quantity("3", "angular_rate", "f")
    with pytest.raises(InputError, match="not finite"):
        parse_quantity("nan deg/h", "angular_rate", "f")
    assert parse_quantity("7", "acceleration", "f", default_unit="ug") == pytest.approx(7 * MICRO_G)


def test_every_flag_names_a_scenario_key():
    for name, flag in FLAGS.items():
        for key in flag.keys:
            section, _, k = key.partition(".")
            assert k in SCHEMA[section], name


def test_with_changes_and_unknown_keys():
    scen = scenario_from_dict({"scheme": {"name": "two-position"}})
    changed = scen.with_changes({"scheme.stop": "60 s", "site.latitude": "10 deg"})
    assert changed.scheme_stop == 60.0 and changed.site.lat == pytest.approx(10 * DEG)
    assert scen.scheme_stop == 300.0  # the original is untouched
    with pytest.raises(InputError, match="scheme.stopp"):
        scen.with_changes({"scheme.stopp": "60 s"})


def test_heading_history_file(tmp_path):
    (tmp_path / "h.csv").write_text("# time_s, heading_deg\n0, 10\n100, 20\n200, 10\n")
    (tmp_path / "s.toml").write_text(
        '[scenario]\nduration = "200 s"\n[motion]\ntype = "heading-history"\nfile = "h.csv"\n'
    )
    scen = load_scenario(tmp_path / "s.toml")
    assert scen.motion.heading_at(np.array([50.0]))[0] == pytest.approx(15 * DEG)
    tl = scen.timeline()
    assert tl.meta["exact_intervals"] == len(tl.omega_n)  # piecewise-constant heading rate
    (tmp_path / "s.toml").write_text(
        '[scenario]\nduration = "300 s"\n[motion]\ntype = "heading-history"\nfile = "h.csv"\n'
    )
    with pytest.raises(InputError, match="motion.heading_history"):
        load_scenario(tmp_path / "s.toml")
