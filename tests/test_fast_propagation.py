"""The fast engine against the step-by-step exact engine and against closed forms.

Three kinds of truth:

* On a :class:`~inserr.model.timeline.Timeline` both engines solve the same
  piecewise-constant-rate problem, so they must agree to round-off. The exact engine
  is :mod:`inserr.model.exact_propagation` (python-control / structured expm per step),
  an independent implementation (augmented 33-state transitions vs modal scalars and
  quadrature).
* On the continuous motion (:class:`~inserr.schemes.composition.ScheduleHistory`) the
  exact engine needs sub-steps; its error is O(h^2) (geodesic sub-steps), so the two
  must converge: halving h divides the difference by about 4, and the Richardson
  extrapolation of the exact engine agrees with the fast one far better than either
  sub-step does.
* Closed forms: the modal decomposition reproduces F and expm(F t); Fejér quadrature
  and the spectral integration matrix are exact for polynomials; the white-noise
  covariance equals Van Loan's discretization stepped by the exact engine.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import scipy.linalg as sl
from scipy.spatial.transform import Rotation

from inserr.core.earth import Site
from inserr.core.imu import ImuErrors, InitialErrors
from inserr.core.units import ARCSEC, DEG, DEG_PER_HOUR, DEG_PER_SQRT_HOUR, MICRO_G, PPM
from inserr.drift.analysis import analyze_drift, output_grid
from inserr.model import fast_propagation as fp
from inserr.model import quadrature as q
from inserr.model.attitude_history import TimelineHistory
from inserr.model.discretization import Discretizer
from inserr.model.exact_propagation import propagate_covariance
from inserr.model.modal import NavModes
from inserr.model.psi_model import ErrorModel, Layout
from inserr.model.timeline import Timeline
from inserr.schemes.catalogue import build_scheme
from inserr.schemes.composition import ScheduleHistory, build_timeline
from inserr.schemes.vehicle_motion import HeadingHistory, Motion, Turn, YawSwing

SITE = Site.from_degrees(34.246, 108.91, 380.0)
#: P0-like budget with every kind of constant error (different per axis, so that an
#: axis or frame mix-up cannot cancel).
IMU = ImuErrors(
    gyro_bias=np.array([0.003, -0.002, 0.004]) * DEG_PER_HOUR,
    accel_bias=np.array([30.0, -20.0, 10.0]) * MICRO_G,
    gyro_scale_factor=np.array([10.0, -7.0, 12.0]) * PPM,
    accel_scale_factor=np.array([-10.0, 8.0, 5.0]) * PPM,
    gyro_misalignment=np.array([10.0, -6.0, 4.0, 8.0, -9.0, 3.0]) * ARCSEC,
    accel_misalignment=np.array([-5.0, 7.0, 10.0, -3.0, 6.0, -8.0]) * ARCSEC,
)
INIT = InitialErrors(
    np.array([10.0, -10.0, 60.0]) * ARCSEC, np.array([0.01, -0.02, 0.0]), np.array([10.0, 5.0, 0.0])
)
SWING = YawSwing(heading=15 * DEG, pitch=1 * DEG, roll=-2 * DEG, amplitude=6 * DEG, period=120.0)


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    """Largest difference relative to the largest magnitude, per column, over time.

    A column that is zero in physics (e.g. an east position error seen in the east
    position of a clamped, Schuler-neutral combination) carries round-off of the size of
    the *whole* response: columns below 1e-6 of the largest are compared with that floor
    (1e-9 of it is 1e-15 of the largest response, i.e. round-off).
    """
    col = np.abs(b).max(axis=0)
    scale = np.maximum(col, 1e-6 * col.max() + 1e-300)
    return float((np.abs(a - b).max(axis=0) / scale).max())


def _drift_difference(a, b) -> float:
    """:func:`_relative` of two drift results: the larger of the signed navigation errors'
    and the per-source horizontal errors' (every source a column)."""
    n = len(b.t_cov)
    return max(
        _relative(a.nav, b.nav),
        _relative(a.source_horizontal.reshape(n, -1), b.source_horizontal.reshape(n, -1)),
    )


def _both(history, hours_out=(10.0, 60.0), **kw):
    fast = analyze_drift(SITE, IMU, INIT, history, dt_out=hours_out[0], dt_cov=hours_out[1], **kw)
    return fast


# --- modal decomposition --------------------------------------------------------------
@pytest.mark.parametrize("vertical", ["clamped", "free"])
@pytest.mark.parametrize("lat", [0.0, 34.0, -60.0, 89.9])
def test_modes_reproduce_the_navigation_block_and_its_exponential(lat, vertical):
    model = ErrorModel(Site.from_degrees(lat), vertical=vertical)
    modes = NavModes(model)
    f = model.nav_matrix
    v, vinv, lam = modes.out_all, modes.inv_all, modes.lam_all
    active = np.abs(v).sum(axis=1) > 0
    # V diag(lambda) V^-1 = F on the active states (clamped vertical states are dropped),
    # compared on the balanced state (psi * R, dv / w_s, dr: all in metres of the same
    # size), where F's entries are all O(w_s) and round-off is uniform.
    rebuilt = (v @ np.diag(lam) @ vinv).real
    ws = math.sqrt(model.site.g / model.site.mean_radius)
    d = np.repeat([model.site.mean_radius, 1.0 / ws, 1.0], 3)
    bal = lambda a: d[:, None] * a / d[None, :]  # noqa: E731
    target = bal(f * active[:, None] * active[None, :])
    assert np.abs(bal(rebuilt) - target).max() < 1e-12 * np.abs(target).max()
    # The real transition over 1000 s from the kept modes equals expm (longer times make
    # the reference's own scaling-and-squaring error, ~eps |F t|, the larger one).
    t = 1000.0
    x0 = np.random.default_rng(1).normal(size=9) * active
    z = modes.to_modes(x0) * np.exp(modes.lam * t)
    ref = sl.expm(f * t) @ x0
    assert np.allclose(modes.to_nav(z), ref * active, rtol=1e-9, atol=1e-9 * np.abs(ref).max())


# --- quadrature ------------------------------------------------------------------------
@pytest.mark.parametrize("n", [1, 2, 5, 12, 26])
def test_fejer_and_spectral_integration_are_exact_for_polynomials(n):
    x = q.chebyshev_points(n)
    rng = np.random.default_rng(n)
    c = rng.normal(size=n)  # a polynomial of degree n - 1
    p = np.polynomial.Polynomial(c)
    antider = p.integ(lbnd=-1.0)
    assert math.isclose(q.fejer_weights(n) @ p(x), antider(1.0), rel_tol=1e-12, abs_tol=1e-12)
    pts = np.linspace(-1.0, 1.0, 7)
    assert np.allclose(q.integration_matrix(pts, n) @ p(x), antider(pts), atol=1e-12)


def test_points_for_the_phase_budget_integrate_an_oscillation_to_round_off():
    # The table in quadrature.py claims ~1e-15: check the worst case of each entry, a
    # complex exponential whose phase over the interval is the entry's budget.
    for budget, n in q._POINTS[1:]:
        x = q.chebyshev_points(n)
        w = budget / 2.0  # on [-1, 1] the phase budget W (b - a) is 2 w
        f = np.exp(1j * w * x)
        exact = 2.0 * math.sin(w) / w
        assert abs(q.fejer_weights(n) @ f - exact) < 1e-14, (budget, n)
        pts = np.linspace(-1, 1, 11)
        ex = (np.exp(1j * w * pts) - np.exp(-1j * w)) / (1j * w)
        assert np.abs(q.integration_matrix(pts, n) @ f - ex).max() < 5e-14, (budget, n)


# --- the same piecewise-constant-rate problem: round-off agreement ------------------
def _timeline_cases():
    tl_swing = build_timeline(
        build_scheme("two-position", 6 * DEG, 300.0).plan(SWING, 3600.0), SWING, 3600.0, 1.0
    )
    turn = Turn(heading=10 * DEG, pitch=2 * DEG, roll=1 * DEG, rate=0.5 * DEG)
    hh = HeadingHistory(
        pitch=1 * DEG,
        roll=1 * DEG,
        times=np.arange(0.0, 3700.0, 7.0),
        headings=np.cumsum(np.random.default_rng(3).normal(size=529)) * 0.02,
    )
    static = Motion(heading=30 * DEG, pitch=1 * DEG, roll=-2 * DEG)
    cases = {
        "static-four-position-modified": (static, "four-position-modified", 7200.0),
        "static-sixteen-position": (static, "sixteen-position", 7200.0),
        "turn-continuous": (turn, "continuous", 3600.0),
        "static-continuous": (static, "continuous", 3600.0),
        "swing-flexible": (SWING, "flexible-two-position", 3600.0),
        "swing-isolation": (SWING, "heading-isolation", 1800.0),
        "history-nulling": (hh, "nulling-two-position", 3600.0),
    }
    out = {"swing-two-position": tl_swing}
    for key, (motion, scheme, dur) in cases.items():
        table = build_scheme(scheme, 6 * DEG, 120.0).plan(motion, dur)
        out[key] = build_timeline(table, motion, dur, 1.0)
    return out


TIMELINES = _timeline_cases()


@pytest.mark.parametrize("name", sorted(TIMELINES))
def test_fast_equals_exact_on_the_same_timeline(name):
    tl = TIMELINES[name]
    fast = analyze_drift(SITE, IMU, INIT, tl, dt_out=10.0, dt_cov=60.0, engine="fast")
    exact = analyze_drift(SITE, IMU, INIT, tl, dt_out=10.0, dt_cov=60.0, engine="exact")
    # Both solve this problem exactly, up to the step engine's own error: its expm of a
    # whole 60 s turn or 300 s stop (|A h| ~ 600 to 3000) is good to ~1e-13, which
    # accumulates to ~1e-7 of the smallest responses within an hour (the next tests
    # settle which engine errs with an 80-bit expm chain), hence 3e-7 here.
    assert _relative(fast.nav, exact.nav) < 3e-7
    n = len(fast.t_cov)
    h_f, h_e = fast.source_horizontal.reshape(n, -1), exact.source_horizontal.reshape(n, -1)
    assert _relative(h_f, h_e) < 3e-7
    assert _relative(fast.source_heading, exact.source_heading) < 3e-7


def _expm_longdouble(a: np.ndarray, h: float) -> np.ndarray:
    """expm(A h) in 80-bit extended precision: Taylor series with scaling and squaring."""
    ld = np.longdouble
    b = a.astype(ld) * ld(h)
    norm = float(np.abs(b).sum(axis=1).max())
    s = max(0, math.ceil(math.log2(norm / 0.05))) if norm > 0 else 0
    b = b / ld(2**s)
    out = np.eye(len(a), dtype=ld)
    term = np.eye(len(a), dtype=ld)
    for k in range(1, 30):  # |B| <= 0.05: the series is exhausted long before 30 terms
        term = term @ b / ld(k)
        out = out + term
    for _ in range(s):
        out = out @ out
    return out


def _extended_precision_response(tl: Timeline, imu: ImuErrors, source: str) -> tuple:
    """Final horizontal error of one source through an 80-bit expm chain over the timeline."""
    from inserr.model.error_sources import constant_sources, layout_for, source_matrix

    model = ErrorModel(SITE, layout_for(imu))
    srcs = constant_sources(imu, InitialErrors())
    j = [s.name for s in srcs].index(source)
    x = (source_matrix(model, [srcs[j]], tl.c_sn[0])[:, 0] * srcs[j].value).astype(np.longdouble)
    cache: dict = {}
    for k in range(len(tl.omega_n)):
        key = (tuple(np.round(tl.omega_n[k], 15)), round(tl.times[k + 1] - tl.times[k], 12))
        if key not in cache:
            cache[key] = _expm_longdouble(model.matrix(tl.omega_n[k]), key[1])
        x = cache[key] @ x
    return j, x[6:8].astype(float)


@pytest.mark.parametrize(
    ("name", "source"),
    [
        ("static-continuous", "gyro_misalignment_zx"),
        ("static-sixteen-position", "gyro_misalignment_zy"),
    ],
)
def test_fast_engine_equals_an_extended_precision_expm_chain(name, source):
    # Arbiter for the fast-vs-exact differences above: 80-bit expm of the augmented
    # matrix per interval, chained in 80 bits. The fast engine agrees to round-off.
    tl = TIMELINES[name]
    j, ref = _extended_precision_response(tl, IMU, source)
    fast = analyze_drift(SITE, IMU, InitialErrors(), tl, dt_out=10.0, dt_cov=60.0)
    got = fast.source_horizontal[-1, j]
    assert np.linalg.norm(got - ref) < 1e-10 * np.linalg.norm(ref)


def test_over_a_day_the_fast_engine_keeps_round_off_where_the_step_engine_drifts():
    # Static four-position indexing cancels most of an accelerometer bias, so the 24 h
    # residual is a small difference of large terms: the step-by-step engine's per-step
    # expm error (~1e-13 relative on |A h| ~ 3000) accumulates over ~1000 stops to
    # ~1e-6 of the residual; the fast engine's closed forms stay at round-off.
    motion = Motion()
    dur = 24 * 3600.0
    tl = build_timeline(
        build_scheme("four-position", 6 * DEG, 300.0).plan(motion, dur), motion, dur
    )
    imu = ImuErrors(accel_bias=np.array([100.0, 0.0, 0.0]) * MICRO_G)
    j, ref = _extended_precision_response(tl, imu, "accel_bias_x")
    fast = analyze_drift(SITE, imu, InitialErrors(), tl, dt_out=600.0, dt_cov=600.0)
    assert np.linalg.norm(fast.source_horizontal[-1, j] - ref) < 1e-11 * np.linalg.norm(ref)


def test_free_vertical_channel_agrees_over_a_short_run():
    # The unstable vertical mode (time constant ~570 s) exercises the blocked scans.
    tl = TIMELINES["static-sixteen-position"]
    kw = dict(dt_out=10.0, dt_cov=60.0, vertical="free")
    init = InitialErrors(np.zeros(3), np.array([0.0, 0.0, 0.01]), np.array([0.0, 0.0, 1.0]))
    fast = analyze_drift(SITE, IMU, init, tl, engine="fast", **kw)
    exact = analyze_drift(SITE, IMU, init, tl, engine="exact", **kw)
    assert np.all(np.isfinite(fast.nav))
    assert _relative(fast.nav, exact.nav) < 1e-7  # as in the test above


# --- the continuous motion: convergence of the sub-stepped exact engine ---------------
@pytest.mark.parametrize("scheme", ["two-position", "flexible-two-position", "heading-isolation"])
def test_exact_engine_converges_to_the_fast_one_as_its_substep_shrinks(scheme):
    dur = 1800.0
    hist = ScheduleHistory(build_scheme(scheme, 6 * DEG, 300.0).plan(SWING, dur), SWING, dur)
    fast = analyze_drift(SITE, IMU, INIT, hist, dt_out=10.0, dt_cov=60.0)
    n = len(fast.t_cov)

    def views(r):  # signed response (fine grid) and per-source responses (coarse grid)
        return r.nav, r.source_horizontal.reshape(n, -1)

    runs = [
        views(analyze_drift(SITE, IMU, INIT, hist, dt_out=10.0, dt_cov=60.0, engine="exact",
                            substep=h))
        for h in (1.0, 0.5)
    ]  # fmt: skip
    for which, ref in enumerate(views(fast)):
        errs = [_relative(r[which], ref) for r in runs]
        # Second order: halving h divides the error by 4 (3 to 5 allowed: the error is
        # not exactly h^2 where stops end between sub-step nodes).
        assert 3.0 < errs[0] / errs[1] < 5.0
        richardson = runs[1][which] + (runs[1][which] - runs[0][which]) / 3.0
        assert _relative(richardson, ref) < errs[1] / 20.0


@pytest.mark.parametrize(
    ("scheme", "dt_out"),
    [("nulling-two-position", 1.0), ("nulling-two-position", 7.0), ("four-position", 1.0),
     ("flexible-two-position", 1.0)],
)  # fmt: skip
def test_phase_cache_equals_direct_sampling(scheme, dt_out):
    # Stops on a periodic vehicle reuse the vehicle part per phase; forbidding that
    # (no phase step) must change nothing but round-off. A 7 s output step does not
    # divide the 20 s phase step: fine times then fall anywhere in the cached windows.
    # Four-position and the flexible rule stop at table angles whose matrices are not
    # symmetric (a transposed table would show), nulling at 0 and 180 deg.
    dur = 3600.0
    hist = ScheduleHistory(build_scheme(scheme, 6 * DEG, 300.0).plan(SWING, dur), SWING, dur)
    model = ErrorModel(SITE, Layout(scale_misalignment=True))
    from inserr.model.error_sources import constant_sources, source_set

    src = source_set(model, constant_sources(IMU, INIT))
    t, tc = output_grid(dur, dt_out), output_grid(dur, 60.0)
    cached = fp.constant_error_response(model, hist, src, t, tc)
    assert cached.windows["cached"] > 0
    real_step = fp.phase_step
    try:
        fp.phase_step = lambda *a, **k: None
        direct = fp.constant_error_response(model, hist, src, t, tc)
    finally:
        fp.phase_step = real_step
    assert direct.windows["cached"] == 0
    assert _relative(cached.fine, direct.fine) < 1e-11
    assert _relative(cached.coarse.reshape(len(tc), -1), direct.coarse.reshape(len(tc), -1)) < 1e-11


# --- white noise ------------------------------------------------------------------------
@pytest.mark.parametrize("vertical", ["clamped", "free"])
def test_white_noise_closed_form_equals_stepped_van_loan(vertical):
    model = ErrorModel(SITE, Layout(bias=False), vertical=vertical)
    arw, vrw = 0.001 * DEG / 60.0, 10 * MICRO_G
    t = output_grid(4 * 3600.0 if vertical == "clamped" else 1800.0, 60.0)
    closed = fp.white_noise_covariance(model, arw, vrw, t)
    disc = Discretizer(model, model.noise_intensity(arw, vrw))
    stepped = propagate_covariance(disc, Timeline.static(np.eye(3), t[-1]), np.zeros((9, 9)), t)
    d = np.sqrt(np.maximum(np.diagonal(stepped, axis1=1, axis2=2), 1e-300))
    # Compare correlation-normalised entries: both exact, Van Loan stepped 240 times.
    norm = d[:, :, None] * d[:, None, :]
    err = np.abs(closed - stepped) / np.where(norm > 0, norm, 1.0)
    assert err[1:].max() < 1e-9
    # Limiting case: early on the attitude variance grows as ARW^2 t (per axis).
    assert math.isclose(closed[1, 0, 0], arw**2 * 60.0, rel_tol=1e-3)


@pytest.mark.parametrize("scheme", ["two-position", "heading-isolation", "nulling-two-position"])
def test_quadrature_is_converged(monkeypatch, scheme):
    # Halving the phase budget of every window (twice the windows, each sampled at the
    # rate its own budget asks) must change nothing beyond round-off: the windows'
    # Chebyshev quadrature is converged on the continuous motion.
    dur = 3600.0
    hist = ScheduleHistory(build_scheme(scheme, 6 * DEG, 300.0).plan(SWING, dur), SWING, dur)
    ref = analyze_drift(SITE, IMU, INIT, hist, dt_out=1.0, dt_cov=60.0)
    monkeypatch.setattr(fp, "MAX_PHASE", fp.MAX_PHASE / 2.0)
    finer = analyze_drift(SITE, IMU, INIT, hist, dt_out=1.0, dt_cov=60.0)
    assert _drift_difference(finer, ref) < 1e-11


# The step engine chains 4320 expm steps of 60 s: its round-off grows to ~4e-9.
@pytest.mark.parametrize(("engine", "rtol"), [("fast", 1e-10), ("exact", 1e-8)])
def test_vertical_gyro_bias_drifts_east_at_r_b_sin_cos_and_leaves_heading_bounded(engine, rtol):
    # Closed form (docs/theory.md, 4.1): the zero mode (psi along the Earth axis) grows
    # as -b sin L t; the Schuler loop keeps the true tilt bounded, so dr_E grows at
    # R_N b sin L cos L and the secular heading terms cancel. Everything else is a sum of
    # sinusoids at the mode frequencies, so a least-squares fit on [1, t, sinusoids] is
    # exact up to round-off.
    from inserr.model.psi_model import modes

    site = Site.from_degrees(34.0)
    b = 0.01 * DEG_PER_HOUR
    imu = ImuErrors(gyro_bias=np.array([0.0, 0.0, b]))
    hist = ScheduleHistory(
        build_scheme("none", 6 * DEG, 300.0).plan(Motion(), 72 * 3600.0), Motion(), 72 * 3600.0
    )
    res = analyze_drift(site, imu, InitialErrors(), hist, dt_out=60.0, engine=engine)
    ev = modes(ErrorModel(site)).eigenvalues
    freqs = np.unique(np.round(np.abs(ev.imag[ev.imag > 1e-9]), 15))
    t = res.t
    basis = np.stack([np.ones_like(t), t] + [f(w * t) for w in freqs for f in (np.cos, np.sin)], 1)
    slope_e = np.linalg.lstsq(basis, res.nav[:, 6], rcond=None)[0][1]
    slope_h = np.linalg.lstsq(basis, res.attitude[:, 2], rcond=None)[0][1]
    lat = math.radians(34.0)
    expected = site.r_n * b * math.sin(lat) * math.cos(lat)
    assert math.isclose(slope_e, expected, rel_tol=rtol)
    assert abs(slope_h) < 1e-9 * b  # rad/s: no secular heading drift


def _gm_reference(model_site, tl, sigma, tau, sensor, t, vertical="clamped"):
    """Step-by-step covariance of the augmented model (GM states started stationary)."""
    model = ErrorModel(
        model_site,
        Layout(bias=False, bias_instability=True),
        vertical=vertical,
        gyro_correlation_time=tau,
        accel_correlation_time=tau,
    )
    g, a = (sigma, 0.0) if sensor == "gyro" else (0.0, sigma)
    disc = Discretizer(model, model.noise_intensity(0.0, 0.0, g, a))
    p0 = np.zeros((model.layout.n,) * 2)
    bias = model.layout["bg" if sensor == "gyro" else "ba"]
    p0[bias, bias] = sigma**2 * np.eye(3)
    return propagate_covariance(disc, tl, p0, t)[:, :9, :9]


def _cov_close(got, ref, rtol):
    """Correlation-normalised comparison of the states that carry variance.

    States are compared on the balanced scale (psi in metres of the Earth's surface, dv
    in metres per Schuler radian, dr in metres); a state whose spread is below 1e-6 of
    the largest carries only round-off (e.g. psi under accelerometer noise) and is left
    out.
    """
    d = np.sqrt(np.maximum(np.diagonal(ref, axis1=1, axis2=2), 0.0))[-1]
    ws = math.sqrt(SITE.g / SITE.mean_radius)
    bal = d * np.repeat([SITE.mean_radius, 1.0 / ws, 1.0], 3)
    live = bal > 1e-6 * bal.max()
    scale = np.outer(d, d)[np.ix_(live, live)]
    err = np.abs(got[-1] - ref[-1])[np.ix_(live, live)] / scale
    return float(err.max()) < rtol


@pytest.mark.parametrize("sensor", ["gyro", "accel"])
@pytest.mark.parametrize("name", ["swing-two-position", "static-four-position-modified"])
def test_gauss_markov_covariance_equals_the_step_engine(name, sensor):
    # Same piecewise-constant-rate problem (the timeline): the augmented step-by-step
    # covariance (Van Loan per step) against the fast engine's cross-covariance form.
    tl = TIMELINES[name]
    t = output_grid(tl.duration, 60.0)
    sigma = 0.005 * DEG_PER_HOUR if sensor == "gyro" else 20 * MICRO_G
    ref = _gm_reference(SITE, tl, sigma, 1800.0, sensor, t)
    got = fp.gauss_markov_covariance(
        ErrorModel(SITE), TimelineHistory(tl), sigma, 1800.0, sensor, t
    )
    # Both exact for this problem; 1e-7 leaves room for the step engine's accumulated
    # round-off (as in test_fast_equals_exact_on_the_same_timeline).
    assert _cov_close(got, ref, 1e-7)


def test_gauss_markov_stationary_limit_equals_white_noise():
    # A bias much shorter-correlated than the run is white noise of PSD 2 sigma^2 tau
    # (its integral over a time >> tau): compare with the white-noise closed form.
    tl = Timeline.static(np.eye(3), 4 * 3600.0)
    t = output_grid(tl.duration, 600.0)
    sigma, tau = 0.05 * DEG_PER_HOUR, 2.0
    got = fp.gauss_markov_covariance(ErrorModel(SITE), TimelineHistory(tl), sigma, tau, "gyro", t)
    arw = math.sqrt(2.0 * sigma**2 * tau)
    white = fp.white_noise_covariance(ErrorModel(SITE, Layout(bias=False)), arw, 0.0, t)
    # Relative difference O(tau / T) for the variance growth: 2 s against hours.
    assert np.allclose(got[-1], white[-1], rtol=2e-3, atol=1e-3 * np.abs(white[-1]).max())


@pytest.mark.parametrize(
    ("motion", "scheme"),
    [(Motion(heading=0.3, pitch=0.02, roll=-0.03), "sixteen-position"),
     (Motion(), "continuous"),
     (SWING, "two-position"),
     (SWING, "none"),
     (Motion(), "four-position"),
     # Closed-loop rules whose flown schedule repeats (a realized period).
     (Motion(heading=0.3, pitch=0.02, roll=-0.03), "nulling-two-position"),
     (Motion(heading=0.3, pitch=0.02, roll=-0.03), "heading-isolation"),
     (SWING, "heading-isolation")],
)  # fmt: skip
def test_periodic_lifting_equals_the_whole_run(monkeypatch, motion, scheme):
    # A periodic history (open-loop table on a static or periodic vehicle) is computed
    # for one period and copied: identical to computing every window of the run.
    dur = 6 * 3600.0
    hist = ScheduleHistory(build_scheme(scheme, 6 * DEG, 120.0).plan(motion, dur), motion, dur)
    assert hist.period() is not None
    # The lifting period is a whole number of the history's periods that both output
    # grids divide (four-position: a 570 s cycle lifts with 1140 s on the 60 s grid).
    lift = fp._lifting(hist, output_grid(dur, 1.0), output_grid(dur, 60.0))
    assert lift is not None
    ratio = lift[1] / hist.period()[1]
    assert abs(ratio - round(ratio)) < 1e-9 and abs(lift[1] / 60.0 - round(lift[1] / 60.0)) < 1e-9
    lifted = analyze_drift(SITE, IMU, INIT, hist, dt_out=1.0, dt_cov=60.0)
    monkeypatch.setattr(fp, "_lifting", lambda *a: None)
    whole = analyze_drift(SITE, IMU, INIT, hist, dt_out=1.0, dt_cov=60.0)
    assert _drift_difference(lifted, whole) < 1e-10


def test_history_period_is_the_common_period_of_table_and_vehicle():
    # Two-position, 300 s stops at 6 deg/s: cycle 4 (300 + 30) = 1320 s; a 120 s swing
    # divides it (11 swings); a 90 s swing does not: 1320 and 90 meet at 3960 s.
    table = build_scheme("two-position", 6 * DEG, 300.0).plan(SWING, 72 * 3600.0)
    assert ScheduleHistory(table, SWING, 72 * 3600.0).period() == (0.0, 1320.0)
    swing90 = YawSwing(amplitude=6 * DEG, period=90.0)
    t90 = build_scheme("two-position", 6 * DEG, 300.0).plan(swing90, 72 * 3600.0)
    t0, p = ScheduleHistory(t90, swing90, 72 * 3600.0).period()
    assert t0 == 0.0 and math.isclose(p, 3960.0, rel_tol=1e-12)
    # A closed-loop rule has no period.
    flex = build_scheme("flexible-two-position", 6 * DEG, 300.0).plan(SWING, 7200.0)
    assert ScheduleHistory(flex, SWING, 7200.0).period() is None


def _holds_on_the_swing():
    """Isolation holds of 130 s (more than the 120 s swing) at targets 0, 0.3 rad, a full
    turn and 0.3 rad plus a full turn, then an indexing turn with the yaw compensated;
    stops and a half turn of the outer gimbal between them."""
    from inserr.schemes.turntable import ScheduleBuilder

    b = ScheduleBuilder()
    for target in (0.0, 0.3, 2 * math.pi, 0.3 + 2 * math.pi):
        a0 = float(SWING.heading_at(b.t)) - target  # level: IMU heading = H - a
        b.isolate(130.0, target, a0, float(SWING.heading_at(b.t + 130.0)) - target)
        b.stop(20.0)
        b.rotate("outer", math.pi, 6 * DEG)
    a0 = float(SWING.heading_at(b.t)) - 0.3
    b.isolate(60.0, 0.3, a0, a0 - 60.0 * 2 * DEG, target_rate=2 * DEG, label="index")
    b.stop(20.0)
    return b.build()


def _pieces_cases():
    from inserr.schemes.vehicle_motion import Turn

    mounting = sl.expm(np.array([[0.0, -0.35, -0.61], [0.35, 0.0, -0.87], [0.61, 0.87, 0.0]]))
    tilted = Motion(heading=0.3, pitch=2 * DEG, roll=-3 * DEG)
    turn = Turn(heading=0.2, pitch=3 * DEG, roll=2 * DEG, rate=0.5 * DEG)
    # A heading history at rates changing every 13 s (one interval flat).
    times = np.arange(0.0, 820.0, 13.0)
    rates = np.random.default_rng(4).normal(size=len(times) - 1) * 0.3 * DEG
    rates[5] = 0.0
    headings = np.concatenate([[0.4], 0.4 + np.cumsum(rates * 13.0)])
    history = HeadingHistory(pitch=2 * DEG, roll=1 * DEG, times=times, headings=headings)
    from inserr.schemes.turntable import ScheduleBuilder

    half_second = ScheduleBuilder()  # half-second turns between stops
    for _ in range(4):
        half_second.stop(20.0)
        half_second.rotate("outer", 3 * DEG, 6 * DEG)
        half_second.stop(20.0)
        half_second.rotate("outer", -3 * DEG, 6 * DEG)
    return {
        "swing-two-position-mounted": (
            build_scheme("two-position", 6 * DEG, 40.0, mounting=mounting).plan(SWING, 800.0),
            SWING),
        "swing-isolation-holds": (_holds_on_the_swing(), SWING),
        "tilted-four-position": (build_scheme("four-position", 6 * DEG, 40.0).plan(tilted, 800.0),
                                 tilted),
        "tilted-heading-isolation": (
            build_scheme("heading-isolation", 6 * DEG, 40.0).plan(tilted, 800.0), tilted),
        "turn-two-position": (build_scheme("two-position", 6 * DEG, 40.0).plan(turn, 800.0), turn),
        "history-two-position": (build_scheme("two-position", 6 * DEG, 40.0).plan(history, 800.0),
                                 history),
        "tilted-half-second-turns": (half_second.build(), tilted),
    }  # fmt: skip


@pytest.mark.parametrize("name", sorted(_pieces_cases()))
def test_schedule_pieces_describe_the_attitude_they_cut(name):
    # What the pieces tell the fast engine, against the attitude sampled inside each piece
    # (19 interior times): `still` exactly where C_s^n does not change; `constant` (or
    # still) exactly where w_ns^n does not change; the bandwidth about at least every
    # |w_ns^n| (the vehicle bound plus the gimbal rate of a turn, the heading rate of an
    # isolation); for a stop the table matrix C_s^b = C_b^n^T C_s^n; the phase classes
    # (periodic vehicle): 0 for stops, the same class k >= 1 for isolation holds that
    # are the same function of the vehicle phase (compared at equal phases), -1 else.
    # Round-off of the sampled attitudes and rates: ~1e-15; differences that count are
    # >= 1e-6 (a 0.5 deg/s turn over a second).
    table, motion = _pieces_cases()[name]
    dur = float(min(table.end, 800.0))
    hist = ScheduleHistory(table, motion, dur)
    pc = hist.pieces()
    a, b = pc.breaks[:-1], pc.breaks[1:]
    frac = np.linspace(0.05, 0.95, 19)
    t = a[:, None] + frac[None, :] * (b - a)[:, None]
    piece = np.repeat(np.arange(len(a)), len(frac))
    c, w = hist.evaluate(t.ravel(), piece)
    c = c.reshape(len(a), len(frac), 3, 3)
    w = w.reshape(len(a), len(frac), 3)
    c_still = np.abs(c - c[:, :1]).max(axis=(1, 2, 3)) < 1e-12
    w_still = np.abs(w - w[:, :1]).max(axis=(1, 2)) < 1e-12
    assert np.array_equal(pc.still, c_still)
    assert np.array_equal(pc.constant | pc.still, w_still)
    # (An isolation turn on a tilted vehicle turns 0.2 % faster than its heading rate,
    # the stated bandwidth: the gimbal rate varies. The quadrature's points carry a
    # larger margin than that; 1 % here.)
    assert np.all(pc.bandwidth >= np.linalg.norm(w, axis=2).max(axis=1) * (1 - 1e-2))
    seg = np.searchsorted(table.t0, 0.5 * (a + b), side="right") - 1
    kind = np.array(table.kind)[seg]
    gimbal = np.where(kind == "rotate", np.abs(table.rate[seg]), 0.0)
    gimbal = np.where(kind == "isolate", np.abs(table.target_rate[seg]), gimbal)
    assert np.allclose(pc.bandwidth, motion.rate_bound(a, b) + gimbal, rtol=1e-15, atol=0)
    stop = kind == "stop"
    c_bn = motion.attitude(t.ravel()).reshape(len(a), len(frac), 3, 3)
    c_sb = np.swapaxes(c_bn, 2, 3) @ c
    assert np.all(np.abs(pc.table[stop][:, None] - c_sb[stop]) < 1e-12)
    assert np.all(np.isnan(pc.table[~stop]))
    if motion.repeat_period() is None:
        assert pc.vehicle_period is None and np.all(pc.phase_class == -1)
        return
    period = motion.repeat_period()
    assert pc.vehicle_period == period
    hold = (kind == "isolate") & (table.target_rate[seg] == 0.0)
    assert np.all(pc.phase_class[stop] == 0) and np.all(pc.phase_class[~stop & ~hold] == -1)
    assert np.all(pc.phase_class[hold] >= 1)
    holds = np.flatnonzero(hold)
    phase = np.linspace(1.0, period - 1.0, 9)
    for i in holds:
        for j in holds:
            # The times of piece j at the phases of the first times of piece i.
            ti = a[i] + 1.0 + phase
            tj = ti + np.ceil((a[j] + 1.0 - ti) / period) * period
            assert np.all(tj < b[j] - 1e-3)
            ci, _ = hist.evaluate(ti, np.full(len(ti), i))
            cj, _ = hist.evaluate(tj, np.full(len(tj), j))
            same = np.abs(ci - cj).max() < 1e-9
            assert same == (pc.phase_class[i] == pc.phase_class[j]), (i, j)
    if name == "swing-isolation-holds":
        assert len(set(pc.phase_class[holds])) == 2  # 0 = 2 pi, 0.3 = 0.3 + 2 pi


_RATE = 6 * DEG  # table rate of the hand-built schedules below (half turn: 30 s)
_TILTED = Motion(heading=0.3, pitch=2 * DEG, roll=-3 * DEG)


def _cycles(builder, n, last=None, net=-math.pi, dwell=40.0):
    """``n`` cycles of stop, outer half turn, stop, outer turn by ``net`` (140 s when
    ``net`` is -180 deg); ``last(builder)`` replaces the last cycle's final turn."""
    for i in range(n):
        builder.stop(dwell, "A")
        builder.rotate("outer", math.pi, _RATE)
        builder.stop(40.0, "B")
        if i == n - 1 and last is not None:
            last(builder)
        else:
            builder.rotate("outer", net, _RATE)
    return builder


def _period_cases():
    from inserr.schemes.turntable import ScheduleBuilder as B

    def built(b, cycle):
        return b.build(cycle=cycle)

    def short_cycle():  # a cycle with half-second turns: 81 s
        b = B()
        for _ in range(3):
            b.stop(40.0)
            b.rotate("outer", 3 * DEG, _RATE)
            b.stop(40.0)
            b.rotate("outer", -3 * DEG, _RATE)
        return b

    def first_turn():  # a half-second turn, then the 140 s cycles
        b = B()
        b.rotate("outer", 3 * DEG, _RATE)
        return _cycles(b, 3)

    def isolation(targets):  # holds of the IMU heading at the given targets, then stops
        b = B()
        for target in targets:
            b.isolate(50.0, target, 0.0, 0.0)
            b.stop(40.0)
        return b

    def late_inner(b):  # the last turn by the inner gimbal
        b.rotate("inner", -math.pi, _RATE)

    def long_first_dwell():
        b = B()
        b.stop(300.0)
        b.rotate("outer", math.pi, _RATE)
        b.stop(40.0)
        b.rotate("outer", -math.pi, _RATE)
        return b

    def shorter(eps):  # the last turn eps shorter (same rate): it ends eps * rate short
        return lambda b: b.rotate("outer", -math.pi * (1 - eps / 30.0), _RATE)

    def faster(eps):  # the last turn at a rate 1 + eps faster, over the same 30 s
        return lambda b: b.rotate("outer", -math.pi * (1 + eps), _RATE * (1 + eps))

    # name: (schedule, duration, expected (t0, P) or None)
    return {
        "cycles": (built(_cycles(B(), 3), 140.0), 420.0, (0.0, 140.0)),
        "half-second-turns": (built(short_cycle(), 81.0), 243.0, (0.0, 81.0)),
        "first-turn-then-cycles": (built(first_turn(), 140.0), 420.5, (0.5, 140.0)),
        "a-full-turn-per-cycle": (built(_cycles(B(), 3, net=math.pi), 140.0), 420.0, (0.0, 140.0)),
        "creeping-45-deg-per-cycle": (
            built(_cycles(B(), 3, net=-135 * DEG), 132.5), 397.5, None),
        "declared-cycle-half-a-second-off": (
            built(_cycles(B(), 3, dwell=40.5), 140.0), 421.0, None),
        "segments-end-after-two-cycles": (built(_cycles(B(), 2), 140.0), 420.0, None),
        "last-turn-0.5-s-short": (built(_cycles(B(), 3, shorter(0.5)), 140.0), 420.0, None),
        "last-turn-5e-9-s-short": (built(_cycles(B(), 3, shorter(5e-9)), 140.0), 420.0, None),
        "last-turn-faster-by-5e-8": (built(_cycles(B(), 3, faster(5e-8)), 140.0), 420.0, None),
        "last-turn-by-the-inner-gimbal-at-the-end": (
            built(_cycles(B(), 3, late_inner), 140.0), 390.5, None),
        "isolation-holds-at-other-headings": (
            built(isolation([0.0, 45 * DEG, 0.0, 45 * DEG]), 90.0), 360.0, None),
        "first-dwell-longer-than-the-run-leaves": (built(long_first_dwell(), 140.0), 420.0, None),
    }  # fmt: skip


@pytest.mark.parametrize("name", sorted(_period_cases()))
def test_history_period_is_found_exactly_when_the_attitude_repeats(name):
    # Truth from the attitude itself: C_s^n(t + P) = C_s^n(t) for every t in [t0, D - P]
    # (sampled every 0.25 s and at the ends, with the table's angles and the vehicle's
    # attitude, not the history's evaluation). Periodic schedules must be found (the
    # engine then computes one period); near misses (a turn 5e-9 s short, a rate 5e-8
    # faster, a cycle creeping by 45 deg, a declared cycle 0.5 s off, isolation holds at
    # other headings, a mismatch in the last half second) must not be taken for periodic.
    # The near misses differ by >= 5e-10 rad somewhere; the comparison's round-off is
    # ~1e-15.
    table, dur, expected = _period_cases()[name]

    def attitude(t):
        return _TILTED.attitude(t) @ table.dcm_at(t, _TILTED)

    def mismatch(t0, p):
        t = np.concatenate([np.arange(t0, dur - p, 0.25), [dur - p]])
        return float(np.abs(attitude(t + p) - attitude(t)).max())

    found = ScheduleHistory(table, _TILTED, dur).period()
    assert found == (pytest.approx(expected) if expected else None)
    if expected is None:
        # The schedule does not repeat with its declared cycle after 0 nor after its
        # first segment (or no whole cycle fits after it).
        for t0 in (0.0, float(table.t0[1])):
            assert t0 + table.cycle > dur or mismatch(t0, table.cycle) > 4e-10
    else:
        assert mismatch(*found) < 1e-13


def _attitude_mismatch(table, motion, dur, t0, p):
    """Largest |C_s^n(t + P) - C_s^n(t)| over [t0, dur - P] (every 0.25 s and the end),
    from the table's angles and the vehicle's attitude, not the history's evaluation."""
    t = np.concatenate([np.arange(t0, dur - p, 0.25), [dur - p]])

    def attitude(tt):
        return motion.attitude(tt) @ table.dcm_at(tt, motion)

    return float(np.abs(attitude(t + p) - attitude(t)).max())


def test_a_closed_loop_schedule_that_repeats_has_its_realized_period():
    # A closed-loop rule declares no cycle; what it flew may still repeat. Truth from the
    # attitude itself (as above): found periods repeat to round-off, near misses do not.
    from inserr.schemes.turntable import ScheduleBuilder, isolation_angle

    def holds(motion, targets, last_shift=0.0):
        # Isolation holds of 50 s with 40 s stops between, then one more hold at the first
        # target: the table jumps from hold to hold (no turn between them), so it ends
        # where its next period would begin and the attitude check reaches the end.
        b = ScheduleBuilder()
        targets = [*targets, targets[0]]
        for i, target in enumerate(targets):
            target = target + (last_shift if i == len(targets) - 1 else 0.0)
            # The angles the hold starts and ends at (the stop after it holds the end).
            a = isolation_angle(motion.attitude(np.array([b.t, b.t + 50.0])), 0.0, None, target)
            b.isolate(50.0, target, float(a[0]), float(a[1]))
            if i < len(targets) - 1:
                b.stop(40.0)
        return b.build()

    # Holds at 0 and 45 deg in turn: 180 s, four segments (not the 90 s of two).
    table = holds(_TILTED, [0.0, 45 * DEG] * 3)
    assert table.cycle is None
    assert ScheduleHistory(table, _TILTED, 590.0).period() == (0.0, 180.0)
    assert _attitude_mismatch(table, _TILTED, 590.0, 0.0, 180.0) < 1e-13
    # The last hold 1e-8 rad off its target: the attitude differs there, no period.
    near = holds(_TILTED, [0.0, 45 * DEG] * 3, last_shift=1e-8)
    assert ScheduleHistory(near, _TILTED, 590.0).period() is None
    assert _attitude_mismatch(near, _TILTED, 590.0, 0.0, 180.0) > 4e-10
    # On a swinging vehicle the holds repeat with the least common multiple of the
    # table's 180 s and the swing's 120 s: 360 s (two periods need 720 s of the 770 s).
    swing = YawSwing(heading=0.3, pitch=2 * DEG, roll=-3 * DEG, amplitude=6 * DEG, period=120.0)
    table = holds(swing, [0.0, 45 * DEG] * 4)
    assert ScheduleHistory(table, swing, 770.0).period() == (0.0, 360.0)
    assert _attitude_mismatch(table, swing, 770.0, 0.0, 360.0) < 1e-13
    assert ScheduleHistory(table, swing, 719.0).period() is None
    # The catalogue rules: on a static base the nulling rule's stops all take the
    # minimum (300 s) and its turns go +, -, -, +: 4 (300 + 30) s. Heading isolation holds
    # the same headings for the same times. On the swing the nulling rule lengthens its
    # stops by the swing's phase and the flexible rule turns by what it measured: no
    # period, and none is claimed.
    dur = 4 * 3600.0
    for name, motion, expected in (
        ("nulling-two-position", _TILTED, (0.0, 1320.0)),
        ("heading-isolation", _TILTED, (0.0, 1320.0)),
        ("heading-isolation", SWING, (0.0, 1320.0)),
        ("nulling-two-position", SWING, None),
        ("flexible-two-position", SWING, None),
    ):
        table = build_scheme(name, 6 * DEG, 300.0).plan(motion, dur)
        found = ScheduleHistory(table, motion, dur).period()
        assert found == expected, name
        if found is not None:
            assert _attitude_mismatch(table, motion, dur, *found) < 1e-12, name


def test_history_period_needs_two_periods_and_a_commensurate_vehicle():
    # The "none" scheme repeats with the vehicle (its least period), or with an hour on a
    # static base; two-position (1320 s cycle) needs two cycles in the run (2640 s)
    # and a vehicle period commensurate with its cycle (100 sqrt 2 s is not).
    none = build_scheme("none", 6 * DEG, 300.0)
    assert ScheduleHistory(none.plan(SWING, 7200.0), SWING, 7200.0).period() == (0.0, 120.0)
    assert ScheduleHistory(none.plan(Motion(), 7200.0), Motion(), 7200.0).period() == (0.0, 3600.0)
    two = build_scheme("two-position", 6 * DEG, 300.0)
    for dur, expected in ((2640.0, (0.0, 1320.0)), (3300.0, (0.0, 1320.0)), (2639.0, None)):
        assert ScheduleHistory(two.plan(Motion(), dur), Motion(), dur).period() == expected
    odd = YawSwing(amplitude=6 * DEG, period=100.0 * math.sqrt(2.0))
    assert ScheduleHistory(two.plan(odd, 7200.0), odd, 7200.0).period() is None


def test_common_period_is_the_least_common_multiple_within_the_search():
    from inserr.schemes.composition import _common_period

    # p a = q b with the smallest p: 120 s and 240 s meet at 240 s (q = 1), 3 s and 7 s
    # at 21 s; periods equal to 1e-9 count as equal (1e-10 off still meets, relative
    # to p a); the search stops at p = 1000 (999 s and 1000 s meet at p = 1000, 1000 s and
    # 1001 s would need p = 1001).
    assert _common_period(120.0, 240.0) == 240.0
    assert _common_period(120.0 * (1 + 1e-11), 240.0) == pytest.approx(240.0, rel=1e-10)
    assert _common_period(3.0, 7.0 * (1 + 1e-10)) == 21.0
    assert _common_period(999.0, 1000.0) == 999000.0
    assert _common_period(1000.0, 1001.0) is None
    assert _common_period(1.0, math.sqrt(2.0)) is None


@pytest.mark.parametrize(
    "scheme", ["heading-isolation", "four-position-modified", "nulling-two-position"]
)
def test_static_schedule_equals_the_step_engine_on_its_timeline(scheme):
    # On a still vehicle the step engine on the schedule's timeline solves (nearly, see
    # below) the same problem as the fast engine on the schedule. The fast engine reads
    # the schedule's own pieces (an isolation hold on a still vehicle is a stop) and its
    # outputs on a 1 s grid fall at fractions of a second into windows that start off the
    # grid (the modified and nulling stops are not whole seconds): one delta per window.
    static = Motion(heading=30 * DEG, pitch=1 * DEG, roll=-2 * DEG)
    dur = 3600.0
    table = build_scheme(scheme, 6 * DEG, 137.3).plan(static, dur)
    hist = ScheduleHistory(table, static, dur)
    fast = analyze_drift(SITE, IMU, INIT, hist, dt_out=1.0, dt_cov=60.0)
    # An isolation turn on a tilted vehicle is not a constant-rate turn (a constant heading
    # rate needs a varying gimbal rate): its timeline sub-steps are O(h^2) off the motion,
    # 4e-7 at 1 s, 3e-8 at 0.25 s. The other pieces are exact on any timeline.
    exact = analyze_drift(SITE, IMU, INIT, build_timeline(table, static, dur, 0.25), dt_out=1.0,
                          dt_cov=60.0, engine="exact")  # fmt: skip
    # The step engine's expm of whole stops and turns is good to ~1e-13 per step (see
    # test_fast_equals_exact_on_the_same_timeline): 3e-7 of the smallest responses.
    assert _drift_difference(fast, exact) < 3e-7


@pytest.mark.parametrize(
    ("scheme", "motion", "dt_out", "paths"),
    [("two-position", SWING, 1.0, {"states-grid", "cached-aligned"}),
     ("two-position", SWING, 7.0, {"fine-each", "states-each", "cached-anywhere"}),
     ("nulling-two-position", SWING, 1.0, {"fine-grid", "cached-blocks", "partial-table"}),
     ("four-position", Motion(), 1.0, {"fine-grid", "rotation-products"}),
     ("four-position", Motion(), 7.0, {"fine-each", "states-each", "rotation-each"})],
)  # fmt: skip
def test_engine_takes_the_faster_paths_where_they_apply(scheme, motion, dt_out, paths):
    # The faster ways change only the work, so the numbers cannot show them: the engine
    # reports them. Where each must be taken: a periodic history (two-position: 4 (300
    # + 30) = 1320 s, 11 swings; the 1 s and 60 s grids divide it) is computed for one
    # period and copied (3 periods in the hour, the last one cut), unless the fine step
    # does not divide the period (7 s: 7 periods would be needed); stops on the periodic
    # swing reuse the vehicle part per phase, on a step that divides the swing period
    # and the coarse step, is a multiple of the fine step when it can be, and keeps a
    # window's phase within MAX_PHASE; outputs on a uniform grid are one product per
    # run shape (a run: a whole stop, or a whole turn with its harmonics); a static
    # base needs no sampled window at all (stops and turns in closed form).
    dur = 3600.0
    hist = ScheduleHistory(build_scheme(scheme, 6 * DEG, 300.0).plan(motion, dur), motion, dur)
    res = analyze_drift(SITE, IMU, INIT, hist, dt_out=dt_out, dt_cov=60.0)
    win, taken = res.engine["windows"], set(res.engine["paths"])
    assert paths <= taken, taken
    if scheme == "two-position" and dt_out == 1.0:
        assert win["lift_period"] == 1320.0 and win["periods"] == 3
    else:
        assert win["lift_period"] == 0.0 and win["periods"] == 0
    if motion is SWING:
        step = win["phase_step"]
        assert _is_whole(120.0 / step) and _is_whole(60.0 / step)
        assert _is_whole(step / dt_out) == (dt_out == 1.0)
        fastest = float(np.max(np.abs(NavModes(ErrorModel(SITE)).lam)))
        bandwidth = float(SWING.rate_bound(np.zeros(1), np.ones(1))[0])
        assert step * (2 * bandwidth + fastest) <= fp.MAX_PHASE
        assert win["cached"] > 0 and win["still"] == win["rotation"] == 0
    else:
        assert win["phase_step"] == 0.0 and win["cached"] == win["partial"] == 0
        assert win["direct"] == 0 and win["still"] > 0 and win["rotation"] > 0
        # One attitude evaluation per stop and per turn (closed forms; a stop cut by the
        # coarse grid into several windows holds one attitude, a turn's windows take its
        # harmonics from its start).
        stops = int(np.count_nonzero(hist.pieces().still))
        turns = len(hist.pieces().still) - stops
        assert 1 < stops < win["still"] and 1 < turns <= win["rotation"]
        assert res.engine["nodes"] == stops + turns
    if dt_out == 7.0:  # the step engine reports nothing
        still = Timeline.static(np.eye(3), 600.0)
        assert analyze_drift(SITE, IMU, INIT, still, dt_out=60.0, engine="exact").engine == {}
    # The paths agree with each other: the 1 s and 7 s outputs at their common times.
    if dt_out == 7.0:
        ones = analyze_drift(SITE, IMU, INIT, hist, dt_out=1.0, dt_cov=60.0)
        common = np.isin(ones.t, res.t)
        assert _relative(res.nav[np.isin(res.t, ones.t)], ones.nav[common]) < 1e-11


# 0.40013 rad/s puts 2 P (2 bandwidth + fastest) / MAX_PHASE just above 3: the budget
# then decides between 3 and 4 steps per period; a 3630 s coarse step (two coarse
# times) is divided only by every fourth step length.
@pytest.mark.parametrize("bandwidth", [0.05, 0.3, 0.40013, 1.2])
@pytest.mark.parametrize("dt_coarse, dt_fine", [(60.0, 1.0), (60.0, 7.0), (45.0, 1.0), (120.0, 1.0),
                                                (3630.0, 1.0), (60.0, None)])  # fmt: skip
def test_phase_step_is_the_longest_within_the_phase_budget_among_the_best_aligned(
    bandwidth, dt_coarse, dt_fine
):
    # The documented choice, checked as properties of the returned step g = P / m (P the
    # 120 s vehicle period): g keeps a window's phase (2 bandwidth + fastest mode) g
    # within MAX_PHASE; no step P / m' within the budget is better aligned (dividing the
    # coarse step counts first, being a multiple of the fine step second); none as well
    # aligned is longer. Pieces without phase classes, without a vehicle period, or with
    # nothing cacheable (all still or constant-rate) get no step.
    from inserr.model.attitude_history import Pieces

    period, fastest = 120.0, 1.24e-3
    n = 4
    pieces = Pieces(np.arange(n + 1) * 30.0, np.full(n, bandwidth), np.zeros(n, bool),
                    np.full((n, 3, 3), np.nan), period, None, np.zeros(n, int))  # fmt: skip
    t_coarse = np.arange(0.0, 3600.0 + dt_coarse / 2, dt_coarse)
    g = fp.phase_step(pieces, t_coarse, dt_fine, fastest)
    m = round(period / g)
    assert _is_whole(period / g) and m >= 1
    rate = 2 * bandwidth + fastest
    assert g * rate <= fp.MAX_PHASE

    def score(step):
        fine = dt_fine is not None and _is_whole(step / dt_fine) and step >= dt_fine
        return 2 * int(_is_whole(dt_coarse / step)) + int(fine)

    for m2 in range(1, m + 400):
        g2 = period / m2
        if g2 * rate <= fp.MAX_PHASE:
            assert score(g2) < score(g) or (score(g2) == score(g) and g2 <= g), (m2, g2)
    for change in ({"phase_class": None}, {"vehicle_period": None},
                   {"still": np.ones(n, bool)}, {"constant": np.ones(n, bool)}):  # fmt: skip
        other = dataclasses.replace(pieces, **change)
        assert fp.phase_step(other, t_coarse, dt_fine, fastest) is None


def test_grid_step_recognises_uniform_grids_from_zero():
    # 0, h, 2h, ... with a shorter last step is a grid of step h; anything else is not.
    assert fp._grid_step(np.array([0.0, 1.0, 2.0, 3.0])) == 1.0
    assert fp._grid_step(np.array([0.0, 1.0, 2.0, 2.5])) == 1.0
    assert fp._grid_step(np.array([0.0, 60.0])) == 60.0
    assert fp._grid_step(np.array([0.0, 1.0, 1.5])) == 1.0
    for t in ([0.0], [1.0, 2.0, 3.0], [0.0, 1.0, 2.5, 3.0], [0.0, 1.0, 2.0, 3.5, 4.0],
              [0.0, 1.0, 2.000001, 3.0], [0.0, 1.0, 2.0 + 5e-9, 3.0]):  # fmt: skip
        assert fp._grid_step(np.array(t)) is None, t


@pytest.mark.parametrize(
    ("t0_steps", "period_steps", "count"),
    [(0, 22, 4321), (3, 7, 3 + 2 * 7 + 1), (5, 4, 5 + 2 * 4), (1, 6, 1 + 9 * 6 + 5), (0, 1, 500)],
)
@pytest.mark.parametrize("zero_mode", [False, True])
def test_lifted_coarse_states_equal_the_scan(t0_steps, period_steps, count, zero_mode):
    # Inputs that repeat every period after t0 (anything before it): the per-period
    # recurrence must give the scan's states, whole periods, a cut last one, t0 > 0.
    # Both are the same sums in another order: round-off of the largest state (1e-13).
    # With a mode at lambda = 0 the geometric sum of the period starts is k itself.
    rng = np.random.default_rng(t0_steps + count)
    lam = NavModes(ErrorModel(SITE, Layout(bias=False))).lam
    if zero_mode:
        lam = np.append(lam, 0.0)
    h = 60.0
    t = np.arange(count) * h
    shape = (len(lam), 5)

    def noise(*lead):
        return rng.normal(size=lead + shape) + 1j * rng.normal(size=lead + shape)

    one = noise(period_steps)
    reps = -(-(count - 1 - t0_steps) // period_steps)
    inputs = np.concatenate([noise(1 + t0_steps), np.tile(one, (reps, 1, 1))])[:count]
    z0 = noise()
    want = np.concatenate([z0[None], fp.scan(lam, 0.0, z0, t[1:], inputs[1:])])
    got = np.empty_like(want)
    got[0] = z0
    fp._lifted_coarse(lam, t, inputs, (t0_steps * h, period_steps * h), got)
    assert np.abs(got - want).max() <= 1e-13 * np.abs(want).max()


def test_lifting_needs_two_whole_periods_after_the_start():
    # Two-position on the swing repeats every 1320 s: lifted from exactly two periods
    # on. A static table whose 140 s cycle starts after a 60 s stop repeats from 60 s;
    # both grids (1 s, 60 s) divide 3 cycles, 420 s, so the run needs 60 + 2 x 420 s.
    from inserr.schemes.turntable import ScheduleBuilder

    two = build_scheme("two-position", 6 * DEG, 300.0)
    for dur, expected in ((2640.0, (0.0, 1320.0)), (2580.0, None)):
        hist = ScheduleHistory(two.plan(SWING, dur), SWING, dur)
        assert fp._lifting(hist, output_grid(dur, 1.0), output_grid(dur, 60.0)) == expected
    b = ScheduleBuilder()
    b.stop(60.0)
    table = _cycles(b, 7).build(cycle=140.0)
    for dur, expected in ((900.0, (60.0, 420.0)), (840.0, None)):
        hist = ScheduleHistory(table, Motion(), dur)
        assert hist.period() == (60.0, 140.0)
        assert fp._lifting(hist, output_grid(dur, 1.0), output_grid(dur, 60.0)) == expected
    # Outputs that are not a uniform grid do not recur period after period: no lifting.
    irregular = np.concatenate([[0.0, 0.5], np.arange(1.0, 901.0)])
    hist = ScheduleHistory(table, Motion(), 900.0)
    assert fp._lifting(hist, irregular, output_grid(900.0, 60.0)) is None
    assert fp._lifting(hist, output_grid(900.0, 1.0), irregular) is None


def test_drift_analysis_defaults_are_one_second_outputs_one_minute_budget_one_second_steps():
    # Documented defaults: dt_out 1 s, dt_cov 60 s, and the step engine cuts continuous
    # motion into 1 s sub-steps (the same numbers as asking for 1 s).
    dur = 600.0
    hist = ScheduleHistory(build_scheme("two-position", 6 * DEG, 120.0).plan(SWING, dur), SWING,
                           dur)  # fmt: skip
    res = analyze_drift(SITE, IMU, INIT, hist)
    assert np.array_equal(res.t, np.arange(0.0, dur + 0.5, 1.0))
    assert np.array_equal(res.t_cov, np.arange(0.0, dur + 30.0, 60.0))
    kw = dict(dt_out=60.0, engine="exact")
    assert np.array_equal(analyze_drift(SITE, IMU, INIT, hist, **kw).nav,
                          analyze_drift(SITE, IMU, INIT, hist, substep=1.0, **kw).nav)  # fmt: skip


def _is_whole(x: float) -> bool:
    return abs(x - round(x)) < 1e-9


def test_fine_blocks_cover_the_outputs_and_depend_on_their_count_only():
    for n in (0, 1, 7, fp.SPLIT_FINE, fp.SPLIT_FINE + 1, 259_201, 2_592_001):
        blocks = fp._blocks(n)
        edges = [lo for lo, _ in blocks] + [blocks[-1][1]] if blocks else [0]
        assert edges[0] == 0 and edges[-1] == n
        assert all(hi > lo for lo, hi in blocks)
        assert all(b[1] == c[0] for b, c in zip(blocks[:-1], blocks[1:], strict=True))
        assert all(hi - lo <= fp.CHUNK_FINE for lo, hi in blocks)
        assert len(blocks) >= (2 if n > fp.SPLIT_FINE else min(n, 1))


def test_engine_threads_follow_the_environment(monkeypatch):
    for var in ("INSERR_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setenv("INSERR_THREADS", "1")
    assert fp.engine_threads() == 1
    monkeypatch.delenv("INSERR_THREADS")
    monkeypatch.setenv("OMP_NUM_THREADS", "1")  # a sweep worker: parallel across points
    assert fp.engine_threads() == 1
    monkeypatch.setenv("INSERR_THREADS", "2")  # an explicit choice wins
    assert fp.engine_threads() == 2


@pytest.mark.parametrize(
    "scheme", ["nulling-two-position", "flexible-two-position", "two-position"]
)
def test_results_do_not_depend_on_the_thread_count(monkeypatch, scheme):
    """The fine outputs go in blocks that depend on their count only, computed on one
    thread or two, the phase-template and sampled windows side by side, and the noise
    alongside the constant errors: bit-for-bit the same numbers either way (closed-loop
    schedules on the swing, and a periodic one, whose periods are lifted). 15 h at 1 s:
    more outputs than one block takes."""
    duration = 15 * 3600.0
    history = ScheduleHistory(build_scheme(scheme, 6 * DEG, 300.0).plan(SWING, duration), SWING,
                              duration)  # fmt: skip
    # With white noise too (computed alongside the constant errors).
    imu = dataclasses.replace(IMU, arw=0.002 * DEG_PER_SQRT_HOUR, vrw=5e-5)
    runs = {}
    for threads in ("1", "2"):
        monkeypatch.setenv("INSERR_THREADS", threads)
        runs[threads] = analyze_drift(SITE, imu, INIT, history, dt_out=1.0, dt_cov=60.0)
    one, two = runs["1"], runs["2"]
    assert len(one.t) > fp.SPLIT_FINE and set(one.noise_cov) == {"arw", "vrw"}
    if scheme != "two-position":  # both window stages ran, side by side on two threads
        assert one.engine["windows"]["cached"] > 0 and one.engine["windows"]["direct"] > 0
    for name in ("nav", "attitude", "source_horizontal", "source_heading"):
        assert np.array_equal(getattr(one, name), getattr(two, name)), name
    assert one.noise_cov.keys() == two.noise_cov.keys()
    for k in one.noise_cov:
        assert np.array_equal(one.noise_cov[k], two.noise_cov[k]), k


def test_white_noise_covariance_kept_for_reuse_is_a_fresh_copy_each_time():
    """A sweep's points share the white-noise covariance (same site, noise, grid): the
    kept one must equal a new computation, and a caller changing its copy must not
    change what the next caller gets."""
    model = ErrorModel(SITE, Layout(bias=False))
    t = output_grid(6 * 3600.0, 60.0)
    first = fp.white_noise_covariance(model, 1e-6, 2e-5, t)
    first[:] = np.nan  # a caller scribbling on its result
    second = fp.white_noise_covariance(model, 1e-6, 2e-5, t)
    fp._WHITE_CACHE.clear()
    fresh = fp.white_noise_covariance(model, 1e-6, 2e-5, t)
    assert np.array_equal(second, fresh) and np.all(np.isfinite(second))
    # Another density is another covariance (the key includes it): P is linear in the
    # PSD, so doubling it doubles P (to round-off of the largest entry: 1e-12 of it).
    double = fp.white_noise_covariance(model, np.sqrt(2) * 1e-6, 0.0, t)
    alone = fp.white_noise_covariance(model, 1e-6, 0.0, t)
    np.testing.assert_allclose(double, 2 * alone, rtol=0, atol=1e-12 * np.abs(alone).max())


def test_scan_in_several_blocks_equals_the_recurrence():
    # Modes that grow or decay fast (|Re lambda| t far beyond SCAN_SPAN) make the scan
    # restart its blocks many times; each state must still be the plain recurrence
    # z_k = e^{lambda (t_k - t_{k-1})} z_{k-1} + incr_k (computed here step by step).
    rng = np.random.default_rng(5)
    lam = np.array([-3.0, 0.3 + 0.2j, -0.01 + 1j, 0.0])
    t = np.cumsum(rng.uniform(0.5, 3.0, 400))  # ~700 s: |Re lambda| t up to 2000
    incr = rng.normal(size=(400, 4, 2)) + 1j * rng.normal(size=(400, 4, 2))
    z0 = rng.normal(size=(4, 2)) + 0j
    got = fp.scan(lam, 0.0, z0, t, incr)
    want, z, tz = np.empty_like(incr), z0, 0.0
    for k in range(len(t)):
        z = np.exp(lam * (t[k] - tz))[:, None] * z + incr[k]
        want[k], tz = z, t[k]
    # Relative to each mode's own size (one grows by e^210): round-off of ~400 steps.
    scale = np.abs(want).max(axis=(0, 2))
    assert np.all(np.abs(got - want).max(axis=(0, 2)) <= 1e-12 * scale)
    assert 3.0 * t[-1] > 5 * fp.SCAN_SPAN  # several blocks indeed


def test_group_sum_adds_rows_of_equal_keys_in_any_order():
    v = np.arange(12.0).reshape(6, 2)
    for keys in ([3, 1, 3, 0, 1, 3], [0, 0, 1, 3, 3, 3], [0, 1, 2, 4, 5, 7]):
        keys = np.array(keys)
        got_k, got_v = fp._group_sum(keys, v)
        want_k = np.unique(keys)
        want_v = np.array([v[keys == k].sum(axis=0) for k in want_k])
        assert np.array_equal(got_k, want_k) and np.array_equal(got_v, want_v)
    one_k, one_v = fp._group_sum(np.array([4]), v[:1])
    assert np.array_equal(one_k, [4]) and np.array_equal(one_v, v[:1])


def test_group_sum_of_mostly_single_rows_is_reduceat_to_the_bit():
    # Sorted keys where most groups are one row (a stop cut by the coarse grid): pairs
    # are added directly and longer groups by reduceat on their own. The sums must be
    # reduceat's over all groups, to the last bit (the engine promises results that do
    # not depend on the path), whichever group comes last.
    rng = np.random.default_rng(11)
    fixed = [
        [0, 1, 2, 3, 4, 5, 6, 7, 8, 8, 8],
        [0, 1, 2, 3, 4, 5, 6, 7, 8, 8],
        [0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8],
        [0, 1, 1, 1, 2, 3, 4, 5, 5, 6, 7, 8, 9],
    ]
    drawn = []
    for trial in range(60):
        n = int(rng.integers(4, 300))
        # Mostly single rows: a few repeats among distinct sorted keys.
        keys = np.sort(np.concatenate([np.arange(n), rng.integers(0, n, int(n * 0.15))]))
        tail = [[], [n] * 2, [n] * 3][trial % 3]  # ends with a single, a pair, a long group
        drawn.append(np.concatenate([keys, tail]).astype(int))
    for keys in [np.array(k) for k in fixed] + drawn:
        start = np.flatnonzero(np.concatenate([[True], keys[1:] != keys[:-1]]))
        assert 4 * len(start) >= 3 * len(keys)  # the path for mostly single rows
        v = rng.normal(size=(len(keys), 2, 3)) + 1j * rng.normal(size=(len(keys), 2, 3))
        got_k, got_v = fp._group_sum(keys, v)
        assert np.array_equal(got_k, keys[start])
        assert np.array_equal(got_v, np.add.reduceat(v, start, axis=0))


def test_vehicle_to_imu_for_one_table_is_the_batched_transform():
    # One table (2-D M) as a batch of one, and both against the features of C_b^n M
    # computed directly (C, C w^s, C f^s with w^s = M^T w^b, f^s = M^T f^b).
    rng = np.random.default_rng(9)
    c_bn = Rotation.random(5, random_state=2).as_matrix()
    w_b, f_b = rng.normal(size=(5, 3)), rng.normal(size=(5, 3))
    m = Rotation.random(random_state=3).as_matrix()
    y = fp._features(c_bn, w_b, f_b)  # (5, 63) vehicle features
    direct = fp._features(c_bn @ m, w_b @ m, f_b @ m)
    one = fp.vehicle_to_imu(y, m)
    assert one.shape == y.shape
    np.testing.assert_allclose(one, direct, rtol=0, atol=1e-14)
    batched = fp.vehicle_to_imu(y[None], m[None])[0]
    np.testing.assert_allclose(batched, one, rtol=0, atol=1e-15)


def test_white_noise_leaves_a_clamped_vertical_channel_still():
    # With the vertical channel clamped, neither VRW nor anything else moves dv_U or dr_U:
    # their variances and covariances stay exactly 0; free, VRW makes dv_U grow as VRW^2 t.
    arw, vrw = 0.001 * DEG / 60.0, 10 * MICRO_G
    t = output_grid(3600.0, 60.0)
    clamped = fp.white_noise_covariance(ErrorModel(SITE, Layout(bias=False)), arw, vrw, t)
    assert np.all(clamped[:, 5, :] == 0.0) and np.all(clamped[:, :, 8] == 0.0)
    assert np.all(clamped[1:, 3, 3] > 0.0)  # the horizontal channels do move
    free = fp.white_noise_covariance(
        ErrorModel(SITE, Layout(bias=False), vertical="free"), arw, vrw, t
    )
    # Free, dv_U' = k dr_U + w with k = 2 g / R: P_vv = VRW^2 t (1 + k t^2 / 3 + O((k t^2)^2));
    # after 60 s k t^2 = 0.011, so the next term is ~1e-5 of it: 1e-4 allows for it.
    k = 2.0 * SITE.g / SITE.mean_radius
    assert free[1, 5, 5] == pytest.approx(vrw**2 * 60.0 * (1 + k * 60.0**2 / 3), rel=1e-4)


def test_sampled_windows_in_many_chunks_equal_one_chunk(monkeypatch):
    # The turns on the swing are sampled in chunks of CHUNK_NODES nodes (memory); cut
    # into chunks of ~300 nodes, every output must be the same sums (to round-off).
    dur = 3600.0
    hist = ScheduleHistory(
        build_scheme("flexible-two-position", 6 * DEG, 300.0).plan(SWING, dur), SWING, dur
    )
    one = analyze_drift(SITE, IMU, INIT, hist, dt_out=1.0, dt_cov=60.0)
    assert one.engine["windows"]["direct"] >= 10  # the turns of the first hour
    monkeypatch.setattr(fp, "CHUNK_NODES", 300)
    many = analyze_drift(SITE, IMU, INIT, hist, dt_out=1.0, dt_cov=60.0)
    assert _drift_difference(many, one) < 1e-12


def test_window_of_is_the_first_window_end_at_or_after_each_output():
    # Outputs exactly at window ends, within MERGE of them, between them and past the
    # last one: the index found by placing the ends among the outputs is searchsorted's.
    rng = np.random.default_rng(11)
    b = np.cumsum(rng.uniform(0.5, 70.0, 300))
    t = np.sort(np.concatenate([
        rng.uniform(0.0, b[-1] + 50.0, 4000), b[::3], b[1::7] + 0.5 * fp.MERGE,
        b[2::5] + 2.0 * fp.MERGE, [0.0, b[-1] + 10.0],
    ]))  # fmt: skip
    want = np.searchsorted(b, t - fp.MERGE, side="left").clip(0, len(b) - 1)
    assert np.array_equal(fp._window_of(b, t), want)
    assert np.array_equal(fp._window_of(b, t[:0]), want[:0])


def test_interval_sums_add_each_terms_input_into_its_interval():
    # S[j] = sum over the terms m of interval j of coef[m, r] per[col[m], r, :], with
    # repeated (interval, column) pairs, unsorted terms and columns never used.
    rng = np.random.default_rng(12)
    m, n_r, n_src, n_col = 500, 4, 7, 9
    j = rng.integers(3, 60, m)
    col = rng.integers(0, n_col - 2, m)
    coef = rng.normal(size=(m, n_r)) + 1j * rng.normal(size=(m, n_r))
    per = rng.normal(size=(n_col, n_r, n_src)) + 1j * rng.normal(size=(n_col, n_r, n_src))
    jj, sums = fp._interval_sums(j, col, coef, per)
    assert np.array_equal(jj, np.unique(j))
    want = np.zeros((len(jj), n_r, n_src), dtype=complex)
    for k in range(m):
        want[np.searchsorted(jj, j[k])] += coef[k][:, None] * per[col[k]]
    assert np.abs(sums - want).max() <= 1e-13 * np.abs(want).max()
    target = np.zeros((80, n_r, n_src), dtype=complex)
    fp._add_rows(target, jj, sums)  # not consecutive: a scatter
    fp._add_rows(target, np.arange(5, 8), np.ones((3, n_r, n_src)))  # consecutive: a slice
    want_t = np.zeros_like(target)
    want_t[jj] += sums
    want_t[5:8] += 1.0
    assert np.array_equal(target, want_t)


@pytest.mark.parametrize("scheme", ["four-position-modified", "flexible-two-position"])
def test_static_runs_of_whole_stops_and_turns_equal_the_per_output_path(monkeypatch, scheme):
    # On a static base the 1 s outputs are computed per run (a whole stop, or a whole
    # turn from its harmonics, however the coarse grid cuts it; neither scheme's stops
    # are whole seconds, so every run starts a fraction of a second off the grid), and
    # stops and turns that recur share their features (to 1e-12). Both are checked here
    # against paths that use neither: the 7 s outputs (each output's state from its own
    # window) at the common times, and a run with every stop and turn evaluated on its
    # own. The per-source responses are also checked against the signed run they add
    # up to (superposition: one path sums sources' inputs, the other the signed input).
    static = Motion(heading=30 * DEG, pitch=1 * DEG, roll=-2 * DEG)
    dur = 4 * 3600.0
    hist = ScheduleHistory(build_scheme(scheme, 6 * DEG, 300.0).plan(static, dur), static, dur)
    res = analyze_drift(SITE, IMU, INIT, hist, dt_out=1.0, dt_cov=60.0)
    assert {"fine-grid", "rotation-products"} <= set(res.engine["paths"])
    sevens = analyze_drift(SITE, IMU, INIT, hist, dt_out=7.0, dt_cov=60.0)
    assert "fine-each" in sevens.engine["paths"]
    common = np.isin(res.t, sevens.t)
    # Round-off of the products and of the phases e^{i k theta0} (angles of ~1e3 rad).
    assert _relative(res.nav[common], sevens.nav[np.isin(sevens.t, res.t)]) < 1e-11
    monkeypatch.setattr(fp, "_distinct", lambda c, w: (np.arange(len(c)), np.arange(len(c))))
    alone = analyze_drift(SITE, IMU, INIT, hist, dt_out=1.0, dt_cov=60.0)
    assert _relative(res.nav, alone.nav) < 1e-11
    n = len(res.t_cov)
    h_a, h_b = res.source_horizontal.reshape(n, -1), alone.source_horizontal.reshape(n, -1)
    assert _relative(h_a, h_b) < 1e-11
    at_cov = np.isin(res.t, res.t_cov)
    signed = res.source_horizontal.sum(axis=1)  # values are signed: the sum is the run
    assert _relative(signed, res.nav[at_cov][:, 6:8]) < 1e-11


def test_derived_curves_made_with_the_result_are_its_own_to_the_bit():
    # The analysis computes the derived curves on two threads while it makes the result
    # (the worst case over unknown signs split between them by rows) and keeps them as
    # the result's cached properties: they must be exactly what the properties compute.
    static = Motion(heading=30 * DEG, pitch=1 * DEG, roll=-2 * DEG)
    dur = 2 * 3600.0
    hist = ScheduleHistory(build_scheme("four-position-modified", 6 * DEG, 300.0).plan(static, dur),
                           static, dur)  # fmt: skip
    res = analyze_drift(SITE, IMU, INIT, hist, dt_out=1.0, dt_cov=60.0)
    fresh = dataclasses.replace(res)  # a new result: its properties computed on first use
    for name in ("horizontal", "rms_horizontal", "worst_horizontal", "finite", "attitude_extent"):
        assert name in vars(res) and name not in vars(fresh)
        assert np.array_equal(getattr(res, name), getattr(fresh, name)), name
    assert res.finite is True


@pytest.mark.parametrize("case", ["steady-turn", "long-timeline-turn"])
def test_long_turns_keep_their_exact_rate_in_runs(case):
    # A run of a turn spans the whole piece (cut every RUN_OUTPUTS outputs): its tables
    # must use the turn's exact rate, or a phase error grows with the run (a rate
    # rounded to 1e-12 rad/s gave 1e-9 of the response after 24 h of a steady turn). The
    # 1 s outputs (runs, products) against the 7 s ones (each from its own window).
    rate = 0.01234567891234567  # rad/s, no round number of 1e-12 rad/s
    if case == "steady-turn":
        motion = Turn(rate=rate, pitch=1 * DEG, roll=-2 * DEG)
        dur = 24 * 3600.0
        hist = ScheduleHistory(build_scheme("none", 6 * DEG, 300.0).plan(motion, dur), motion, dur)
    else:
        dur = 20 * 3600.0
        c0 = Rotation.from_euler("zyx", [0.3, 0.01, -0.02]).as_matrix()
        c1 = Rotation.from_euler("z", rate * dur).as_matrix() @ c0
        hist = Timeline(np.array([0.0, dur]), np.stack([c0, c1]), np.array([[0.0, 0.0, rate]]))
    ones = analyze_drift(SITE, IMU, INIT, hist, dt_out=1.0, dt_cov=60.0)
    sevens = analyze_drift(SITE, IMU, INIT, hist, dt_out=7.0, dt_cov=60.0)
    assert "rotation-products" in ones.engine["paths"]
    common, back = np.isin(ones.t, sevens.t), np.isin(sevens.t, ones.t)
    # Round-off of the products and tables: 1e-14 of the response seen; 1e-11 is a
    # wide bound that the rounded rate failed by two orders.
    assert _relative(ones.nav[common], sevens.nav[back]) < 1e-11
    assert _relative(ones.attitude[common], sevens.attitude[back]) < 1e-11


def test_runs_cut_anywhere_give_the_same_outputs(monkeypatch):
    # Runs are cut every RUN_OUTPUTS outputs (bounding the products' tables): the
    # outputs must not depend on where, here cut every 37 outputs instead of 4096.
    static = Motion(heading=30 * DEG, pitch=1 * DEG, roll=-2 * DEG)
    dur = 3 * 3600.0
    cases = [ScheduleHistory(build_scheme("four-position-modified", 6 * DEG, 300.0)
                             .plan(static, dur), static, dur)]  # fmt: skip
    turn = Turn(rate=0.0123, pitch=1 * DEG, roll=-2 * DEG)
    cases.append(ScheduleHistory(build_scheme("none", 6 * DEG, 300.0).plan(turn, dur), turn, dur))
    for hist in cases:
        whole = analyze_drift(SITE, IMU, INIT, hist, dt_out=1.0, dt_cov=60.0)
        with monkeypatch.context() as m:
            m.setattr(fp, "RUN_OUTPUTS", 37)
            cut = analyze_drift(SITE, IMU, INIT, hist, dt_out=1.0, dt_cov=60.0)
        assert _relative(whole.nav, cut.nav) < 1e-12
        assert _relative(whole.attitude, cut.attitude) < 1e-12
