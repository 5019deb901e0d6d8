"""The P1 analysis script: its scenario file parses to the published set-up, bad keys are
named, and the verdict wording of its write-up (:mod:`inserr.calibration.comparison_report`)
follows the numbers (not the other way round)."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import pytest

from inserr.calibration.comparison import compare_sigmas
from inserr.calibration.comparison_report import sensitivity_sentence, verdict_text
from inserr.core.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "analyses" / "p1_calibration" / "run.py"


@pytest.fixture(scope="module")
def run_module():
    spec = importlib.util.spec_from_file_location("p1_calibration_run", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_scenario_is_p1(run_module):
    sc = run_module.load(SCRIPT.parent / "scenario.toml")
    deg_h = math.pi / 180 / 3600
    assert sc.site.lat == pytest.approx(math.radians(34.0))
    assert sc.imu.gyro_bias / deg_h == pytest.approx([2.04173693, 3.01844241, 2.09545751])
    assert sc.imu.gyro_scale_factor == pytest.approx([1e-4] * 3)
    assert sc.imu.gyro_misalignment == pytest.approx([2.145e-5] * 6)
    assert sc.value("calibration.positioning_error") == pytest.approx(math.radians(3 / 3600))
    assert sc.value("scenario.runs") == 100
    assert sc.value("imu.sample_rate") == 100.0
    assert sc.scheme_stop == 300.0  # P1 gives no dwell: a 5-minute stop
    assert sc.value("analysis.methods.sets") == ("offaxis-four-position", "six-position")


def test_scenario_errors_name_the_field(run_module, tmp_path):
    text = (SCRIPT.parent / "scenario.toml").read_text()
    bad = tmp_path / "s.toml"
    bad.write_text(text.replace('latitude = "34 deg"', 'latitude = "34 deg"\nlongitud = "1 deg"'))
    with pytest.raises(InputError) as exc:
        run_module.load(bad)
    assert exc.value.field == "site.longitud"
    bad.write_text(text.replace('stop = "300 s"', 'stop = "300 m"'))
    with pytest.raises(InputError) as exc:
        run_module.load(bad)
    assert exc.value.field == "scheme.stop"
    bad.write_text(text.replace("tolerance = 0.10", "tolerance = 0.10\ntolerence = 1"))
    with pytest.raises(InputError) as exc:
        run_module.load(bad)
    assert exc.value.field == "analysis.verdict.tolerence"


def _comparison(ratios):
    import numpy as np

    return compare_sigmas(np.array(ratios), np.ones(12), 0.10)


def test_verdict_follows_the_numbers():
    sc = {
        "tolerance": 0.10,
        "dwell_s": 300.0,
        "table_rate_deg_s": 6.0,
        "arw_deg_per_sqrt_h": 5e-4,
        "positioning_error_arcsec": 3.0,
    }
    same = _comparison([1.05] * 12)
    worse = _comparison([1.3] * 3 + [1.0] * 9)
    v = {
        "time_four_s": 1290.0,
        "time_six_s": 1905.0,
        "time_saving": 1 - 1290 / 1905,
        "dwell_only_saving": 1 / 3,
        "equal_dwell": same,
        "noise_free": same,
        "equal_time": same,
        "d_efficiency_four_over_six": 1.0,
        "best_six": {
            "mechanism": "trunnion",
            "stops_outer_inner_deg": [(0, 0)],
            "total_time_s": 1875.0,
            "equal_dwell": same,
            "equal_time": same,
            "noise_free": same,
        },
    }
    assert "claim holds" in verdict_text(v, sc, "four", "six")[-1]
    v["equal_dwell"] = worse
    text = verdict_text(v, sc, "four", "six")[-1]
    assert "does not hold" in text and "3 of 12" in text


def test_sensitivity_sentence_follows_the_numbers():
    from inserr.calibration.summary import positioning_sensitivity_summary
    from inserr.calibration.two_axis_table import six_position
    from inserr.core.earth import Site

    block = positioning_sensitivity_summary(six_position(), Site(math.radians(34.0)), "gyro")
    text = sensitivity_sentence("six", block, 3.0)
    # The classical set's x gyro only sees the vertical Earth rate: an east tilt at the
    # x-up/x-down stops (p4, p5) feeds the north rate straight into sf_x.
    assert "sf_x among the scale factors" in text and "about east at p4 and p5" in text
    assert "all 3 biases equally" in text
    block["sf_y"]["largest"]["abs_ppm_per_arcsec"] = 10.0  # make sf_y the largest
    assert "sf_y among the scale factors (10 ppm/arcsec" in sensitivity_sentence("six", block, 3.0)
