"""``inserr design``: the objective against ``inserr run``, constraints computed independently,
determinism, early exit, resume, a loopback cluster, the motion sets and bad input.

Every design here is tiny (two swings, a 1-2 h horizon, a handful of candidates) so the
file runs in well under a minute; the physics of the objective is the drift engine's,
tested elsewhere. What is tested here is that the design computes what it says.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from design_base import TINY_DESIGN, comparable, make_scenario, p0_tiny, run_interrupted

from inserr.cli.main import main
from inserr.core.units import DEG, HOUR, NMI
from inserr.design import study
from inserr.design.cache import EvaluationCache
from inserr.design.families import balance, build_family
from inserr.design.motions import build_motion, design_motions, held_out_motions
from inserr.design.objective import ErrorBudget, Horizon, Limits, schedule_metrics
from inserr.scenario.schema import load_scenario, scenario_from_dict

# P0's IMU budget and tilted swinging vehicle, shortened: the design problem in small.
BASE = p0_tiny(
    {"name": "tiny design", "duration": "2 h", "seed": 3},
    {**TINY_DESIGN, "verify": 3},
)


def scenario(duration: str | None = None, **design):
    return make_scenario(BASE, duration, **design)


def write_scenario(path: Path, **design) -> Path:
    """BASE as a TOML file (a few lines written by hand: strings, numbers, one list)."""
    data = json.loads(json.dumps(BASE))
    data["design"].update(design)
    lines = []
    for section, table in data.items():
        lines.append(f"[{section}]")
        for k, v in table.items():
            lines.append(f"{k} = {json.dumps(v)}")
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The reference design, in this process (sync), written to a directory."""
    out = tmp_path_factory.mktemp("design") / "out"
    res = study.run_design(scenario(), out_dir=out, scheduler="sync")
    return res


# --- the objective ----------------------------------------------------------------------
def test_objective_is_what_inserr_run_reports_for_the_written_schedule(tmp_path, capsys):
    """Design for the scenario's own swing with every source in: the verified value of the
    chosen schedule is the RMS that ``inserr run`` prints for the file the design wrote,
    and without the z-gyro bias it is the RMS of the drift result's other sources."""
    scen = scenario(motions="scenario", exclude=[], held_out=0)
    res = study.run_design(scen, out_dir=tmp_path / "d", scheduler="sync", compare=False)
    toml = tmp_path / "d" / study.CHOSEN_TOML
    assert main(["run", str(toml), "--out", str(tmp_path / "r"), "--json"]) == 0
    run = json.loads(capsys.readouterr().out)["runs"][0]
    # The engine's quadrature windows depend slightly on the fine output grid (1 s here,
    # none in the design): the two agree to the engine's quadrature accuracy (1e-11, see
    # docs/theory.md 4.1), far inside 1e-9.
    assert res.chosen.worst == pytest.approx(run["rms_horizontal_error_nmi"], rel=1e-9)
    assert run["scheme"] == "custom"

    from inserr.drift.study import run_scheme
    from inserr.drift.unknown_signs import rms_norm

    drift = run_scheme(load_scenario(toml)).result
    keep = [j for j, s in enumerate(drift.sources) if s.name != "gyro_bias_z"]
    direct = rms_norm(drift.source_horizontal[:, keep]).max() / NMI
    budget = ErrorBudget(load_scenario(toml), ("gyro_bias_z",))
    sched = load_scenario(toml)
    table = sched.scheme().plan(sched.motion, sched.duration)
    assert budget.rms_nmi(table, sched.motion, Horizon(sched.duration, 60.0, ())) == (
        pytest.approx(direct, rel=1e-9)
    )


def test_written_file_reproduces_the_candidate_exactly(reference):
    """The chosen_scheme.toml table plans the same schedule as the candidate it came from."""
    scen = scenario()
    written = load_scenario(reference.out_dir / study.CHOSEN_TOML)
    fam = build_family(scen)
    mine = fam.decode(reference.chosen.desc["vars"]).scheme.plan(scen.motion, scen.duration)
    theirs = written.scheme().plan(written.motion, written.duration)
    assert np.array_equal(mine.t0, theirs.t0) and np.array_equal(mine.duration, theirs.duration)
    assert np.array_equal(mine.a0, theirs.a0) and mine.kind == theirs.kind


# --- constraints ------------------------------------------------------------------------
def _independent_metrics(first: float, steps: list[tuple[float, float]], rate: float, duration):
    """Starts/h, turning fraction and range of a repeated table, from its rows alone.

    ``steps`` are (turn angle rad, stop after it s); the run opens with ``first`` s at 0.
    The table plans whole steps until the step that ends at or after ``duration``.
    """
    t, angle, starts, turning, extent = first, 0.0, 0, 0.0, 0.0
    while t < duration:
        for turn, stop in steps:
            dur = abs(turn) / rate
            starts += 1  # every row turns (the family merges zero turns)
            turning += max(0.0, min(t + dur, duration) - t)
            angle += turn
            extent = max(extent, abs(angle))
            t += dur + stop
            if t >= duration:
                break
    return starts * HOUR / duration, turning / duration, extent / DEG


def test_constraints_match_an_independent_count():
    scen = scenario(stops=6)
    fam = build_family(scen)
    rng = np.random.default_rng(7)
    checked = 0
    for _ in range(200):
        x = fam.round([rng.uniform(v.lower, v.upper) for v in fam.variables()])
        dec = fam.decode(x)
        if dec.scheme is None:
            continue
        sch = dec.scheme
        rows = [(s.angle, s.dwell) for s in sch.steps]
        want = _independent_metrics(sch.first_dwell, rows, sch.rate, scen.duration)
        got = schedule_metrics(sch.plan(scen.motion, scen.duration), scen.duration)
        assert got["starts_per_hour"] == pytest.approx(want[0], rel=1e-12)
        assert got["turning_fraction"] == pytest.approx(want[1], rel=1e-9)
        assert got["range_deg"] == pytest.approx(want[2], rel=1e-12)
        assert got["range_deg"] <= 360.0 + 1e-9  # positions within the table range
        checked += 1
    assert checked > 50


def test_limits_and_penalty():
    lim = Limits(10.0, 0.2, 360.0)
    assert lim.violation({"starts_per_hour": 10.0, "turning_fraction": 0.2, "range_deg": 360}) == {}
    v = lim.violation({"starts_per_hour": 12.0, "turning_fraction": 0.3, "range_deg": 720})
    assert v == pytest.approx({"starts": 0.2, "turning": 0.5, "range": 1.0})


def test_balanced_cycle_cancels_every_horizontal_bias():
    """The balanced stop times make the cycle integral of exp(i a(t)) vanish, turns included:
    checked by integrating the planned table angle numerically over one cycle."""
    scen = scenario(stops=8)
    fam = build_family(scen)
    rng = np.random.default_rng(1)
    done = 0
    for _ in range(100):
        dec = fam.decode(fam.round([rng.uniform(v.lower, v.upper) for v in fam.variables()]))
        if dec.violation:
            continue
        sch = dec.scheme
        cycle = sch.cycle_time
        table = sch.plan(scen.motion, 3 * cycle)
        # one cycle, from the end of the opening stop: composite trapezoid on 1 ms steps
        t = np.linspace(sch.first_dwell, sch.first_dwell + cycle, int(cycle * 1000) + 1)
        a, _ = table.angles_at(t)
        z = np.exp(1j * a)
        integral = np.sum(0.5 * (z[1:] + z[:-1])) * (t[1] - t[0])
        # trapezoid error ~ cycle * (1e-3 s * rate)^2 / 12 ~ 1e-8 s; kinks add < 1e-6 s
        assert abs(integral) < 1e-3, (dec.summary, integral)
        done += 1
    assert done >= 10
    # a cycle that cannot be balanced within the stop range reports the residual
    d, resid = balance(np.array([0.0, 90 * DEG]), np.array([300.0, 300.0]), 6 * DEG, 300, 600)
    assert resid > 100


def test_dual_axis_cycle_must_close():
    scen = scenario(family="dual-axis", stops=4)
    fam = build_family(scen)
    assert fam.decode([0, 1, 2, 3, 300.0]).violation == {}
    assert fam.decode([0, 0, 2, 3, 300.0]).violation == {"closure": 2.0}


# --- the search -------------------------------------------------------------------------
def test_determinism_same_seed_same_result(reference):
    again = study.run_design(scenario(), out_dir=None, scheduler="sync")
    assert comparable(again.results) == comparable(reference.results)
    seed4 = scenario().with_changes({"scenario.seed": 4})
    other = study.run_design(seed4, out_dir=None, scheduler="sync", compare=False)
    assert other.search.evaluated.keys() != reference.search.evaluated.keys()


def test_early_exit_changes_no_decision(monkeypatch):
    """The search with early exits is the search that evaluates every motion."""
    from inserr.design import search
    from inserr.sweep.runner import open_engine

    scen = scenario(periods="30, 45, 120, 330, 660 s", duration="1 h")
    st = study.design_settings(scen)

    def run():
        ev = search.Evaluator(scen, open_engine("sync"), EvaluationCache(None))
        return search.optimize(
            st.family, ev, st.motions, st.screen, st.limits, budget=48, population=6, seed=2
        )

    fast = run()
    monkeypatch.setattr(search._Map, "__call__", _full_call(search._Map.__call__))
    full = run()
    assert full.best == fast.best and full.best_value == fast.best_value
    assert [g.best for g in full.generations] == [g.best for g in fast.generations]
    # and the early exits did happen
    assert any(not o.complete and o.feasible for _, o in fast.evaluated.values())


def _full_call(call):
    def wrapped(self, func, population):
        self.thresholds = None
        return call(self, func, population)

    return wrapped


def test_interrupted_and_resumed_gives_the_same_front(reference, tmp_path, monkeypatch):
    """Stop the design after some evaluations (as Ctrl-C would), rerun: same results."""
    out = tmp_path / "out"
    run_interrupted(monkeypatch, scenario(), out, after=25)
    assert len((out / "evaluations.jsonl").read_text().splitlines()) == 25
    assert not (out / "results.json").exists()  # no report of an unfinished design
    resumed = study.run_design(scenario(), out_dir=out, scheduler="sync")
    assert resumed.cached > 0 and resumed.computed > 0
    assert comparable(resumed.results) == comparable(reference.results)
    assert resumed.results["front"] == reference.results["front"]
    # a third run is served from the cache entirely
    third = study.run_design(scenario(), out_dir=out, scheduler="sync")
    assert third.computed == 0
    assert comparable(third.results) == comparable(reference.results)


def test_local_processes_give_the_same_result(reference):
    res = study.run_design(scenario(), out_dir=None, scheduler="processes", workers=2)
    assert comparable(res.results) == comparable(reference.results)


def test_loopback_cluster_gives_the_same_result(reference):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(
        host="127.0.0.1", n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as cluster:
        res = study.run_design(scenario(), out_dir=None, scheduler=cluster.scheduler_address)
    assert res.engine.startswith("dask.distributed")
    assert comparable(res.results) == comparable(reference.results)


# --- the report -------------------------------------------------------------------------
def test_report_compares_every_catalogue_scheme(reference):
    from inserr.schemes.catalogue import SCHEMES

    r = json.loads((reference.out_dir / "results.json").read_text())
    assert {c["label"] for c in r["catalogue"]} == set(SCHEMES) - {"custom"}
    for c in r["catalogue"] + [r["chosen"]]:
        assert len(c["rms_nmi"]) == 2 and len(c["held_out_rms_nmi"]) == 2
    # the chosen schedule is the best verified one that meets the constraints
    ok = [v for v in r["verified"] if v["meets_constraints"]]
    assert r["chosen"]["worst_nmi"] == min(v["worst_nmi"] for v in ok)
    assert r["chosen"]["starts_per_hour"] <= r["settings"]["limits"]["max_starts"]
    # the front is non-dominated: starts up, worst down
    f = r["front"]
    assert all(a["starts_per_hour"] <= b["starts_per_hour"] for a, b in zip(f, f[1:], strict=False))
    assert all(a["worst_nmi"] > b["worst_nmi"] for a, b in zip(f, f[1:], strict=False))
    text = (reference.out_dir / "report.md").read_text()
    for name in ("compare_motion_set.png", "compare_held_out.png", "front.png", "schedule.png"):
        assert name in text and (reference.out_dir / name).is_file()


def test_default_max_starts_is_the_traditional_cycle():
    scen = scenario()
    st = study.design_settings(scen)
    # two-position: 4 turns of 30 s and 4 stops of 300 s per 1320 s cycle, after a first
    # 300 s stop; over 2 h: turns start at 300 + k*330 s < 7200 s -> k = 0..20, 21 starts.
    assert st.limits.max_starts == pytest.approx(21 / 2.0)


# --- motion sets ------------------------------------------------------------------------
def test_motion_sets(tmp_path):
    scen = scenario()
    grid = design_motions(scen)
    assert [(m.period, m.amplitude) for m in grid] == [(45.0, 6 * DEG), (330.0, 6 * DEG)]
    assert all(m.spec["heading"] == pytest.approx(15 * DEG) for m in grid)
    held = held_out_motions(scenario(held_out=5, heading_range="0, 360 deg"))
    again = held_out_motions(scenario(held_out=5, heading_range="0, 360 deg"))
    assert [m.key for m in held] == [m.key for m in again]  # seeded
    drawn = design_motions(scenario(motions="random", draws=5, heading_range="0, 360 deg"))
    assert {m.key for m in drawn}.isdisjoint(m.key for m in held)  # another stream
    for m in held:
        assert 20 <= m.period <= 1200 and DEG <= m.amplitude <= 6 * DEG
        assert 0 <= m.spec["heading"] <= 2 * math.pi
    # a heading history file; the motion rebuilt from its spec is the file's
    f = tmp_path / "h.csv"
    f.write_text("0, 10\n3600, 20\n7200, 10\n")
    data = json.loads(json.dumps(BASE))
    data["design"].update({"motions": "files", "files": ["h.csv"]})
    hist = design_motions(scenario_from_dict(data, tmp_path))
    assert hist[0].spec["type"] == "heading-history"
    assert build_motion(hist[0].spec).heading_at(np.array([1800.0]))[0] == pytest.approx(15 * DEG)


# --- bad input --------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("extra", "field"),
    [
        (["--family", "triple-axis"], "--family (design.family)"),
        (["--budget", "2"], "--budget (design.budget)"),
        (["--max-starts", "-1"], "--max-starts (design.max_starts)"),
    ],
)
def test_bad_flags_fail_before_any_output(tmp_path, capsys, extra, field):
    path = write_scenario(tmp_path / "s.toml")
    out = tmp_path / "out"
    assert main(["design", str(path), "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0]
    assert not out.exists()


def test_bad_scenario_keys_and_foreign_directories(tmp_path, capsys):
    path = write_scenario(tmp_path / "s.toml", exclude=["gyro_bias_w"])
    assert main(["design", str(path), "--out", str(tmp_path / "o")]) == 2
    assert "design.exclude" in capsys.readouterr().err
    path = write_scenario(tmp_path / "s.toml", stop_range="600, 300 s")
    assert main(["design", str(path), "--out", str(tmp_path / "o")]) == 2
    assert "design.stop_range" in capsys.readouterr().err
    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "notes.txt").write_text("keep me")
    path = write_scenario(tmp_path / "s.toml")
    assert main(["design", str(path), "--out", str(foreign)]) == 2
    assert "not an inserr design directory" in capsys.readouterr().err
    assert (foreign / "notes.txt").read_text() == "keep me"
    assert sorted(p.name for p in foreign.iterdir()) == ["notes.txt"]
