"""Hostile inputs (issue 14): a fixed corpus of named bad inputs, and generated ones.

Every bad input must give exit status 2 and one clear line on stderr (``inserr CMD:
error: ...``), no traceback, and write nothing; a legal input outside the linear
model's range must run and say so. CLI cases run in-process (``main(argv)``) and are
refused before any work, so the corpus is fast.
"""

from __future__ import annotations

import io
import json
import math
import os
import signal
import subprocess
import sys
import time
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from inserr.cli.main import main
from inserr.core.errors import InputError

ROOT = Path(__file__).resolve().parents[1]

# --- running the CLI in-process ---------------------------------------------------------


def run_cli(argv: list[str]) -> tuple[int, str, str]:
    """``main(argv)``: (status, stdout, stderr); argparse's SystemExit becomes a status."""
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        try:
            rc = main(list(argv))
        except SystemExit as exc:  # argparse's own errors
            rc = exc.code if isinstance(exc.code, int) else 2
    return rc, out.getvalue(), err.getvalue()


def snapshot(root: Path) -> dict[str, bytes]:
    """Every file under ``root`` with its bytes (to prove nothing changed)."""
    return {str(p.relative_to(root)): p.read_bytes() for p in root.rglob("*") if p.is_file()}


def assert_one_clear_line(rc: int, err: str, command: str | None = None) -> None:
    assert rc == 2, err
    assert "Traceback" not in err, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert ": error: " in lines[0], err
    if command is not None:
        assert lines[0].startswith(f"inserr {command}"), err


def finite_numbers(obj) -> bool:
    """Whether every number in a JSON document is finite (None counts as non-finite)."""
    if isinstance(obj, dict):
        return all(finite_numbers(v) for k, v in obj.items() if k != "report")
    if isinstance(obj, list):
        return all(finite_numbers(v) for v in obj)
    if obj is None:
        return False
    if isinstance(obj, float):
        return math.isfinite(obj)
    return True


# --- the corpus: CLI flags ----------------------------------------------------------------

#: Short, cheap runs: 1 h, coarse steps.
SHORT = ["--duration", "1h", "--step", "60", "--covariance-step", "600"]

#: flag -> values outside its range (beyond the garbage every flag gets).
OUT_OF_RANGE = {
    "duration": ["0s", "-1h", "1e-12h", "1e-9 s", "400d", "1e6min"],
    "lat": ["90", "-90", "91", "1e3"],
    "lon": ["400", "-1e9"],
    "height": ["-7000000", "1e8", "1e12", "-6378137", "200000"],
    "gyro-bias": ["1e300", "2e4", "1,2"],
    "accel-bias": ["1e6", "-2e5"],
    "gyro-sf": ["2e5"],
    "accel-sf": ["-3e5"],
    "gyro-misalignment": ["1e6", "1,2,3"],
    "accel-misalignment": ["-1e6"],
    "arw": ["-0.1", "1e4"],
    "vrw": ["-5", "1e9"],
    "gyro-bias-instability": ["-0.01", "1e5"],
    "accel-bias-instability": ["-1"],
    "gyro-correlation-time": ["0", "-60"],
    "accel-correlation-time": ["0"],
    "initial-attitude": ["1e6", "0,0,1e9"],
    "initial-velocity": ["5000", "0,0,-1e4"],
    "initial-position": ["1e7"],
    "heading": ["1000"],
    "pitch": ["95", "-91"],
    "roll": ["181"],
    "turn-rate": ["1e3"],
    "rate": ["0", "1e4"],
    "stop": ["-5", "1e9"],
    "step": ["0", "-1", "1e9"],
    "covariance-step": ["0"],
    "substep": ["-1"],
}

#: Values no numeric flag accepts.
GARBAGE = ["nan", "inf", "-inf", "abc", "1e400"]

CLI_BAD: dict[str, list[str]] = {}
for _flag, _values in OUT_OF_RANGE.items():
    for _v in [*_values, *GARBAGE]:
        CLI_BAD[f"drift --{_flag} {_v}"] = ["drift", *SHORT, f"--{_flag}={_v}"]

CLI_BAD.update(
    {
        # issue 14's reproductions (flags renamed since: --hours -> --duration ...)
        "issue modes height -7e6": ["modes", "--lat", "45", "--height=-7000000"],
        "phase bogus": ["drift", *SHORT, "--scheme", "nulling-two-position", "--phase", "bogus"],
        "phase on two-position": [
            "drift",
            *SHORT,
            "--scheme",
            "two-position",
            "--phase",
            "synchronous",
        ],
        "issue modes height 1e8": ["modes", "--lat", "45", "--height", "1e8"],
        "issue modes height 1e12": ["modes", "--lat", "45", "--height", "1e12"],
        "issue align seed -1": ["align", "--seed=-1", "--duration", "1min"],
        "issue validate seed -1": [
            "validate",
            "--duration",
            "0.1h",
            "--seed=-1",
            "--runs",
            "2",
            "--arw",
            "0.001",
        ],  # fmt: skip
        "issue northfind 1e6 min": [
            "northfind",
            "--lat",
            "34",
            "--heading",
            "30",
            "--duration",
            "1e6min",
            "--runs",
            "2",
        ],  # fmt: skip
        "northfind 200 d at 100 Hz": [
            "northfind",
            "--lat",
            "34",
            "--heading",
            "30",
            "--duration",
            "200d",
            "--runs",
            "2",
        ],  # fmt: skip
        "issue free vertical 72 h": [
            "drift",
            "--vertical",
            "free",
            "--duration",
            "72h",
            "--gyro-bias",
            "0.01",
            "--accel-bias",
            "50",
            "--arw",
            "0.001",
            "--json",
        ],  # fmt: skip
        "issue compare empty item": [
            "compare",
            *SHORT,
            "--scheme",
            "four-position",
            "--schemes",
            "two-position,,heading-isolation",
        ],  # fmt: skip
        "compare trailing comma": ["compare", *SHORT, "--schemes", "two-position,"],
        "compare only commas": ["compare", *SHORT, "--schemes", ",,"],
        "issue delta -1": [
            "drift",
            *SHORT,
            "--scheme",
            "flexible-two-position",
            "--delta=-1",
        ],  # fmt: skip
        "delta 0": ["drift", *SHORT, "--scheme", "flexible-two-position", "--delta", "0"],
        "delta 2": ["drift", *SHORT, "--scheme", "flexible-two-position", "--delta", "2"],
        "delta ignored by two-position": [
            "drift",
            *SHORT,
            "--scheme",
            "two-position",
            "--delta",
            "0.5",
        ],  # fmt: skip
        "reversal ignored by four-position": [
            "drift",
            *SHORT,
            "--scheme",
            "four-position",
            "--reversal",
            "600",
        ],  # fmt: skip
        "yaw swing without amplitude": ["drift", *SHORT, "--yaw-swing", "0,60"],
        "issue schemes bogus": ["compare", *SHORT, "--schemes", "bogus"],
        "unknown scheme": ["drift", *SHORT, "--scheme", "seventeen-position"],
        "unknown vertical": ["drift", *SHORT, "--vertical", "loose"],
        "unknown engine": ["drift", *SHORT, "--engine", "warp"],
        "unknown flag": ["drift", *SHORT, "--gyro-bi", "0.1"],
        "unknown command": ["drfit"],
        "seed -1": ["align", "--seed=-1"],
        "seed 2**64": ["align", "--seed", str(2**64)],
        "seed text": ["align", "--seed", "one"],
        "runs 0": ["validate", "--runs", "0"],
        "runs -3": ["northfind", "--runs=-3"],
        "missing scenario file": ["drift", "no-such-file.toml"],
        "scenario is a directory": ["drift", "."],
    }
)


@pytest.mark.parametrize("argv", list(CLI_BAD.values()), ids=list(CLI_BAD))
def test_bad_cli_input_is_one_line_and_exit_2(argv, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    rc, out, err = run_cli(argv)
    assert_one_clear_line(rc, err)
    assert out == ""
    assert list(tmp_path.iterdir()) == []  # nothing written


def test_corpus_is_large_enough():
    # Issue 14: at least 150 named bad inputs (all kinds together).
    assert len(CLI_BAD) + len(SCENARIO_BAD) + len(OUT_BAD) + len(API_BAD) >= 150


def test_a_flag_error_names_the_flag_and_the_key():
    rc, _, err = run_cli(["modes", "--height=-7000000"])
    assert_one_clear_line(rc, err, "modes")
    assert "--height (site.height)" in err and "-11000 to 100000 m" in err


# --- the corpus: scenario files -----------------------------------------------------------

SCENARIO_BAD: dict[str, str] = {
    "duration 1e-11 s": '[scenario]\nduration = "1e-11 s"\n',
    "duration 0": '[scenario]\nduration = "0 s"\n',
    "duration negative": '[scenario]\nduration = "-1 h"\n',
    "duration without unit": "[scenario]\nduration = 3600\n",
    "duration nan": '[scenario]\nduration = "nan h"\n',
    "seed -1": "[scenario]\nseed = -1\n",
    "seed float": "[scenario]\nseed = 1.5\n",
    "seed string": '[scenario]\nseed = "0"\n',
    "seed too big": f"[scenario]\nseed = {2**63}\n",
    "runs 0": "[scenario]\nruns = 0\n",
    "gyro bias 1e308": '[scenario]\nduration = "1 h"\n[imu]\ngyro_bias = "1e308 deg/h"\n',
    "gyro bias inf": '[imu]\ngyro_bias = "inf deg/h"\n',
    "gyro bias bare number": "[imu]\ngyro_bias = 0.01\n",
    "gyro bias wrong unit": '[imu]\ngyro_bias = "0.01 m/s"\n',
    "gyro bias four values": '[imu]\ngyro_bias = "1, 2, 3, 4 deg/h"\n',
    "gyro bias empty item": '[imu]\ngyro_bias = "1,, 3 deg/h"\n',
    "arw negative": '[imu]\narw = "-0.01 deg/sqrt(h)"\n',
    "sample rate 0": '[imu]\nsample_rate = "0 Hz"\n',
    "height below the Earth": '[site]\nheight = "-7000 km"\n',
    "latitude 90": '[site]\nlatitude = "90 deg"\n',
    "latitude as number": "[site]\nlatitude = 34\n",
    "earth unknown": '[site]\nearth = "flat"\n',
    "unknown section": "[imus]\n",
    "unknown key": '[imu]\ngyro_biass = "0 deg/h"\n',
    "section not a table": 'site = "here"\n',
    "steps on a non-custom scheme": (
        '[scheme]\nname = "two-position"\n'
        '[[scheme.steps]]\ngimbal = "inner"\nangle = "180 deg"\ndwell = "10 s"\n'
    ),
    "custom step of 0 deg": (
        '[scheme]\nname = "custom"\n'
        '[[scheme.steps]]\ngimbal = "outer"\nangle = "0 deg"\ndwell = "10 s"\n'
        '[[scheme.steps]]\ngimbal = "outer"\nangle = "180 deg"\ndwell = "10 s"\n'
        '[[scheme.steps]]\ngimbal = "outer"\nangle = "-180 deg"\ndwell = "10 s"\n'
    ),
    "delta on two-position": '[scheme]\nname = "two-position"\ndelta = 0.5\n',
    "variant on none": '[scheme]\nvariant = "crossing"\n',
    "phase unknown": '[scheme]\nname = "nulling-two-position"\nphase = "resonant"\n',
    "phase on two-position": '[scheme]\nname = "two-position"\nphase = "synchronous"\n',
    "reversal on two-position": '[scheme]\nname = "two-position"\nreversal = "60 s"\n',
    "stop 0 s on two-position": '[scheme]\nname = "two-position"\nstop = "-1 s"\n',
    "yaw-swing without amplitude": '[motion]\ntype = "yaw-swing"\n',
    "amplitude on a static vehicle": '[motion]\namplitude = "2 deg/s"\n',
    "turn rate on a yaw swing": (
        '[motion]\ntype = "yaw-swing"\namplitude = "2 deg/s"\nrate = "1 deg/s"\n'
    ),
    "heading history without file": '[motion]\ntype = "heading-history"\n',
    "pitch 100 deg": '[motion]\npitch = "100 deg"\n',
    "compare empty item": '[compare]\nschemes = ["two-position", "", "none"]\n',
    "compare blank item": '[compare]\nschemes = ["  "]\n',
    "compare not a list": '[compare]\nschemes = "two-position"\n',
    "output substep 0": '[output]\nsubstep = "0 s"\n',
    "output vertical free 72 h": '[scenario]\nduration = "72 h"\n[output]\nvertical = "free"\n',
    "malformed TOML": "[scenario\n",
    "not UTF-8": "\udcff",  # written as bytes below
    "duplicate key": '[scenario]\nduration = "1 h"\nduration = "2 h"\n',
}


@pytest.mark.parametrize("text", list(SCENARIO_BAD.values()), ids=list(SCENARIO_BAD))
def test_bad_scenario_file_is_one_line_and_exit_2(text, tmp_path, monkeypatch):
    path = tmp_path / "bad.toml"
    if text == "\udcff":
        path.write_bytes(b"\xff\xfe[site]\n")
    else:
        path.write_text(text, encoding="utf-8")
    before = snapshot(tmp_path)
    monkeypatch.chdir(tmp_path)
    rc, out, err = run_cli(["drift", str(path), "--step", "60", "--json"])
    assert_one_clear_line(rc, err, "drift")
    assert out == "" and snapshot(tmp_path) == before


def test_cycle_refuses_a_custom_table_that_does_not_return_to_its_start(tmp_path):
    path = tmp_path / "c.toml"
    rows = '[[scheme.steps]]\ngimbal = "inner"\nangle = "{}"\ndwell = "100 s"\n'
    path.write_text('[scheme]\nname = "custom"\n' + rows.format("90 deg"), encoding="utf-8")
    rc, _, err = run_cli(["cycle", str(path), "--json"])
    assert_one_clear_line(rc, err, "cycle")
    assert "scheme.steps" in err and "90 deg" in err
    # +90 then -90 (or four times +90) returns to the start: accepted.
    for angles in (["90 deg", "-90 deg"], ["90 deg"] * 4):
        text = '[scheme]\nname = "custom"\n' + "".join(rows.format(a) for a in angles)
        path.write_text(text, encoding="utf-8")
        rc, _, err = run_cli(["cycle", str(path), "--json"])
        assert rc == 0, err


def test_a_utf8_bom_is_accepted(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes('\ufeff[scenario]\nduration = "1 h"\n'.encode())
    rc, out, err = run_cli(["drift", str(path), *SHORT[2:], "--json"])
    assert rc == 0, err
    assert json.loads(out)["hours"] == pytest.approx(1.0)


# --- the corpus: --out paths --------------------------------------------------------------

#: name -> how to prepare tmp_path; returns (argv, files that must stay as they are).
OUT_BAD = {
    "D1 results.json + report.md + a thesis": "d1",
    "D3 notes.txt in an earlier report": "d3",
    "D4 scenario inside the report folder": "d4",
    "edited file in an earlier report": "edited",
    "out is a file": "file",
    "out is the working directory": "cwd",
    "out is a symlink to a user folder": "symlink",
    "out inside a regular file": "under-file",
    "out read-only": "readonly",
}


def _prepare_out(case: str, tmp: Path, ok: Path) -> tuple[list[str], Path]:
    out = tmp / "w"
    run = ["run", str(ok), "--out"]
    if case == "d1":
        out.mkdir()
        (out / "results.json").write_text("{}")
        (out / "report.md").write_text("x")
        (out / "thesis.tex").write_text("t")
    elif case in ("d3", "edited", "d4"):
        assert run_cli([*run, str(out)])[0] == 0
        if case == "d3":
            (out / "notes.txt").write_text("mine")
        elif case == "edited":
            (out / "report.md").write_text("my edits")
        else:
            (out / "ok.toml").write_bytes(ok.read_bytes())
            return ["run", str(out / "ok.toml"), "--out", str(out)], out
    elif case == "file":
        out.write_text("a file")
    elif case == "cwd":
        return [*run, "."], tmp
    elif case == "symlink":
        (tmp / "mine").mkdir()
        (tmp / "mine" / "a.txt").write_text("a")
        out.symlink_to(tmp / "mine")
    elif case == "under-file":
        (tmp / "f").write_text("x")
        return [*run, str(tmp / "f" / "sub")], tmp
    elif case == "readonly":
        out.mkdir()
        out.chmod(0o500)
    return [*run, str(out)], out


@pytest.mark.parametrize("case", list(OUT_BAD.values()), ids=list(OUT_BAD))
def test_out_directory_that_is_not_inserrs_is_refused_untouched(
    case, tmp_path, monkeypatch, ok_scenario
):
    if case == "readonly" and os.geteuid() == 0:
        # As root permission bits do not apply; the write probe is what refuses a
        # read-only place (test_write_probe_refuses_a_read_only_file_system).
        pytest.skip("root ignores permission bits")
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    argv, _ = _prepare_out(case, work, ok_scenario)
    before = snapshot(work)
    rc, out, err = run_cli(argv)
    assert_one_clear_line(rc, err, "run")
    assert "Fix:" in err
    assert snapshot(work) == before
    if case in ("d1", "d3"):  # names the (first) file inserr did not write
        assert "which inserr did not write" in err
    if case == "d3":
        assert "notes.txt" in err


def test_write_probe_refuses_a_read_only_file_system(tmp_path, monkeypatch, ok_scenario):
    """EROFS (a read-only mount: refused even for root) is found before any work."""
    import errno

    import inserr.output.outdir as outdir

    real_open = os.open

    def read_only(path, flags, *a, **k):
        if ".inserr-probe-" in str(path):
            raise OSError(errno.EROFS, "Read-only file system")
        return real_open(path, flags, *a, **k)

    monkeypatch.setattr(outdir.os, "open", read_only)
    calls = []
    import inserr.drift.study as study

    monkeypatch.setattr(study, "analyze_drift", lambda *a, **k: calls.append(1))
    rc, _, err = run_cli(["run", str(ok_scenario), "--out", str(tmp_path / "r")])
    assert_one_clear_line(rc, err, "run")
    assert "read-only file system" in err and calls == []


def test_an_earlier_report_is_replaced_and_leftovers_of_a_killed_run_cleaned(tmp_path, ok_scenario):
    from inserr.output.outdir import TMP_TAG

    out = tmp_path / "r"
    assert run_cli(["run", str(ok_scenario), "--out", str(out)])[0] == 0
    first = snapshot(out)
    # A killed run's temporaries: the pid is one that cannot run (pid_max < 2**22).
    dead = 4_194_999
    ours = tmp_path / f".r.tmp-{dead}-abcd"
    ours.mkdir()
    (ours / TMP_TAG).write_text(f"{dead} {os.uname().nodename}\n")
    (ours / "report.md").write_text("half")
    theirs = tmp_path / f".r.tmp-{dead}-efgh"  # same pattern, no tag: not provably ours
    theirs.mkdir()
    (theirs / "data").write_text("user")
    assert run_cli(["run", str(ok_scenario), "--out", str(out)])[0] == 0
    assert not ours.exists()
    assert (theirs / "data").read_text() == "user"
    assert set(snapshot(out)) == set(first)


def test_killing_a_sweep_takes_its_workers_with_it(tmp_path):
    """SIGKILL of the main process: its worker processes end within a few seconds."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cmd = [
        sys.executable, "-m", "inserr.cli.main", "sweep", "--scheme", "four-position",
        "--duration", "24h", "--gyro-bias", "0.02", "--param", "stop=20,30,40,50,60,70,80,90",
        "--workers", "2", "--no-plots", "--out", str(tmp_path / "s"),
    ]  # fmt: skip
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

    def children() -> list[int]:
        try:
            text = Path(f"/proc/{proc.pid}/task/{proc.pid}/children").read_text()
        except OSError:
            return []
        return [int(p) for p in text.split()]

    # Wait for the worker pool (generous: the machine may be loaded).
    deadline = time.monotonic() + 60
    kids: list[int] = []
    while time.monotonic() < deadline and len(kids) < 2:
        time.sleep(0.2)
        kids = children()
    try:
        assert len(kids) >= 2, "the sweep started no worker processes"
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()

    def alive(pid: int) -> bool:
        try:
            stat = Path(f"/proc/{pid}/stat").read_text()
        except OSError:
            return False
        return stat.rsplit(")", 1)[1].split()[0] != "Z"

    # Workers poll their parent every 0.5 s; allow for a loaded machine.
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and any(alive(p) for p in kids):
        time.sleep(0.2)
    assert not any(alive(p) for p in kids)


# --- the corpus: the Python API -----------------------------------------------------------


def _api(case: str):
    from inserr.core.earth import Site
    from inserr.core.imu import ImuErrors
    from inserr.drift.study import run_scheme
    from inserr.scenario.schema import load_scenario, scenario_from_dict

    ok = scenario_from_dict({"scenario": {"duration": "1 h"}, "output": {"step": "60 s"}})
    return {
        "gyro_bias None": lambda: scenario_from_dict({"imu": {"gyro_bias": None}}),
        "gyro_bias list of numbers": lambda: scenario_from_dict({"imu": {"gyro_bias": [1, 2]}}),
        "latitude a list": lambda: scenario_from_dict({"site": {"latitude": ["34 deg"]}}),
        "height 1e12": lambda: scenario_from_dict({"site": {"height": "1e12 m"}}),
        "seed None": lambda: scenario_from_dict({"scenario": {"seed": None}}),
        "seed -1": lambda: scenario_from_dict({"scenario": {"seed": -1}}),
        "section a list": lambda: scenario_from_dict({"imu": [1]}),
        "duration 1e-9 s": lambda: scenario_from_dict({"scenario": {"duration": "1e-9 s"}}),
        "empty scheme name": lambda: run_scheme(ok, ""),
        "blank scheme name": lambda: run_scheme(ok, "  "),
        "unknown scheme name": lambda: run_scheme(ok, "bogus"),
        "scheme name a number": lambda: run_scheme(ok, 5),
        "Site latitude a string": lambda: Site("34", 0.0, 0.0),
        "Site latitude None": lambda: Site(None, 0.0, 0.0),
        "Site height a list": lambda: Site(0.5, 0.0, [1.0]),
        "ImuErrors gyro_bias a string": lambda: ImuErrors(gyro_bias="0.01"),
        "ImuErrors gyro_bias None": lambda: ImuErrors(gyro_bias=None),
        "ImuErrors gyro_bias strings": lambda: ImuErrors(gyro_bias=["1", "2", "3"]),
        "ImuErrors gyro_bias four values": lambda: ImuErrors(gyro_bias=[1e-6] * 4),
        "scenario_from_dict None": lambda: scenario_from_dict(None),
        "scenario_from_dict a list": lambda: scenario_from_dict([1]),
        "load_scenario None": lambda: load_scenario(None),
        "scenario None": lambda: run_scheme(None),
        "scenario a string": lambda: run_scheme("ok.toml"),
    }[case]


API_BAD = [
    "Site latitude a string",
    "Site latitude None",
    "Site height a list",
    "ImuErrors gyro_bias a string",
    "ImuErrors gyro_bias None",
    "ImuErrors gyro_bias strings",
    "ImuErrors gyro_bias four values",
    "scenario_from_dict None",
    "scenario_from_dict a list",
    "load_scenario None",
    "gyro_bias None",
    "gyro_bias list of numbers",
    "latitude a list",
    "height 1e12",
    "seed None",
    "seed -1",
    "section a list",
    "duration 1e-9 s",
    "empty scheme name",
    "blank scheme name",
    "unknown scheme name",
    "scheme name a number",
    "scenario None",
    "scenario a string",
]


@pytest.mark.parametrize("case", API_BAD)
def test_api_raises_input_error_or_type_error(case):
    call = _api(case)
    with pytest.raises((InputError, TypeError)) as info:
        call()
    # The message names what is wrong: a scenario key for InputError.
    if isinstance(info.value, InputError):
        assert info.value.field


# --- legal but outside the model: a correct result with a warning ------------------------


@pytest.mark.parametrize(
    "argv, fragment",
    [
        # issue 14: heading error -36.6 deg near the pole with nothing said
        (["--lat", "89.999", "--gyro-bias", "0.02", "--accel-bias", "100"], "polar limit"),
        # issue 14: 100 deg/h over 72 h: here 1 h is enough to pass 1 deg of heading
        (["--gyro-bias", "100"], "heading error reaches"),
        (["--initial-attitude", "3600,0,0"], "tilt error reaches"),
        (["--initial-velocity", "0,900,0"], "fixed-site linearization"),
        (["--vertical", "free"], "free vertical channel"),
    ],
    ids=["pole band", "heading past limit", "tilt past limit", "fixed site", "free vertical"],
)
def test_legal_input_outside_the_linear_model_runs_with_a_warning(argv, fragment, tmp_path):
    rc, out, err = run_cli(["drift", *SHORT, *argv, "--json"])
    assert rc == 0, err
    doc = json.loads(out)
    warnings = doc["warnings"]
    assert any(fragment in w for w in warnings), warnings
    assert finite_numbers(doc)
    # ... in the human output and the report too
    rc, out, err = run_cli(["drift", *SHORT, *argv, "--out", str(tmp_path / "r")])
    assert rc == 0 and fragment in out + err
    assert fragment in (tmp_path / "r" / "report.md").read_text(encoding="utf-8")


def test_an_ordinary_run_has_no_validity_warning():
    rc, out, _ = run_cli(["drift", *SHORT, "--gyro-bias", "0.02", "--accel-bias", "50", "--json"])
    assert rc == 0 and json.loads(out)["warnings"] == []


def test_free_vertical_time_constant_is_sqrt_r_over_2g():
    """The unstable root of h'' = (2 g / R) h: tau = sqrt(R / (2 g)), closed form."""
    from inserr.core.earth import Site
    from inserr.drift.validity import vertical_time_constant

    # Near the pole (L = 1.55 rad) the Coriolis coupling of the vertical to the east
    # channel, (2 Omega cos L)^2 / (2 g / R) ~ 3e-6, is negligible, so the unstable
    # root is the free-air gradient's alone (at mid latitudes it shifts tau by ~0.2 %).
    site = Site(1.55, 0.0, 0.0, spherical=True)
    tau = vertical_time_constant(site)
    expected = math.sqrt(site.mean_radius / (2.0 * site.g))
    assert tau == pytest.approx(expected, rel=1e-5)


def test_schuler_resonance_flags_only_real_near_resonances():
    from inserr.drift.validity import near_schuler_resonance

    ts = 5067.0
    day = 86400.0
    # Issue 14's case: a 48120 s cycle is 9.5 Schuler periods; the 9th and 10th
    # harmonics are 1/(2 x 48120 s) from f_s, outside the 1/(2 x 24 h) band.
    assert near_schuler_resonance(48120.0, ts, day) is None
    # Exactly 4 Schuler periods: the 4th harmonic is at f_s.
    assert near_schuler_resonance(4 * ts, ts, day) == 4
    # Detuned by half the band: flagged; by twice the band: not.
    for k in (1, 3, 9):
        inside = k / (1.0 / ts + 0.5 / (2.0 * day))
        outside = k / (1.0 / ts + 2.0 / (2.0 * day))
        assert near_schuler_resonance(inside, ts, day) == k
        assert near_schuler_resonance(outside, ts, day) is None
    # A short cycle far from the Schuler period is never flagged.
    assert near_schuler_resonance(600.0, ts, day) is None


def test_non_finite_results_are_an_error():
    from inserr.drift.validity import check_finite

    class Res:
        nav = np.zeros((2, 9))
        attitude = np.zeros((2, 3))
        source_horizontal = np.zeros((1, 0, 2))
        noise_cov = {"arw": np.full((2, 9, 9), np.nan)}

    with pytest.raises(InputError, match="non-finite"):
        check_finite(Res(), "none")
    Res.noise_cov = {}
    check_finite(Res(), "none")
    # One bad entry anywhere, of either sign or kind, in any of the arrays.
    for bad in (np.nan, np.inf, -np.inf):
        for name in ("nav", "attitude"):
            arr = np.zeros((5, 9 if name == "nav" else 3))
            arr[3, 1] = bad
            setattr(Res, name, arr)
            with pytest.raises(InputError, match="non-finite"):
                check_finite(Res(), "none")
            setattr(Res, name, np.zeros_like(arr))
    check_finite(Res(), "none")


def test_attitude_extent_is_the_largest_tilt_and_heading_error():
    from inserr.drift.validity import attitude_extent

    rng = np.random.default_rng(3)
    att = rng.normal(size=(1001, 3))
    att[500, 1], att[17, 2] = -9.0, 7.0  # a negative tilt and a positive heading extreme
    assert attitude_extent(att) == (9.0, 7.0)
    assert attitude_extent(-att) == (9.0, 7.0)
    assert attitude_extent(np.zeros((0, 3))) == (0.0, 0.0)


def test_a_drift_result_knows_whether_it_is_finite(monkeypatch):
    # The analysis finds finiteness with its derived curves (on two threads) and keeps
    # it; a result with one bad entry in any of its arrays must say it is not finite.
    import dataclasses

    from inserr.core.earth import Site
    from inserr.core.imu import ImuErrors, InitialErrors
    from inserr.core.units import DEG_PER_HOUR, DEG_PER_SQRT_HOUR
    from inserr.drift.analysis import analyze_drift
    from inserr.drift.validity import check_finite
    from inserr.model.timeline import Timeline

    imu = ImuErrors(gyro_bias=np.array([0.01, 0.0, 0.0]) * DEG_PER_HOUR,
                    arw=0.001 * DEG_PER_SQRT_HOUR)  # fmt: skip
    res = analyze_drift(Site.from_degrees(34.0), imu, InitialErrors(),
                        Timeline.static(np.eye(3), 1200.0), dt_out=1.0, dt_cov=60.0)  # fmt: skip
    assert vars(res)["finite"] is True and res.finite
    check_finite(res, "none")
    for name in ("nav", "attitude", "source_horizontal", "source_heading", "noise_cov"):
        for bad in (np.nan, np.inf):
            if name == "noise_cov":
                value = {k: np.where(np.eye(9) > 0, bad, v) for k, v in res.noise_cov.items()}
            else:
                value = getattr(res, name).copy()
                value.flat[value.size // 2] = bad
            broken = dataclasses.replace(res, **{name: value})
            assert not broken.finite
            with pytest.raises(InputError, match="non-finite"):
                check_finite(broken, "none")
    # ... and the value the analysis itself keeps, when the engine gives a bad number
    # in the fine outputs or in the per-source responses.
    import inserr.drift.analysis as analysis

    real = analysis.constant_error_response
    for part in ("fine", "coarse"):

        def poisoned(*args, part=part, **kwargs):
            resp = real(*args, **kwargs)
            values = getattr(resp, part)
            values[len(values) // 2, 2] = np.nan  # psi_U: the heading error, not the horizontal
            return resp

        monkeypatch.setattr(analysis, "constant_error_response", poisoned)
        still = Timeline.static(np.eye(3), 1200.0)
        bad = analyze_drift(Site.from_degrees(34.0), imu, InitialErrors(), still, dt_out=1.0,
                            dt_cov=60.0)  # fmt: skip
        assert vars(bad)["finite"] is False
        with pytest.raises(InputError, match="non-finite"):
            check_finite(bad, "none")


# --- generated inputs (hypothesis) --------------------------------------------------------

_NUMBERS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True, width=64).map(repr),
    st.integers(-(10**20), 10**20).map(str),
    st.sampled_from(["", "abc", "1,2", "1,,2", "0", "-0", "1e-300", "0x10", "1 h", "2 deg"]),
)

_FLAGS = [
    "lat", "lon", "height", "gyro-bias", "accel-bias", "arw", "vrw", "gyro-sf", "heading",
    "pitch", "roll", "turn-rate", "rate", "stop", "initial-attitude", "initial-velocity",
]  # fmt: skip

_SCHEMES = ["none", "two-position", "four-position", "continuous", "bogus", ""]


def _check_run(argv: list[str], root: Path) -> None:
    before = snapshot(root)
    rc, out, err = run_cli(argv)
    assert rc in (0, 2), (argv, err)
    assert "Traceback" not in err, (argv, err)
    if rc == 2:
        assert len(err.strip().splitlines()) == 1, (argv, err)
        assert snapshot(root) == before
    else:
        assert finite_numbers(json.loads(out)), argv
        # Nothing but the --out directory appears; nothing that was there changes.
        after = snapshot(root)
        assert {k: v for k, v in after.items() if not k.startswith("out/")} == before


@settings(
    max_examples=25,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(
    flags=st.dictionaries(st.sampled_from(_FLAGS), _NUMBERS, max_size=3),
    scheme=st.sampled_from(_SCHEMES),
    out=st.booleans(),
)
def test_generated_cli_arguments(flags, scheme, out, tmp_path_factory):
    root = tmp_path_factory.mktemp("gen")
    (root / "keep.txt").write_text("the user's")
    argv = ["drift", "--duration", "1h", "--step", "300", "--covariance-step", "1800"]
    argv += ["--scheme", scheme] + [f"--{k}={v}" for k, v in flags.items()] + ["--json"]
    if out:
        argv += ["--out", str(root / "out")]
    cwd = os.getcwd()
    os.chdir(root)
    try:
        _check_run(argv, root)
    finally:
        os.chdir(cwd)


_TOML_VALUES = st.one_of(
    st.integers(-(10**6), 10**6),
    st.floats(allow_nan=False, allow_infinity=False),
    st.booleans(),
    st.sampled_from(['"1 h"', '"0.02 deg/h"', '"34 deg"', '"nan deg"', '""', '"x"', "[]"]),
)

_KEYS = [
    ("site", "latitude"), ("site", "height"), ("imu", "gyro_bias"), ("imu", "accel_bias"),
    ("imu", "arw"), ("initial", "attitude"), ("motion", "heading"), ("motion", "type"),
    ("scheme", "name"), ("scheme", "stop"), ("scheme", "delta"), ("output", "vertical"),
    ("compare", "schemes"), ("scenario", "seed"), ("bogus", "key"),
]  # fmt: skip


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    return v


@settings(
    max_examples=25,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(entries=st.dictionaries(st.sampled_from(_KEYS), _TOML_VALUES, max_size=4))
def test_generated_scenario_files(entries, tmp_path_factory):
    root = tmp_path_factory.mktemp("gen")
    sections: dict[str, list[str]] = {}
    for (section, key), value in entries.items():
        sections.setdefault(section, []).append(f"{key} = {_toml_value(value)}")
    text = '[scenario]\nduration = "1 h"\n' if "scenario" not in sections else ""
    for section, lines in sections.items():
        text += f"[{section}]\n" + "\n".join(lines) + "\n"
        if section == "scenario" and not any(k.startswith("duration") for k in lines):
            text += 'duration = "1 h"\n'
    (root / "s.toml").write_text(text, encoding="utf-8")
    argv = ["drift", str(root / "s.toml"), "--step", "300", "--covariance-step", "1800"]
    _check_run([*argv, "--json", "--out", str(root / "out")], root)


# --- fixtures -----------------------------------------------------------------------------


@pytest.fixture
def ok_scenario(tmp_path) -> Path:
    """Issue 14's ``ok.toml``: 1 h, gyro bias 0.02 deg/h (coarse steps: fast)."""
    path = tmp_path / "ok.toml"
    path.write_text(
        '[scenario]\nduration = "1 h"\n[imu]\ngyro_bias = "0.02 deg/h"\n'
        '[output]\nstep = "60 s"\ncovariance_step = "600 s"\n',
        encoding="utf-8",
    )
    return path


@pytest.mark.parametrize(
    "argv, package, extra",
    [
        (["sweep", "--duration", "1h", "--param", "stop=60,300", "--no-plots"], "dask", "sweep"),
        (["validate", "--duration", "0.1h"], "pyins", "reference"),
    ],
    ids=["sweep without dask", "validate without pyins"],
)
def test_missing_optional_extra_names_the_pip_install(argv, package, extra, monkeypatch, tmp_path):
    # A package set to None in sys.modules cannot be imported (ModuleNotFoundError), as
    # after the README's plain ``pip install .``; the modules that import it are
    # dropped so that they import again.
    for name in list(sys.modules):
        if name.split(".")[0] == package or name.startswith(("inserr.sweep", "inserr.cli.sweep")):
            monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, package, None)
    monkeypatch.chdir(tmp_path)
    rc, _, err = run_cli([*argv, "--out", str(tmp_path / "o")])
    assert_one_clear_line(rc, err, argv[0])
    assert f"pip install 'inserr[{extra}]'" in err
    assert list(tmp_path.iterdir()) == []


def test_every_range_is_documented():
    from inserr.scenario.schema import NUMBER_RANGES, RANGES

    text = (ROOT / "docs" / "scenarios.md").read_text(encoding="utf-8")
    section = text.split("## Ranges", 1)[1].split("\n## ", 1)[0]
    for key in [*RANGES, *NUMBER_RANGES]:
        assert f"| `{key}` |" in section, key


@pytest.fixture
def read_only_dir(tmp_path):
    """An empty directory on a read-only bind mount (root ignores permission bits, not
    a read-only mount); skipped where mounting is not allowed."""
    ro = tmp_path / "ro"
    ro.mkdir()
    if os.geteuid() != 0:
        ro.chmod(0o500)
        yield ro
        ro.chmod(0o700)
        return
    try:
        subprocess.run(["mount", "--bind", str(ro), str(ro)], check=True, capture_output=True)
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("cannot bind-mount here")
    try:
        subprocess.run(["mount", "-o", "remount,bind,ro", str(ro)], check=True, capture_output=True)
        yield ro
    finally:
        subprocess.run(["umount", str(ro)], check=False, capture_output=True)


@pytest.mark.parametrize("where", ["itself", "inside"])
@pytest.mark.parametrize("command", ["run", "sweep"])
def test_unwritable_out_is_refused_before_any_work(
    command, where, read_only_dir, ok_scenario, monkeypatch
):
    """Issue 14: run did all the work, then PermissionError/EBUSY; sweep gave EROFS."""
    import inserr.drift.study as study

    calls = []
    monkeypatch.setattr(study, "analyze_drift", lambda *a, **k: calls.append(1))
    out = read_only_dir if where == "itself" else read_only_dir / "new"
    argv = [command, str(ok_scenario), "--out", str(out)]
    if command == "sweep":
        argv += ["--param", "stop=60,300", "--scheme", "two-position", "--workers", "1"]
    rc, _, err = run_cli(argv)
    assert_one_clear_line(rc, err, command)
    assert "cannot write" in err or "mount point" in err, err
    assert calls == [] and list(read_only_dir.iterdir()) == []
