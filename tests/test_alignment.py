"""Tests of the alignment filter and its figures of merit (issue #5).

Independent truth used here: the classic static-alignment limits written from first
principles (tilt = accelerometer bias / g, heading = east gyro bias / (Omega cos L)),
the batch information form of a Kalman filter without process noise (covariance
from the sum of H Phi(t_k) rows, computed here with scipy's expm), the Joseph
update formula, closed-form sigma curves for the convergence time, and a seeded
Monte Carlo for filter consistency (chi-square bounds).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter
from scipy.linalg import expm
from scipy.stats import chi2

from inserr.alignment.filter import (
    STATES,
    Prior,
    Settings,
    convergence_time,
    normalized_eigen,
    observability_degree,
    run_alignment,
)
from inserr.alignment.study import Base, alignment_timeline
from inserr.cli.main import main
from inserr.core import earth
from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.core.imu import ImuErrors
from inserr.core.units import (
    ARCMIN,
    ARCSEC,
    DEG,
    DEG_PER_HOUR,
    DEG_PER_SQRT_HOUR,
    MICRO_G,
    MICRO_G_PER_SQRT_HZ,
)
from inserr.model.psi_model import ErrorModel, Layout
from inserr.model.timeline import Timeline
from inserr.schemes.vehicle_motion import Motion, YawSwing

LAT = 34.0 * DEG
SITE = Site(LAT)
GYRO = 0.003 * DEG_PER_HOUR
ACCEL = 30 * MICRO_G
P0_IMU = ImuErrors(
    gyro_bias=np.full(3, GYRO),
    accel_bias=np.full(3, ACCEL),
    arw=0.0005 * DEG_PER_SQRT_HOUR,
    vrw=5 * MICRO_G_PER_SQRT_HZ,
)
I = {s: i for i, s in enumerate(STATES)}


def _run(scheme, minutes, imu, lat=LAT, stop=60.0, motion=None, attitude=None, **kw):
    site = Site(lat)
    base = Base(site, motion or Motion(), 6 * DEG, stop)
    tl = alignment_timeline(base, scheme, minutes * 60.0)
    prior = Prior(gyro_bias=imu.gyro_bias, accel_bias=imu.accel_bias)
    if attitude is not None:
        prior = Prior(attitude=attitude, gyro_bias=imu.gyro_bias, accel_bias=imu.accel_bias)
    return run_alignment(site, tl, imu, prior, kw.pop("settings", Settings()), **kw)


# --- filterpy ---------------------------------------------------------------------------------


def test_filterpy_update_is_the_joseph_form_and_needs_column_measurements():
    rng = np.random.default_rng(3)
    n, m = 4, 2
    a = rng.normal(size=(n, n))
    p = a @ a.T + np.eye(n)
    h = rng.normal(size=(m, n))
    r = np.diag([0.3, 0.7])
    z = rng.normal(size=(m, 1))
    kf = KalmanFilter(dim_x=n, dim_z=m)
    kf.x = np.zeros((n, 1))
    kf.P = p.copy()
    kf.update(z, R=r, H=h)
    k = p @ h.T @ np.linalg.inv(h @ p @ h.T + r)
    ikh = np.eye(n) - k @ h
    np.testing.assert_allclose(kf.P, ikh @ p @ ikh.T + k @ r @ k.T, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(kf.x, k @ z, rtol=1e-12, atol=1e-12)
    # The trap: with H given, a 1-D z is not reshaped and the residual broadcasts.
    kf2 = KalmanFilter(dim_x=n, dim_z=m)
    kf2.x = np.zeros((n, 1))
    kf2.P = p.copy()
    kf2.update(z[:, 0], R=r, H=h)
    assert kf2.y.shape == (m, m)


# --- the filter against independent results ---------------------------------------------------


def test_covariance_equals_the_batch_information_form():
    """Without process noise the filter's covariance is the batch least-squares one."""
    duration, rate, sigma_v = 120.0, 1.0, 1e-3
    site = SITE
    tl = Timeline.static(np.eye(3), duration)
    prior = Prior(position=5.0)
    imu = ImuErrors(gyro_bias=np.full(3, GYRO), accel_bias=np.full(3, ACCEL))
    res = run_alignment(site, tl, imu, prior, Settings(zupt_rate=rate, zupt_sigma=sigma_v))
    # Hand-built map from reported states (phi, dv, dr, b_g, b_a) to the model state
    # (psi = phi - dtheta(dr), biases resolved in n = IMU frame here).
    m0 = np.eye(15)
    m0[0, 7] = -1.0 / site.r_m  # dtheta_E = -dr_N / R_M
    m0[1, 6] = 1.0 / site.r_n  # dtheta_N = dr_E / R_N
    m0[2, 6] = math.tan(LAT) / site.r_n
    to_model = np.linalg.inv(m0)
    p0 = to_model @ np.diag(prior.sigma() ** 2) @ to_model.T
    a = ErrorModel(site, Layout(bias=True), vertical="free").matrix()
    h = np.zeros((3, 15))
    h[0, 3] = h[1, 4] = h[2, 5] = 1.0
    info = np.linalg.inv(p0)
    for k in range(1, int(duration * rate) + 1):
        hk = h @ expm(a * k / rate)
        info += hk.T @ hk / sigma_v**2
    phi_t = expm(a * duration)
    p_model = phi_t @ np.linalg.inv(info) @ phi_t.T
    p_rep = m0 @ p_model @ m0.T
    sig = np.sqrt(np.diag(p_rep))
    np.testing.assert_allclose(res.final_sigma, sig, rtol=1e-6)


@pytest.mark.parametrize(
    ("lat_deg", "gyro_deg_h", "accel_ug"), [(34.0, 0.003, 30.0), (60.0, 0.01, 100.0)]
)
def test_static_alignment_reaches_the_classic_floors(lat_deg, gyro_deg_h, accel_ug):
    """Tilt -> nabla / g, heading -> eps_E / (Omega cos L), within 3 %.

    The attitude prior is diffuse (1 deg tilt, 10 deg heading: the model is linear, so
    this is only a covariance) and moves the floors by < 0.05 %. The 3 % allow for
    what the textbook formulas leave out: the north gyro bias adds Omega sin L x (tilt
    sigma) to the heading relation (+0.85 % at 60 deg, 100 micro-g), and the runs are
    long enough (20 min, many heading time constants) for the rest to have converged.
    """
    lat = lat_deg * DEG
    imu = ImuErrors(
        gyro_bias=np.full(3, gyro_deg_h * DEG_PER_HOUR), accel_bias=np.full(3, accel_ug * MICRO_G)
    )
    res = _run("none", 20.0, imu, lat=lat, attitude=np.array([1.0, 1.0, 10.0]) * DEG)
    g = earth.gravity(lat)
    tilt = accel_ug * MICRO_G / g
    heading = gyro_deg_h * DEG_PER_HOUR / (earth.OMEGA_IE * math.cos(lat))
    s = res.final_sigma
    assert s[I["phi_e"]] == pytest.approx(tilt, rel=0.03)
    assert s[I["phi_n"]] == pytest.approx(tilt, rel=0.03)
    assert s[I["phi_u"]] == pytest.approx(heading, rel=0.03)
    # What cannot be seen is not estimated: horizontal accelerometer biases and the
    # east (x) gyro bias keep their prior.
    deg = res.observability_degree()
    for name in ("accel_bias_x", "accel_bias_y", "gyro_bias_x"):
        assert deg[I[name]] < 1.05


def test_two_position_beats_the_static_heading_floor_and_sees_the_accel_biases():
    static = _run("none", 10.0, P0_IMU)
    two = _run("two-position", 10.0, P0_IMU, stop=60.0)
    floor = GYRO / (earth.OMEGA_IE * math.cos(LAT))
    assert static.final_sigma[I["phi_u"]] > 0.95 * floor
    assert two.final_sigma[I["phi_u"]] < 0.5 * floor
    for name in ("accel_bias_x", "accel_bias_y"):
        assert static.final_sigma[I[name]] > 0.95 * ACCEL
        assert two.final_sigma[I[name]] < 0.1 * ACCEL
    # Tilt is no longer tied to the accelerometer bias either.
    assert two.final_sigma[I["phi_e"]] < 0.2 * ACCEL / SITE.g


def test_swinging_base_modulates_the_biases_too():
    """P0's yaw swing (6 deg/s peak, 120 s period) turns the IMU by +-115 deg.

    That modulates the horizontal biases like indexing does: heading beats the static floor.
    """
    swing = YawSwing(15 * DEG, 0.0, 0.0, amplitude=6 * DEG, period=120.0)
    res = _run("none", 5.0, P0_IMU, motion=swing)
    floor = GYRO / (earth.OMEGA_IE * math.cos(LAT))
    assert res.final_sigma[I["phi_u"]] < 0.8 * floor


def test_filter_is_consistent_over_a_seeded_monte_carlo():
    """Normalised estimation error squared of attitude and biases ~ chi-square."""
    n_runs = 12
    rng = np.random.default_rng(11)
    prior = Prior(gyro_bias=np.full(3, GYRO), accel_bias=np.full(3, ACCEL))
    base = Base(SITE, Motion(), 6 * DEG, 30.0)
    tl = alignment_timeline(base, "two-position", 180.0)
    shown = [I[s] for s in STATES if s.startswith(("phi", "gyro", "accel"))]
    total = 0.0
    for k in range(n_runs):
        truth0 = prior.sigma() * rng.standard_normal(15)
        res = run_alignment(SITE, tl, P0_IMU, prior, Settings(seed=100 + k), truth0=truth0)
        e = (res.estimate[-1] - res.truth[-1])[shown]
        p = res.p_final[np.ix_(shown, shown)]
        total += float(e @ np.linalg.solve(p, e))
    dof = n_runs * len(shown)
    assert chi2.ppf(0.001, dof) < total < chi2.ppf(0.999, dof)


# --- figures of merit ---------------------------------------------------------------------------


def test_convergence_time_of_an_exponential_sigma():
    t = np.arange(0.0, 601.0)
    s0, sf, tau = 10.0, 1.0, 50.0
    sigma = (sf + (s0 - sf) * np.exp(-t / tau))[:, None]
    # sigma <= 1.1 sf once (s0 - sf) exp(-t/tau) <= 0.1 sf. The final value is
    # sf + 9 exp(-12) instead of sf, which moves the answer by far less than a step.
    expected = tau * math.log((s0 - sf) / (0.1 * sf))
    assert convergence_time(t, sigma)[0] == pytest.approx(expected, abs=1.0)


def test_convergence_time_is_nan_for_an_unestimated_state_and_uses_the_last_exit():
    t = np.arange(5.0)
    flat = np.array([1.0, 1.0, 0.99, 0.98, 0.97])  # fell by 3 %: not estimated
    bumpy = np.array([10.0, 1.0, 3.0, 1.05, 1.0])  # back above 1.1 at t = 2
    out = convergence_time(t, np.column_stack([flat, bumpy]))
    assert math.isnan(out[0])
    assert out[1] == 3.0


def test_observability_degree_and_normalised_eigen():
    np.testing.assert_allclose(observability_degree([2.0, 3.0], [1.0, 3.0]), [2.0, 1.0])
    p0 = np.diag([4.0, 9.0, 0.0])
    w, _ = normalized_eigen(p0, p0)
    np.testing.assert_allclose(sorted(w), [0.0, 1.0, 1.0])  # the zero-prior state drops out
    pk = np.array([[1.0, 1.5, 0.0], [1.5, 9.0, 0.0], [0.0, 0.0, 0.0]])  # correlated
    w, v = normalized_eigen(p0, pk)
    # D0^-1 Pk D0^-1 = [[0.25, 0.25], [0.25, 1]] in the first two states.
    ref = np.linalg.eigvalsh(np.array([[0.25, 0.25], [0.25, 1.0]]))
    np.testing.assert_allclose(sorted(w)[1:], ref, rtol=1e-12)


def test_input_errors():
    with pytest.raises(InputError):
        Settings(zupt_rate=0.0)
    with pytest.raises(InputError):
        Prior(attitude=np.array([-1.0, 0.0, 0.0]))
    with pytest.raises(InputError):
        run_alignment(
            SITE,
            Timeline.static(np.eye(3), 10.0),
            ImuErrors(gyro_bias_instability=1e-8),  # the filter has no Gauss-Markov states
        )


# --- command line ---------------------------------------------------------------------------------


def test_cli_align_static_reproduces_the_floors(capsys):
    argv = ["align", "--scheme", "none", "--lat", "34", "--duration", "20 min",
            "--gyro-bias", "0.003", "--accel-bias", "30", "--json"]  # fmt: skip
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    tilt = 30 * MICRO_G / earth.gravity(LAT) / ARCSEC
    heading = GYRO / (earth.OMEGA_IE * math.cos(LAT)) / ARCMIN
    fs = out["final_sigma"]
    assert fs["phi_e_arcsec"] == pytest.approx(tilt, rel=0.03)
    assert fs["phi_n_arcsec"] == pytest.approx(tilt, rel=0.03)
    assert fs["phi_u_arcmin"] == pytest.approx(heading, rel=0.03)
    for key in (
        "phi_e_arcsec",
        "phi_n_arcsec",
        "phi_u_arcmin",
        "gyro_bias_x_deg_h",
        "gyro_bias_y_deg_h",
        "gyro_bias_z_deg_h",
        "accel_bias_x_ug",
        "accel_bias_y_ug",
        "accel_bias_z_ug",
    ):
        for block in ("final_sigma", "convergence_time_s", "observability_degree"):
            assert key in out[block]
    assert out["convergence_time_s"]["accel_bias_x_ug"] is None  # not estimated


@pytest.mark.parametrize("prior", [None, ("3600", "36000")])
def test_cli_align_floors_account_for_the_attitude_prior(prior, capsys):
    """At 100 micro-g / 0.01 deg/h the default 60 arcsec / 60 arcmin attitude prior is
    real information (tilt 19.5 against nabla/g = 20.6 arcsec): the reported floor must
    combine it (1/s^2 = 1/s0^2 + 1/floor^2), and a diffuse prior must give the textbook
    floor. 2 % covers the Omega sin L coupling and the 20-min convergence (< 0.6 % seen).
    """
    argv = ["align", "--scheme", "none", "--lat", "34", "--duration", "20 min",
            "--gyro-bias", "0.01", "--accel-bias", "100", "--json"]  # fmt: skip
    if prior:  # tilts and heading, all in arcsec (600 arcmin = 36000 arcsec)
        argv += ["--initial-attitude", f"{prior[0]},{prior[0]},{prior[1]}"]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    s0_tilt, s0_head = (60.0, 60.0) if prior is None else (3600.0, 600.0)
    tilt = 100 * MICRO_G / earth.gravity(LAT) / ARCSEC
    heading = 0.01 * DEG_PER_HOUR / (earth.OMEGA_IE * math.cos(LAT)) / ARCMIN
    assert out["static_floor_diffuse_prior"]["phi_n_arcsec"] == pytest.approx(tilt, rel=1e-9)
    assert out["static_floor_diffuse_prior"]["phi_u_arcmin"] == pytest.approx(heading, rel=1e-9)
    want_tilt = (tilt**-2 + s0_tilt**-2) ** -0.5
    want_head = (heading**-2 + s0_head**-2) ** -0.5
    assert out["static_floor"]["phi_n_arcsec"] == pytest.approx(want_tilt, rel=1e-9)
    fs = out["final_sigma"]
    for key in ("phi_e_arcsec", "phi_n_arcsec"):
        assert fs[key] == pytest.approx(want_tilt, rel=0.02)
    assert fs["phi_u_arcmin"] == pytest.approx(want_head, rel=0.02)
    if prior is None:  # the prior matters here: the textbook floor alone is > 4 % off
        assert abs(fs["phi_n_arcsec"] / tilt - 1) > 0.04


def test_cli_align_report(tmp_path, capsys):
    out_dir = tmp_path / "rep"
    argv = ["align", "--schemes", "none,two-position", "--duration", "3 min", "--stop", "30",
            "--arw", "0.0005", "--vrw", "5", "--out", str(out_dir), "--json"]  # fmt: skip
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out["runs"]) == {"none", "two-position"}
    for name in ("report.md", "report.html", "results.json", "sigma.png", "attitude_error.png"):
        assert (out_dir / name).is_file()


@pytest.mark.parametrize(
    "argv",
    [
        ["align", "--scheme", "spin"],
        ["align", "--duration", "0 min"],
        ["align", "--duration", "10"],  # a duration carries its unit
        ["align", "--initial-velocity", "0.01,0.01,0"],  # one prior 1 sigma for all axes
        ["align", "--gyro-bias", "-0.01"],  # also the prior 1 sigma: >= 0
        ["align", "--gyro-bias", "1,2"],
        ["align", "--zupt-rate", "0"],
        ["align", "--yaw-swing", "6"],
    ],
)
def test_cli_align_bad_input_exits_2(argv, capsys):
    assert main(argv) == 2
    assert "error" in capsys.readouterr().err


def test_unmodelled_misalignment_and_scale_factor_kick_the_true_attitude_on_a_turn():
    """The simulated run carries K = S + M the filter does not model.

    On a 180 deg table turn about up, the x gyro's z misalignment m adds m * w_z about
    the rotating IMU x axis: integral of m (cos t, sin t) dt over [0, pi] = (0, 2m), a
    pure north tilt of 2m. The z scale factor adds s * pi of heading. Both closed forms
    hold to < 1 % (the 30 s turn is short against Schuler; Earth-rate terms are
    second order). The filter's sigmas do not depend on K at all.
    """
    site = Site(34.0 * DEG)
    tl = alignment_timeline(Base(site, Motion(), 6.0 * DEG, 60.0), "two-position", 120.0)
    m, sf = 10.0 * ARCSEC, 1e-5
    mis = np.zeros(6)
    mis[1] = m  # xz: x gyro senses z rate
    imu = ImuErrors(gyro_misalignment=mis, gyro_scale_factor=np.array([0.0, 0.0, sf]))
    res = run_alignment(site, tl, imu, truth0=np.zeros(15))
    before, after = np.searchsorted(res.t, [59.0, 95.0])
    assert np.all(np.abs(res.truth[before, :3]) < 0.01 * m)
    phi = res.truth[after, :3]
    assert abs(phi[I["phi_n"]]) == pytest.approx(2 * m, rel=0.01)
    assert abs(phi[I["phi_e"]]) < 0.01 * m
    assert abs(phi[I["phi_u"]]) == pytest.approx(math.pi * sf, rel=0.01)
    plain = run_alignment(site, tl, ImuErrors(), truth0=np.zeros(15))
    np.testing.assert_allclose(res.sigma, plain.sigma, rtol=1e-12, atol=0)
    # Superposition: with noise, the run with K differs from the run without by
    # exactly K's noise-free response (same seed, same noise realization).
    noisy = dict(arw=1e-3 * DEG_PER_SQRT_HOUR, vrw=20 * MICRO_G_PER_SQRT_HZ)
    with_k = run_alignment(site, tl, ImuErrors(**noisy, gyro_misalignment=mis), truth0=np.zeros(15))
    without = run_alignment(site, tl, ImuErrors(**noisy), truth0=np.zeros(15))
    k_only = run_alignment(site, tl, ImuErrors(gyro_misalignment=mis), truth0=np.zeros(15))
    np.testing.assert_allclose(with_k.truth - without.truth, k_only.truth, atol=1e-12)


def test_cli_align_truth_only_errors_move_the_run_not_the_sigmas(capsys):
    base = ["align", "--scheme", "two-position", "--duration", "2 min", "--stop", "30", "--json"]
    assert main(base) == 0
    plain = json.loads(capsys.readouterr().out)
    assert main(base + ["--gyro-misalignment", "10", "--gyro-sf", "10"]) == 0
    with_k = json.loads(capsys.readouterr().out)
    assert with_k["final_sigma"] == plain["final_sigma"]
    # one 180 deg turn: about 2 x 10 arcsec of tilt kick the filter does not model
    kick = abs(with_k["final_error"]["phi_n_arcsec"] - plain["final_error"]["phi_n_arcsec"])
    assert kick > 5.0
    assert main(base + ["--gyro-misalignment", "1,2,3"]) == 2
    assert "--gyro-misalignment" in capsys.readouterr().err


def test_truth_with_unmodelled_k_starts_from_the_given_biases_at_any_attitude():
    """K must not disturb the rest of the truth: at a tilted, turned start the true
    biases (IMU frame) are the ones given, and a vanishing K changes nothing."""
    site = Site(34.0 * DEG)
    base = Base(site, Motion(heading=90.0 * DEG, pitch=1.0 * DEG, roll=-2.0 * DEG), 6 * DEG, 60.0)
    tl = alignment_timeline(base, "none", 30.0)
    gyro = np.array([0.01, 0.02, 0.03]) * DEG_PER_HOUR
    accel = np.array([10.0, 20.0, 30.0]) * MICRO_G
    plain = run_alignment(site, tl, ImuErrors(gyro_bias=gyro, accel_bias=accel))
    tiny = run_alignment(
        site,
        tl,
        ImuErrors(gyro_bias=gyro, accel_bias=accel, gyro_misalignment=np.full(6, 1e-15)),
    )
    for res in (plain, tiny):
        np.testing.assert_allclose(res.truth[-1, 9:12], gyro, rtol=1e-9)
        np.testing.assert_allclose(res.truth[-1, 12:15], accel, rtol=1e-9)
    np.testing.assert_allclose(tiny.truth, plain.truth, rtol=0, atol=1e-9)
