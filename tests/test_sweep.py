"""``inserr sweep``: grid syntax and validation, engines, determinism, resume, failures,
output directory names, figures and their labels."""

from __future__ import annotations

import csv
import io
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from inserr.cli.main import main
from inserr.core.units import DEG, HOUR, MICRO_G
from inserr.scenario.schema import scenario_from_dict
from inserr.sweep.grid import build_grid, default_out_dir, parse_param, slug
from inserr.sweep.store import is_sweep_figure, sweep_figures

# One-hour scenarios keep every point well under a second. The budget has a
# Gauss-Markov gyro bias (rotating noise states) and the grid short stops: the
# combination whose noise results once depended on which points a worker process
# had run before (shared discretization cache), which the identity tests must catch.
BASE = ["--scheme", "four-position", "--lat", "34", "--duration", "1 h", "--gyro-bias", "0.02",
        "--accel-bias", "100", "--arw", "0.001", "--gyro-bias-instability", "0.001"]  # fmt: skip
GRID = ["--param", "stop=20,30", "--param", "rate=6,10"]


def sweep(tmp: Path, *extra: str, grid: list[str] = GRID) -> int:
    """Run ``inserr sweep`` on :data:`BASE` without plots into ``tmp``; return the exit status."""
    return main(["sweep", *BASE, *grid, "--no-plots", "--out", str(tmp), *extra])


def sweep_command(out: Path, param: str, workers: int) -> tuple[list[str], dict[str, str]]:
    """``inserr sweep`` of 2 h points as a separate process (to kill it), and its env."""
    cli = [sys.executable, "-m", "inserr.cli.main", "sweep", *BASE, "--duration", "2 h"]
    cmd = [*cli, "--param", param, "--workers", str(workers), "--no-plots", "--out", str(out)]
    return cmd, {**os.environ, "INSERR_NO_PROGRESS": "1"}


def rows(out: Path) -> list[dict[str, str]]:
    """The rows of ``out/results.csv`` (all values as text)."""
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
    """Flag names, dotted keys, bracketed triples and pairs parse into scenario changes."""
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
    assert parse_param("gyro-correlation-time=600").changes[0] == {
        "imu.gyro_correlation_time": "600 s",
    }
    # The duration has no unit of its own (hours in drift, minutes in studies): a unit
    # is always written.
    assert parse_param("duration=6 h,1 d").changes[1] == {"scenario.duration": "1 d"}


def test_grid_values_reach_the_scenario():
    """Each point's scenario holds its values (last parameter fastest)."""
    base = scenario_from_dict({"scheme": {"name": "two-position"}})
    grid = build_grid(base, ["rate=3,6", "imu.gyro_bias=[0.01,0.02,0.03] deg/h,0.5 deg/h"])
    assert grid.shape == (2, 2) and len(grid.points) == 4
    first, second = (base.with_changes(pt.changes) for pt in grid.points[:2])
    assert first.scheme_rate == second.scheme_rate == pytest.approx(3 * DEG)  # last one fastest
    assert np.allclose(first.imu.gyro_bias, np.array([0.01, 0.02, 0.03]) * DEG / HOUR)
    assert np.allclose(second.imu.gyro_bias, 0.5 * DEG / HOUR)


def test_point_identity_and_seed_do_not_depend_on_the_grid():
    """Ids and seeds depend on the point, not on the grid it is in."""
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


def test_point_identity_follows_the_inserr_version(monkeypatch):
    """A new version gives new point ids (recomputed on resume) but the same seeds."""
    import inserr

    base = scenario_from_dict({"scheme": {"name": "four-position"}})
    before = build_grid(base, ["stop=60,300"]).points
    monkeypatch.setattr(inserr, "__version__", inserr.__version__ + ".post1")
    after = build_grid(base, ["stop=60,300"]).points
    assert {pt.id for pt in before}.isdisjoint({pt.id for pt in after})
    assert [pt.seed for pt in before] == [pt.seed for pt in after]


def test_changed_heading_history_file_recomputes_the_point(tmp_path, capsys, count_runs):
    """Editing the CSV a scenario references (motion.file) makes finished points run again."""
    csv_path = tmp_path / "heading.csv"
    csv_path.write_text("# time_s, heading_deg\n0,0\n3600,10\n")
    scen = tmp_path / "moving.toml"
    scen.write_text(
        '[scenario]\nduration = "1 h"\n[motion]\ntype = "heading-history"\nfile = "heading.csv"\n'
    )
    out = tmp_path / "out"

    def run() -> dict:
        capsys.readouterr()
        args = [str(scen), *BASE, "--param", "stop=20,30", "--workers", "1", "--no-plots"]
        assert main(["sweep", *args, "--out", str(out), "--json"]) == 0
        return json.loads(capsys.readouterr().out)

    assert run()["computed"] == 2
    assert run()["computed"] == 0  # same file: resumed
    first = rows(out)
    csv_path.write_text("# time_s, heading_deg\n0,0\n3600,90\n")  # same name, new data
    again = run()
    assert (again["computed"], again["resumed"]) == (2, 0)
    assert len(count_runs) == 4
    assert [r["seed"] for r in rows(out)] == [r["seed"] for r in first]
    assert rows(out) != first  # the new heading history gave new numbers


@pytest.mark.parametrize(
    "params, fragment",
    [
        (["stop="], "empty list"),
        (["stop=60,,300"], "empty value"),
        (["bogus=1,2"], "unknown parameter"),
        (["scheme.bogus=1 s"], "unknown scenario key"),
        (["compare.schemes=none"], "cannot be swept"),
        (["alignment.zupt_rate=1 Hz,2 Hz"], "cannot be swept"),  # the drift analysis ignores it
        (["duration=6,12"], "has no unit"),
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
    """Bad grids are one-line input errors, with no output directory made."""
    out = tmp_path / "out"
    grid = [x for p in params for x in ("--param", p)]
    assert main(["sweep", *BASE, *grid, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert fragment in err and len(err.splitlines()) == 1
    assert not out.exists()


def test_unreachable_cluster_fails_before_any_work(tmp_path, capsys):
    """An unknown scheduler fails before the output directory exists."""
    out = tmp_path / "out"
    code = main(["sweep", *BASE, *GRID, "--scheduler", "not-a-scheduler", "--out", str(out)])
    assert code == 2 and "--scheduler" in capsys.readouterr().err
    assert not out.exists()


# --- running -----------------------------------------------------------------------------
def test_small_grid_locally(sync_run):
    """Each row is the drift analysis of the base scenario with that point's values."""
    table = rows(sync_run)
    assert [(r["stop"], r["rate"]) for r in table] == [
        ("20", "6"), ("20", "10"), ("30", "6"), ("30", "10")
    ]  # fmt: skip
    assert all(r["status"] == "ok" and r["error"] == "" for r in table)
    # each row is the drift analysis of the base scenario with that point's values
    from inserr.drift.study import run_scheme

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


def _png(**savefig) -> bytes:
    """A small PNG drawn by matplotlib (not by inserr sweep unless ``metadata`` says so)."""
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(1, 1))
    buf = io.BytesIO()
    fig.savefig(buf, format="png", **savefig)
    plt.close(fig)
    return buf.getvalue()


def test_figures_always_belong_to_the_current_results(tmp_path, capsys):
    """Each run leaves exactly its own figures; a file inserr did not write stops the sweep."""
    from inserr.sweep.runner import LocalEngine, run_sweep

    out = tmp_path / "out"
    assert main(["sweep", *BASE, *GRID, "--workers", "1", "--out", str(out), "--no-plots"]) == 0
    foreign = {  # the user's files, some named like inserr's figures
        "sweep_mine.png": _png(),
        "sweep_max_horizontal_error_nmi.png.bak": _png(),
        "notes.txt": b"keep me",
    }
    for name, data in foreign.items():
        before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
        (out / name).write_bytes(data)
        # Refused before any work, naming the file; nothing in the directory changes.
        assert main(["sweep", *BASE, *GRID, "--workers", "1", "--out", str(out)]) == 2
        assert f"holds {name}, which inserr did not write" in capsys.readouterr().err
        after = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
        assert after == {**before, name: data}
        (out / name).unlink()

    def figures_now() -> set[str]:
        return {p.name for p in sweep_figures(out)}

    facets = {"sweep_max_horizontal_error_nmi.png", "sweep_worst_case_horizontal_error_nmi.png"}
    for grid, names in [
        ([*GRID, "--param", "lat=20,40"], facets),
        (["--param", "stop=60,300"], {"sweep.png"}),  # the facets of the last grid must go
        (GRID, {"sweep.png"}),
    ]:
        assert main(["sweep", *BASE, *grid, "--workers", "1", "--out", str(out)]) == 0
        assert figures_now() == names
        assert {p.name for p in out.glob("*.png")} == names

    class Interrupted(LocalEngine):
        def run(self, tasks, on_result):
            raise KeyboardInterrupt

    grid = build_grid(scenario_from_dict({"scheme": {"name": "four-position"}}), ["stop=45,90"])
    with pytest.raises(KeyboardInterrupt):
        run_sweep(grid, out, scheduler=Interrupted("sync", 1))
    assert [r["status"] for r in rows(out)] == ["pending"] * 2
    assert figures_now() == set()  # the figures showed the earlier grid's results

    assert main(["sweep", *BASE, *GRID, "--workers", "1", "--out", str(out)]) == 0
    assert figures_now() == {"sweep.png"}
    assert sweep(out, "--workers", "1") == 0  # --no-plots: no figure of other results is left
    assert figures_now() == set()


def test_figure_mark_is_read_from_the_png_chunks(tmp_path):
    """Only PNG files with inserr's text chunk count as inserr's figures."""
    from inserr.sweep.store import FIGURE_MARK

    cases = {
        "marked.png": _png(metadata=dict([FIGURE_MARK])),
        "plain.png": _png(),
        "other_text.png": _png(metadata={"inserr": "some other figure"}),
        "not_a_png.png": b"sweep figure",
        "truncated.png": _png(metadata=dict([FIGURE_MARK]))[:20],
    }
    for name, data in cases.items():
        (tmp_path / name).write_bytes(data)
    assert [p.name for p in sweep_figures(tmp_path)] == ["marked.png"]
    assert not is_sweep_figure(tmp_path / "missing.png")


def _fake_table(grid) -> tuple[list[str], list[list]]:
    """A results table for ``grid`` with made-up errors (nmi), without running anything."""
    header = ["point", *(p.name for p in grid.params), "seed", "status",
              "max_horizontal_error_nmi", "rms_horizontal_error_nmi",
              "worst_case_horizontal_error_nmi", "error"]  # fmt: skip
    table = [
        [pt.index, *pt.values, pt.seed, "ok", 1.0 + pt.index, 0.5 + pt.index, 2.0 + pt.index, ""]
        for pt in grid.points
    ]
    return header, table


def test_plot_axes_carry_units():
    """Heatmap and line axes name the unit of the values (the flag's, or the written one)."""
    import matplotlib.pyplot as plt

    from inserr.sweep.figures import figures

    base = scenario_from_dict({"scheme": {"name": "four-position"}})

    def draw(params):
        grid = build_grid(base, params)
        figs = figures(grid, *_fake_table(grid))
        axes = [ax for fig in figs.values() for ax in fig.axes if ax.get_label() != "<colorbar>"]
        for fig in figs.values():
            plt.close(fig)
        return axes

    heat = draw(["stop=20,1 min", "rate=6,10"])
    assert {(ax.get_ylabel(), ax.get_xlabel()) for ax in heat} == {("stop (s)", "rate (deg/s)")}
    assert [t.get_text() for t in heat[0].get_yticklabels()] == ["20", "60"]
    assert [t.get_text() for t in heat[0].get_xticklabels()] == ["6", "10"]

    dotted = draw(["scheme.stop=20 s,1 min", "imu.gyro_bias=[0.01,0.02,0.03] deg/h,0.5 deg/h"])
    assert (dotted[0].get_ylabel(), dotted[0].get_xlabel()) == (
        "scheme.stop (s)",
        "imu.gyro_bias (deg/h)",
    )
    assert [t.get_text() for t in dotted[0].get_xticklabels()] == ["[0.01,0.02,0.03]", "0.5"]

    (line,) = draw(["gyro-bias=[0.01,0.02,0.03],0.02"])
    assert line.get_xlabel() == "gyro-bias (deg/h)"
    (line,) = draw(["yaw-swing=[6,60],[3,120]"])
    assert line.get_xlabel() == "yaw-swing (deg/s, s)"
    (line,) = draw(["scheme=two-position,four-position"])
    assert line.get_xlabel() == "scheme"  # names have no unit

    facets = draw(["stop=20,30", "rate=6,10", "lat=20,40"])
    assert {ax.get_xlabel() for ax in facets} == {"rate (deg/s)"}
    assert [ax.get_title() for ax in facets[:2]] == ["lat=20 deg", "lat=40 deg"]


# --- output directory --------------------------------------------------------------------
def test_slug_is_a_safe_directory_name():
    """Spaces, colons, commas, slashes and accents never reach the directory name."""
    name = "sweep-quickstart: 72 h at rest, single- and dual-axis indexing"
    assert slug(name) == "sweep-quickstart-72-h-at-rest-single-and-dual-axis-indexing"
    for text in [name, "a/b\\c", "../..", "Étude N°2", "", "x" * 200, ":::", "A_b-C.toml"]:
        assert re.fullmatch(r"[a-z0-9][a-z0-9_-]*", slug(text)), text
        assert len(slug(text)) <= 60
    assert slug("../..") == "scenario"
    scen = scenario_from_dict({"scenario": {"name": name}})
    assert default_out_dir(scen) == f"sweep-{slug(name)}"
    assert default_out_dir(scen, "analyses/quickstart/Quick Start.toml") == "sweep-quick-start"


def test_default_out_is_named_after_the_scenario_file(tmp_path, monkeypatch):
    """Without --out, the directory is sweep-<slug of the file stem>, in the working directory."""
    name = "sweep-quickstart: 72 h at rest, single- and dual-axis indexing"
    (tmp_path / "Quick Start, v2.toml").write_text(
        f'[scenario]\nname = "{name}"\nduration = "1 h"\n', encoding="utf-8"
    )
    monkeypatch.chdir(tmp_path)
    code = main(["sweep", "Quick Start, v2.toml", *BASE, "--param", "stop=20", "--no-plots"])
    assert code == 0
    made = sorted(p.name for p in tmp_path.iterdir() if p.is_dir())
    assert made == ["sweep-quick-start-v2"]
    assert [r["status"] for r in rows(tmp_path / made[0])] == ["ok"]


def test_processes_give_identical_results(sync_run, tmp_path):
    """Two worker processes give the same results.csv as one process."""
    out = tmp_path / "out"
    code = sweep(out, "--workers", "2", "--scheduler", "processes")
    assert code == 0, (out / "results.csv").read_text()
    assert (out / "results.csv").read_text() == (sync_run / "results.csv").read_text()


def test_loopback_cluster_gives_identical_results(sync_run, tmp_path):
    """A local dask.distributed cluster gives the same results.csv."""
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
    import inserr.drift.study

    calls = []
    real = inserr.drift.study.run_scheme

    def counting(scen, name=None):
        calls.append(scen.scheme_stop)
        return real(scen, name)

    monkeypatch.setattr(inserr.drift.study, "run_scheme", counting)
    return calls


def test_resume_redoes_only_missing_points(sync_run, tmp_path, capsys, count_runs):
    """A rerun computes only the points without a finished record."""
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
    """Adding values to a grid computes only the new points."""
    out = tmp_path / "out"
    assert sweep(out, "--workers", "1", grid=["--param", "stop=60,300"]) == 0
    capsys.readouterr()
    assert sweep(out, "--workers", "1", "--json", grid=["--param", "stop=60,120,300"]) == 0
    assert json.loads(capsys.readouterr().out)["computed"] == 1
    assert sorted(count_runs[:2]) == [60.0, 300.0] and count_runs[2:] == [120.0]


def test_failing_point_does_not_sink_the_sweep(tmp_path, monkeypatch, capsys):
    """A point that raises is recorded as failed and retried on a rerun."""
    import inserr.drift.study

    real = inserr.drift.study.run_scheme

    def flaky(scen, name=None):
        if scen.scheme_stop == 20 and scen.scheme_rate == 10 * DEG:
            raise RuntimeError("simulated failure")
        return real(scen, name)

    monkeypatch.setattr(inserr.drift.study, "run_scheme", flaky)
    out = tmp_path / "out"
    assert sweep(out, "--workers", "1") == 1  # 1: some point failed and may succeed on a rerun
    table = rows(out)
    assert [r["status"] for r in table] == ["ok", "failed", "ok", "ok"]
    assert "RuntimeError: simulated failure" in table[1]["error"]
    assert table[1]["max_horizontal_error_nmi"] == ""
    monkeypatch.setattr(inserr.drift.study, "run_scheme", real)
    capsys.readouterr()
    assert sweep(out, "--workers", "1", "--json") == 0  # the failed point is retried, only it
    assert json.loads(capsys.readouterr().out)["computed"] == 1
    assert [r["status"] for r in rows(out)] == ["ok"] * 4


def test_invalid_combination_is_recorded_and_the_rest_go_on(tmp_path):
    """An invalid combination is recorded as invalid; the other points run."""
    out = tmp_path / "out"
    grid = ["--param", "scheme=continuous,two-position", "--param", "stop=0,60"]
    assert sweep(out, "--workers", "1", grid=grid) == 0
    table = rows(out)
    assert [r["status"] for r in table] == ["ok", "ok", "invalid", "ok"]
    assert "stop time" in table[2]["error"]


def test_killed_sweep_resumes_without_redoing_finished_points(tmp_path):
    """A killed sweep leaves whole records, and a rerun finishes the rest."""
    out = tmp_path / "out"
    cmd, env = sweep_command(out, "stop=30,60,90,120,150,180,240,300", workers=1)
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
    """A killed worker process fails its points only; a rerun retries them."""
    out = tmp_path / "out"
    cmd, env = sweep_command(out, "stop=20,30,40,50,60,70", workers=2)
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


def test_sweep_out_never_mixes_with_a_users_files(tmp_path, monkeypatch, capsys):
    """A sweep refuses a file, the working directory and a directory of other files,
    before any work; an earlier sweep's directory is accepted (that is resuming)."""
    from inserr.cli.main import main
    from inserr.core.errors import InputError
    from inserr.sweep.store import MARKER, check_sweep_dir

    mine = tmp_path / "notes"
    mine.mkdir()
    (mine / "results.csv").write_text("my own table\n")
    argv = ["sweep", "--duration", "1 h", "--param", "stop=60,120"]
    assert main(argv + ["--out", str(mine)]) == 2
    assert "not an inserr sweep" in capsys.readouterr().err
    assert (mine / "results.csv").read_text() == "my own table\n"
    (tmp_path / "afile").write_text("x")
    assert main(argv + ["--out", str(tmp_path / "afile")]) == 2
    assert "not a directory" in capsys.readouterr().err
    monkeypatch.chdir(mine)
    assert main(argv + ["--out", "."]) == 2
    assert "working directory" in capsys.readouterr().err
    # A points/ folder is not enough to pass for a sweep (issue 14, D2): the user's
    # results.csv beside it is never overwritten.
    gis = tmp_path / "gis"
    (gis / "points").mkdir(parents=True)
    (gis / "results.csv").write_text("lat,lon\n")
    assert main(argv + ["--out", str(gis)]) == 2
    assert "gis holds points, which inserr did not write" in capsys.readouterr().err
    assert (gis / "results.csv").read_text() == "lat,lon\n"
    # An earlier sweep's directory is accepted (resuming), with or without its marker
    # (sweeps written before markers are recognized by their content).
    earlier = tmp_path / "earlier"
    assert main(argv + ["--out", str(earlier), "--no-plots"]) == 0
    capsys.readouterr()
    assert check_sweep_dir(earlier) == earlier.resolve()
    (earlier / MARKER).unlink()
    assert check_sweep_dir(earlier) == earlier.resolve()
    (earlier / "points" / "notes.txt").write_text("mine")
    with pytest.raises(InputError, match="not an inserr sweep"):
        check_sweep_dir(earlier)
