"""``inserr sweep``: grid syntax and validation, engines, determinism, resume, failures."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from inserr.cli.main import main
from inserr.scenario import scenario_from_dict
from inserr.sweep import build_grid, parse_param
from inserr.units import DEG, HOUR, MICRO_G

# One-hour scenarios keep every point well under a second. The budget has a
# Gauss-Markov gyro bias (rotating noise states) and the grid short stops: the
# combination whose noise results once depended on which points a worker process
# had run before (shared discretization cache), which the identity tests must catch.
BASE = ["--scheme", "four-position", "--lat", "34", "--hours", "1", "--gyro-bias", "0.02",
        "--accel-bias", "100", "--arw", "0.001", "--gyro-bias-instability", "0.001"]  # fmt: skip
GRID = ["--param", "stop=20,30", "--param", "rate=6,10"]


def sweep(tmp: Path, *extra: str, grid: list[str] = GRID) -> int:
    return main(["sweep", *BASE, *grid, "--no-plots", "--out", str(tmp), *extra])


def rows(out: Path) -> list[dict[str, str]]:
    with open(out / "results.csv", newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def sync_run(tmp_path_factory) -> Path:
    """The reference: the 4-point grid run in this process."""
    out = tmp_path_factory.mktemp("sync") / "out"
    assert sweep(out, "--workers", "1") == 0
    return out


# --- the grid ----------------------------------------------------------------------------
def test_param_syntax_flags_dotted_and_brackets():
    stop = parse_param("stop=60,2 min")
    assert stop.changes == ({"scheme.stop": "60 s"}, {"scheme.stop": "2 min"})
    assert stop.axis() == ([60.0, 120.0], "stop (s)")
    dotted = parse_param("imu.gyro_bias=[0.01,0.02,0.03] deg/h, 0.02 deg/h")
    assert dotted.values == ("[0.01,0.02,0.03] deg/h", "0.02 deg/h")
    assert dotted.changes[0] == {"imu.gyro_bias": "0.01,0.02,0.03 deg/h"}
    assert dotted.axis()[0] is None  # a triple has no single position on an axis
    swing = parse_param("yaw-swing=[6,60],[3,120]")
    assert swing.changes[1] == {
        "motion.type": "yaw-swing",
        "motion.amplitude": "3 deg/s",
        "motion.period": "120 s",
    }
    assert parse_param("scheme.delta=0.005,0.01").changes[0] == {"scheme.delta": 0.005}
    assert parse_param("correlation-time=600").changes[0] == {
        "imu.gyro_correlation_time": "600 s",
        "imu.accel_correlation_time": "600 s",
    }


def test_grid_values_reach_the_scenario():
    base = scenario_from_dict({"scheme": {"name": "two-position"}})
    grid = build_grid(base, ["rate=3,6", "imu.gyro_bias=[0.01,0.02,0.03] deg/h,0.5 deg/h"])
    assert grid.shape == (2, 2) and len(grid.points) == 4
    first, second = (base.with_changes(pt.changes) for pt in grid.points[:2])
    assert first.scheme_rate == second.scheme_rate == pytest.approx(3 * DEG)  # last one fastest
    assert np.allclose(first.imu.gyro_bias, np.array([0.01, 0.02, 0.03]) * DEG / HOUR)
    assert np.allclose(second.imu.gyro_bias, 0.5 * DEG / HOUR)


def test_point_identity_and_seed_do_not_depend_on_the_grid():
    base = scenario_from_dict({"scenario": {"seed": 7}})
    small = build_grid(base, ["stop=60,300", "rate=3"])
    big = build_grid(base, ["stop=30,300,60", "rate=3"])
    ids = {pt.values[0]: (pt.id, pt.seed) for pt in big.points}
    for pt in small.points:
        assert ids[pt.values[0]] == (pt.id, pt.seed)
    assert len({pt.seed for pt in big.points}) == 3  # no shared random stream
    other_seed = build_grid(
        scenario_from_dict({"scenario": {"seed": 8}}), ["stop=60,300", "rate=3"]
    )
    assert {pt.seed for pt in other_seed.points}.isdisjoint({pt.seed for pt in small.points})


@pytest.mark.parametrize(
    "params, fragment",
    [
        (["stop="], "empty list"),
        (["stop=60,,300"], "empty value"),
        (["bogus=1,2"], "unknown parameter"),
        (["scheme.bogus=1 s"], "unknown scenario key"),
        (["compare.schemes=none"], "cannot be swept"),
        (["stop=60,60"], "duplicated"),
        (["stop=60,60 s"], "are the same"),
        (["stop=60", "stop=300"], "given twice"),
        (["stop=60", "scheme.stop=300 s"], "already sets"),
        (["scheme.stop=60,300"], "has no unit"),
        (["stop=60,-5"], "invalid in every point"),
        (["imu.gyro_bias=0.1 deg/fortnight"], "unknown unit"),
        (["gyro-bias=[1,2]"], "expected 1 or 3 values"),
        (["gyro-bias=[1,[2]]"], "nested brackets"),
        (["scheme.delta=small"], "not a number"),
    ],
)
def test_invalid_grids_fail_before_any_work(tmp_path, capsys, params, fragment):
    out = tmp_path / "out"
    grid = [x for p in params for x in ("--param", p)]
    assert main(["sweep", *BASE, *grid, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert fragment in err and len(err.splitlines()) == 1
    assert not out.exists()


def test_unreachable_cluster_fails_before_any_work(tmp_path, capsys):
    out = tmp_path / "out"
    code = main(["sweep", *BASE, *GRID, "--scheduler", "not-a-scheduler", "--out", str(out)])
    assert code == 2 and "--scheduler" in capsys.readouterr().err
    assert not out.exists()


# --- running -----------------------------------------------------------------------------
def test_small_grid_locally(sync_run):
    table = rows(sync_run)
    assert [(r["stop"], r["rate"]) for r in table] == [
        ("20", "6"), ("20", "10"), ("30", "6"), ("30", "10")
    ]  # fmt: skip
    assert all(r["status"] == "ok" and r["error"] == "" for r in table)
    # each row is the drift analysis of the base scenario with that point's values
    from inserr.summary import run_scheme

    scen = scenario_from_dict(
        {
            "scenario": {"duration": "1 h"},
            "site": {"latitude": "34 deg"},
            "imu": {"gyro_bias": "0.02 deg/h", "accel_bias": "100 ug", "arw": "0.001 deg/sqrt(h)",
                    "gyro_bias_instability": "0.001 deg/h"},
            "scheme": {"name": "four-position", "stop": "30 s", "rate": "6 deg/s"},
        }
    )  # fmt: skip
    direct = run_scheme(scen).metrics()
    assert float(table[2]["max_horizontal_error_nmi"]) == direct["max_horizontal_error_nmi"]
    assert (
        float(table[2]["worst_case_horizontal_error_nmi"])
        == direct["worst_case_horizontal_error_nmi"]
    )
    assert scen.imu.accel_bias[0] == pytest.approx(100 * MICRO_G)
    assert len(list((sync_run / "points").glob("*.json"))) == 4


def test_plots_follow_the_number_of_parameters(tmp_path):
    for grid, names in [
        (["--param", "stop=60,300"], {"sweep.png"}),
        (GRID, {"sweep.png"}),
        (
            [*GRID, "--param", "lat=20,40"],
            {"sweep_max_horizontal_error_nmi.png", "sweep_worst_case_horizontal_error_nmi.png"},
        ),
    ]:
        out = tmp_path / str(len(grid))
        assert main(["sweep", *BASE, *grid, "--workers", "1", "--out", str(out)]) == 0
        assert {p.name for p in out.glob("*.png")} == names


def test_processes_give_identical_results(sync_run, tmp_path):
    out = tmp_path / "out"
    code = sweep(out, "--workers", "2", "--scheduler", "processes")
    assert code == 0, (out / "results.csv").read_text()
    assert (out / "results.csv").read_text() == (sync_run / "results.csv").read_text()


def test_loopback_cluster_gives_identical_results(sync_run, tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        host="127.0.0.1", n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as cluster:
        out = tmp_path / "out"
        code = sweep(out, "--scheduler", cluster.scheduler_address, "--json")
    assert code == 0, (out / "results.csv").read_text()
    assert (out / "results.csv").read_text() == (sync_run / "results.csv").read_text()


# --- resume and failures -----------------------------------------------------------------
@pytest.fixture
def count_runs(monkeypatch):
    """Count the drift analyses done in this process (sync scheduler)."""
    import inserr.summary

    calls = []
    real = inserr.summary.run_scheme

    def counting(scen, name=None):
        calls.append(scen.scheme_stop)
        return real(scen, name)

    monkeypatch.setattr(inserr.summary, "run_scheme", counting)
    return calls


def test_resume_redoes_only_missing_points(sync_run, tmp_path, capsys, count_runs):
    out = tmp_path / "out"
    assert sweep(out, "--workers", "1") == 0
    assert len(count_runs) == 4
    files = sorted((out / "points").glob("*.json"))
    for gone in files[:2]:  # as if the run had been interrupted before these two
        gone.unlink()
    kept = {f: f.stat().st_mtime_ns for f in files[2:]}
    capsys.readouterr()
    assert sweep(out, "--workers", "1", "--json") == 0
    result = json.loads(capsys.readouterr().out)
    assert (result["computed"], result["resumed"]) == (2, 2)
    assert len(count_runs) == 6
    assert {f: f.stat().st_mtime_ns for f in kept} == kept  # finished points untouched
    assert (out / "results.csv").read_text() == (sync_run / "results.csv").read_text()


def test_growing_the_grid_reuses_finished_points(tmp_path, capsys, count_runs):
    out = tmp_path / "out"
    assert sweep(out, "--workers", "1", grid=["--param", "stop=60,300"]) == 0
    capsys.readouterr()
    assert sweep(out, "--workers", "1", "--json", grid=["--param", "stop=60,120,300"]) == 0
    assert json.loads(capsys.readouterr().out)["computed"] == 1
    assert sorted(count_runs[:2]) == [60.0, 300.0] and count_runs[2:] == [120.0]


def test_failing_point_does_not_sink_the_sweep(tmp_path, monkeypatch, capsys):
    import inserr.summary

    real = inserr.summary.run_scheme

    def flaky(scen, name=None):
        if scen.scheme_stop == 20 and scen.scheme_rate == 10 * DEG:
            raise RuntimeError("simulated failure")
        return real(scen, name)

    monkeypatch.setattr(inserr.summary, "run_scheme", flaky)
    out = tmp_path / "out"
    assert sweep(out, "--workers", "1") == 1  # 1: some point failed and may succeed on a rerun
    table = rows(out)
    assert [r["status"] for r in table] == ["ok", "failed", "ok", "ok"]
    assert "RuntimeError: simulated failure" in table[1]["error"]
    assert table[1]["max_horizontal_error_nmi"] == ""
    monkeypatch.setattr(inserr.summary, "run_scheme", real)
    capsys.readouterr()
    assert sweep(out, "--workers", "1", "--json") == 0  # the failed point is retried, only it
    assert json.loads(capsys.readouterr().out)["computed"] == 1
    assert [r["status"] for r in rows(out)] == ["ok"] * 4


def test_invalid_combination_is_recorded_and_the_rest_go_on(tmp_path):
    out = tmp_path / "out"
    grid = ["--param", "scheme=continuous,two-position", "--param", "stop=0,60"]
    assert sweep(out, "--workers", "1", grid=grid) == 0
    table = rows(out)
    assert [r["status"] for r in table] == ["ok", "ok", "invalid", "ok"]
    assert "stop time" in table[2]["error"]


def test_killed_sweep_resumes_without_redoing_finished_points(tmp_path):
    out = tmp_path / "out"
    cmd = [
        sys.executable,
        "-m",
        "inserr.cli.main",
        "sweep",
        *BASE,
        "--hours",
        "2",
        "--param",
        "stop=30,60,90,120,150,180,240,300",
        "--workers",
        "1",
        "--no-plots",
        "--out",
        str(out),
    ]
    env = {**os.environ, "INSERR_NO_PROGRESS": "1"}
    proc = subprocess.Popen(
        cmd, env=env, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    deadline = time.monotonic() + 120
    while not list((out / "points").glob("*.json")) and time.monotonic() < deadline:
        time.sleep(0.01)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    done = {f: f.stat().st_mtime_ns for f in (out / "points").glob("*.json")}
    assert 1 <= len(done) < 8
    for f in done:
        assert json.loads(f.read_text())["status"] == "ok"  # nothing half-written
    result = subprocess.run([*cmd, "--json"], env=env, capture_output=True, text=True, check=True)
    summary = json.loads(result.stdout)
    assert (summary["computed"], summary["resumed"]) == (8 - len(done), len(done))
    assert {f: f.stat().st_mtime_ns for f in done} == done
    assert [r["status"] for r in rows(out)] == ["ok"] * 8
    assert not [p for p in (out / "points").iterdir() if p.name.startswith(".")]


def _spawned_workers(parent: int) -> list[int]:
    """Worker processes (multiprocessing spawn) whose parent is ``parent``."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            cmd = (entry / "cmdline").read_bytes()
        except OSError:
            continue
        ppid = int(stat.rsplit(")", 1)[1].split()[1])
        if ppid == parent and b"spawn_main" in cmd:
            found.append(int(entry.name))
    return found


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="needs /proc to find worker processes")
def test_lost_worker_fails_its_points_only(tmp_path):
    out = tmp_path / "out"
    cmd = [
        sys.executable,
        "-m",
        "inserr.cli.main",
        "sweep",
        *BASE,
        "--hours",
        "2",
        "--param",
        "stop=20,30,40,50,60,70",
        "--workers",
        "2",
        "--no-plots",
        "--out",
        str(out),
    ]
    env = {**os.environ, "INSERR_NO_PROGRESS": "1"}
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120
    workers: list[int] = []
    while not workers and proc.poll() is None and time.monotonic() < deadline:
        workers = _spawned_workers(proc.pid)
        time.sleep(0.01)
    assert workers, "no worker process appeared"
    os.kill(workers[0], signal.SIGKILL)  # as if the OOM killer took it
    assert proc.wait(timeout=300) == 1  # some point failed
    status = [r["status"] for r in rows(out)]
    lost = [r for r in rows(out) if r["status"] == "failed"]
    assert 1 <= len(lost) <= 2 and status.count("ok") == 6 - len(lost)
    assert all("worker process lost" in r["error"] for r in lost)
    rerun = subprocess.run([*cmd, "--json"], env=env, capture_output=True, text=True)
    assert rerun.returncode == 0, rerun.stderr
    assert json.loads(rerun.stdout)["computed"] == len(lost)
