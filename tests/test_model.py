"""Physics of the psi-angle error model against independent closed forms."""

import math

import numpy as np
import pytest
import scipy.linalg as sl
from scipy.integrate import quad_vec

from inserr.core.earth import OMEGA_IE, Site
from inserr.core.units import DEG, DEG_PER_HOUR, MICRO_G, PPM
from inserr.model.discretization import Discretizer
from inserr.model.exact_propagation import propagate_states
from inserr.model.psi_model import DR, PSI, ErrorModel, Layout, attitude_error, modes
from inserr.model.timeline import Timeline


@pytest.mark.parametrize("lat", [0.0, 34.0, 60.0])
def test_eigen_periods_match_schuler_and_foucault_formulas(lat):
    # Spherical Earth: the horizontal channels obey z'' + 2i Omega sinL z' + ws^2 z = 0
    # exactly, whose roots are the Foucault-split pair sqrt(ws^2 + (Omega sinL)^2) +- Omega sinL.
    site = Site.from_degrees(lat, spherical=True)
    m = modes(ErrorModel(site))
    ws = math.sqrt(site.g / site.r_n)
    ou = OMEGA_IE * math.sin(site.lat)
    pair = np.sort(m.eigenvalues.imag[m.eigenvalues.imag > 0])[-2:]  # Schuler band, rad/s
    hi, lo = math.sqrt(ws**2 + ou**2) + ou, math.sqrt(ws**2 + ou**2) - ou
    # rtol 1e-9: eigvals of a 9x9 real matrix, entries O(g), eigenvalues O(1e-3).
    assert pair[1] == pytest.approx(hi, rel=1e-9)
    assert pair[0] == pytest.approx(lo, rel=1e-9)
    assert m.schuler_period_s == pytest.approx(2 * math.pi * math.sqrt(site.r_n / site.g), rel=1e-9)
    if lat == 0.0:
        assert math.isinf(m.foucault_period_s)
    else:
        assert m.foucault_period_s == pytest.approx(2 * math.pi / ou, rel=1e-9)
    assert m.earth_period_s == pytest.approx(2 * math.pi / OMEGA_IE, rel=1e-12)


def test_ellipsoid_modes_at_34_deg_meet_issue_figures():
    # WGS84: east and north Schuler frequencies differ by ~0.2 %, which perturbs the
    # Foucault split by (dw/2)^2 / (2 ou^2) ~ 6e-4 relative at 34 deg.
    site = Site.from_degrees(34.0)
    m = modes(ErrorModel(site))
    assert 84.4 <= m.schuler_period_s / 60 <= 84.6
    # Geometric mean of sqrt(g/R_N) and sqrt(g/R_M) up to the anisotropy's effect on the
    # split, ~(dw/ou)^2 ~ 1e-3 of a ~1e-3 correction.
    assert m.schuler_period_s == pytest.approx(
        2 * math.pi * (site.r_m * site.r_n) ** 0.25 / math.sqrt(site.g), rel=1e-5
    )
    assert m.foucault_period_s / 3600 == pytest.approx(
        23.9345 / math.sin(math.radians(34)), rel=2e-3
    )
    assert m.earth_period_s / 3600 == pytest.approx(23.9345, abs=1e-3)


def test_control_discretization_equals_expm_of_augmented_matrix():
    model = ErrorModel(
        Site.from_degrees(34.0), Layout(scale_misalignment=True, bias_instability=True)
    )
    w = np.array([0.01, -0.02, 0.1])
    d = Discretizer(model)
    phi = d.transition(w, 7.3)
    n = model.layout.n
    aug = np.zeros((n + 1, n + 1))
    aug[:n, :n] = model.matrix(w)
    ref = sl.expm(aug * 7.3)[:n, :n]
    # Entries reach O(g dt) ~ 600; both are scaling-and-squaring expm: agree to ~1e-14 relative.
    tol = 1e-14 * np.abs(ref).max()
    assert np.allclose(phi, ref, rtol=0, atol=tol)
    # The batched path used for continuous motion gives the same numbers.
    batch = d.transitions(np.array([w, -w]), np.array([7.3, 2.0]))
    assert np.allclose(batch[0], ref, atol=tol)
    assert np.allclose(batch[1], sl.expm(model.matrix(-w) * 2.0), atol=tol)
    # Short pieces of a stop (w = 0) take the same structured path: still expm.
    zero = np.zeros(3)
    for h in (0.37, 59.9):
        assert d._use_structured(d.key(zero, h))
        ref = sl.expm(model.matrix(zero) * h)
        tol_h = 1e-14 * np.abs(ref).max()  # entries reach ~3e5 (dr per bias) at 60 s
        assert np.allclose(d.transitions(zero[None], np.array([h]))[0], ref, rtol=0, atol=tol_h)
    assert not d._use_structured(d.key(zero, 300.0))  # a whole stop: python-control


def test_structured_path_respects_a_short_correlation_time():
    """A 1 s Gauss-Markov bias makes the integrand decay fast: a 59 s stop piece must not
    take the quadrature (it gave a 6e-2 relative error); a 0.2 s one may, exactly."""
    model = ErrorModel(
        Site.from_degrees(34.0),
        Layout(bias_instability=True),
        gyro_correlation_time=1.0,
        accel_correlation_time=1.0,
    )
    d = Discretizer(model)
    zero = np.zeros(3)
    for h, structured in ((59.0, False), (0.2, True)):
        assert d._use_structured(d.key(zero, h)) is structured
        ref = sl.expm(model.matrix(zero) * h)
        got = d.transitions(zero[None], np.array([h]))[0]
        # Two scaling-and-squaring expm of a stiff matrix (1/tau = 1 against Schuler
        # 1e-3) agree to ~2e-13 of the largest entry; the quadrature, when wrongly
        # used, was off by 6e-2.
        assert np.allclose(got, ref, rtol=0, atol=1e-12 * np.abs(ref).max())


def test_van_loan_noise_equals_quadrature():
    model = ErrorModel(
        Site.from_degrees(34.0),
        Layout(bias=False, bias_instability=True),
        gyro_correlation_time=500.0,
        accel_correlation_time=800.0,
    )
    q = model.noise_intensity(1e-5, 1e-4, 1e-6, 1e-4)
    d = Discretizer(model, q)
    w = np.array([0.0, 0.0, 0.1])
    a = model.matrix(w)
    g = model.noise_input()
    dt = 30.0
    ref, _ = quad_vec(
        lambda s: sl.expm(a * s) @ g @ q @ g.T @ sl.expm(a * s).T,
        0.0,
        dt,
        epsabs=1e-20,
        epsrel=1e-12,
    )
    qd = d.noise(w, dt)
    # Adaptive quadrature at epsrel 1e-12 vs Van Loan's expm: 1e-12 of the largest entry.
    assert np.allclose(qd, ref, rtol=0, atol=1e-12 * np.abs(ref).max())


def _psi_closed_form(site, eps_n, t):
    """psi(t) for a constant n-frame gyro error: rotation about Omega (Rodrigues)."""
    om = site.earth_rate_n
    w = np.linalg.norm(om)
    u = om / w
    par = u * (u @ eps_n)
    perp = eps_n - par
    return -(par * t + math.sin(w * t) / w * perp - (1 - math.cos(w * t)) / w * np.cross(u, perp))


def _static_run(site, layout, x0, t_out, **kw):
    model = ErrorModel(site, layout, **kw)
    tl = Timeline.static(np.eye(3), float(t_out[-1]))
    return propagate_states(Discretizer(model), tl, x0, t_out)


def test_psi_obeys_closed_form_for_constant_gyro_bias():
    # psi' = -Omega x psi - eps is decoupled from velocity and position in the psi model.
    site = Site.from_degrees(34.0)
    model = ErrorModel(site)
    x0 = np.zeros(model.layout.n)
    eps = np.array([0.01, -0.02, 0.03]) * DEG_PER_HOUR
    x0[model.layout["eps"]] = eps
    t = np.array([0.0, 3600.0, 86400.0, 3 * 86400.0])
    nav = _static_run(site, model.layout, x0, t)
    for k, tk in enumerate(t):
        # 1e-7: one expm over a whole day of a matrix with O(g) entries loses ~1e-8 to
        # scaling-and-squaring roundoff.
        assert np.allclose(nav[k, PSI], _psi_closed_form(site, eps, tk), rtol=1e-7, atol=1e-15)


def test_accelerometer_bias_gives_foucault_modulated_schuler_tilt():
    # Spherical Earth, constant horizontal accel bias a = nE + i nN: the horizontal error
    # z = dr_E + i dr_N solves z'' + 2i ou z' + ws^2 z = a, z(0) = z'(0) = 0; psi stays 0.
    site = Site.from_degrees(34.0, spherical=True)
    model = ErrorModel(site)
    nab = np.array([100.0, -50.0, 0.0]) * MICRO_G
    x0 = np.zeros(model.layout.n)
    x0[model.layout["nabla"]] = nab
    t = np.linspace(0, 6 * 3600.0, 7)
    nav = _static_run(site, model.layout, x0, t)
    ws2 = site.g / site.r_n
    ou = OMEGA_IE * math.sin(site.lat)
    lam = np.array([-ou + math.sqrt(ou**2 + ws2), -ou - math.sqrt(ou**2 + ws2)])
    a = nab[0] + 1j * nab[1]
    # Homogeneous coefficients from z(0) = -a/ws^2 (particular part a/ws^2) and z'(0) = 0.
    coef = np.linalg.solve(
        np.array([[1, 1], [lam[0], lam[1]]], dtype=complex), np.array([-a / ws2, 0])
    )
    z = a / ws2 + coef[0] * np.exp(1j * lam[0] * t) + coef[1] * np.exp(1j * lam[1] * t)
    assert np.allclose(nav[:, 6] + 1j * nav[:, 7], z, rtol=0, atol=1e-6 * abs(a) / ws2)
    assert np.allclose(nav[:, PSI], 0.0)
    # Tilt phi = dtheta: its time average is the classic -nabla/g level error (phi_N = nE/g).
    tt = np.linspace(0, 2 * math.pi / math.sqrt(ws2), 400, endpoint=False)
    navf = _static_run(site, model.layout, x0, tt)
    phi = attitude_error(site, navf)
    assert phi[:, 1].mean() == pytest.approx(
        nab[0] / site.g, rel=2e-2
    )  # 2 %: Foucault turn in one period
    assert phi[:, 0].mean() == pytest.approx(-nab[1] / site.g, rel=4e-2)


def test_longitude_error_grows_with_gyro_drift_along_earth_axis():
    # Classic static-INS result: the drift component along Earth's axis, eps . Omega_hat,
    # makes the longitude error grow at that rate; the other components give bounded
    # (24 h periodic) errors. Measured over one sidereal day to cancel those.
    site = Site.from_degrees(34.0)
    model = ErrorModel(site)
    for eps in (np.array([0, 0.01, 0]), np.array([0, 0, 0.01]), np.array([0.01, 0, 0])):
        eps = eps * DEG_PER_HOUR
        x0 = np.zeros(model.layout.n)
        x0[model.layout["eps"]] = eps
        day = 2 * math.pi / OMEGA_IE
        t = np.array([0.0, day, 2 * day])
        nav = _static_run(site, model.layout, x0, t)
        dlon = nav[:, 6] / (site.r_n * math.cos(site.lat))
        slope = (dlon[2] - dlon[1]) / day
        expected = eps @ site.earth_rate_n / OMEGA_IE
        # 1e-2 of the largest drift: quasi-static Schuler tracking is exact to (Omega/ws)^2 ~ 3e-3
        # and the Schuler transient is bounded.
        assert slope == pytest.approx(expected, abs=1e-2 * 0.01 * DEG_PER_HOUR)


def test_up_gyro_bias_gives_heading_drift():
    site = Site.from_degrees(34.0)
    model = ErrorModel(site)
    x0 = np.zeros(model.layout.n)
    eps_u = 0.02 * DEG_PER_HOUR
    x0[model.layout["eps"]] = [0, 0, eps_u]
    t = np.array([0.0, 300.0, 600.0])
    phi = attitude_error(site, _static_run(site, model.layout, x0, t))
    # phi_U = -eps_U t up to (Omega t)^2 / 6 ~ 3e-4 relative at 10 min.
    assert phi[1:, 2] == pytest.approx(-eps_u * t[1:], rel=1e-3)


def test_scale_factor_times_table_rate_grows_heading_error():
    # A level IMU turning at w about up with z-gyro scale-factor error dK: the gyro
    # over-reads the total up rate (w + Omega sinL) by dK, so phi_U' = -dK (w + Omega sinL).
    site = Site.from_degrees(34.0)
    model = ErrorModel(site, Layout(scale_misalignment=True))
    dk = 50 * PPM
    w = 6 * DEG
    x0 = np.zeros(model.layout.n)
    k = np.diag([0.0, 0.0, dk])
    x0[model.layout["kg"]] = k.reshape(-1)  # invariant under rotation about z
    tl = Timeline(
        np.array([0.0, 60.0, 120.0]), np.stack([np.eye(3)] * 3), np.array([[0, 0, w], [0, 0, w]])
    )
    t = np.array([0.0, 30.0, 120.0])
    phi = attitude_error(site, propagate_states(Discretizer(model), tl, x0, t))
    rate = -dk * (w + OMEGA_IE * math.sin(site.lat))
    # psi_U leaks into psi_E at Omega cos L and back: a relative (Omega cos L t)^2 / 6
    # = 9e-6 at 2 min; 2e-5 bounds it.
    assert phi[1:, 2] == pytest.approx(rate * t[1:], rel=2e-5)


def test_imu_frame_model_has_textbook_input_matrix():
    site = Site.from_degrees(34.0)
    model = ErrorModel(site)
    c = Timeline.static(np.eye(3), 1.0).c_sn[0]
    rng = np.random.default_rng(3)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    c = q * np.sign(np.linalg.det(q))
    sys = model.state_space_imu(c)
    lay = model.layout
    assert np.allclose(sys.A[PSI, lay["eps"]], -c)
    # The vertical velocity row is clamped (aided vertical channel) by default.
    assert np.allclose(sys.A[3:5, lay["nabla"]], c[:2])
    assert np.allclose(sys.A[5, :], 0.0)
    assert np.allclose(sys.A[lay["eps"], :], 0.0)


def test_free_vertical_channel_diverges_with_sqrt_2g_over_r():
    site = Site.from_degrees(34.0)
    m = modes(ErrorModel(site, vertical="free"))
    # Coriolis couples dv_U and dv_E (2 Omega cos L), shifting s^2 = 2g/R by (2 Omega cos L)^2:
    # a relative (2 Omega cos L)^2 / (4 g / R) = 2.4e-3 change of the time constant.
    assert m.vertical_time_constant_s == pytest.approx(
        math.sqrt(site.mean_radius / (2 * site.g)), rel=3e-3
    )


def test_position_error_initial_condition_keeps_phi():
    # An initial position error alone is not an attitude error: phi(0) = 0.
    site = Site.from_degrees(34.0)
    from inserr.model.error_sources import Source, unit_column

    model = ErrorModel(site)
    x = unit_column(model, Source("initial_position_e", "initial_position", 10.0), np.eye(3)) * 10.0
    assert np.allclose(attitude_error(site, x[:9]), 0.0, atol=1e-18)
    assert x[DR][0] == 10.0


def test_imu_transform_resolves_every_error_block_in_the_imu_frame():
    # Built by hand: IMU-frame biases b resolved in n are C b, error matrices K are
    # C K C^T (vec row-major); T must take them back to b and K, every block, and leave
    # the navigation states alone.
    model = ErrorModel(
        Site.from_degrees(34.0),
        Layout(bias=True, scale_misalignment=True, bias_instability=True),
    )
    lay = model.layout
    rng = np.random.default_rng(3)
    c = sl.expm(np.cross(np.eye(3), rng.normal(size=3)))  # a random rotation C_s^n
    x, want = np.zeros(lay.n), np.zeros(lay.n)
    x[:9] = want[:9] = rng.normal(size=9)
    for key in ("eps", "nabla", "bg", "ba"):
        b = rng.normal(size=3)
        x[lay[key]], want[lay[key]] = c @ b, b
    for key in ("kg", "ka"):
        k = rng.normal(size=(3, 3))
        x[lay[key]], want[lay[key]] = (c @ k @ c.T).ravel(), k.ravel()
    assert np.allclose(model.imu_transform(c) @ x, want, rtol=0, atol=1e-12)


def test_noise_intensity_and_attitude_error_of_augmented_states():
    # White-noise PSDs: ARW^2 (gyro), VRW^2 (accelerometer), 2 sigma^2 / tau per
    # Gauss-Markov bias, none by default. phi reads the first nine states of a longer
    # state (psi + dtheta with dtheta = [-dr_N / R_M, dr_E / R_N, dr_E tan L / R_N]).
    site = Site.from_degrees(34.0)
    model = ErrorModel(site, gyro_correlation_time=100.0, accel_correlation_time=50.0)
    q = np.diag(model.noise_intensity(2e-6, 3e-5))
    assert np.array_equal(q, np.repeat([4e-12, 9e-10, 0.0, 0.0], 3))
    q = np.diag(model.noise_intensity(2e-6, 3e-5, 1e-7, 2e-4))
    assert np.allclose(q, np.repeat([4e-12, 9e-10, 2e-14 / 100.0, 8e-8 / 50.0], 3), rtol=1e-15)
    x = np.zeros(15)
    x[:3] = [1e-6, -2e-6, 3e-6]
    x[6:8] = [100.0, -50.0]
    x[9:] = 7.0  # augmented states: not read
    tan = math.tan(math.radians(34.0))
    want = [1e-6 + 50.0 / site.r_m, -2e-6 + 100.0 / site.r_n, 3e-6 + 100.0 * tan / site.r_n]
    assert np.allclose(attitude_error(site, x), want, rtol=1e-12, atol=0)


@pytest.mark.parametrize("vertical", ["clamped", "free"])
def test_coupled_exo_is_the_input_block_times_the_exo_exponential(vertical):
    # Its definition: B(w) expm(E(w) s), with B the nav-by-exo block and E the exo block
    # of the model's own matrix, the exponential by scipy; every exo kind, both vertical
    # modes (clamped: no dv_U rows), two rates and three times at once.
    model = ErrorModel(
        Site.from_degrees(34.0),
        Layout(bias=True, scale_misalignment=True, bias_instability=True),
        vertical=vertical,
        gyro_correlation_time=300.0,
        accel_correlation_time=200.0,
    )
    w = np.array([[0.0, 0.0, 0.0], [0.02, -0.05, 0.1]])
    s = np.array([0.0, 7.5, 40.0])
    got = model.coupled_exo(w, s)
    assert got.shape == (2, 3, 9, model.layout.n - 9)
    for k in range(2):
        a = model.matrix(w[k])
        b, e = a[:9, 9:], a[9:, 9:]
        for j in range(3):
            want = b @ sl.expm(e * s[j])
            assert np.allclose(got[k, j], want, rtol=1e-12, atol=1e-12 * np.abs(want).max())
    assert np.any(got[..., 5, :] != 0.0) == (vertical == "free")
    # One rate and one time given as (3,) and a float: the same, shaped (1, 1, ...).
    assert np.array_equal(model.coupled_exo(w[1], 7.5), got[1:2, 1:2])
    e_s = model.exo_transition(w[1], 7.5)
    assert e_s.shape == (1, 1, model.layout.n - 9, model.layout.n - 9)
    want = sl.expm(model.matrix(w[1])[9:, 9:] * 7.5)
    assert np.allclose(e_s[0, 0], want, rtol=1e-12, atol=1e-13)


def test_timeline_takes_sequences_and_refuses_what_is_not_a_timeline():
    from inserr.core.errors import InputError

    # Plain sequences become float arrays of the documented shapes (omega_n may come
    # flat), and the labels default to one empty label per interval.
    eye = np.eye(3).tolist()
    tl = Timeline([0, 60, 90], [eye, eye, eye], [0.0, 0.0, 0.1, 0.0, 0.0, -0.1])
    assert isinstance(tl.times, np.ndarray) and tl.times.dtype == float
    assert isinstance(tl.c_sn, np.ndarray) and tl.c_sn.shape == (3, 3, 3)
    assert isinstance(tl.omega_n, np.ndarray) and tl.omega_n.shape == (2, 3)
    assert tl.omega_n[1, 2] == -0.1 and tl.labels == ("", "") and tl.duration == 90.0
    still = Timeline.static(np.eye(3), 30.0, "hold")
    assert still.labels == ("hold",) and np.array_equal(still.times, [0.0, 30.0])
    assert np.array_equal(still.omega_n, np.zeros((1, 3)))
    # Each condition on its own is refused.
    c3, w2 = np.stack([np.eye(3)] * 3), np.zeros((2, 3))
    for times, c, w in (
        ([1.0, 60.0, 90.0], c3, w2),  # does not start at 0
        ([0.0, 60.0, 60.0], c3, w2),  # a node repeated: an empty interval
        ([0.0, 60.0, 30.0], c3, w2),  # decreasing
        ([[0.0, 60.0, 90.0]], c3, w2),  # not one-dimensional
        ([0.0], c3[:1], np.zeros((0, 3))),  # one node: no interval
        ([0.0, 60.0, 90.0], c3[:2], w2),  # one attitude short
        ([0.0, 60.0, 90.0], c3, np.zeros((3, 3))),  # one rate too many
    ):
        with pytest.raises(InputError, match="timeline"):
            Timeline(np.array(times), c, w)


def test_layout_blocks_are_where_the_documented_names_are():
    # Every block a layout documents, read through layout[key], holds the states of
    # that name (psi, dv, dr, nav first; then the carried error blocks in order).
    lay = Layout(bias=True, scale_misalignment=True, bias_instability=True)
    assert (lay["psi"], lay["dv"], lay["dr"], lay["nav"]) == (
        slice(0, 3),
        slice(3, 6),
        slice(6, 9),
        slice(0, 9),
    )
    prefixes = {"psi": "psi_", "dv": "dv_", "dr": "dr_", "eps": "eps_", "nabla": "nabla_",
                "kg": "kg_", "ka": "ka_", "bg": "bg_", "ba": "ba_"}  # fmt: skip
    for key, prefix in prefixes.items():
        names = lay.names[lay[key]]
        assert len(names) == (9 if key in ("kg", "ka") else 3)
        assert all(n.startswith(prefix) for n in names), (key, names)
    assert lay.names[lay["nav"]] == lay.names[:9] and lay.n == 9 + 6 + 18 + 6
    assert set(Layout(bias=False).slices) == {"psi", "dv", "dr", "nav"}


def test_vertical_initial_errors_count_only_with_a_free_vertical_channel():
    # Clamped, the vertical velocity and position errors are dropped; free, each counts
    # with its own value (neither scaled nor dropped), the horizontal ones either way.
    from inserr.core.imu import ImuErrors, InitialErrors
    from inserr.model.error_sources import constant_sources

    init = InitialErrors(velocity=np.array([0.1, 0.2, 0.3]), position=np.array([4.0, 5.0, 6.0]))
    for vertical, kept in (("clamped", {}), ("free", {"initial_velocity_u": 0.3,
                                                     "initial_position_u": 6.0})):  # fmt: skip
        got = {s.name: s.value for s in constant_sources(ImuErrors(), init, vertical)}
        want = {"initial_velocity_e": 0.1, "initial_velocity_n": 0.2,
                "initial_position_e": 4.0, "initial_position_n": 5.0, **kept}  # fmt: skip
        assert got == want, vertical
