"""The tools a reproduction uses to set a paper's figures beside the model's.

Truths written here: brute force over all 2^N sign patterns (the range of
``M(s) = max_t |sum_i s_i v_i(t)|``, the pattern closest to a target), hand-built
vectors whose figures follow by inspection, products of answer sets, and the
arithmetic of a stop-and-turn step against a swing period.
"""

from __future__ import annotations

import itertools
import math
from types import SimpleNamespace

import numpy as np
import pytest

from inserr.drift.comparison import (
    ERROR_SETS,
    Case,
    budget_figures,
    ratio_verdict,
    step_resonance,
    turn_phase_coherence,
)
from inserr.drift.paper import check_claims, closest_reading, readings
from inserr.drift.unknown_signs import (
    closest_pattern,
    figure_reach,
    pattern_maximum,
    sign_pattern_range,
)
from inserr.schemes.turntable import ScheduleBuilder


def _patterns(n: int) -> np.ndarray:
    """Every sign pattern of n sources with the first sign +1, (2^(n-1), n)."""
    rest = np.array(list(itertools.product((1.0, -1.0), repeat=n - 1))).reshape(-1, n - 1)
    return np.hstack([np.ones((len(rest), 1)), rest])


def _maxima(v: np.ndarray, pats: np.ndarray) -> np.ndarray:
    """M(s) of each pattern (rows of pats), brute force straight from the definition
    (M(s) = M(-s), so the patterns of :func:`_patterns` give every value there is)."""
    sums = np.einsum("tnd,pn->ptd", v, pats)
    return np.max(np.hypot(sums[..., 0], sums[..., 1]), axis=1)


def _vectors(seed: int, t: int = 30, n: int = 7) -> np.ndarray:
    """Smooth per-source tracks of different sizes, as error histories are."""
    rng = np.random.default_rng(seed)
    tt = np.linspace(0.0, 1.0, t)[:, None]
    amp = rng.uniform(0.1, 3.0, size=(1, n))
    w = rng.uniform(0.5, 6.0, size=(1, n))
    ph = rng.uniform(0, 2 * np.pi, size=(1, n))
    return np.stack([amp * tt * np.cos(w * tt + ph), amp * tt * np.sin(w * tt + ph)], axis=-1)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_sign_pattern_range_matches_brute_force_when_exhaustive(seed):
    v = _vectors(seed)
    m = _maxima(v, _patterns(v.shape[1]))
    r = sign_pattern_range(v, exhaustive=7, times=30)
    # Both ends are maxima of the same sums: roundoff only.
    assert r.highest == pytest.approx(m.max(), rel=1e-12)
    assert r.lowest == pytest.approx(m.min(), rel=1e-12)
    assert r.lowest_bound <= m.min() * (1 + 1e-12)
    # The patterns returned give the values returned.
    assert pattern_maximum(v, r.highest_signs) == pytest.approx(r.highest, rel=1e-12)
    assert pattern_maximum(v, r.lowest_signs) == pytest.approx(r.lowest, rel=1e-12)


@pytest.mark.parametrize("seed", [4, 5])
def test_sign_pattern_range_brackets_the_minimum_with_few_exhaustive_sources(seed):
    # Only the 4 largest of 10 sources are searched exhaustively, at 8 of 30 times:
    # the bound must still lie below every pattern and the found value above the minimum.
    v = _vectors(seed, n=10)
    m = _maxima(v, _patterns(v.shape[1]))
    r = sign_pattern_range(v, exhaustive=4, times=8, starts=4)
    true_min = m.min()
    assert r.lowest_bound <= true_min * (1 + 1e-12)
    assert r.lowest >= true_min * (1 - 1e-12)
    assert r.highest == pytest.approx(m.max(), rel=1e-12)


def test_sign_pattern_range_of_a_hand_built_pair():
    # Two constant vectors, lengths 3 and 1 along x: M is 4 (same signs) or 2 (opposite).
    v = np.zeros((5, 2, 2))
    v[:, 0, 0], v[:, 1, 0] = 3.0, 1.0
    r = sign_pattern_range(v)
    assert (r.highest, r.lowest, r.lowest_bound) == pytest.approx((4.0, 2.0, 2.0), abs=1e-12)


@pytest.mark.parametrize("seed", [6, 7])
def test_closest_pattern_is_within_the_largest_source_and_near_brute_force(seed):
    v = _vectors(seed)
    m = _maxima(v, _patterns(v.shape[1]))
    values = np.array(np.sort(m))
    largest = np.max(np.hypot(v[..., 0], v[..., 1]))
    for target in np.linspace(values[0], values[-1], 5):
        best = np.min(np.abs(values - target))
        # Few sources: every pattern is tried, so the answer is the brute-force one.
        signs, value = closest_pattern(v, float(target))
        assert abs(value - target) == pytest.approx(best, abs=1e-12)
        # The search used for many sources, forced here.
        signs, value = closest_pattern(v, float(target), exhaustive=0)
        assert value == pytest.approx(pattern_maximum(v, signs), rel=1e-12)
        # The documented guarantee (a flip moves M by at most 2 max|v_i|; the walk
        # keeps the best): within the largest source of the target.
        assert abs(value - target) <= largest + 1e-12
        # And no better than the best pattern there is (brute force).
        assert abs(value - target) >= best - 1e-12


def test_figure_reach_verdicts():
    v = _vectors(8)
    m = _maxima(v, _patterns(v.shape[1]))
    lo, hi = m.min(), m.max()
    # A value some pattern takes exactly is reached; outside the range it is proved out.
    some = np.sort(m)[len(m) // 3]
    assert figure_reach(v, some)["verdict"] == "reached"
    assert figure_reach(v, 1.5 * hi)["verdict"] == "above every pattern"
    below = figure_reach(v, 0.5 * lo)
    assert below["verdict"] == "below every pattern"
    assert below["lowest_bound"] <= lo * (1 + 1e-12)


def test_budget_figures_by_inspection_and_error_sets():
    # Three sources, constant in time after t=0: x-gyro (3, 0), z-gyro (0, 4), and an
    # initial error (-1, 0); in metres of 1 nmi so the figures read directly in nmi.
    nmi = 1852.0
    names = ["gyro_bias_x", "gyro_bias_z", "initial_position_e"]
    v = np.zeros((3, 3, 2))
    v[1:, 0] = (3 * nmi, 0)
    v[1:, 1] = (0, 4 * nmi)
    v[1:, 2] = (-1 * nmi, 0)
    run = SimpleNamespace(sources=[SimpleNamespace(name=n) for n in names], source_horizontal=v)
    full = budget_figures(run, "full")
    assert full["all_positive_nmi"] == pytest.approx(math.hypot(2, 4), rel=1e-12)
    assert full["rms_nmi"] == pytest.approx(math.sqrt(9 + 16 + 1), rel=1e-12)
    assert full["worst_nmi"] == pytest.approx(math.hypot(4, 4), rel=1e-12)
    assert list(full["budget_nmi"]) == ["gyro_bias_z", "gyro_bias_x", "initial_position_e"]
    noz = budget_figures(run, "no z-gyro bias")
    assert noz["all_positive_nmi"] == pytest.approx(2.0, rel=1e-12)
    assert noz["worst_nmi"] == pytest.approx(4.0, rel=1e-12)
    imu = budget_figures(run, "IMU only")
    assert imu["rms_nmi"] == pytest.approx(5.0, rel=1e-12)
    assert set(ERROR_SETS) >= {"full", "no z-gyro bias", "IMU only", "biases only"}


def test_readings_are_every_combination_and_merge_changes():
    q = {
        "convention": {"cw": {"a": 1}, "ccw": {"a": -1}},
        "start": {"stop": {"b": "stop"}, "turn": {"b": "turn"}},
        "figure": {"rms": {}, "worst": {}, "all": {}},
    }
    rds = readings(q)
    assert len(rds) == 2 * 2 * 3
    assert len({r.label for r in rds}) == len(rds)
    ccw_turn = [r for r in rds if r.label.startswith("ccw, turn")]
    assert len(ccw_turn) == 3
    assert all(r.changes == {"a": -1, "b": "turn"} for r in ccw_turn)


def test_closest_reading_and_claims():
    label, value, gap = closest_reading({"a": 2.0, "b": 3.1, "c": 5.0}, 3.0)
    assert (label, value) == ("b", 3.1)
    assert gap == pytest.approx(0.1 / 3.0, rel=1e-12)
    with pytest.raises(ValueError):
        closest_reading({}, 1.0)
    claims = check_claims({"x > 1": lambda a: {"cw": 2, "ccw": 0}[a] > 1}, ["cw", "ccw"])
    assert claims == [{"claim": "x > 1", "cw": True, "ccw": False}]


def test_case_applies_its_scheme_and_changes():
    seen = {}
    scen = SimpleNamespace(with_changes=lambda d: seen.update(d) or "new")
    assert Case("f", "flexible-two-position", (("scheme.variant", "crossing"),)).scenario(scen)
    assert seen == {"scheme.name": "flexible-two-position", "scheme.variant": "crossing"}


@pytest.mark.parametrize(
    ("step", "period", "k", "resonant"),
    [(330.0, 120.0, 2.75, False), (330.0, 60.0, 5.5, True), (360.0, 120.0, 3.0, True)],
)
def test_step_resonance(step, period, k, resonant):
    got_k, got_res = step_resonance(step, period)
    assert got_k == pytest.approx(k, rel=1e-12)
    assert got_res is resonant


def test_turn_phase_coherence_locks_when_the_step_is_a_whole_number_of_periods():
    # Stop 270 s + 180 deg at 6 deg/s (30 s): a 300 s step, 20 turns. Against a 100 s
    # swing every turn starts at the same phase (coherence 1 at nu = 0); against a
    # 400 s swing the phases step by 3 pi / 2 and nu = pi/2, m = 1 adds them up (so do
    # nu = pi, m = 2: ties).
    b = ScheduleBuilder()
    for _ in range(20):
        b.stop(270.0)
        b.rotate("outer", math.pi, math.radians(6.0))
    table = b.build()
    c = turn_phase_coherence(table, 100.0, 1e9)
    assert c["value"] == pytest.approx(1.0, abs=1e-12)
    c = turn_phase_coherence(table, 400.0, 1e9)
    assert c["value"] == pytest.approx(1.0, abs=1e-12)
    # A 1500 s swing: the phase steps by 2 pi / 5, so m phi_k + nu k steps by
    # 2 pi (4 m + 5 j) / 20, never a whole turn for m = 1..3, j = 0..3; over 20 turns
    # each such sum of unit phasors is exactly zero.
    assert turn_phase_coherence(table, 1500.0, 1e9)["value"] == pytest.approx(0.0, abs=1e-12)
    # Fewer than four turns: nothing to say.
    assert turn_phase_coherence(table, 100.0, 700.0) is None


def test_ratio_verdict_counts_by_hand():
    pts = []
    for p, a, ref, other in [(60, 6, 1.0, 0.5), (120, 6, 2.0, 2.2), (240, 6, 1.0, 1.01)]:
        pts.append({"period_s": p, "amplitude_deg_s": a, "label": "ref", "x": ref})
        pts.append({"period_s": p, "amplitude_deg_s": a, "label": "new", "x": other})
    v = ratio_verdict(pts, "ref", key="x")["new"]
    assert v["cases"] == 3
    assert v["better_or_equal"] == 1  # only 0.5; 1.1 and 1.01 are worse
    assert (v["better_2pct"], v["level_2pct"], v["worse_2pct"]) == (1, 1, 1)
    assert v["largest_ratio"]["ratio"] == pytest.approx(1.1, rel=1e-12)
    assert v["median_ratio"] == pytest.approx(1.01, rel=1e-12)


def test_sign_pattern_range_of_no_source_and_of_one_source():
    r = sign_pattern_range(np.zeros((4, 0, 2)))
    assert (r.highest, r.lowest, r.lowest_bound) == (0.0, 0.0, 0.0)
    assert r.highest_signs.shape == r.lowest_signs.shape == (0,)
    # One source: both signs give the same maximum, its largest length (3-4-5 triangle).
    v = np.zeros((3, 1, 2))
    v[1, 0] = (3.0, 4.0)
    r = sign_pattern_range(v)
    assert (r.highest, r.lowest, r.lowest_bound) == pytest.approx((5.0, 5.0, 5.0), abs=1e-12)
    assert r.highest_signs.shape == r.lowest_signs.shape == (1,)


@pytest.mark.parametrize("seed", [9, 10])
def test_sign_pattern_range_bound_is_the_documented_bracket(seed):
    # The docstring's bound, rebuilt independently: the `exhaustive` largest sources
    # (by max_t |v_i|) searched over every pattern at `times` evenly spaced times (last
    # included), the rest bounded by their lengths; then no larger than the value found.
    v = _vectors(seed, t=40, n=12)
    r = sign_pattern_range(v, exhaustive=9, times=15, starts=3)
    size = np.max(np.hypot(v[..., 0], v[..., 1]), axis=0)
    big = np.argsort(-size)[:9]
    small = np.setdiff1d(np.arange(12), big)
    sel = np.unique(np.round(np.linspace(0, 39, 15)).astype(int))
    slack = np.hypot(v[sel][:, small, 0], v[sel][:, small, 1]).sum(axis=1)
    sums = np.einsum("tnd,pn->ptd", v[sel][:, big], _patterns(9))
    bound = np.max(np.hypot(sums[..., 0], sums[..., 1]) - slack, axis=1).min()
    assert r.lowest_bound == pytest.approx(min(max(bound, 0.0), r.lowest), rel=1e-12)
    # And it is a bracket of the true minimum (brute force over all 2^11 patterns).
    true = _maxima(v, _patterns(12))
    assert r.lowest_bound <= true.min() * (1 + 1e-12) <= r.lowest * (1 + 2e-12)
    assert r.highest == pytest.approx(true.max(), rel=1e-12)


@pytest.mark.parametrize("seed, y_scale", [(11, 1.0), (12, 1.0), (11, 0.05)])
def test_descent_ends_where_no_single_flip_lowers_the_maximum(seed, y_scale):
    # `lowest` comes from single-flip descent: at its pattern no flip lowers M (the
    # documented stopping rule), and M of the pattern is the value returned. One source
    # searched exhaustively, so the descent starts far from a minimum; errors mostly
    # along one axis (y_scale) as well as in the plane.
    v = _vectors(seed, n=10) * np.array([1.0, y_scale])
    r = sign_pattern_range(v, exhaustive=1, times=5, starts=1)
    s = r.lowest_signs
    assert r.lowest == pytest.approx(pattern_maximum(v, s), rel=1e-12)
    flips = np.where(np.eye(10, dtype=bool), -s, s)  # row i: s with sign i flipped
    assert np.all(_maxima(v, flips) >= r.lowest * (1 - 1e-12))


@pytest.mark.parametrize("seed", [13, 14])
def test_closest_pattern_many_sources_is_a_local_optimum_and_exact_when_few(seed):
    v = _vectors(seed, n=14)
    pats = _patterns(14)
    m = _maxima(v, pats)
    for target in np.quantile(m, [0.1, 0.5, 0.9]):
        # 14 sources: all 8192 patterns are tried (in blocks of 4096): the brute-force
        # answer, to round-off.
        signs, value = closest_pattern(v, float(target))
        assert abs(value - target) == pytest.approx(np.min(np.abs(m - target)), abs=1e-12)
        assert value == pytest.approx(pattern_maximum(v, signs), rel=1e-12)
        # The walk and descent of many sources (forced): no single flip gets closer.
        signs, value = closest_pattern(v, float(target), exhaustive=0, walks=4)
        flips = np.where(np.eye(14, dtype=bool), -signs, signs)
        assert np.all(np.abs(_maxima(v, flips) - target) >= abs(value - target) - 1e-12)


def test_figure_reach_reports_the_range_and_its_closest_pattern():
    v = _vectors(15)
    m = _maxima(v, _patterns(7))
    target = float(np.quantile(m, 0.7))
    out = figure_reach(v, target)
    r = sign_pattern_range(v)
    assert (out["lowest_bound"], out["lowest"], out["highest"]) == (
        r.lowest_bound,
        r.lowest,
        r.highest,
    )
    assert out["closest"] == pytest.approx(pattern_maximum(v, out["closest_signs"]), rel=1e-12)
    assert out["closest"] == pytest.approx(m[np.argmin(np.abs(m - target))], rel=1e-12)
    # Inside the range, missed by more than the tolerance: a tolerance of 0 and a target
    # between two neighbouring values that no pattern takes.
    vals = np.unique(np.round(m, 12))
    gap = int(np.argmax(np.diff(vals)))
    mid = 0.5 * (vals[gap] + vals[gap + 1])
    assert figure_reach(v, float(mid), tol=0.0)["verdict"] == "not found"
