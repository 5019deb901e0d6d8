"""``inserr design``, second pass (issue 17): the training motions (grid + draws) against the
held-out ones, the objective over such a set, and the golden-order single-axis family.

Designs here are tiny (four swings, a 1-2 h horizon, a handful of candidates): what is
tested is that the design computes what it says, not the drift engine's physics.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from design_base import TINY_DESIGN, comparable, make_scenario, p0_tiny, run_interrupted

from inserr.core.units import DEG, NMI
from inserr.design import study
from inserr.design.cache import EvaluationCache
from inserr.design.families import GOLDEN_SLOPE, build_family, golden_word
from inserr.design.motions import (
    DESIGN_STREAM,
    HELD_OUT_STREAM,
    design_motions,
    held_out_motions,
    random_motions,
)
from inserr.design.search import Evaluator, Request, family_candidate
from inserr.scenario.schema import scenario_from_dict

# P0's IMU budget and tilted swinging vehicle, shortened (as tests/test_design.py).
BASE = p0_tiny(
    {"name": "tiny robust design", "duration": "2 h", "seed": 5},
    {
        "motions": "grid+draws",
        **TINY_DESIGN,
        "draws": 2,
        "period_range": "20, 1200 s",
        "amplitude_range": "1, 6 deg/s",
        "heading_range": "0, 360 deg",
        "verify": 2,
    },
)


def scenario(duration: str | None = None, **design):
    return make_scenario(BASE, duration, **design)


# --- the motion sets ----------------------------------------------------------------------
def test_grid_plus_draws_is_the_grid_then_training_draws_never_held_out():
    scen = scenario(draws=40, held_out=40)
    motions = design_motions(scen)
    grid = design_motions(scenario(motions="grid"))
    assert [m.key for m in motions[:2]] == [m.key for m in grid]  # the grid first, unchanged
    draws = motions[2:]
    assert len(draws) == 40
    assert [m.key for m in draws] == [m.key for m in random_motions(scen, 40, DESIGN_STREAM)]
    held = held_out_motions(scen)
    assert [m.key for m in held] == [m.key for m in random_motions(scen, 40, HELD_OUT_STREAM)]
    # No held-out motion is in the design set, not even one value of one: the two streams
    # are independent draws of continuous values (a coincidence has probability zero).
    assert {m.key for m in held}.isdisjoint(m.key for m in motions)
    for name in ("period", "amplitude", "heading"):
        assert {m.spec[name] for m in held}.isdisjoint(m.spec[name] for m in draws)
    # The training draws vary what the grid holds fixed, within the held-out ranges.
    for m in draws:
        assert 20 <= m.period <= 1200 and DEG <= m.amplitude <= 6 * DEG
        assert 0 <= m.spec["heading"] <= 2 * math.pi
    assert len({round(m.spec["heading"], 9) for m in draws}) == 40
    # Each stream depends on its own count only: more held-out swings leave the training
    # set as it was (and the other way round), so the held-out test cannot leak into it.
    assert [m.key for m in design_motions(scenario(draws=40, held_out=3))] == [
        m.key for m in motions
    ]
    assert [m.key for m in held_out_motions(scenario(draws=3, held_out=40))] == [
        m.key for m in held
    ]


def test_grid_plus_draws_needs_draws(capsys, tmp_path):
    from inserr.core.errors import InputError

    with pytest.raises(InputError, match="design.draws"):
        design_motions(scenario(draws=0))


# --- the objective over grid + draws --------------------------------------------------------
def test_objective_over_grid_and_draws_is_the_worst_of_what_inserr_run_reports():
    """The design's value of a candidate over grid + draws is the largest, over the motions,
    of the RMS that ``run_scheme`` (``inserr run``/``inserr drift``) reports for the
    candidate's table on each motion alone, without the z-gyro bias."""
    from inserr.drift.study import run_scheme
    from inserr.drift.unknown_signs import rms_norm
    from inserr.sweep.runner import open_engine

    scen = scenario(duration="1 h")
    st = study.design_settings(scen)
    assert len(st.motions) == 4
    cand = family_candidate(st.family, st.family.start())
    ev = Evaluator(scen, open_engine("sync"), EvaluationCache(None))
    out = ev.run([Request(cand, st.motions, st.full, st.limits)])[0]
    assert out.complete and out.feasible
    table = st.family.decode(cand.desc["vars"]).table
    direct = []
    for m in st.motions:
        data = json.loads(json.dumps(BASE))
        data["scenario"]["duration"] = "1 h"
        data.pop("design")
        data["scheme"] = table
        s = m.spec
        data["motion"] = {
            "type": "yaw-swing",
            "heading": f"{s['heading'] / DEG!r} deg",
            "pitch": f"{s['pitch'] / DEG!r} deg",
            "roll": f"{s['roll'] / DEG!r} deg",
            "amplitude": f"{s['amplitude'] / DEG!r} deg/s",
            "period": f"{s['period']!r} s",
        }
        drift = run_scheme(scenario_from_dict(data)).result
        keep = [j for j, src in enumerate(drift.sources) if src.name != "gyro_bias_z"]
        direct.append(rms_norm(drift.source_horizontal[:, keep]).max() / NMI)
    # The engine's quadrature windows depend slightly on the fine output grid (1 s in
    # run_scheme, none in the design): agreement to its quadrature accuracy (1e-11, docs/
    # theory.md 4.1), far inside 1e-9; the degree round trip of the spec adds ~1e-16.
    assert [out.rms[i] for i in range(4)] == pytest.approx(direct, rel=1e-9)
    assert out.value == pytest.approx(max(direct), rel=1e-9)
    assert out.value == max(out.rms.values())


# --- the golden-order family ----------------------------------------------------------------
def test_golden_word_is_the_fibonacci_word():
    """Letters 1.. of the Sturmian word of slope 1/phi^2 are the Fibonacci word, the fixed
    point of the substitution 0 -> 01, 1 -> 0 (an independent construction)."""
    fib = "0"
    while len(fib) < 400:
        fib = "".join("01" if c == "0" else "0" for c in fib)
    word = golden_word(401)
    assert "".join(map(str, word[1:])) == fib[:400]
    assert sum(word) / len(word) == pytest.approx(GOLDEN_SLOPE, abs=2 / len(word))
    # never periodic: no period up to 100 letters holds over the 401
    for p in range(1, 101):
        assert any(word[i] != word[i + p] for i in range(len(word) - p))


def _cycle_starts(sch, motion, duration: float, m: int) -> np.ndarray:
    """Start times of the cycles of a single-axis table of ``m`` stops per cycle: the
    beginning of every m-th stop of the planned schedule."""
    table = sch.plan(motion, duration)
    stops = [k for k in range(len(table)) if table.kind[k] == "stop"]
    assert all(table.a0[k] == 0.0 for k in stops[::m])  # every cycle starts at 0
    return np.array([table.t0[k] for k in stops[::m]])


def test_golden_cycles_are_balanced_and_break_the_resonance():
    """Every cycle of the golden table cancels the horizontal biases (integral of exp(i a)
    over it, turns included, vanishes), the cycle lengths follow the golden word, and a
    swing whose period divides cycle A meets the cycles at spread phases, where the
    repeated cycle meets it at one phase (|mean exp(i w t_c)| = 1)."""
    scen = scenario(family="single-axis-golden", duration="72 h")
    fam = build_family(scen)
    # positions 0, 90, 180, 270 deg (codes 1, 2, 3 of the 90 deg step: no merge), stops
    # 300-400 s, stretch 1.382 (cycle B's stops within the 600 s bound)
    x = fam.round([1, 2, 3, 300.0, 340.0, 300.0, 340.0, 1.382])
    dec = fam.decode(x)
    assert dec.violation == {}
    sch = dec.scheme
    m = 4
    table = sch.plan(scen.motion, scen.duration)
    starts = _cycle_starts(sch, scen.motion, scen.duration, m)
    lengths = np.diff(starts)
    la, lb = np.unique(np.round(lengths, 6))
    word = golden_word(len(lengths))
    assert np.array_equal(np.round(lengths, 6) == lb, np.array(word) == 1)
    for c in range(6):
        t = np.linspace(starts[c], starts[c + 1], int((starts[c + 1] - starts[c]) * 1000) + 1)
        a, _ = table.angles_at(t)
        z = np.exp(1j * a)
        integral = np.sum(0.5 * (z[1:] + z[:-1])) * (t[1] - t[0])
        # trapezoid on 1 ms steps: error ~ 1e-8 s, kinks < 1e-6 s; balance tolerance 1e-3 s
        assert abs(integral) < 2e-3, (c, integral)
    # phases of the swing at the cycle starts, for swings whose period divides cycle A
    periodic = build_family(scenario(duration="72 h"))
    rep = periodic.decode(periodic.round(x[:-1])).scheme
    rep_starts = _cycle_starts(rep, scen.motion, scen.duration, m)
    assert np.allclose(np.diff(rep_starts), la, rtol=0, atol=1e-6)  # cycle A repeated
    for k in (1, 2, 3):
        w = 2 * math.pi * k / la
        # Repeated cycle A: every start at the same phase.
        assert abs(np.mean(np.exp(1j * w * rep_starts))) == pytest.approx(1.0, abs=1e-9)
        # Golden order: the phase advances by theta = w (L_B - L_A) at each B cycle and not
        # at an A cycle; over the J ~ 60 B cycles of 72 h a geometric sum of ratio
        # e^{i theta} averages to at most ~ 1 / (J |sin(theta / 2)|), under 0.15 for theta
        # 0.3 rad or more away from a multiple of 2 pi (the 1 or 2 A cycles between B
        # cycles weigh the terms unevenly, by at most 2: hence 0.2).
        theta = w * (lb - la)
        assert abs(math.remainder(theta, 2 * math.pi)) > 0.3  # away from a multiple
        assert abs(np.mean(np.exp(1j * w * starts))) < 0.2


def test_golden_design_is_deterministic_and_resumes(tmp_path, monkeypatch):
    """Grid + draws with the golden family: the same seed gives the same result, and an
    interrupted design resumed from its directory gives the same front."""
    scen = scenario(family="single-axis-golden", duration="1 h")
    ref = study.run_design(scen, out_dir=None, scheduler="sync")
    again = study.run_design(scen, out_dir=None, scheduler="sync")
    assert comparable(again.results) == comparable(ref.results)
    out = tmp_path / "out"
    run_interrupted(monkeypatch, scen, out, after=30)
    assert not (out / "results.json").exists()
    resumed = study.run_design(scen, out_dir=out, scheduler="sync")
    assert resumed.cached > 0 and resumed.computed > 0
    assert resumed.results["front"] == ref.results["front"]
    assert comparable(resumed.results) == comparable(ref.results)
    # the chosen golden schedule, written as a custom table, plans the same schedule
    from inserr.scenario.schema import load_scenario

    written = load_scenario(out / study.CHOSEN_TOML)
    mine = (
        build_family(scen).decode(ref.chosen.desc["vars"]).scheme.plan(scen.motion, scen.duration)
    )
    theirs = written.scheme().plan(written.motion, written.duration)
    assert np.array_equal(mine.t0, theirs.t0) and np.array_equal(mine.a0, theirs.a0)


def test_breakdown_is_the_budget_of_the_peak():
    """The per-source budget at the peak: its root sum of squares is the RMS the objective
    reports (unknown independent signs), and no output time has a larger RMS."""
    from inserr.design.motions import build_motion
    from inserr.design.objective import ErrorBudget

    scen = scenario(duration="1 h")
    st = study.design_settings(scen)
    dec = st.family.decode(st.family.round(st.family.start()))
    budget = ErrorBudget(scen, st.full.exclude)
    motion = build_motion(st.motions[1].spec)
    table = dec.scheme.plan(motion, st.full.duration)
    t, rms, src = budget.breakdown(table, motion, st.full)
    assert rms == pytest.approx(budget.rms_nmi(table, motion, st.full), rel=1e-12)
    assert math.sqrt(sum(v**2 for _, v in src)) == pytest.approx(rms, rel=1e-12)
    assert [v for _, v in src] == sorted((v for _, v in src), reverse=True)
    assert "gyro_bias_z" not in {n for n, _ in src}  # excluded by default
    assert 0 < t <= st.full.duration
