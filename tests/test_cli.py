"""The core CLI commands: results, JSON keys, and bad input (one clear error, exit 2, no output)."""

import json
import math

import pytest

from inserr.cli.main import main
from inserr.core.earth import OMEGA_IE


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
            "--duration",
            "24 h",
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
    d = _json(capsys, ["drift", "--duration", "6 h", "--arw", "0.001", "--vrw", "10", "--json"])
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
    # The report's figures against the other engine path: the same scenario run by the
    # step-by-step reference engine through the library. 1e-6: on a static base the two
    # engines agree to 3e-7 (tests/test_fast_propagation.py, Phi products in double).
    from inserr.drift.study import run_scheme
    from inserr.scenario.schema import load_scenario

    exact_scen = load_scenario(scen).with_changes({"output.engine": "exact"})
    text = (out / "report.md").read_text()
    for run in res["runs"]:
        exact = run_scheme(exact_scen, run["scheme"]).metrics()
        for key in (
            "max_horizontal_error_nmi",
            "rms_horizontal_error_nmi",
            "worst_case_horizontal_error_nmi",
            "final_horizontal_1sigma_nmi",
        ):
            assert run[key] == pytest.approx(exact[key], rel=1e-6), (run["scheme"], key)
        # The write-up's table quotes results.json (4 significant digits).
        row = next(ln for ln in text.splitlines() if ln.startswith(f"| {run['scheme']} |"))
        assert f"{run['max_horizontal_error_nmi']:.4g}" in row.split("|")[2]
    # Unmodulated, the x/y gyro biases give the larger error: two-position must help.
    assert res["runs"][0]["rms_horizontal_error_nmi"] < res["runs"][1]["rms_horizontal_error_nmi"]


BAD = [
    (["drift", "--scheme", "three-position"], "--scheme (scheme.name)"),
    (["drift", "--lat", "90"], "--lat (site.latitude)"),
    (["drift", "--lat", "-95"], "--lat (site.latitude)"),
    (["drift", "--duration", "-3 h"], "--duration (scenario.duration)"),
    (["drift", "--duration", "0 h"], "--duration (scenario.duration)"),
    (["drift", "--duration", "3"], "no unit"),  # hours in drift, minutes in align: no default
    (["drift", "--gyro-correlation-time", "0"], "--gyro-correlation-time"),
    (["drift", "--gyro-bias", "nan"], "imu.gyro_bias"),
    (["drift", "--gyro-bias", "0.02 furlongs"], "imu.gyro_bias"),
    (["drift", "--gyro-bias", "1,2"], "imu.gyro_bias"),
    (["drift", "--yaw-swing", "6"], "--yaw-swing"),
    (["cycle", "--scheme", "flexible-two-position"], "--scheme (scheme.name)"),
    (["cycle"], "scheme.name"),
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
        ('[scheme]\nname = "spin"\n', "scheme.name"),
        ('[site]\nlatitude = "90 deg"\n', "site.latitude"),
        ('[compare]\nschemes = ["none", "spin"]\n', "compare.schemes"),
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
        "--duration",
        "3 h",
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


def test_out_never_replaces_a_directory_inserr_did_not_write(tmp_path, capsys, monkeypatch):
    # A report directory is replaced as a whole; a user's directory must survive.
    precious = tmp_path / "precious"
    precious.mkdir()
    (precious / "notes.txt").write_text("keep me")
    argv = ["drift", "--duration", "1 h", "--gyro-bias", "0.01"]
    assert main(argv + ["--out", str(precious)]) == 2
    err = capsys.readouterr().err
    assert "--out" in err and "not an inserr report" in err
    assert [p.name for p in precious.iterdir()] == ["notes.txt"]
    monkeypatch.chdir(precious)
    for target in (".", str(tmp_path)):  # the working directory and a parent of it
        assert main(argv + ["--out", target]) == 2
        assert "working directory" in capsys.readouterr().err
    assert main(argv + ["--out", "notes.txt/sub"]) == 2
    assert "is a file" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["precious"]
    assert (precious / "notes.txt").read_text() == "keep me"


def test_out_replaces_an_earlier_report(tmp_path, capsys):
    out = tmp_path / "rep"

    def argv(bias):
        return ["drift", "--duration", "1 h", "--gyro-bias", bias, "--json", "--out", str(out)]

    assert main(argv("0.01")) == 0
    first = json.loads(capsys.readouterr().out)
    assert main(argv("0.02")) == 0
    capsys.readouterr()
    again = json.loads((out / "results.json").read_text())
    assert again["runs"][0]["max_horizontal_error_nmi"] > first["max_horizontal_error_nmi"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rep"]


def test_non_utf8_scenario_and_oversized_run_are_input_errors(tmp_path, capsys):
    scen = tmp_path / "binary.toml"
    scen.write_bytes(b"\xff\xfe[site]\n")
    assert main(["run", str(scen), "--out", str(tmp_path / "r")]) == 2
    assert "UTF-8" in capsys.readouterr().err
    # 5000 h at 1 s would need ~6.5 GB; refused before any work, naming the key and the
    # fix (5000 h = 1.8e7 s over 3e6 samples: at least 6 s). output.step was not given as
    # a flag, so the message names no flag.
    assert main(["drift", "--duration", "5000 h"]) == 2
    err = capsys.readouterr().err
    assert "error: output.step: " in err and "at least 6 s" in err
    assert main(["drift", "--duration", "5000 h", "--step", "3"]) == 2
    assert "error: --step (output.step): " in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["binary.toml"]


def test_interrupt_is_one_line_and_status_130(monkeypatch, capsys):
    import inserr.cli.modes as modes

    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(modes, "run", interrupted)
    assert main(["modes", "--lat", "34"]) == 130
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "interrupted" in err[0]


def test_flag_errors_name_the_flag_typed(capsys):
    assert main(["drift", "--duration", "1 h", "--arw", "-1"]) == 2
    assert capsys.readouterr().err.startswith("inserr drift: error: --arw (imu.arw):")
    assert main(["drift", "--duration", "1 h", "--gyro-misalignment", "1,2"]) == 2
    assert "xy,xz,yx,yz,zx,zy" in capsys.readouterr().err


def test_every_run_in_a_report_gets_its_noise_envelope():
    # The README's main job compares several schemes: each panel must carry its own
    # 1-sigma noise envelope, RMS and worst-case curves, not just the first run.
    from inserr.drift import figures as plots
    from inserr.drift.study import run_scheme
    from inserr.scenario.schema import scenario_from_dict

    scen = scenario_from_dict(
        {
            "scenario": {"duration": "2 h"},
            "imu": {"gyro_bias": "0.01 deg/h", "arw": "0.002 deg/sqrt(h)"},
            "output": {"covariance_step": "600 s"},
        }
    )
    runs = {n: run_scheme(scen, n).result for n in ("none", "two-position", "four-position")}
    fig = plots.horizontal_error(runs)
    panels = [ax for ax in fig.axes if ax.get_visible()]
    assert [ax.get_title() for ax in panels] == list(runs)
    for ax in panels:
        assert len(ax.lines) == 3 and len(ax.collections) == 1
