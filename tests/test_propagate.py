"""The propagation engine against an independent step-by-step matrix exponential."""

import math

import numpy as np
import pytest
import scipy.linalg as sl

from inserr.core.earth import Site
from inserr.core.imu import ImuErrors, InitialErrors
from inserr.core.rotations import rot_z
from inserr.core.units import (
    ARCSEC,
    DEG,
    DEG_PER_HOUR,
    DEG_PER_SQRT_HOUR,
    MICRO_G,
    MICRO_G_PER_SQRT_HZ,
    PPM,
)
from inserr.drift.analysis import analyze_drift
from inserr.drift.unknown_signs import worst_case_norm
from inserr.model.discretization import Discretizer
from inserr.model.exact_propagation import propagate_covariance, propagate_states
from inserr.model.psi_model import ErrorModel, Layout
from inserr.model.timeline import Timeline


def _stop_and_turn_timeline():
    # stop 100 s, turn +90 deg at 6 deg/s (15 s), stop 37.5 s, turn -90 deg about a tilted axis
    w1 = np.array([0.0, 0.0, 6 * DEG])
    axis = np.array([0.1, -0.2, 1.0]) / np.linalg.norm([0.1, -0.2, 1.0])
    w2 = -6 * DEG * axis
    times = np.array([0.0, 100.0, 115.0, 152.5, 167.5])
    omegas = np.array([[0, 0, 0], w1, [0, 0, 0], w2], dtype=float)
    c = [np.eye(3)]
    for k in range(4):
        c.append(sl.expm(np.cross(np.eye(3), omegas[k]) * -(times[k + 1] - times[k])).T @ c[-1])
    return Timeline(times, np.array(c), omegas)


def test_engine_equals_naive_expm_chain():
    site = Site.from_degrees(34.0)
    model = ErrorModel(site, Layout(scale_misalignment=True))
    tl = _stop_and_turn_timeline()
    rng = np.random.default_rng(0)
    x0 = rng.normal(size=(model.layout.n, 3)) * 1e-5
    t_out = np.arange(0.0, 167.5, 1.25)
    got = propagate_states(Discretizer(model), tl, x0, t_out, rows=slice(None))
    # Independent: integrate with scipy expm on a fine uniform grid, interval by interval.
    x = x0.copy()
    ref = [x.copy()]
    for t0, t1 in zip(t_out[:-1], t_out[1:], strict=True):
        k = tl.interval_index(np.array([0.5 * (t0 + t1)]))[0]
        x = sl.expm(model.matrix(tl.omega_n[k]) * (t1 - t0)) @ x
        ref.append(x.copy())
    ref = np.array(ref)
    # Same exact transition, different grouping (powers vs single steps): roundoff only.
    assert np.allclose(got, ref, rtol=1e-10, atol=1e-14)
    # By default the nine navigation states are recorded, of one state or of many.
    nav = propagate_states(Discretizer(model), tl, x0, t_out)
    assert nav.shape == (len(t_out), 9, 3) and np.allclose(nav, ref[:, :9], rtol=1e-10, atol=1e-14)
    one = propagate_states(Discretizer(model), tl, x0[:, 1], t_out)
    assert one.shape == (len(t_out), 9) and np.allclose(one, ref[:, :9, 1], rtol=1e-10, atol=1e-14)
    # Several grids in one pass, none starting at 0: a uniform one from 30 s (runs of
    # equal steps), the timeline's own nodes (steps of different lengths), one empty;
    # index arrays for rows and columns.
    from inserr.model.exact_propagation import Output, propagate_outputs

    later = np.flatnonzero(t_out >= 30.0)
    nodes = np.array([100.0, 115.0, 152.5])
    rows, cols = np.array([6, 7, 0]), np.array([2, 0])
    a, b, empty = propagate_outputs(
        Discretizer(model), tl, x0,
        [Output(t_out[later], rows, cols), Output(nodes, slice(0, 9), slice(1, 2)),
         Output(np.array([]))],
    )  # fmt: skip
    assert np.allclose(a, ref[later][:, rows][:, :, cols], rtol=1e-10, atol=1e-14)
    at_nodes = np.array([ref[np.flatnonzero(np.isclose(t_out, t))[0]] for t in nodes[:2]])
    assert np.allclose(b[:2], at_nodes[:, :9, 1:2], rtol=1e-10, atol=1e-14)
    assert empty.shape == (0, 9, 3)
    noisy = Discretizer(model, model.noise_intensity(1e-6, 1e-5))
    none = propagate_covariance(noisy, tl, np.eye(model.layout.n), np.array([]))
    assert none.shape == (0, model.layout.n, model.layout.n)


def test_exostates_follow_the_imu_attitude():
    # The n-resolved bias state must equal C_s^n(t) b^s at every time: the exosystem
    # reproduces the attitude history it was built from.
    model = ErrorModel(Site.from_degrees(34.0))
    tl = _stop_and_turn_timeline()
    b = np.array([1.0, 2.0, 3.0])
    x0 = np.zeros(model.layout.n)
    x0[model.layout["eps"]] = b
    t = np.linspace(0, tl.duration, 60)
    eps_n = propagate_states(Discretizer(model), tl, x0, t, rows=model.layout["eps"])
    assert np.allclose(eps_n, tl.attitude_at(t) @ b, atol=1e-12)


def test_superposition_of_sources():
    site = Site.from_degrees(34.0)
    imu = ImuErrors(
        gyro_bias=np.array([0.01, -0.02, 0.005]) * DEG_PER_HOUR,
        accel_bias=np.array([50, -30, 10]) * MICRO_G,
        gyro_scale_factor=np.full(3, 20 * PPM),
        gyro_misalignment=np.array([5, -3, 2, 8, -1, 4]) * ARCSEC,
    )
    init = InitialErrors(
        attitude=np.array([10, -5, 60]) * ARCSEC, velocity=[0.01, 0, 0], position=[5, -3, 0]
    )
    c = rot_z(0.3)
    tl = Timeline(
        np.array([0, 500.0, 530.0, 3600.0]),
        np.stack([c, c, rot_z(0.3 + math.pi) @ np.eye(3), rot_z(0.3 + math.pi)]),
        np.array([[0, 0, 0], [0, 0, math.pi / 30], [0, 0, 0]]),
    )
    r = analyze_drift(site, imu, init, tl, dt_out=60.0, dt_cov=60.0)
    # The deterministic run (one column, all sources with signs) equals the sum of the
    # per-source responses (N columns): linearity of the whole pipeline.
    summed = r.source_horizontal.sum(axis=1)
    assert np.allclose(summed, r.nav[:, 6:8], rtol=1e-9, atol=1e-9)
    # Flipping every sign flips the response.
    neg = analyze_drift(
        site,
        imu.scaled(-1.0),
        InitialErrors(-init.attitude, -init.velocity, -init.position),
        tl,
        dt_out=60.0,
        dt_cov=60.0,
    )
    assert np.allclose(neg.nav, -r.nav, rtol=1e-12, atol=1e-15)


def test_covariance_is_symmetric_psd_after_30_days_and_grows_like_random_walk():
    site = Site.from_degrees(34.0)
    imu = ImuErrors(
        arw=0.001 * DEG_PER_SQRT_HOUR,
        vrw=10 * MICRO_G_PER_SQRT_HZ,
        gyro_bias_instability=0.002 * DEG_PER_HOUR,
        accel_bias_instability=20 * MICRO_G,
    )
    model = ErrorModel(site, Layout(bias=False, bias_instability=True))
    q = model.noise_intensity(
        imu.arw, imu.vrw, imu.gyro_bias_instability, imu.accel_bias_instability
    )
    disc = Discretizer(model, q)
    p0 = np.zeros((model.layout.n,) * 2)
    p0[model.layout["bg"], model.layout["bg"]] = imu.gyro_bias_instability**2 * np.eye(3)
    p0[model.layout["ba"], model.layout["ba"]] = imu.accel_bias_instability**2 * np.eye(3)
    tl = Timeline.static(np.eye(3), 30 * 86400.0)
    t = np.arange(0, 30 * 86400.0 + 1, 3600.0)
    p = propagate_covariance(disc, tl, p0, t)
    last = p[-1]
    assert np.allclose(last, last.T, rtol=0, atol=0)
    ev = np.linalg.eigvalsh(last / np.sqrt(np.outer(np.diag(last), np.diag(last)) + 1e-300))
    assert ev.min() > -1e-9  # normalised (correlation) matrix: PSD up to roundoff
    # Short-time heading variance from ARW alone is arw^2 t (a random walk of the angle).
    model2 = ErrorModel(site, Layout(bias=False))
    d2 = Discretizer(model2, model2.noise_intensity(imu.arw, 0.0))
    p2 = propagate_covariance(
        d2, Timeline.static(np.eye(3), 600.0), np.zeros((9, 9)), np.array([0.0, 600.0])
    )
    # (Omega t)^2 leakage between psi components: < 1e-3 relative over 10 min.
    assert p2[-1, 2, 2] == pytest.approx(imu.arw**2 * 600.0, rel=1e-3, abs=0)


def test_noise_covariance_matches_monte_carlo_of_the_discrete_model():
    # Independent check of Qd and propagation: simulate the discrete model with white
    # noise samples at 1 s and compare the sample covariance of psi_E after 1 h.
    site = Site.from_degrees(34.0)
    model = ErrorModel(site, Layout(bias=False))
    arw = 0.01 * DEG_PER_SQRT_HOUR
    disc = Discretizer(model, model.noise_intensity(arw, 0.0))
    t_end = 3600.0
    p = propagate_covariance(
        disc, Timeline.static(np.eye(3), t_end), np.zeros((9, 9)), np.array([0.0, t_end])
    )[-1]
    rng = np.random.default_rng(42)
    n_runs = 4000
    phi1 = sl.expm(model.matrix() * 1.0)
    x = np.zeros((9, n_runs))
    for _ in range(int(t_end)):
        x = phi1 @ x
        x[0:3] -= arw * rng.normal(size=(3, n_runs))  # angle increment of white rate noise over 1 s
    var = x[0].var()
    # Sample variance of 4000 normal draws: relative sd sqrt(2/4000) = 2.2 %; 4 sigma = 9 %.
    # (Noise applied at step ends vs Van Loan's continuous form: (Omega dt) ~ 1e-4, negligible.)
    assert var == pytest.approx(p[0, 0], rel=0.09)


def test_worst_case_sign_pattern_matches_brute_force():
    rng = np.random.default_rng(5)
    for _ in range(20):
        v = rng.normal(size=(7, 2)) * rng.uniform(0.1, 3, size=(7, 1))
        best = 0.0
        for mask in range(2**7):
            s = np.array([1 if (mask >> i) & 1 else -1 for i in range(7)])
            best = max(best, np.linalg.norm(s @ v))
        norm, signs = worst_case_norm(v)
        assert norm == pytest.approx(best, rel=1e-12)
        assert np.linalg.norm(signs @ v) == pytest.approx(best, rel=1e-12)


def test_results_do_not_depend_on_cache_history():
    # The shared discretization cache must give bit-identical numbers whatever ran
    # before (sweeps rely on it: same grid, same numbers, any worker count).
    from inserr.model import discretization as discretize
    from inserr.schemes.catalogue import build_scheme
    from inserr.schemes.composition import build_timeline
    from inserr.schemes.vehicle_motion import YawSwing

    site = Site.from_degrees(34.0)
    imu = ImuErrors(
        gyro_bias=np.full(3, 0.01 * DEG_PER_HOUR),
        gyro_scale_factor=np.full(3, 10 * PPM),
        arw=0.001 * DEG_PER_SQRT_HOUR,
    )
    motion = YawSwing(pitch=0.02, roll=-0.03, amplitude=6 * DEG, period=120.0)

    def run(name):
        tl = build_timeline(build_scheme(name, 6 * DEG, 120.0).plan(motion, 1800.0), motion, 1800.0)
        r = analyze_drift(site, imu, InitialErrors(), tl, dt_out=10.0, dt_cov=60.0)
        return r.nav, r.noise_cov["arw"]

    discretize._shared.cache_clear()
    fresh = run("two-position")
    run("flexible-two-position")  # fills the cache with other sub-steps
    again = run("two-position")
    assert np.array_equal(fresh[0], again[0]) and np.array_equal(fresh[1], again[1])


@pytest.mark.parametrize(
    "t_out",
    [[0.0, 50.0, 50.0, 100.0], [0.0, 50.0, 150.0], [10.0, 5.0], [0.0, np.nan], [-1.0, 0.0, 50.0]],
)
def test_bad_output_grids_are_refused_not_extrapolated(t_out):
    # A duplicate time used to leave its row uninitialised; a time past the end was
    # extrapolated with the last interval's rate. Both must fail loudly.
    model = ErrorModel(Site(0.6), Layout(bias=True))
    tl = Timeline.static(np.eye(3), 100.0)
    with pytest.raises(ValueError, match="output times"):
        propagate_states(Discretizer(model), tl, np.zeros(model.layout.n), np.array(t_out))


def test_steps_end_at_every_timeline_node_and_output_time_by_default():
    # make_steps' default uses the timeline: every step lies inside one interval, so the
    # steps end at the nodes and at the output times; without it, at the outputs only.
    from inserr.model.exact_propagation import make_steps

    tl = _stop_and_turn_timeline()
    t_out = np.array([0.0, 50.0, 120.0, 167.5])
    ends = np.cumsum(make_steps(tl, t_out).dt)
    assert np.allclose(ends, [50.0, 100.0, 115.0, 120.0, 152.5, 167.5], rtol=0, atol=1e-9)
    plain = np.cumsum(make_steps(tl, t_out, use_omega=False).dt)
    assert np.allclose(plain, [50.0, 120.0, 167.5], rtol=0, atol=1e-9)


def test_cycle_integrals_accept_a_motion_that_does_not_move():
    from inserr.schemes.catalogue import build_scheme
    from inserr.schemes.cycle_integrals import cycle_integrals
    from inserr.schemes.vehicle_motion import Motion, Turn

    scheme = build_scheme("four-position", math.radians(6.0), 300.0)
    a = cycle_integrals(scheme, Motion())
    b = cycle_integrals(scheme, Turn(rate=0.0))
    np.testing.assert_allclose(a.full, b.full, rtol=0, atol=1e-12)
