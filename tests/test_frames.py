"""Frame equivalences of the error model that need no optional extra (issue 18, item 1).

Every expected value here is built without the code's own projection of IMU-frame
errors into the navigation frame: the comparison run is an IMU aligned with ENU
(``C_s^n = I``, where any projection, right or transposed, is the identity) whose
errors are resolved by hand in this file (``C b``, ``C K C^T``), or a closed form
with the WGS84 radii and gravity computed here from the defining constants.

Both discretization paths of the engine are exercised: 1 s output steps take the
structured (quadrature) path, whole 900 s steps python-control's ``sample_system``
(see :mod:`inserr.model.discretization`), so a sign or transpose slipped into only
one of the two is caught.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from inserr.core.earth import Site
from inserr.core.imu import ImuErrors, InitialErrors
from inserr.core.units import ARCSEC, DEG, DEG_PER_HOUR, MICRO_G, PPM
from inserr.drift.analysis import analyze_drift
from inserr.model.discretization import Discretizer
from inserr.model.exact_propagation import propagate_states
from inserr.model.psi_model import ErrorModel, Layout, attitude_error, position_angle
from inserr.model.timeline import Timeline

# --- WGS84, from its defining constants (independent of inserr.core.earth) ----------
WGS84_A = 6378137.0
WGS84_F = 1.0 / 298.257223563
WGS84_E2 = WGS84_F * (2.0 - WGS84_F)
WGS84_GAMMA_E = 9.7803253359
WGS84_GAMMA_P = 9.8321849378
EARTH_RATE = 7.292115e-5  # rad/s, the WGS84 value

#: Both engines of analyze_drift: the fast (modal) one, the default; the step-by-step
#: exact one with 1 s steps (structured path) and with 900 s steps (python-control).
PATHS = pytest.mark.parametrize(
    "engine, dt_out, dt_cov",
    [("fast", 1.0, 60.0), ("exact", 1.0, 60.0), ("exact", 900.0, 900.0)],
    ids=["fast", "exact-structured", "exact-python-control"],
)


def wgs84_radii(lat: float) -> tuple[float, float]:
    """Meridian R_M and prime-vertical R_N radii of curvature at the ellipsoid, m."""
    s2 = math.sin(lat) ** 2
    r_n = WGS84_A / math.sqrt(1.0 - WGS84_E2 * s2)
    r_m = WGS84_A * (1.0 - WGS84_E2) / (1.0 - WGS84_E2 * s2) ** 1.5
    return r_m, r_n


def wgs84_gravity(lat: float) -> float:
    """Somigliana normal gravity on the ellipsoid, m/s^2."""
    b = WGS84_A * (1.0 - WGS84_F)
    k = b * WGS84_GAMMA_P / (WGS84_A * WGS84_GAMMA_E) - 1.0
    s2 = math.sin(lat) ** 2
    return WGS84_GAMMA_E * (1.0 + k * s2) / math.sqrt(1.0 - WGS84_E2 * s2)


def _random_rotation(seed: int) -> np.ndarray:
    """A proper rotation (det +1) from the QR factors of a Gaussian matrix."""
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q * np.linalg.det(q)


def _rot_up(angle: float) -> np.ndarray:
    """Right-hand turn by ``angle`` about ENU up, written out (no inserr rotation code)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _imu_from_k(gyro_bias, accel_bias, k_g, k_a) -> ImuErrors:
    """ImuErrors whose error matrices are ``k_g``, ``k_a`` (diagonal = scale factors;
    misalignments in the documented order xy, xz, yx, yz, zx, zy = K[row, column])."""
    order = [(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)]
    return ImuErrors(
        gyro_bias=gyro_bias,
        accel_bias=accel_bias,
        gyro_scale_factor=np.diag(k_g).copy(),
        accel_scale_factor=np.diag(k_a).copy(),
        gyro_misalignment=np.array([k_g[i, j] for i, j in order]),
        accel_misalignment=np.array([k_a[i, j] for i, j in order]),
    )


def _stop_turn_stop(c0: np.ndarray, rate: float = 6 * DEG) -> Timeline:
    """Stop 600 s, turn about ENU up at ``rate`` for 60 s, stop 1740 s (40 min in all).

    Node attitudes ``rot_up(angle) @ c0`` are written out here, so the turning IMU's
    attitude history does not come from the code under test.
    """
    times = np.array([0.0, 600.0, 660.0, 2400.0])
    c_turned = _rot_up(rate * 60.0) @ c0
    return Timeline(
        times,
        np.stack([c0, c0, c_turned, c_turned]),
        np.array([[0, 0, 0], [0, 0, rate], [0, 0, 0]]),
    )


#: Roundoff floors per navigation state (psi rad, dv m/s, dr m): states a source does not
#: drive (e.g. psi under an accelerometer error) hold ~1e-17 of python-control roundoff.
NAV_FLOOR = np.array([1e-15] * 3 + [1e-12] * 3 + [1e-9] * 3)


def _assert_same_nav(a, b, rtol=1e-9):
    # The two runs differ only by where C multiplies the initial exo state (C @ e vs a
    # hand-resolved vector): roundoff ~1e-16 relative, amplified by nothing (the same
    # transition matrices act on both). 1e-9 of each state's largest value leaves room
    # for the cancellation in near-zero components; a frame error is O(1) relative.
    scale = np.abs(b).max(axis=0)
    assert np.all(np.abs(a - b) <= rtol * scale + NAV_FLOOR)


@PATHS
def test_imu_frame_errors_on_a_turned_tilted_imu_equal_hand_resolved_errors_on_an_aligned_imu(
    engine, dt_out, dt_cov
):
    """IMU at a random (turned and tilted) attitude C with IMU-frame biases b and
    error matrices K equals an IMU aligned with ENU carrying C b and C K C^T.

    For a static base this is an identity the model must satisfy; here the IMU also
    turns about ENU up (C(t) = R(t) C against R(t) I), which keeps it an identity
    because the IMU errors resolved in n are the same at every time.
    """
    site = Site.from_degrees(34.0)
    c = _random_rotation(11)
    assert abs(math.acos(c[2, 2])) > 10 * DEG  # tilted, not just turned
    rng = np.random.default_rng(12)
    b_g = rng.normal(size=3) * 0.01 * DEG_PER_HOUR
    b_a = rng.normal(size=3) * 50 * MICRO_G
    k_g = rng.normal(size=(3, 3)) * 20 * PPM
    k_a = rng.normal(size=(3, 3)) * 30 * PPM
    turned = analyze_drift(
        site,
        _imu_from_k(b_g, b_a, k_g, k_a),
        InitialErrors(),
        _stop_turn_stop(c),
        dt_out=dt_out,
        dt_cov=dt_cov,
        engine=engine,
    )
    aligned = analyze_drift(
        site,
        _imu_from_k(c @ b_g, c @ b_a, c @ k_g @ c.T, c @ k_a @ c.T),
        InitialErrors(),
        _stop_turn_stop(np.eye(3)),
        dt_out=dt_out,
        dt_cov=dt_cov,
        engine=engine,
    )
    assert np.abs(aligned.nav[-1, 6:8]).max() > 1.0  # metres: a real response, not zeros
    _assert_same_nav(turned.nav, aligned.nav)


@PATHS
def test_heading_rotated_static_imu_x_gyro_bias_is_the_rotated_bias(engine, dt_out, dt_cov):
    """An IMU at heading 90 deg (y forward pointing east, x right pointing south, z up)
    with an x gyro bias b is an aligned IMU with a y (north) gyro bias of -b.

    The run must start from the timeline's C_s^n(0), not from the identity.
    """
    site = Site.from_degrees(34.0)
    # Columns: IMU x -> south, IMU y -> east, IMU z -> up (ENU components).
    c_east = np.array([[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    b = 0.02 * DEG_PER_HOUR
    tl_east = Timeline.static(c_east, 7200.0)
    tl_north = Timeline.static(np.eye(3), 7200.0)
    east = analyze_drift(
        site,
        ImuErrors(gyro_bias=[b, 0, 0]),
        InitialErrors(),
        tl_east,
        dt_out=dt_out,
        dt_cov=dt_cov,
        engine=engine,
    )
    north = analyze_drift(
        site,
        ImuErrors(gyro_bias=[0, -b, 0]),
        InitialErrors(),
        tl_north,
        dt_out=dt_out,
        dt_cov=dt_cov,
        engine=engine,
    )
    _assert_same_nav(east.nav, north.nav)
    # And it is not the unrotated bias (which would drive the east tilt instead).
    wrong = analyze_drift(
        site,
        ImuErrors(gyro_bias=[b, 0, 0]),
        InitialErrors(),
        tl_north,
        dt_out=dt_out,
        dt_cov=dt_cov,
        engine=engine,
    )
    assert np.abs(wrong.nav[-1] - east.nav[-1]).max() > 0.1 * np.abs(east.nav[-1]).max()


# Sensor-model sign convention (inserr.core.imu): measured = (I + K) true + bias, with
# K[row, col] the sensitivity of the row sensor to the column input; misalignment "xz"
# is K[0, 2], the x sensor's sensitivity to the z input. On a level IMU aligned with ENU
# at rest the true inputs are the Earth rate [0, W cos L, W sin L] (gyros) and the
# specific force [0, 0, g] (accelerometers), so K[i, j] k acts exactly as a bias
# k * input_j on axis i.
K_CASES = [
    # (sensor, scale-factor axis or misalignment name, axis that sees the error, input)
    ("accel", "xz", 0, "g"),
    ("accel", "yz", 1, "g"),
    ("gyro", "z", 2, "up"),
    ("gyro", "y", 1, "north"),
    ("gyro", "xz", 0, "up"),
    ("gyro", "xy", 0, "north"),
    ("gyro", "zy", 2, "north"),
]


@PATHS
@pytest.mark.parametrize("sensor, name, axis, source", K_CASES)
def test_error_matrix_entry_on_a_static_aligned_imu_equals_a_bias(
    sensor, name, axis, source, engine, dt_out, dt_cov
):
    lat = 34.0 * DEG
    site = Site(lat)
    k = 40 * PPM
    inputs = {
        "g": wgs84_gravity(lat),
        "up": EARTH_RATE * math.sin(lat),
        "north": EARTH_RATE * math.cos(lat),
    }
    order = ("xy", "xz", "yx", "yz", "zx", "zy")
    kw = {}
    if name in order:
        mis = np.zeros(6)
        mis[order.index(name)] = k
        kw[f"{sensor}_misalignment"] = mis
    else:
        sf = np.zeros(3)
        sf["xyz".index(name)] = k
        kw[f"{sensor}_scale_factor"] = sf
    bias = np.zeros(3)
    bias[axis] = k * inputs[source]
    tl = Timeline.static(np.eye(3), 7200.0)
    with_k = analyze_drift(
        site, ImuErrors(**kw), InitialErrors(), tl, dt_out=dt_out, dt_cov=dt_cov, engine=engine
    )
    with_bias = analyze_drift(
        site,
        ImuErrors(**{f"{sensor}_bias": bias}),
        InitialErrors(),
        tl,
        dt_out=dt_out,
        dt_cov=dt_cov,
        engine=engine,
    )
    assert np.abs(with_bias.nav[-1, 6:8]).max() > 1e-3  # a real response (metres)
    # Gravity: the test's Somigliana from the WGS84 defining constants and the code's
    # differ by ~1e-15 relative; everything else is the same propagation.
    _assert_same_nav(with_k.nav, with_bias.nav, rtol=1e-9)


def test_kg_and_ka_states_follow_c_k_ct_on_a_turning_tilted_imu():
    # K^n(t) = C_s^n(t) K C_s^n(t)^T at every node, with the node attitudes written out.
    site = Site.from_degrees(34.0)
    model = ErrorModel(site, Layout(scale_misalignment=True))
    c0 = _random_rotation(21)
    tl = _stop_turn_stop(c0)
    k = np.random.default_rng(22).normal(size=(3, 3))
    x0 = np.zeros(model.layout.n)
    x0[model.layout["kg"]] = (c0 @ k @ c0.T).reshape(-1)
    x0[model.layout["ka"]] = (c0 @ (2 * k) @ c0.T).reshape(-1)
    # Output at the nodes and in the middle of the turn (1 s steps: structured path).
    t = np.concatenate([tl.times, np.arange(601.0, 660.0, 7.0)])
    t = np.unique(t)
    rows = np.r_[model.layout["kg"], model.layout["ka"]]
    got = propagate_states(Discretizer(model), tl, x0, t, rows=rows)
    for j, tj in enumerate(t):
        angle = 6 * DEG * min(max(tj - 600.0, 0.0), 60.0)
        cj = _rot_up(angle) @ c0
        want_g = (cj @ k @ cj.T).reshape(-1)
        # The engine quantizes w to OMEGA_QUANTUM = 1e-13 rad/s: up to 5e-14 rad/s x 60 s
        # = 3e-12 rad of turn, times entries of O(3); 1e-10 bounds it. A transposed or
        # sign-flipped rotation law is wrong by O(1).
        assert np.allclose(got[j, :9], want_g, rtol=0, atol=1e-10)
        assert np.allclose(got[j, 9:], 2 * want_g, rtol=0, atol=1e-10)


@PATHS
def test_east_and_north_schuler_channels_use_r_n_and_r_m(engine, dt_out, dt_cov):
    """At the equator the clamped horizontal channels decouple exactly (Omega sin L = 0
    removes the Coriolis and Foucault coupling; psi is not excited by a velocity error),
    so an initial velocity error v gives dr = v / w sin(w t) with w_E = sqrt(g / R_N)
    east and w_N = sqrt(g / R_M) north. R_N and R_M differ by 0.7 % at the equator:
    after five Schuler periods a swap moves the phase by 0.1 rad.
    """
    site = Site(0.0)
    g = wgs84_gravity(0.0)
    r_m, r_n = wgs84_radii(0.0)
    w_e, w_n = math.sqrt(g / r_n), math.sqrt(g / r_m)
    v = 0.1
    duration = 5 * 2 * math.pi / w_e
    res = analyze_drift(
        site,
        ImuErrors(),
        InitialErrors(velocity=[v, -v, 0.0]),
        Timeline.static(np.eye(3), duration),
        dt_out=dt_out,
        dt_cov=dt_cov,
        engine=engine,
    )
    t = res.t
    amp = v / w_e
    # 1e-7 of the amplitude: the exact transition over up to 7 h loses ~1e-9 relative
    # to roundoff; a swap of the radii is an error of ~0.1 of the amplitude.
    assert np.allclose(res.nav[:, 6], v / w_e * np.sin(w_e * t), rtol=0, atol=1e-7 * amp)
    assert np.allclose(res.nav[:, 7], -v / w_n * np.sin(w_n * t), rtol=0, atol=1e-7 * amp)
    assert np.allclose(res.nav[:, 3], v * np.cos(w_e * t), rtol=0, atol=1e-7 * v)
    assert np.allclose(res.nav[:, 4], -v * np.cos(w_n * t), rtol=0, atol=1e-7 * v)


def test_position_error_angle_uses_r_m_north_and_r_n_east():
    # dtheta = [-dr_N / R_M, dr_E / R_N, dr_E tan L / R_N] (docs/theory.md), radii here.
    lat = 34.0 * DEG
    site = Site(lat)
    r_m, r_n = wgs84_radii(lat)
    dr = np.array([[120.0, -75.0, 3.0], [-40.0, 310.0, 0.0]])
    want = np.stack([-dr[:, 1] / r_m, dr[:, 0] / r_n, dr[:, 0] * math.tan(lat) / r_n], axis=-1)
    # Radii from the same WGS84 constants: agree to ~1e-15 relative.
    assert np.allclose(position_angle(site, dr), want, rtol=1e-12, atol=0)
    psi = np.array([1e-5, -2e-5, 3e-5])
    nav = np.concatenate([psi, np.zeros(3), dr[0]])
    assert np.allclose(attitude_error(site, nav), psi + want[0], rtol=1e-12, atol=0)


@PATHS
def test_initial_east_position_error_at_the_equator_stays_put(engine, dt_out, dt_cov):
    """An initial east position error alone is not an attitude error: psi(0) = -dtheta
    = [0, -d / R_N, 0] is parallel to the Earth rate at the equator and exactly balances
    the gravity-gradient term g / R_N d, so nothing moves and phi stays zero."""
    site = Site(0.0)
    d = 500.0
    res = analyze_drift(
        site,
        ImuErrors(),
        InitialErrors(position=[d, 0.0, 0.0]),
        Timeline.static(np.eye(3), 6 * 3600.0),
        dt_out=dt_out,
        dt_cov=dt_cov,
        engine=engine,
    )
    # A wrong radius in psi(0) leaves g d (1/R_M - 1/R_N) ~ 5e-6 m/s^2 unbalanced, i.e.
    # ~ d (1 - R_M/R_N) = 3 m of Schuler oscillation; roundoff is ~1e-9 m.
    assert np.allclose(res.nav[:, 6], d, rtol=0, atol=1e-6)
    assert np.allclose(res.nav[:, 7], 0.0, rtol=0, atol=1e-6)
    assert np.allclose(res.attitude, 0.0, rtol=0, atol=1e-12)


def test_misalignment_sources_keep_their_names_and_signs_in_the_budget():
    # The per-source budget of a single xz accelerometer misalignment on a level aligned
    # IMU is the budget of the x accelerometer bias k g (same horizontal error, m).
    site = Site.from_degrees(34.0)
    k = 30 * ARCSEC
    tl = Timeline.static(np.eye(3), 3600.0)
    mis = analyze_drift(
        site, ImuErrors(accel_misalignment=[0, k, 0, 0, 0, 0]), InitialErrors(), tl, dt_cov=60.0
    )
    bias = analyze_drift(
        site,
        ImuErrors(accel_bias=[k * wgs84_gravity(site.lat), 0, 0]),
        InitialErrors(),
        tl,
        dt_cov=60.0,
    )
    assert [s.name for s in mis.sources] == ["accel_misalignment_xz"]
    assert mis.sources[0].value == k
    got = mis.metrics["error_budget"]["accel_misalignment_xz"]
    want = bias.metrics["error_budget"]["accel_bias_x"]
    assert want > 0 and got == pytest.approx(want, rel=1e-9)


def test_fast_engine_on_a_schedule_equals_the_exact_engine_on_its_timeline():
    """P2's four-position table (stops at -135, 45, 135, -45 deg: table matrices that are
    not symmetric, unlike the half turns of the dual-axis tables, so M and M^T differ) on a
    turned, tilted static base with every kind of IMU error:
    the fast engine reads the schedule (vehicle attitude seen through the table, never
    sub-stepped), the exact engine the timeline built from it (node attitudes from the
    gimbal geometry, rates from the gimbal axes). Two independent paths from the table
    to C_s^n(t), so a transposed table or gimbal geometry in either shows up."""
    from inserr.schemes.catalogue import build_scheme
    from inserr.schemes.composition import ScheduleHistory
    from inserr.schemes.vehicle_motion import Motion

    motion = Motion(heading=0.4, pitch=3 * DEG, roll=-2 * DEG)
    duration = 3600.0
    history = ScheduleHistory(
        build_scheme("four-position", 6 * DEG, 120.0).plan(motion, duration), motion, duration
    )
    rng = np.random.default_rng(3)
    imu = ImuErrors(
        gyro_bias=rng.normal(size=3) * 0.01 * DEG_PER_HOUR,
        accel_bias=rng.normal(size=3) * 50 * MICRO_G,
        gyro_scale_factor=rng.normal(size=3) * 20 * PPM,
        gyro_misalignment=rng.normal(size=6) * 20 * PPM,
        accel_misalignment=rng.normal(size=6) * 30 * PPM,
    )
    site = Site.from_degrees(34.0)
    kw = {"dt_out": 60.0, "dt_cov": 600.0}
    fast = analyze_drift(site, imu, InitialErrors(), history, **kw)
    exact = analyze_drift(site, imu, InitialErrors(), history, engine="exact", **kw)
    # Measured agreement ~3e-10 of each state's largest value (the fast engine's modal
    # quadrature); 1e-7 leaves room, a transposed table is an O(1) error.
    _assert_same_nav(fast.nav, exact.nav, rtol=1e-7)
