"""The core CLI commands: results, JSON keys, and bad input (one clear error, exit 2, no output)."""

import json
import math

import pytest

from inserr.cli.main import main
from inserr.earth import OMEGA_IE


def _json(capsys, argv):
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_modes_json_reads_periods_off_the_eigenvalues(capsys):
    d = _json(capsys, ["modes", "--lat", "34", "--json"])
    assert 84.4 <= d["schuler_period_min"] <= 84.6
    assert d["foucault_period_h"] == pytest.approx(42.8, abs=0.1)
    assert d["earth_period_h"] == pytest.approx(2 * math.pi / OMEGA_IE / 3600, rel=1e-9)


def test_drift_json_keys_and_static_longitude_drift(capsys):
    d = _json(
        capsys,
        [
            "drift",
            "--scheme",
            "none",
            "--lat",
            "34",
            "--hours",
            "24",
            "--gyro-bias",
            "0.02",
            "--accel-bias",
            "100",
            "--json",
        ],
    )
    for key in (
        "scheme",
        "hours",
        "max_horizontal_error_nmi",
        "final_horizontal_error_nmi",
        "final_horizontal_1sigma_nmi",
        "final_heading_error_deg",
        "rms_horizontal_error_nmi",
        "worst_case_horizontal_error_nmi",
        "error_budget",
        "motor_starts_per_hour",
    ):
        assert key in d
    assert d["final_horizontal_1sigma_nmi"] == 0.0  # no noise given
    # The drift along Earth's axis, 0.02 deg/h (cos L + sin L), turns into longitude
    # error at that rate: 0.667 deg of longitude in 24 h, i.e. 33.2 nmi at 34 deg.
    lon_rate = 0.02 * (math.cos(math.radians(34)) + math.sin(math.radians(34)))
    expected = lon_rate * 24 * 60 * math.cos(math.radians(34))
    # Within 3 %: the east-gyro part adds a bounded (24 h periodic) latitude error.
    assert d["final_horizontal_error_nmi"] == pytest.approx(expected, rel=0.03)
    # Worst sign pattern >= the given pattern; RMS of independent signs below the worst.
    assert d["worst_case_horizontal_error_nmi"] >= d["max_horizontal_error_nmi"] - 1e-9
    assert d["rms_horizontal_error_nmi"] <= d["worst_case_horizontal_error_nmi"]


def test_drift_with_noise_reports_covariance(capsys):
    d = _json(capsys, ["drift", "--hours", "6", "--arw", "0.001", "--vrw", "10", "--json"])
    assert d["final_horizontal_1sigma_nmi"] > 0
    assert set(d["error_budget"]) == {"arw", "vrw"}


def test_cycle_json(capsys):
    d = _json(
        capsys, ["cycle", "--scheme", "four-position", "--rate", "6", "--stop", "300", "--json"]
    )
    assert d["horizontal_cycle_integral_s"][0][0] == pytest.approx(27.009, abs=1e-3)
    assert d["horizontal_cycle_integral_s"][1][1] == pytest.approx(27.009, abs=1e-3)
    assert abs(d["horizontal_cycle_integral_s"][0][1]) < 1e-9
    for name in ("two-position", "four-position-modified"):
        d = _json(capsys, ["cycle", "--scheme", name, "--json"])
        assert max(abs(v) for row in d["horizontal_cycle_integral_s"] for v in row) < 1e-9


def test_run_writes_a_complete_report(tmp_path, capsys):
    scen = tmp_path / "s.toml"
    scen.write_text(
        '[scenario]\nname = "t"\nduration = "2 h"\n'
        '[imu]\ngyro_bias = "0.01 deg/h"\narw = "0.001 deg/sqrt(h)"\n'
        '[scheme]\nname = "two-position"\nstop = "120 s"\n[compare]\nschemes = ["none"]\n'
    )
    out = tmp_path / "rep"
    assert main(["run", str(scen), "--out", str(out), "--json"]) == 0
    names = {p.name for p in out.iterdir()}
    assert {
        "report.md",
        "report.html",
        "results.json",
        "horizontal_error.png",
        "attitude_errors.png",
    } <= names
    res = json.loads((out / "results.json").read_text())
    assert [r["scheme"] for r in res["runs"]] == ["two-position", "none"]
    assert "<img" in (out / "report.html").read_text()


BAD = [
    (["drift", "--scheme", "three-position"], "--scheme"),
    (["drift", "--lat", "90"], "latitude"),
    (["drift", "--lat", "-95"], "latitude"),
    (["drift", "--hours", "-3"], "duration"),
    (["drift", "--hours", "0"], "duration"),
    (["drift", "--gyro-bias", "nan"], "imu.gyro_bias"),
    (["drift", "--gyro-bias", "0.02 furlongs"], "imu.gyro_bias"),
    (["drift", "--gyro-bias", "1,2"], "imu.gyro_bias"),
    (["drift", "--yaw-swing", "6"], "--yaw-swing"),
    (["cycle", "--scheme", "flexible-two-position"], "--scheme"),
]


@pytest.mark.parametrize("argv,field", BAD)
def test_bad_flags_give_one_clear_error(argv, field, capsys, tmp_path):
    out = tmp_path / "never"
    extra = ["--out", str(out)] if argv[0] == "drift" else []
    assert main(argv + extra) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0] and "error" in err[0]
    assert not out.exists()


@pytest.mark.parametrize(
    "content,field",
    [
        ('[imu]\ngyro_bias = "0.02 deg/fortnight"\n', "imu.gyro_bias"),
        ('[imu]\ngyro_bias = "0.02"\n', "imu.gyro_bias"),  # scenario values must carry units
        ('[imu]\ngyro_bais = "0.02 deg/h"\n', "imu.gyro_bais"),
        ('[sight]\nlatitude = "34 deg"\n', "sight"),
        ('[imu\ngyro_bias = "0.02 deg/h"\n', "malformed TOML"),
        ('[scheme]\nname = "spin"\n', "--scheme"),
        ('[site]\nlatitude = "90 deg"\n', "latitude"),
        ('[scenario]\nduration = "-1 h"\n', "scenario.duration"),
        ('[motion]\ntype = "heave"\n', "motion.type"),
    ],
)
def test_bad_scenario_files_fail_before_any_output(content, field, tmp_path, capsys):
    scen = tmp_path / "bad.toml"
    scen.write_text(content)
    out = tmp_path / "report"
    assert main(["run", str(scen), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0]
    assert not out.exists()
    assert not any(p.name.startswith(".report") for p in tmp_path.iterdir())


def test_missing_scenario_file(capsys, tmp_path):
    assert main(["run", str(tmp_path / "nope.toml")]) == 2
    assert "not found" in capsys.readouterr().err


def test_same_inputs_same_numbers(capsys):
    argv = [
        "drift",
        "--scheme",
        "flexible-two-position",
        "--hours",
        "3",
        "--gyro-bias",
        "0.01",
        "--yaw-swing",
        "6,120",
        "--pitch",
        "1",
        "--json",
    ]
    a = _json(capsys, argv)
    b = _json(capsys, argv)
    assert a == b
