"""RMS and worst case over unknown signs, tested directly (issue 18, item 3).

Truths written here: the root-sum-square, a brute-force search over all 2^N sign
patterns, and a seeded random-sign Monte Carlo whose mean squared norm is the RMS^2
(E |sum s_i v_i|^2 = sum |v_i|^2 for independent signs of zero mean).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from inserr.core.earth import Site
from inserr.core.imu import ImuErrors, InitialErrors
from inserr.core.units import ARCSEC, DEG_PER_HOUR, DEG_PER_SQRT_HOUR, MICRO_G, NMI, PPM
from inserr.drift.analysis import analyze_drift
from inserr.drift.unknown_signs import rms_norm, worst_case_norm
from inserr.model.timeline import Timeline


def _brute_force(v: np.ndarray) -> float:
    """max over s in {-1, +1}^N of |sum_i s_i v_i| for one (N, 2) set."""
    best = 0.0
    for signs in itertools.product((-1.0, 1.0), repeat=len(v)):
        best = max(best, math.hypot(*(np.asarray(signs) @ v)))
    return best


def test_rms_norm_is_the_root_sum_square_over_sources_for_every_time():
    rng = np.random.default_rng(1)
    v = rng.normal(size=(4, 6, 2)) * rng.uniform(0.1, 5.0, size=(4, 6, 1))  # (times, N, 2)
    want = np.array([math.sqrt(sum(x * x + y * y for x, y in v[k])) for k in range(4)])
    # Sums of a dozen squares: roundoff ~1e-16.
    assert rms_norm(v) == pytest.approx(want, rel=1e-13)
    # One source: the RMS is its length; doubling every source doubles it.
    assert rms_norm(v[:, :1]) == pytest.approx(np.hypot(v[:, 0, 0], v[:, 0, 1]), rel=1e-13)
    assert rms_norm(2 * v) == pytest.approx(2 * want, rel=1e-13)


def test_rms_is_the_random_sign_monte_carlo_rms():
    # E |sum s_i v_i|^2 = sum |v_i|^2: 20000 seeded sign draws.
    rng = np.random.default_rng(2)
    v = rng.normal(size=(9, 2)) * rng.uniform(0.2, 3.0, size=(9, 1))
    s = rng.choice([-1.0, 1.0], size=(20000, 9))
    sq = np.sum((s @ v) ** 2, axis=1)
    mc = math.sqrt(sq.mean())
    # Standard error of the mean of sq: std(sq)/sqrt(n); 4 of them, halved for the sqrt.
    tol = 4 * sq.std() / math.sqrt(len(sq)) / sq.mean() / 2
    assert rms_norm(v) == pytest.approx(mc, rel=tol)
    # A mean instead of a sum over sources would be 1/sqrt(N) = 1/3 of it: far outside.
    assert tol < 0.05


@pytest.mark.parametrize("n", [1, 2, 5, 8])
def test_worst_case_norm_is_the_brute_force_maximum_for_batches(n):
    rng = np.random.default_rng(10 + n)
    v = rng.normal(size=(3, 4, n, 2)) * rng.uniform(0.1, 3.0, size=(3, 4, n, 1))
    norm, signs = worst_case_norm(v)
    assert norm.shape == (3, 4) and signs.shape == (3, 4, n)
    for i in range(3):
        for j in range(4):
            best = _brute_force(v[i, j])
            # Same sums, different order of additions: ~1e-15 relative.
            assert norm[i, j] == pytest.approx(best, rel=1e-12)
            assert np.all(np.abs(signs[i, j]) == 1.0)
            assert math.hypot(*(signs[i, j] @ v[i, j])) == pytest.approx(best, rel=1e-12)
    # The norm-only walk (what the drift metrics use) gives the same norms, bit for bit.
    alone, none = worst_case_norm(v, signs=False)
    assert none is None and np.array_equal(alone, norm)


def test_worst_case_bounds_every_random_sign_pattern_and_the_rms():
    rng = np.random.default_rng(3)
    v = rng.normal(size=(7, 2))
    worst, _ = worst_case_norm(v)
    draws = np.linalg.norm(rng.choice([-1.0, 1.0], size=(5000, 7)) @ v, axis=1)
    assert draws.max() <= worst * (1 + 1e-12)
    assert rms_norm(v) <= worst
    # Collinear sources: all signs aligned, the worst case is the plain sum of lengths.
    u = np.array([[1.0, 2.0], [-0.5, -1.0], [3.0, 6.0]])
    lengths = np.hypot(u[:, 0], u[:, 1])
    assert worst_case_norm(u)[0] == pytest.approx(lengths.sum(), rel=1e-12)


def test_drift_result_rms_and_worst_are_those_of_its_per_source_responses():
    # Through the public drift analysis: the RMS and worst-sign curves and the headline
    # numbers are the root-sum-square and the brute-force maximum of the per-source
    # horizontal responses it reports (2^7 patterns, every coarse time).
    site = Site.from_degrees(34.0)
    imu = ImuErrors(
        gyro_bias=np.array([0.01, -0.02, 0.005]) * DEG_PER_HOUR,
        accel_bias=np.array([40.0, -30.0, 0.0]) * MICRO_G,
        gyro_scale_factor=[0.0, 0.0, 20 * PPM],
    )
    init = InitialErrors(attitude=np.array([0.0, 0.0, 30.0]) * ARCSEC)
    res = analyze_drift(site, imu, init, Timeline.static(np.eye(3), 4 * 3600.0), dt_cov=900.0)
    v = res.source_horizontal  # (Mc, N, 2), metres, scaled by the magnitudes
    assert v.shape[1] == 7
    rss = np.sqrt(np.sum(v**2, axis=(1, 2)))
    assert res.rms_horizontal == pytest.approx(rss, rel=1e-13, abs=0)
    brute = np.array([_brute_force(v[k]) for k in range(len(v))])
    assert res.worst_horizontal == pytest.approx(brute, rel=1e-12, abs=0)
    m = res.metrics
    assert m["rms_horizontal_error_nmi"] == pytest.approx(rss.max() / NMI, rel=1e-13)
    assert m["worst_case_horizontal_error_nmi"] == pytest.approx(brute.max() / NMI, rel=1e-12)
    # The budget line of each source is its own horizontal error at the end.
    for j, s in enumerate(res.sources):
        assert m["error_budget"][s.name] == pytest.approx(np.hypot(*v[-1, j]) / NMI, rel=1e-13)
    # The signed sum of the per-source responses is the deterministic run (superposition).
    fine_at_coarse = np.searchsorted(res.t, res.t_cov)
    assert np.allclose(v.sum(axis=1), res.nav[fine_at_coarse, 6:8], rtol=1e-9, atol=1e-9)


def test_worst_case_norm_matches_brute_force_on_many_random_sets():
    # 400 sets of 9 vectors, some nearly collinear (narrow vertex cones), all 2^9
    # patterns at once: the exact vertex search must find every maximum.
    rng = np.random.default_rng(4)
    n = 9
    base = rng.normal(size=(400, 1, 2))
    v = rng.normal(size=(400, n, 2)) * rng.uniform(0.01, 3.0, size=(400, n, 1))
    v[:200] = base[:200] * rng.uniform(-2, 2, size=(200, n, 1)) + 0.05 * v[:200]
    signs = np.array(list(itertools.product((-1.0, 1.0), repeat=n)))  # (512, n)
    brute = np.linalg.norm(np.einsum("pn,snd->spd", signs, v), axis=-1).max(axis=1)
    norm, best = worst_case_norm(v)
    assert norm == pytest.approx(brute, rel=1e-12, abs=0)
    assert np.linalg.norm(np.einsum("sn,snd->sd", best, v), axis=-1) == pytest.approx(
        brute, rel=1e-12
    )


def test_no_sources_give_zero_rms_and_worst_case_with_batch_shapes():
    v = np.zeros((3, 4, 0, 2))
    norm, signs = worst_case_norm(v)
    assert norm.shape == (3, 4) and signs.shape == (3, 4, 0)
    assert np.all(norm == 0.0)
    assert rms_norm(v).shape == (3, 4) and np.all(rms_norm(v) == 0.0)


def test_headline_figures_are_those_of_the_histories():
    # Every headline number against the histories it summarises (units at the edge:
    # nmi, deg, h), and the per-source heading errors add up to the deterministic one.
    site = Site.from_degrees(34.0)
    imu = ImuErrors(
        gyro_bias=np.array([0.01, -0.02, 0.005]) * DEG_PER_HOUR,
        accel_bias=np.array([40.0, -30.0, 0.0]) * MICRO_G,
        arw=0.001 * DEG_PER_SQRT_HOUR,
    )
    init = InitialErrors(attitude=np.array([5.0, -5.0, 30.0]) * ARCSEC)
    duration = 3 * 3600.0
    res = analyze_drift(site, imu, init, Timeline.static(np.eye(3), duration), dt_cov=600.0)
    m = res.metrics
    h = np.hypot(res.nav[:, 6], res.nav[:, 7])
    assert m["hours"] == pytest.approx(3.0, rel=1e-12)
    assert m["max_horizontal_error_nmi"] == pytest.approx(h.max() / NMI, rel=1e-12)
    assert m["final_horizontal_error_nmi"] == pytest.approx(h[-1] / NMI, rel=1e-12)
    assert m["final_heading_error_deg"] == pytest.approx(
        math.degrees(res.attitude[-1, 2]), rel=1e-12
    )
    noise = np.sqrt(res.noise_cov["arw"][:, 6, 6] + res.noise_cov["arw"][:, 7, 7])
    assert m["final_horizontal_1sigma_nmi"] == pytest.approx(noise[-1] / NMI, rel=1e-12)
    total = np.sqrt(np.sum(res.source_horizontal**2, axis=(1, 2)) + noise**2)
    assert m["rms_total_horizontal_error_nmi"] == pytest.approx(total.max() / NMI, rel=1e-12)
    budget = list(m["error_budget"].items())
    assert [v for _, v in budget] == sorted((v for _, v in budget), reverse=True)
    assert {k for k, _ in budget} == {s.name for s in res.sources} | {"arw"}
    assert m["error_budget"]["arw"] == pytest.approx(noise[-1] / NMI, rel=1e-12)
    # Heading per source (rad), scaled by the magnitudes: their sum is the signed run's.
    at_coarse = np.searchsorted(res.t, res.t_cov)
    assert res.source_heading.shape == (len(res.t_cov), len(res.sources))
    assert np.allclose(
        res.source_heading.sum(axis=1), res.attitude[at_coarse, 2], rtol=1e-9, atol=1e-15
    )


def test_no_constant_sources_give_empty_per_source_results():
    res = analyze_drift(
        Site.from_degrees(34.0),
        ImuErrors(vrw=1e-5),
        InitialErrors(),
        Timeline.static(np.eye(3), 1800.0),
        dt_cov=600.0,
    )
    assert res.sources == []
    assert res.source_horizontal.shape == (4, 0, 2) and res.source_heading.shape == (4, 0)
    assert np.all(res.rms_horizontal == 0.0) and np.all(res.worst_horizontal == 0.0)
    assert np.all(res.nav == 0.0)
    assert res.metrics["rms_horizontal_error_nmi"] == 0.0
    assert list(res.metrics["error_budget"]) == ["vrw"]
    assert res.metrics["final_horizontal_1sigma_nmi"] > 0.0


def test_vertical_initial_errors_are_dropped_when_the_vertical_channel_is_clamped():
    # Clamped (aided) vertical channel: vertical initial velocity and position errors are
    # no sources and move nothing. Free: they are, and the vertical error diverges as
    # cosh(sqrt(2 g / R) t) (a 6 h run grows a 1 m error by orders of magnitude).
    site = Site.from_degrees(34.0)
    init = InitialErrors(velocity=[0.0, 0.0, 0.01], position=[0.0, 0.0, 1.0])
    tl = Timeline.static(np.eye(3), 6 * 3600.0)
    clamped = analyze_drift(site, ImuErrors(), init, tl, dt_cov=600.0)
    assert clamped.sources == [] and np.all(clamped.nav == 0.0)
    free = analyze_drift(site, ImuErrors(), init, tl, dt_cov=600.0, vertical="free")
    assert [s.name for s in free.sources] == ["initial_velocity_u", "initial_position_u"]
    assert free.nav[-1, 8] > 100.0


def test_worst_case_norm_is_exact_on_axes_ties_and_zero_vectors():
    # Small integer vectors: many on the axes (x = 0 with either sign of y, y = 0),
    # zeros, duplicates, opposites and equal angles, where the crossing order is a tie
    # and the half-plane rule (x = 0: y >= 0) decides. Brute force over 2^7 patterns;
    # integer sums are exact, so the norms agree to the last bit but for the sqrt.
    rng = np.random.default_rng(5)
    v = rng.integers(-2, 3, size=(600, 7, 2)).astype(float)
    v[:100, :, 0] = 0.0  # all on the y axis
    v[100:200, :, 1] = 0.0  # all on the x axis
    v[200:250] = 0.0  # no error at all (t = 0 of a run without initial errors)
    v[250:300, 1] = -v[250:300, 0]  # opposite pairs
    v[300:350, 2] = 2 * v[300:350, 3]  # same angle, different lengths
    signs = np.array(list(itertools.product((-1.0, 1.0), repeat=7)))
    brute = np.linalg.norm(np.einsum("pn,snd->spd", signs, v), axis=-1).max(axis=1)
    norm, best = worst_case_norm(v)
    assert norm == pytest.approx(brute, rel=1e-15, abs=0)
    assert np.all(np.abs(best) == 1.0)
    reached = np.linalg.norm(np.einsum("sn,snd->sd", best, v), axis=-1)
    assert reached == pytest.approx(brute, rel=1e-15, abs=0)
