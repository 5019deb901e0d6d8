"""Tests of the rotation-modulation north finder (issue #7, P3).

Truth used here is independent of the code under test: closed-form sinusoids written
out with scalar trigonometry, finite differences, textbook least-squares variances,
the reflection symmetry of the gyro plane, and the input values themselves.

Speed: noise-free checks use 10 Hz and two table turns. The sensors are integrating
(increments are exact integrals), so the noise-free filter input does not depend on
the sample rate at all; and white-noise information depends on the record length and
PSD, not on the sample rate, so statistical checks could use a lower rate too. The
Monte Carlo checks keep the default 100 Hz because they are fast enough.
"""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from inserr.cli.main import main
from inserr.core import earth
from inserr.core.errors import InputError
from inserr.core.units import DEG, DEG_PER_S, MIL
from inserr.northfinder.bounds import crlb
from inserr.northfinder.filter import (
    measurement_rows,
    period_measurements,
    run_filter,
    solve,
    wrap_angle,
)
from inserr.northfinder.instrument import (
    Instrument,
    Pose,
    SensorGrade,
    coefficient_jacobian,
    mirror_pose,
    simulate,
    true_coefficients,
)
from inserr.northfinder.study import (
    EQUATORIAL_BAND,
    POLAR_BAND,
    diagnose,
    monte_carlo,
    table_elevation,
)

OMEGA = earth.OMEGA_IE
GRADE = SensorGrade()
#: Mounting angles of a real (calibrated) instrument, so the exact inversion is exercised.
MOUNTED = Instrument(
    sample_rate=10.0, gyro_tilt=0.7 * DEG, accel_azimuth=1.5 * DEG, accel_tilt=-0.4 * DEG
)
TWO_TURNS = 2 * 360.0 / 6.0  # s at the default 6 deg/s


def _noise_free_solution(pose, instrument, *, lat=None, hemisphere=1, model="exact"):
    data = simulate(pose, instrument, GRADE.without_noise(), TWO_TURNS)
    out = run_filter(period_measurements(data, instrument), instrument, GRADE)
    return solve(out.x[-1, :, 0], instrument, lat=lat, hemisphere=hemisphere, model=model)


# --- sensor simulation --------------------------------------------------------------


def test_simulation_matches_closed_form_sinusoids():
    """Noise-free increments equal the integral of the written-out P3-type signal.

    Independent closed form (heading clockwise, table counter-clockwise, ENU /
    right-front-up), with exact mounting terms:
    gyro  = cos th1 [ (cos p cos h W_N + sin p W_U) cos a
                    + (cos p sin r W_U - (sin p sin r cos h - cos r sin h) W_N) sin a ]
            + sin th1 (W_z + rate) + bias
    accel = cos eta [ g sin p cos(a + phi) + g cos p sin r sin(a + phi) ] + sin eta f_z + bias
    """
    lat, h, p, r = 0.61, 2.3, 0.03, -0.05
    pose = Pose(lat, h, p, r)
    ins = dataclasses.replace(MOUNTED, sample_rate=20.0)
    data = simulate(pose, ins, GRADE.without_noise(), 40.0)
    wn, wu, g = OMEGA * math.cos(lat), OMEGA * math.sin(lat), earth.gravity(lat)
    a_coef = math.cos(p) * math.cos(h) * wn + math.sin(p) * wu
    b_coef = (
        math.cos(p) * math.sin(r) * wu
        - (math.sin(p) * math.sin(r) * math.cos(h) - math.cos(r) * math.sin(h)) * wn
    )
    # Body z in ENU: rolled right by r, then nose up by p (tips z back), turned by -h.
    z_n = np.array(
        [
            math.cos(h) * math.sin(r) - math.sin(h) * math.sin(p) * math.cos(r),
            -math.sin(h) * math.sin(r) - math.cos(h) * math.sin(p) * math.cos(r),
            math.cos(p) * math.cos(r),
        ]
    )
    w_z = z_n @ np.array([0.0, wn, wu])
    f_z = g * z_n[2]
    th1, phi, eta = ins.gyro_tilt, ins.accel_azimuth, ins.accel_tilt
    rate, h_s = ins.table_rate, 1.0 / ins.sample_rate
    t = np.arange(data.gyro.shape[1]) * h_s
    a0, a1 = rate * t, rate * (t + h_s)
    int_cos = (np.sin(a1) - np.sin(a0)) / rate
    int_sin = (np.cos(a0) - np.cos(a1)) / rate
    gyro = math.cos(th1) * (a_coef * int_cos + b_coef * int_sin) + h_s * (
        math.sin(th1) * (w_z + rate) + GRADE.gyro_bias
    )
    c0, d0 = g * math.sin(p), g * math.cos(p) * math.sin(r)
    int_cos_phi = (np.sin(a1 + phi) - np.sin(a0 + phi)) / rate
    int_sin_phi = (np.cos(a0 + phi) - np.cos(a1 + phi)) / rate
    accel = math.cos(eta) * (c0 * int_cos_phi + d0 * int_sin_phi) + h_s * (
        math.sin(eta) * f_z + GRADE.accel_bias
    )
    # (sin a1 - sin a0)/rate loses ~1e-16/(rate h) relative to the increments: 1e-12 is ample.
    np.testing.assert_allclose(data.gyro[0], gyro, rtol=0, atol=1e-12 * np.abs(gyro).max())
    np.testing.assert_allclose(data.accel[0], accel, rtol=0, atol=1e-12 * np.abs(accel).max())


def test_white_noise_and_gauss_markov_statistics():
    """Increment noise has variance ARW^2 h; the bias instability is stationary GM."""
    ins = Instrument(sample_rate=100.0)
    grade = SensorGrade(
        gyro_arw=1e-4,
        gyro_bias=0.0,
        gyro_bias_instability=0.0,
        accel_vrw=0.0,
        accel_bias=0.0,
    )
    pose = Pose(0.5, 0.0)
    clean = simulate(pose, ins, grade.without_noise(), 1000.0)
    noisy = simulate(pose, ins, grade, 1000.0, seed=3)
    e = (noisy.gyro - clean.gyro)[0] / math.sqrt(noisy.sample_interval)
    # 1e5 samples: the std estimate has 0.22 % relative spread; 2 % is > 9 sigma.
    assert abs(e.std() / 1e-4 - 1) < 0.02
    gm = SensorGrade(
        gyro_arw=0.0,
        gyro_bias=0.0,
        gyro_bias_instability=2e-6,
        gyro_correlation_time=2.0,
        accel_vrw=0.0,
        accel_bias=0.0,
    )
    b = (simulate(pose, ins, gm, 1000.0, seed=4).gyro - clean.gyro)[0] / noisy.sample_interval
    # 500 correlation times: variance estimate spread ~ sqrt(2 tau / T) = 6 %; allow 25 %.
    assert abs(b.var() / 2e-6**2 - 1) < 0.25
    lag1 = np.corrcoef(b[:-1], b[1:])[0, 1]
    assert lag1 == pytest.approx(math.exp(-0.01 / 2.0), abs=2e-3)


def test_same_seed_same_numbers_and_runs_independent_of_chunking():
    pose = Pose.from_degrees(34, 30, 1, -2)
    ins = Instrument(sample_rate=20.0)
    a = simulate(pose, ins, GRADE, 30.0, n_runs=3, seed=9)
    b = simulate(pose, ins, GRADE, 30.0, n_runs=3, seed=9)
    c = simulate(pose, ins, GRADE, 30.0, n_runs=1, seed=9, first_run=2)
    np.testing.assert_array_equal(a.gyro, b.gyro)
    np.testing.assert_array_equal(a.gyro[2], c.gyro[0])
    assert not np.array_equal(a.gyro[0], a.gyro[1])
    r1 = monte_carlo(pose, ins, GRADE, 60.0, n_runs=6, seed=5, chunk_size=6)
    r2 = monte_carlo(pose, ins, GRADE, 60.0, n_runs=6, seed=5, chunk_size=4)
    # Same noise per run; only the BLAS blocking of the filter's K y product may differ.
    np.testing.assert_allclose(r1.heading_error, r2.heading_error, rtol=0, atol=1e-12)


def test_jacobian_matches_finite_differences():
    pose = Pose.from_degrees(-41, 200, 2.5, -1.5)
    jac = coefficient_jacobian(pose, MOUNTED)
    x0 = np.array([pose.heading, pose.lat, pose.pitch, pose.roll])

    def coeffs(x):
        q = dataclasses.replace(pose, heading=x[0], lat=x[1], pitch=x[2], roll=x[3])
        return true_coefficients(q, MOUNTED, GRADE)[:4]

    step = 1e-6
    num = np.stack(
        [(coeffs(x0 + step * e) - coeffs(x0 - step * e)) / (2 * step) for e in np.eye(4)],
        axis=-1,
    )
    # Central differences: truncation ~step^2 ~1e-12, round-off ~1e-16/step ~1e-10 relative.
    scale = np.abs(jac).max(axis=1, keepdims=True)
    assert np.all(np.abs(jac - num) <= 1e-8 * scale)


# --- estimator: noise-free recovery --------------------------------------------------


@pytest.mark.parametrize("lat", [34.0, -34.0, 62.0, -62.0, 15.0, -15.0])
@pytest.mark.parametrize("heading", [0.0, 37.0, 128.0, 211.0, 304.0, 359.9])
def test_noise_free_recovery_all_quadrants_both_hemispheres(lat, heading):
    """Heading, latitude, pitch and roll to near machine precision, latitude unknown.

    Pitch/roll of a few degrees (signs varied with the case) and non-zero mounting
    angles: the inversion is exact, so the only error left is the pull of the filter's
    finite prior, P P0^-1 ~ 1e-13 of each state, i.e. ~1e-13 rad of heading. 1e-10 rad
    (1e-7 mil) leaves room for round-off.
    """
    pitch = 3.0 * math.copysign(1.0, math.sin(math.radians(heading + 20)))
    roll = -2.5 * math.copysign(1.0, lat)
    pose = Pose.from_degrees(lat, heading, pitch, roll)
    hemi = 1 if lat > 0 else -1
    sol = _noise_free_solution(pose, MOUNTED, hemisphere=hemi)
    assert abs(wrap_angle(sol.heading - pose.heading)) < 1e-10
    assert abs(sol.lat - pose.lat) < 1e-10
    assert abs(sol.pitch - pose.pitch) < 1e-12
    assert abs(sol.roll - pose.roll) < 1e-12
    assert not sol.ambiguous
    known = _noise_free_solution(pose, MOUNTED, lat=pose.lat)
    assert abs(wrap_angle(known.heading - pose.heading)) < 1e-10


def test_p3_small_angle_model_error_is_the_gyro_tilt_cosine():
    """P3's model drops cos(th1): the horizontal rate looks cos(th1) too small.

    For a level table the latitude then solves cos(L') = cos(th1) cos(L) while the
    heading (a ratio of A and B) is unaffected; the exact model has no such error.
    """
    ins = Instrument(sample_rate=10.0, gyro_tilt=2.0 * DEG)
    pose = Pose.from_degrees(34, 75, 0, 0)
    p3 = _noise_free_solution(pose, ins, model="p3")
    exact = _noise_free_solution(pose, ins)
    expected = math.acos(math.cos(ins.gyro_tilt) * math.cos(pose.lat))
    assert p3.lat == pytest.approx(expected, abs=1e-10)
    assert p3.lat - pose.lat > 5e-4  # 0.05 deg: large against the 0.04 deg noise bound
    assert abs(wrap_angle(p3.heading - pose.heading)) < 1e-10
    assert abs(exact.lat - pose.lat) < 1e-10


def test_hemisphere_ambiguity_is_physical():
    """The Earth rate mirrored through the table plane gives the same gyro amplitudes.

    So no estimator can tell the two roots apart from the rotating gyro: telling the
    finder the hemisphere (one bit) is necessary, and the other choice returns the
    mirror solution.
    """
    pose = Pose.from_degrees(34, 30, 1, -2)
    mh, ml = mirror_pose(pose)
    mirror = Pose(ml, mh, pose.pitch, pose.roll)
    assert ml < 0
    ab = true_coefficients(pose, MOUNTED, GRADE)[:2]
    ab_m = true_coefficients(mirror, MOUNTED, GRADE)[:2]
    np.testing.assert_allclose(ab_m, ab, rtol=0, atol=1e-15 * OMEGA)
    wrong = _noise_free_solution(pose, MOUNTED, hemisphere=-1)
    # Only normal gravity differs between the two worlds: dg/dL * 0.15 deg ~ 1e-4 m/s^2
    # (1e-5 relative) moves the levelled 2 deg tilt by ~4e-7 rad. Allow 2e-6 rad; the
    # two roots are 3 deg (5e-2 rad) apart.
    assert abs(wrap_angle(wrong.heading - mh)) < 2e-6
    assert abs(wrong.lat - ml) < 2e-6
    assert abs(wrap_angle(mh - pose.heading)) > 2 * DEG


def test_equatorial_band_is_flagged_ambiguous():
    """Table tilted toward the equator by more than |L|: both roots are northern.

    Facing north with the nose 3 deg up at 2 deg N, the table normal leans 3 deg
    south, the north celestial pole (2 deg up) sinks below the table plane and the
    "pole above the table" rule returns the mirror root. The finder says so.
    """
    tilted = Pose.from_degrees(2.0, 0.0, 3.0, 0.0)
    sol = _noise_free_solution(tilted, MOUNTED)
    assert sol.ambiguous
    mh, ml = mirror_pose(tilted)
    assert ml > 0
    assert abs(sol.lat - ml) < 2e-6  # the mirror root, up to the gravity difference
    clear = _noise_free_solution(Pose.from_degrees(20.0, 0.0, 3.0, 0.0), MOUNTED)
    assert not clear.ambiguous


# --- Cramér-Rao bound ------------------------------------------------------------------


@pytest.mark.parametrize("lat", [5.0, 34.0, -34.0, 60.0, 85.0])
def test_crlb_level_table_matches_least_squares_closed_form(lat):
    """Level table, whole turns: sigma_A = ARW sqrt(2/T), heading sigma_A/(W cos L),
    latitude sigma_A/(W |sin L|).

    Tolerance 1e-4: the pitch/roll uncertainty (~1 microrad) adds W_U * 1e-6 to the
    amplitude noise (< 1e-5 relative), the per-sample sinc loss is ~1e-7.
    """
    duration = 180.0  # 3 turns at 6 deg/s
    pose = Pose.from_degrees(lat, 123.0)
    b = crlb(pose, Instrument(), GRADE, duration)
    sigma_a = GRADE.gyro_arw * math.sqrt(2.0 / duration)
    assert b.heading[-1] == pytest.approx(sigma_a / (OMEGA * math.cos(pose.lat)), rel=1e-4)
    assert b.lat[-1] == pytest.approx(sigma_a / (OMEGA * abs(math.sin(pose.lat))), rel=1e-4)


def test_latitude_observability_is_lost_at_the_equator():
    """sigma_L ~ 1/|sin L|: d(ln sigma_L)/d(ln |sin L|) = -1, singular at L = 0.

    The gyro measures the horizontal rate W cos L, whose slope in L is W sin L.
    Heading stays observable there (its bound grows only toward the poles, 1/cos L).
    """
    lats = np.array([0.5, 2.0, 10.0, 45.0])
    sig = np.array(
        [crlb(Pose.from_degrees(x, 10.0), Instrument(), GRADE, 180.0).lat[-1] for x in lats]
    )
    slope = np.diff(np.log(sig)) / np.diff(np.log(np.sin(np.radians(lats))))
    np.testing.assert_allclose(slope, -1.0, atol=1e-3)
    at_equator = crlb(Pose.from_degrees(0.0, 10.0), Instrument(), GRADE, 180.0)
    assert not np.isfinite(at_equator.lat[-1])
    assert np.isfinite(at_equator.heading[-1])
    near_pole = crlb(Pose.from_degrees(89.0, 10.0), Instrument(), GRADE, 180.0).heading[-1]
    at_45 = crlb(Pose.from_degrees(45.0, 10.0), Instrument(), GRADE, 180.0).heading[-1]
    assert near_pole / at_45 == pytest.approx(
        math.cos(math.radians(45)) / math.cos(math.radians(89)), rel=1e-3
    )


def test_tilt_couples_heading_to_unknown_latitude_near_the_equator():
    """With a tilted table the unknown latitude leaks into heading near the equator.

    At 34 deg the latitude-known and -unknown heading bounds agree to 1 %; at the
    equator the unknown-latitude bound is several times worse.
    """

    def ratio(lat):
        pose = Pose.from_degrees(lat, 30.0, 1.0, -2.0)
        unknown = crlb(pose, Instrument(), GRADE, 180.0).heading[-1]
        known = crlb(pose, Instrument(), GRADE, 180.0, latitude_known=True).heading[-1]
        return unknown / known

    assert ratio(34.0) == pytest.approx(1.0, abs=0.01)
    assert ratio(0.0) > 3.0


# --- Monte Carlo against the bound -------------------------------------------------------


@pytest.mark.parametrize("latitude_known", [False, True])
def test_monte_carlo_heading_sigma_within_20_percent_of_crlb(latitude_known):
    """Default grade, 3 min, 200 runs: sigma-hat has ~5 % relative spread, so 20 % is
    a 4-sigma band; the bias must be within 4 standard errors of zero."""
    pose = Pose.from_degrees(34, 30, 1, -2)
    res = monte_carlo(
        pose, Instrument(), GRADE, 180.0, n_runs=200, seed=11, latitude_known=latitude_known
    )
    sigma = res.heading_sigma()[-1]
    assert sigma / res.bound.heading[-1] == pytest.approx(1.0, abs=0.2)
    assert abs(res.heading_bias()[-1]) < 4 * sigma / math.sqrt(res.n_runs)
    if not latitude_known:
        assert res.lat_sigma()[-1] / res.bound.lat[-1] == pytest.approx(1.0, abs=0.2)


def test_convergence_time_definition():
    """Earliest time from which >= 68 % of runs stay within 0.5 mil until the end."""
    pose = Pose.from_degrees(34, 30)
    res = monte_carlo(pose, Instrument(sample_rate=10.0), GRADE, 10.0, n_runs=4, seed=0)
    err = np.full((10, 100), 2.0 * MIL)
    err[3:, :70] = 0.1 * MIL  # 70 % converged from period 3 ...
    err[5, :5] = 2.0 * MIL  # ... except a relapse to 65 % at period 5
    synthetic = dataclasses.replace(res, heading_error=err)
    assert synthetic.convergence_time() == pytest.approx(res.times[6])
    err[-1, :] = 2.0 * MIL
    assert dataclasses.replace(res, heading_error=err).convergence_time() is None


def test_filter_runs_are_independent_filters():
    """Each run has its own filter: a run's states do not depend on the other runs."""
    pose = Pose.from_degrees(-20, 250, 2, 1)
    ins = Instrument(sample_rate=10.0)
    z = period_measurements(simulate(pose, ins, GRADE, 60.0, n_runs=3, seed=2), ins)
    many = run_filter(z, ins, GRADE).x[-1]
    one = run_filter(z[:, :, 1:2], ins, GRADE).x[-1, :, 0]
    np.testing.assert_array_equal(many[:, 1], one)
    assert not np.allclose(many[:, 0], many[:, 1])


def test_filter_equals_weighted_least_squares():
    """With constant states (no bias instability, Q = 0) and a diffuse prior, the Kalman
    filter is the weighted least-squares fit of all period measurements.

    Independent truth: numpy's lstsq on the stacked rows, gyro and accelerometer rows
    scaled by 1/ARW and 1/VRW. The prior's pull is ~(sigma_x / prior)^2 < 1e-10, but the
    first updates, with prior variances ~1e14 times the measurement variances, leave
    round-off of a few 1e-4 of each state's sigma; 2e-3 sigma leaves margin. A filter
    fed a mis-shaped z (filterpy's (dim_z, 1) contract broken) would be off by the
    signal itself, thousands of sigmas.
    """
    grade = GRADE.replace(gyro_bias_instability=0.0)
    ins = Instrument(sample_rate=10.0)
    pose = Pose.from_degrees(48, 140, -1.5, 2)
    z = period_measurements(simulate(pose, ins, grade, 120.0, n_runs=2, seed=4), ins)
    out = run_filter(z, ins, grade)
    h = measurement_rows(ins, z.shape[0])
    w = np.array([1.0 / grade.gyro_arw, 1.0 / grade.accel_vrw])
    a = (h * w[None, :, None]).reshape(-1, 6)
    for run in range(2):
        b = (z[:, :, run] * w[None, :]).reshape(-1)
        x_ls = np.linalg.lstsq(a, b, rcond=None)[0]
        sigma = np.sqrt(np.diag(out.P[-1]))
        assert np.all(np.abs(out.x[-1, :, run] - x_ls) < 2e-3 * sigma)


# --- hemisphere declaration and warnings ------------------------------------------------


def test_hemisphere_is_declared_not_taken_from_the_truth():
    """Default declaration is north whatever the simulated latitude; a southern site
    declared north gets the mirror solution (and a warning), declared south the truth."""
    pose = Pose.from_degrees(-34, 30, 1, -2)
    ins = Instrument(sample_rate=10.0)
    default = monte_carlo(pose, ins, GRADE, 180.0, n_runs=20, seed=3)
    assert default.hemisphere == 1
    mirror_h, _ = mirror_pose(pose)
    offset = wrap_angle(mirror_h - pose.heading)
    assert abs(offset) > 2 * DEG  # the two roots are far apart here
    # 20 runs of 0.5 mil sigma: the mean is within ~0.1 mil of the mirror's offset.
    assert default.heading_bias()[-1] == pytest.approx(offset, abs=0.5 * MIL)
    assert any(w.startswith("hemisphere:") for w in default.warnings)
    south = monte_carlo(pose, ins, GRADE, 180.0, n_runs=20, seed=3, hemisphere="south")
    assert south.summary()["hemisphere_declared"] == "south"
    assert abs(south.heading_bias()[-1]) < 0.5 * MIL
    assert not any(w.startswith(("hemisphere:", "mirror root:")) for w in south.warnings)
    with pytest.raises(InputError):
        monte_carlo(pose, ins, GRADE, 180.0, n_runs=2, hemisphere="up")


def test_observability_bands_are_where_the_bounds_are_ten_times_their_best():
    """Polar band: heading bound 10 x its equatorial value; equatorial band: latitude
    bound 10 x its value at the pole (level table, closed forms of the CRLB test)."""
    ins = Instrument(sample_rate=10.0)

    def bound(lat_rad):
        return crlb(Pose(lat_rad, 0.4), ins, GRADE, 180.0)

    assert bound(POLAR_BAND).heading[-1] / bound(0.0).heading[-1] == pytest.approx(10, rel=1e-3)
    near_pole = math.radians(89.99)
    ratio = bound(EQUATORIAL_BAND).lat[-1] / bound(near_pole).lat[-1]
    assert ratio == pytest.approx(10.0 * math.sin(near_pole), rel=1e-3)
    # E is the latitude on a level table and moves by the tilt toward north.
    assert table_elevation(Pose.from_degrees(20, 0)) == pytest.approx(math.radians(20))
    # Facing north nose-up tips the table normal south: E = L - pitch.
    assert table_elevation(Pose.from_degrees(20, 0, 3, 0)) == pytest.approx(math.radians(17))


@pytest.mark.parametrize("lat, unresolved", [(1.5, True), (3.0, False), (34.0, False)])
def test_latitude_resolution_band_of_a_level_table(lat, unresolved):
    """Level table, default grade, 3 min: the data resolve the latitude where
    |L| >= 3 sigma_L, i.e. |L| sin|L| >= 3 sigma_A / Omega, |L| >~ 2.0 deg."""
    sigma_a = GRADE.gyro_arw * math.sqrt(2.0 / 180.0)
    edge = math.degrees(math.sqrt(3.0 * sigma_a / OMEGA))
    assert edge == pytest.approx(2.03, abs=0.01)
    res = monte_carlo(
        Pose.from_degrees(lat, 30), Instrument(sample_rate=10.0), GRADE, 180.0, n_runs=2, seed=1
    )
    tags = [w.split(":")[0] for w in res.warnings]
    assert ("latitude not resolved" in tags) is unresolved
    assert ("equatorial band" in tags) is (lat < math.degrees(EQUATORIAL_BAND))


def test_sigma_over_crlb_above_range_is_explained():
    """At 150 deg/s the 1 s period sums keep sinc(75 deg) = 0.74 of the signal, so the
    filter's sigma is ~1.35 x the raw-sample bound (100 runs: +-7 %)."""
    ins = Instrument(table_rate=150.0 * DEG_PER_S, sample_rate=20.0)
    res = monte_carlo(Pose.from_degrees(34, 30, 1, -2), ins, GRADE, 180.0, n_runs=100, seed=2)
    ratio = res.heading_sigma()[-1] / res.bound.heading[-1]
    assert ratio > 1.2
    (msg,) = [w for w in res.warnings if w.startswith("sigma/CRLB")]
    assert "sinc" in msg


def test_diagnose_is_what_monte_carlo_stores():
    pose = Pose.from_degrees(2, 30, 1, -2)
    ins = Instrument(sample_rate=10.0)
    res = monte_carlo(pose, ins, GRADE, 60.0, n_runs=3, seed=0)
    assert list(res.warnings) == diagnose(res, pose, ins, GRADE)
    assert res.summary()["warnings"] == list(res.warnings)


# --- input errors -------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"lat": math.pi / 2, "heading": 0.0}, "lat"),
        ({"lat": -math.pi / 2, "heading": 0.0}, "lat"),
        ({"lat": math.nan, "heading": 0.0}, "lat"),
        ({"lat": 0.5, "heading": 0.0, "pitch": 1.0}, "pitch"),
    ],
)
def test_pose_rejects_bad_input(kwargs, field):
    with pytest.raises(InputError) as err:
        Pose(**kwargs)
    assert err.value.field == field


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"table_rate": 0.0}, "table_rate"),
        ({"table_rate": 200 * DEG_PER_S}, "table_rate"),
        ({"sample_rate": 100.0, "filter_period": 0.015}, "filter_period"),
    ],
)
def test_instrument_rejects_bad_input(kwargs, field):
    with pytest.raises(InputError) as err:
        Instrument(**kwargs)
    assert err.value.field == field


# --- CLI ----------------------------------------------------------------------------------

DONE_WHEN = "--lat 34 --heading 30 --pitch 1 --roll -2 --duration 3min --runs 50 --seed 1 --json"


def test_cli_done_when_command(capsys, tmp_path):
    out = tmp_path / "report"
    rc = main(["northfind", *DONE_WHEN.split(), "--out", str(out)])
    assert rc == 0
    res = json.loads(capsys.readouterr().out)
    for key in (
        "heading_error_1sigma_mil",
        "heading_bias_mil",
        "latitude_error_1sigma_deg",
        "crlb_heading_mil",
        "convergence_time_s",
    ):
        assert key in res
    assert res["latitude_known"] is False
    assert res["hemisphere_declared"] == "north"
    assert res["warnings"] == []
    # 50 runs: sigma-hat spread ~10 %, so 20 % is a 2-sigma statement (the bar).
    assert res["heading_error_1sigma_mil"] / res["crlb_heading_mil"] == pytest.approx(1, abs=0.2)
    saved = json.loads((out / "results.json").read_text())
    assert saved["crlb_heading_mil"] == res["crlb_heading_mil"]
    assert (out / "heading_error.png").stat().st_size > 0


@pytest.mark.parametrize(
    "change, flag",
    [
        (["--lat", "90"], "--lat (site.latitude)"),
        (["--lat", "-90"], "--lat (site.latitude)"),
        (["--lat", "nan"], "--lat (site.latitude)"),
        (["--duration=-3min"], "--duration (scenario.duration)"),
        (["--duration", "0.5s"], "--duration (scenario.duration)"),  # < one filter period
        (["--arw", "0.001 deg/h"], "--arw (imu.arw)"),
        (["--arw", "0"], "--arw (imu.arw)"),  # the bound needs white noise
        (["--lat", "34 m"], "--lat (site.latitude)"),
        (["--runs", "0"], "--runs (scenario.runs)"),
        (["--rate", "0"], "--rate (scheme.rate)"),
        (["--filter-period", "0.015"], "--filter-period (northfinder.filter_period)"),
        (["--gyro-bias", "0.1,0.2,0.3"], "--gyro-bias (imu.gyro_bias)"),  # a single gyro
    ],
)
def test_cli_bad_input_one_line_exit_2_no_output(change, flag, capsys, tmp_path):
    args = ["northfind", "--lat", "34", "--heading", "30", "--runs", "2", "--duration", "1min"]
    out = tmp_path / "report"
    rc = main([*args, *change, "--out", str(out)])
    captured = capsys.readouterr()
    assert rc == 2
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and flag in lines[0]
    assert captured.out == ""
    assert not out.exists()


def test_cli_declared_hemisphere_not_the_simulated_one(capsys):
    """No --hemisphere means north, even at a southern --lat: mirror root and a warning."""
    base = ["northfind", "--lat", "-34", "--heading", "30", "--pitch", "1", "--roll", "-2"]
    fast = ["--runs", "10", "--duration", "2 min", "--sample-rate", "10", "--json"]
    assert main([*base, *fast]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["hemisphere_declared"] == "north"
    assert abs(res["heading_bias_mil"]) > 40  # the mirror root is ~54 mil away
    assert any(w.startswith("hemisphere:") for w in res["warnings"])
    assert main([*base, *fast, "--hemisphere", "south"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["hemisphere_declared"] == "south"
    assert abs(res["heading_bias_mil"]) < 1
    assert res["warnings"] == []


def test_cli_warns_at_the_equator(capsys):
    """The audit's case: sigma 0.6 mil against a 7 mil bound, because the latitude is not
    resolved and the hemisphere constraint biases the estimator."""
    args = ["northfind", "--lat", "0", "--heading", "30", "--pitch", "1", "--roll", "-2"]
    assert main([*args, "--runs", "50", "--seed", "1", "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert res["heading_sigma_over_crlb"] < 0.8
    tags = [w.split(":")[0] for w in res["warnings"]]
    for tag in ("equatorial band", "latitude not resolved", "sigma/CRLB"):
        assert tag in tags
    (ratio,) = [w for w in res["warnings"] if w.startswith("sigma/CRLB")]
    assert "not resolved" in ratio
    assert main([*args, "--runs", "50", "--seed", "1"]) == 0
    human = capsys.readouterr().out
    assert "warnings:" in human and "equatorial band" in human
    assert main([*args, "--runs", "5", "--latitude-known", "--json"]) == 0
    known = json.loads(capsys.readouterr().out)
    assert not any(w.startswith("equatorial band") for w in known["warnings"])


def test_cli_warns_near_the_pole(capsys):
    args = ["northfind", "--lat", "89.9", "--heading", "30", "--runs", "20", "--json"]
    assert main(args) == 0
    res = json.loads(capsys.readouterr().out)
    tags = [w.split(":")[0] for w in res["warnings"]]
    assert "polar band" in tags and "large errors" in tags
    assert main([*args[:2], "84", *args[3:]]) == 0
    assert "polar band" not in capsys.readouterr().out


def test_coefficient_information_is_the_white_noise_information_of_whole_turns():
    # Each increment over h is u . [A, B, eps'] + white noise of variance PSD h, with
    # u = (int cos alpha, int sin alpha, h): information sum u u^T / (PSD h). Over a
    # sample int cos alpha = h cos(alpha_mid) sinc(w h / 2), so over whole table turns
    # the cos and sin entries are (T / 2) sinc^2(w h / 2) and the cross terms and
    # sum h cos vanish: the gyro block is diag((T/2) s2, (T/2) s2, T) / ARW^2, the
    # accelerometer block the same over VRW^2, and the blocks do not couple.
    from inserr.northfinder.bounds import coefficient_information
    from inserr.northfinder.instrument import Instrument, SensorGrade

    # 7.5 Hz: 15 samples per 2 s period; no sample time is a multiple of a table period.
    ins = Instrument(table_rate=6 * DEG_PER_S, sample_rate=7.5, filter_period=2.0)
    grade = SensorGrade(gyro_arw=3e-6, accel_vrw=7e-4)
    times, info = coefficient_information(ins, grade, 121.0)  # 60 whole periods: 2 turns
    assert np.array_equal(times, 2.0 * np.arange(1, 61))
    big_t, x = 120.0, 0.5 * ins.table_rate / ins.sample_rate
    s2 = (math.sin(x) / x) ** 2  # 1 - 1.6e-5
    for idx, psd in (([0, 1, 4], grade.gyro_arw**2), ([2, 3, 5], grade.accel_vrw**2)):
        block = info[-1][np.ix_(idx, idx)] * psd
        # Sums of 1200 terms: round-off ~1e-13 of T.
        np.testing.assert_allclose(
            block, np.diag([big_t / 2 * s2, big_t / 2 * s2, big_t]), rtol=1e-12, atol=1e-11
        )
    assert np.all(info[:, [0, 1, 4]][:, :, [2, 3, 5]] == 0.0)
    # Information accumulates: after 7 periods (14 s, part of a turn) the constant's is
    # 14 s / PSD whatever the turn.
    assert info[6, 4, 4] * grade.gyro_arw**2 == pytest.approx(14.0, rel=1e-12)
    assert info[6, 5, 5] * grade.accel_vrw**2 == pytest.approx(14.0, rel=1e-12)
    # The filter, like the bound, refuses a grade without white noise on either sensor.
    from inserr.northfinder.filter import make_filter

    for bad in (
        dataclasses.replace(grade, gyro_arw=0.0),
        dataclasses.replace(grade, accel_vrw=0.0),
    ):
        with pytest.raises(InputError, match="ARW and VRW"):
            make_filter(ins, bad)
    # Without white noise on either sensor the bound is infinite: refused.
    for bad in (
        dataclasses.replace(grade, gyro_arw=0.0),
        dataclasses.replace(grade, accel_vrw=0.0),
    ):
        with pytest.raises(InputError, match="infinite"):
            coefficient_information(ins, bad, 121.0)
