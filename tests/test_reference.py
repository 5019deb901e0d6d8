"""The nonlinear reference (pyins) against the linear model, closed forms and itself.

Sample rates. The reference's own discretisation error (pyins's two-sample
coning/sculling and trapezoid position update, the rotation spline of the inverse
navigation near table start/stop) grows with the sample interval; it is zero for an
IMU at rest (constant increments). Static scenarios therefore run at 2 Hz, which
samples the 84-min Schuler oscillation 10^4 times per period. Scenarios with a
6 deg/s table run at 20 Hz (0.3 deg per sample). Both keep the reference's own error
far below the tolerances used here.

Tolerances. A convention error (a sign, a swapped axis, a wrong frame for an error
term) changes a response by O(1). The physical difference between the linear and
the nonlinear model is second order: relative size about the largest attitude error
in rad, below 1e-3 in every scenario here (heading error < 300 arcsec). The
comparisons therefore use 1e-2: ten times the expected physical difference, a
hundred times finer than any convention error.
"""

from __future__ import annotations

import json
import math
import sys

import numpy as np
import pytest

from inserr.core.errors import InputError
from inserr.core.imu import ImuErrors, InitialErrors
from inserr.core.rotations import body_to_nav, rot_z
from inserr.core.units import ARCSEC, DEG, DEG_PER_HOUR, MICRO_G
from inserr.scenario.schema import scenario_from_dict

#: See the module docstring.
REL_TOL = 1e-2

TILTED = {"heading": "30 deg", "pitch": "1 deg", "roll": "-2 deg"}
BIASES = {"gyro_bias": "0.02,-0.01,0.015 deg/h", "accel_bias": "100,-50,80 ug"}
SCALE_MIS = {
    "gyro_scale_factor": "100,-50,80 ppm",
    "accel_scale_factor": "100,-50,80 ppm",
    "gyro_misalignment": "20,-10,15,30,-25,10 arcsec",
    "accel_misalignment": "20,-10,15,30,-25,10 arcsec",
}


@pytest.fixture(scope="module")
def pyins():
    return pytest.importorskip("pyins")


def scenario(hours: float, scheme: dict, imu: dict, initial: dict | None = None, **extra):
    data = {
        "scenario": {"duration": f"{hours} h"},
        "site": {"latitude": "34 deg", "longitude": "108.9 deg", "height": "380 m"},
        "motion": dict(TILTED),
        "imu": imu,
        "scheme": scheme,
        **extra,
    }
    if initial:
        data["initial"] = initial
    return scenario_from_dict(data)


# --- the optional extra -------------------------------------------------------------
def _hide_pyins(monkeypatch):
    for name in list(sys.modules):
        if name == "pyins" or name.startswith("pyins."):
            monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "pyins", None)  # makes "import pyins" raise ImportError


def test_missing_extra_names_the_install_command(monkeypatch):
    from inserr.reference.strapdown import require_pyins

    _hide_pyins(monkeypatch)
    with pytest.raises(InputError) as exc:
        require_pyins()
    assert "python-ins" in str(exc.value)
    assert "pip install 'inserr[reference]'" in str(exc.value)


def test_validate_command_without_the_extra_exits_2_with_the_message(monkeypatch, capsys):
    from inserr.cli.main import main

    _hide_pyins(monkeypatch)
    status = main(["validate", "--duration", "0.1 h", "--gyro-bias", "0.02", "--json"])
    err = capsys.readouterr().err
    assert status == 2
    assert "inserr[reference]" in err
    assert "Traceback" not in err


# --- frame mapping ---------------------------------------------------------------------
def test_swap_relabels_enu_as_ned_and_right_front_up_as_forward_right_down():
    from inserr.reference.strapdown import SWAP, swap_vectors

    east, north, up = np.eye(3)
    # NED components of the ENU unit vectors; FRD components of right, front, up.
    assert np.array_equal(swap_vectors(east), [0, 1, 0])
    assert np.array_equal(swap_vectors(north), [1, 0, 0])
    assert np.array_equal(swap_vectors(up), [0, 0, -1])
    assert np.linalg.det(SWAP) == pytest.approx(1.0)
    assert np.array_equal(SWAP @ SWAP, np.eye(3))


@pytest.mark.parametrize("hpr", [(15.0, 1.0, -2.0), (250.0, -30.0, 60.0), (90.0, 0.0, 0.0)])
def test_euler_angles_mean_the_same_thing_in_both_libraries(pyins, hpr):
    # Heading clockwise from north, pitch nose-up, roll right-wing-down in both
    # (aerospace convention), so the pyins (roll, pitch, heading) of the mapped DCM
    # must be the inserr angles themselves.
    from inserr.reference.strapdown import from_pyins_dcm, to_pyins_dcm

    h, p, r = hpr
    c = body_to_nav(h * DEG, p * DEG, r * DEG)
    rph = pyins.transform.mat_to_rph(to_pyins_dcm(c))
    assert np.mod(rph - [r, p, h] + 180.0, 360.0) - 180.0 == pytest.approx(np.zeros(3), abs=1e-12)
    assert np.allclose(from_pyins_dcm(pyins.transform.mat_from_rph(rph)), c, atol=1e-15)


def test_pure_heading_rotation_gives_the_expected_gyro_and_accel_increments(pyins):
    # A tilted IMU turning clockwise at r about the local vertical: C_s^n = rot_z(-H(t)) C_tilt,
    # H = H0 + r t. Its rate is w_is^s = C_tilt^T rot_z(H) [0, W cos L, W sin L - r] and its
    # specific force f^s = C_tilt^T [0, 0, g] (rot_z leaves the vertical alone), so the
    # increments over [t_{k-1}, t_k] are closed-form integrals of cos H and sin H.
    from inserr.core.earth import OMEGA_IE, Site
    from inserr.reference.strapdown import MARGIN, ideal_increments

    site = Site.from_degrees(34.246, 108.91, 380.0)
    tilt = body_to_nav(0.0, 1.0 * DEG, -2.0 * DEG)
    h0, r, rate = 15.0 * DEG, 6.0 * DEG, 10.0
    t = np.arange(0, 601) / rate
    gyro, accel = ideal_increments(site, lambda tt: rot_z(-(h0 + r * tt)) @ tilt, t)

    wc, ws = OMEGA_IE * math.cos(site.lat), OMEGA_IE * math.sin(site.lat)
    hk = h0 + r * t
    level = np.column_stack(
        [
            wc / r * np.diff(np.cos(hk)),  # integral of -wc sin H
            wc / r * np.diff(np.sin(hk)),  # integral of  wc cos H
            np.full(len(t) - 1, (ws - r) / rate),
        ]
    )
    expected = level @ tilt  # rows: C_tilt^T v
    # Away from the ends of the generated span (the spline's end conditions, which the
    # reference's chunk margins discard): 1e-12 rad per 0.1 s increment (2e-6 deg/h),
    # far below any gyro error of interest, far above rounding of ~1e-2 rad increments.
    inner = slice(MARGIN, -MARGIN)
    assert np.allclose(gyro[1:][inner], expected[inner], rtol=0, atol=1e-12)
    assert expected[0, 2] < 0  # clockwise turn reads negative about up (right-front-up)
    assert gyro[1, 2] < 0
    f = tilt.T @ np.array([0.0, 0.0, site.g]) / rate
    # 1e-9 m/s per increment (1e-3 ug): the inverse navigation differentiates Earth-centred
    # positions of 6.4e6 m twice, whose rounding (~1e-9 m) sets this floor.
    assert np.allclose(accel[1:][inner], f, rtol=0, atol=1e-9)


# --- the reference against itself ---------------------------------------------------------
def test_ideal_imu_navigates_without_error_under_the_p0_yaw_swing(pyins):
    # Inverse navigation followed by forward navigation of the same data must give the
    # truth back. 0.05 m in 10 min is 30x less than a 1 ug accelerometer bias would give.
    from inserr.reference.strapdown import RunSpec, attitude_history, simulate

    scen = scenario(
        1 / 6,
        {"name": "two-position", "stop": "60 s"},
        {},
        motion={**TILTED, "type": "yaw-swing", "amplitude": "6 deg/s", "period": "120 s"},
    )
    scen_tl = scen.timeline()
    (h,) = simulate(
        scen.site,
        attitude_history(scen_tl),
        scen.duration,
        [RunSpec(ImuErrors(), InitialErrors(), noise=False)],
        rate=100.0,
    )
    assert h.horizontal.max() < 0.05
    assert np.abs(h.phi).max() < 0.01 * ARCSEC


def test_chunking_does_not_change_the_result(pyins):
    # Chunk edges are where a mistake in the margins, the carried coning sample, the
    # restarted integrator or the noise streams would show. 1e-6 m: rounding of the
    # latitude/longitude in degrees is ~1e-9 m per restart.
    from inserr.reference.strapdown import RunSpec, attitude_history, simulate

    scen = scenario(
        0.25,
        {"name": "two-position", "stop": "60 s"},
        {
            **BIASES,
            "arw": "0.01 deg/sqrt(h)",
            "vrw": "20 ug/sqrt(Hz)",
            "gyro_bias_instability": "0.01 deg/h",
        },
    )
    att = attitude_history(scen.timeline())
    spec = RunSpec(scen.imu, scen.init, np.random.SeedSequence(7), noise=True)
    (one,) = simulate(scen.site, att, scen.duration, [spec], rate=10.0, chunk=3600.0)
    (many,) = simulate(scen.site, att, scen.duration, [spec], rate=10.0, chunk=97.3)
    assert np.array_equal(one.t, many.t)
    assert np.allclose(one.dr, many.dr, rtol=0, atol=1e-6)
    assert np.allclose(one.phi, many.phi, rtol=0, atol=1e-12)


# --- linear vs nonlinear -------------------------------------------------------------------
def _check_agreement(v):
    m = v.metrics
    assert m["relative_difference"] < REL_TOL
    assert m["rms_difference_m"] < REL_TOL * m["linear_max_horizontal_error_m"]
    head = abs(m["linear_final_heading_error_arcsec"])
    assert (
        abs(m["nonlinear_final_heading_error_arcsec"] - m["linear_final_heading_error_arcsec"])
        < REL_TOL * head
    )


def test_static_biases_only(pyins):
    from inserr.reference.validation import validate

    _check_agreement(validate(scenario(2, {"name": "none"}, BIASES), rate=2.0))


def test_indexed_biases_only(pyins):
    from inserr.reference.validation import validate

    _check_agreement(
        validate(scenario(1, {"name": "two-position", "stop": "120 s"}, BIASES), rate=20.0)
    )


@pytest.mark.parametrize(
    "scheme",
    [
        {"name": "two-position", "stop": "120 s"},
        {"name": "continuous", "reversal": "120 s"},
    ],
)
def test_scale_factor_and_misalignment_under_a_rotating_table(pyins, scheme):
    from inserr.reference.validation import validate

    _check_agreement(validate(scenario(1, scheme, SCALE_MIS), rate=20.0))


def test_initial_errors_enter_with_the_linear_models_signs(pyins):
    # Tilt, heading, velocity and position errors alone: any sign or frame slip in
    # their injection would flip or rotate the response.
    from inserr.reference.validation import validate

    init = {
        "attitude": "10,-10,60 arcsec",
        "velocity": "0.01,-0.02,0.01 m/s",
        "position": "10,-20,10 m",
    }
    _check_agreement(validate(scenario(2, {"name": "none"}, {}, init), rate=2.0))


# --- Monte Carlo vs covariance ----------------------------------------------------------------
NOISY = {
    "gyro_bias": "0.01 deg/h",
    "accel_bias": "50 ug",
    "arw": "0.01 deg/sqrt(h)",
    "vrw": "50 ug/sqrt(Hz)",
    "gyro_bias_instability": "0.005 deg/h",
    "accel_bias_instability": "20 ug",
}


@pytest.mark.parametrize("random_constants", [False, True])
def test_monte_carlo_spread_matches_the_covariance(pyins, random_constants):
    # 100 runs: the chi-square test has 198 dof, so a covariance off by a factor of 2
    # (std off by 41 %) is rejected with near certainty while the right one passes
    # with probability 0.99 (the seed is fixed, so the outcome is reproducible).
    from inserr.reference.validation import chi2_consistency, validate

    scen = scenario(1, {"name": "none"}, NOISY, {"attitude": "10,10,60 arcsec"})
    v = validate(scen, rate=2.0, runs=100, seed=3, random_constants=random_constants)
    mc = v.monte_carlo
    assert mc.test is not None and mc.test.consistent
    assert mc.test.dof == 198
    last = mc.samples[:, -1, :]
    assert not chi2_consistency(last, 2.0 * mc.cov[-1]).consistent
    assert not chi2_consistency(last, 0.5 * mc.cov[-1]).consistent
    if random_constants:
        # Zero-mean constants: the mean is within 4 standard errors of 0.
        se = np.sqrt(np.diag(mc.cov[-1]) / len(mc.runs))
        assert np.all(np.abs(last.mean(axis=0)) < 4 * se)


def test_chi2_test_matches_its_distribution():
    # Independent check of the statistic: Gaussian samples drawn with the stated
    # covariance pass about 99 % of the time (binomial 5-sigma band over 400 trials).
    from inserr.reference.validation import chi2_consistency

    rng = np.random.default_rng(0)
    cov = np.array([[4.0, 1.5], [1.5, 2.0]])
    chol = np.linalg.cholesky(cov)
    passed = sum(
        chi2_consistency(rng.standard_normal((20, 2)) @ chol.T + [3.0, -1.0], cov, 0.99).consistent
        for _ in range(400)
    )
    assert abs(passed / 400 - 0.99) < 5 * math.sqrt(0.99 * 0.01 / 400)


def test_chi2_resolution_is_reported():
    # The accepted spread ratio is sqrt(chi2 bound / dof): scaling every sample by a
    # ratio inside it passes, outside it fails (the statistic scales with its square).
    from inserr.reference.validation import chi2_consistency

    rng = np.random.default_rng(3)
    x = rng.standard_normal((3, 2))
    x = (x - x.mean(axis=0)) / np.sqrt(np.sum(x.var(axis=0, ddof=1)) / 2)  # spread ratio 1
    cov = np.eye(2)
    d = chi2_consistency(x, cov, 0.95).as_dict()
    lo, hi = d["accepted_sigma_ratio"]
    assert 0.3 < lo < 0.4 and 1.6 < hi < 1.8  # 4 dof at 95 %
    assert "more runs" in d["note"]
    assert chi2_consistency(x * 0.99 * hi, cov, 0.95).consistent
    assert not chi2_consistency(x * 1.01 * hi, cov, 0.95).consistent
    assert not chi2_consistency(x * 0.99 * lo, cov, 0.95).consistent


def test_same_seed_same_numbers_other_seed_other_numbers(pyins):
    from inserr.reference.validation import validate

    scen = scenario(0.25, {"name": "none"}, NOISY)
    a = validate(scen, rate=2.0, runs=3, seed=11).summary()
    b = validate(scen, rate=2.0, runs=3, seed=11).summary()
    c = validate(scen, rate=2.0, runs=3, seed=12).summary()
    assert json.dumps(a, default=str) == json.dumps(b, default=str)
    assert (
        a["monte_carlo"]["sample_std_horizontal_m"] != c["monte_carlo"]["sample_std_horizontal_m"]
    )


def test_noise_increments_have_the_continuous_psd():
    # ARW in rad/sqrt(s) integrates to increments of std arw sqrt(dt); the Gauss-Markov
    # bias has stationary std sigma and lag-1 correlation exp(-dt / tau).
    from inserr.reference.injection import Injector

    arw, sigma, tau, dt, n = 1e-4, 2e-6, 50.0, 0.5, 200_000
    imu = ImuErrors(arw=arw, gyro_bias_instability=sigma, gyro_correlation_time=tau)
    inj = Injector(imu, np.random.SeedSequence(1))
    g, _ = inj.apply(np.zeros((n, 3)), np.zeros((n, 3)), dt)
    white_only = Injector(imu.replace(gyro_bias_instability=0.0), np.random.SeedSequence(1))
    w, _ = white_only.apply(np.zeros((n, 3)), np.zeros((n, 3)), dt)
    # 3 sigma of a sample std from 6e5 values: 0.3 %.
    assert np.std(w) == pytest.approx(arw * math.sqrt(dt), rel=0.01)
    b = (g - w) / dt  # the bias-instability part, rad/s
    assert np.std(b) == pytest.approx(sigma, rel=0.05)
    rho = np.mean([np.corrcoef(b[:-1, k], b[1:, k])[0, 1] for k in range(3)])
    assert rho == pytest.approx(math.exp(-dt / tau), abs=0.01)


def test_deterministic_injection_is_the_sensor_model():
    from inserr.reference.injection import Injector

    imu = ImuErrors(
        gyro_bias=np.array([1.0, -2.0, 3.0]) * DEG_PER_HOUR,
        accel_bias=np.array([10.0, 20.0, -30.0]) * MICRO_G,
        gyro_scale_factor=np.array([1e-4, 0, 0]),
        accel_misalignment=np.array([0, 0, 0, 0, 0, 5e-5]),  # zy: z sensor sees y input
    )
    g, a = Injector(imu, noise=False).apply(
        np.array([[1.0, 2.0, 3.0]]), np.array([[0.0, 4.0, 0.0]]), 0.01
    )
    assert g[0] == pytest.approx(
        [
            1.0 + 1e-4 + 0.01 * imu.gyro_bias[0],
            2.0 + 0.01 * imu.gyro_bias[1],
            3.0 + 0.01 * imu.gyro_bias[2],
        ],
        rel=1e-15,
    )
    assert a[0] == pytest.approx(
        [
            0.01 * imu.accel_bias[0],
            4.0 + 0.01 * imu.accel_bias[1],
            4.0 * 5e-5 + 0.01 * imu.accel_bias[2],
        ],
        rel=1e-15,
    )


def test_initial_attitude_error_sign_follows_the_phi_definition():
    # phi_U > 0 means the indicated heading is too large (inserr.model.psi_model).
    from inserr.core.rotations import euler_from_dcm
    from inserr.reference.injection import perturbed_dcm

    c = body_to_nav(40 * DEG, 0.0, 0.0)
    heading, _, _ = euler_from_dcm(perturbed_dcm(c, np.array([0.0, 0.0, 60 * ARCSEC])))
    assert heading == pytest.approx(40 * DEG + 60 * ARCSEC, abs=1e-12)


# --- command line --------------------------------------------------------------------------
def test_validate_command_reports_json(pyins, capsys, tmp_path):
    from inserr.cli.main import main

    out = tmp_path / "report"
    status = main(
        [
            "validate",
            "--scheme",
            "two-position",
            "--stop",
            "120",
            "--duration",
            "0.5 h",
            "--gyro-bias",
            "0.02",
            "--accel-bias",
            "100",
            "--sample-rate",
            "20",
            "--out",
            str(out),
            "--json",
        ]
    )
    assert status == 0
    res = json.loads(capsys.readouterr().out)
    for key in (
        "linear_max_horizontal_error_m",
        "nonlinear_max_horizontal_error_m",
        "relative_difference",
        "rms_difference_m",
    ):
        assert res[key] is not None
    assert res["relative_difference"] < REL_TOL
    assert (out / "horizontal_overlay.png").is_file()


def test_monte_carlo_without_a_random_error_is_refused_before_any_work(pyins, capsys):
    from inserr.cli.main import main

    argv = ["validate", "--duration", "0.2 h", "--gyro-bias", "0.02", "--runs", "5", "--json"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "--runs (scenario.runs)" in err and "validate.random_constants" in err
