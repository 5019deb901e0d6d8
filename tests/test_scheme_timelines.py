"""The IMU attitude timelines that schemes and vehicle motions produce are self-consistent.

A :class:`~inserr.model.timeline.Timeline` promises that the constant angular velocity
``w_k`` of each interval carries the node attitude ``C_s^n(t_k)`` into
``C_s^n(t_{k+1}) = expm(dt_k [w_k x]) C_s^n(t_k)``: the error model integrates ``w``, the
projections use the nodes, so the two must agree for every gimbal (outer and inner,
in any order), every motion (static, tilted, swinging) and every sub-step. The check
uses scipy's matrix exponential, not inserr's rotation code.

The cycle integral of ``C_s^n`` read off the timeline (exact per interval, Simpson on
a fine grid along turns) also equals the closed form of
:func:`inserr.schemes.cycle_integrals.cycle_integrals`, which is written from the gimbal
geometry independently of the timeline composition.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg as sl

from inserr.core.units import DEG
from inserr.schemes.catalogue import build_scheme
from inserr.schemes.composition import build_timeline
from inserr.schemes.cycle_integrals import cycle_integrals
from inserr.schemes.open_loop import Step, TableScheme
from inserr.schemes.vehicle_motion import HeadingHistory, Motion, Turn, YawSwing


def _skew(w: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def _max_interval_mismatch(tl) -> float:
    dt = np.diff(tl.times)
    # expm(dt [w x]) by scipy for a handful of intervals, Rodrigues (written below) for all.
    for k in range(min(3, len(dt))):
        assert np.allclose(
            sl.expm(dt[k] * _skew(tl.omega_n[k])), _rodrigues(tl.omega_n[k], dt[k : k + 1])[0]
        )
    carried = np.array(
        [_rodrigues(w, np.array([h]))[0] for w, h in zip(tl.omega_n, dt, strict=True)]
    )
    return float(np.abs(carried @ tl.c_sn[:-1] - tl.c_sn[1:]).max())


TILTED = Motion(heading=0.4, pitch=3 * DEG, roll=-2 * DEG)
#: A dual-axis table with quarter turns of the outer gimbal: the inner axis then lies
#: along body y, where the catalogue's half turns (outer angle 0 or 180 deg) cannot tell
#: the inner axis's sense or the gimbal order apart.
QUARTER = TableScheme(
    "quarter-turns",
    (
        Step("outer", 90 * DEG, 20.0, label="B"),
        Step("inner", 180 * DEG, 20.0, label="C"),
        Step("outer", 90 * DEG, 20.0, label="D"),
        Step("inner", -180 * DEG, 20.0, label="E"),
        Step("outer", -180 * DEG, 20.0, label="A"),
    ),
    6 * DEG,
    20.0,
)


#: Half-second turns (3 deg at 6 deg/s): pieces shorter than a second, sub-step or not.
HALF_SECOND = TableScheme(
    "half-second-turns",
    (Step("outer", 3 * DEG, 20.0, label="B"), Step("outer", -3 * DEG, 20.0, label="A")),
    6 * DEG,
    20.0,
)
#: A steady turn of a tilted vehicle.
TURN = Turn(heading=0.2, pitch=3 * DEG, roll=2 * DEG, rate=0.5 * DEG)


def _scheme(name: str, stop: float):
    special = {"quarter-turns": QUARTER, "half-second-turns": HALF_SECOND}
    return special.get(name) or build_scheme(name, 6 * DEG, stop)


@pytest.mark.parametrize(
    "scheme, motion",
    [
        ("two-position", Motion()),
        ("four-position", TILTED),
        ("eight-position", Motion()),
        ("eight-position", TILTED),
        ("sixteen-position", TILTED),
        ("quarter-turns", Motion()),
        ("quarter-turns", TILTED),
        ("two-position", YawSwing(pitch=2 * DEG, roll=1 * DEG, amplitude=5 * DEG, period=90.0)),
        ("eight-position", YawSwing(pitch=2 * DEG, roll=1 * DEG, amplitude=5 * DEG, period=90.0)),
        ("four-position", TURN),
        ("half-second-turns", TILTED),
        ("two-position", "history"),
    ],
    ids=lambda p: p if isinstance(p, str) else type(p).__name__ + ("-tilted" if p.pitch else ""),
)
def test_interval_rates_carry_each_node_attitude_into_the_next(scheme, motion):
    s = _scheme(scheme, 20.0)
    duration = 1.5 * (s.cycle_time or 200.0)
    if motion == "history":
        # A tilted heading history sampled every 7 s, one sample 1e-12 s after a table
        # segment starts (a piece too short to keep: the rest must still be built), the
        # rate changing from sample to sample (a stop's exact rate is its own piece's).
        table = s.plan(TILTED, duration)
        times = np.union1d(np.arange(0.0, duration + 7.0, 7.0), [table.t0[2] + 1e-12])
        headings = np.cumsum(np.random.default_rng(2).normal(size=len(times))) * 0.03
        motion = HeadingHistory(pitch=3 * DEG, roll=-2 * DEG, times=times, headings=headings)
    table = s.plan(motion, duration)
    tl = build_timeline(table, motion, duration)
    # Exact intervals (stops, turns on a static base): w is the exact rate, error ~1e-15
    # per interval. Sub-steps of a swinging base: w is the geodesic rate between exact
    # nodes, so the nodes are carried exactly too. Wrong gimbal order, axis or frame
    # of a rate: an O(rate x dt) ~ 0.1 error. (A table turn on a steadily turning tilted
    # vehicle is not a constant-rate turn: its axis is not the vehicle's.)
    assert _max_interval_mismatch(tl) < 1e-9
    assert tl.times[0] == 0.0 and tl.times[-1] == duration
    # Every table segment starts at a node; no interval is shorter than 1e-9 s (the
    # history's 1e-12 s piece is dropped, not kept).
    starts = table.t0[table.t0 < duration]
    assert np.abs(tl.times[np.searchsorted(tl.times, starts - 1e-9)] - starts).max() < 1e-9
    assert np.diff(tl.times).min() > 1e-9
    # Each node's label is that of the table segment it lies in.
    seg = np.searchsorted(table.t0, tl.times[:-1] + 1e-6, side="right") - 1
    assert list(tl.labels) == [table.labels[k] for k in seg]
    # What the report and the figures read back: the table's motor starts, its motion.
    assert tl.motor_starts == table.motor_starts()
    assert tl.meta["table"] is table and tl.meta["motion"] is motion


def test_timeline_sub_steps_lie_on_the_global_grid():
    # Continuous motion is cut on the global grid of `substep` seconds (1 s by default):
    # every node of a sub-stepped piece is a piece start or a multiple of the sub-step,
    # and no sub-step is longer than it.
    motion = YawSwing(pitch=2 * DEG, roll=1 * DEG, amplitude=5 * DEG, period=90.0)
    table = build_scheme("two-position", 6 * DEG, 20.0).plan(motion, 300.0)
    from inserr.schemes.composition import ScheduleHistory

    history = ScheduleHistory(table, motion, 300.0)
    for substep, tl in ((1.0, build_timeline(table, motion, 300.0)), (1.0, history.timeline()),
                        (2.5, build_timeline(table, motion, 300.0, 2.5))):  # fmt: skip
        starts = set(np.round(table.t0, 9))
        on_grid = np.abs(tl.times / substep - np.round(tl.times / substep)) < 1e-9
        assert all(g or round(t, 9) in starts for t, g in zip(tl.times, on_grid, strict=True))
        assert np.diff(tl.times).max() <= substep + 1e-9
        assert np.diff(tl.times).max() > 0.99 * substep


def test_timeline_rejects_a_run_or_sub_step_that_is_not_a_positive_time():
    from inserr.core.errors import InputError
    from inserr.schemes.composition import ScheduleHistory

    table = build_scheme("two-position", 6 * DEG, 20.0).plan(Motion(), 10.0)
    assert build_timeline(table, Motion(), 0.5).times[-1] == 0.5  # shorter than a second
    assert ScheduleHistory(table, Motion(), 0.5).duration == 0.5
    for duration, substep in ((0.0, 1.0), (math.inf, 1.0), (10.0, 0.0), (10.0, math.inf)):
        with pytest.raises(InputError):
            build_timeline(table, Motion(), duration, substep)
    for duration in (0.0, -5.0, math.inf):
        with pytest.raises(InputError):
            ScheduleHistory(table, Motion(), duration)


def _timeline_cycle_integral(tl, t0: float, t1: float) -> np.ndarray:
    """int_{t0}^{t1} C_s^n dt along the timeline's own intervals (exact per interval)."""
    total = np.zeros((3, 3))
    for k, w in enumerate(tl.omega_n):
        a, b = max(tl.times[k], t0), min(tl.times[k + 1], t1)
        if b <= a:
            continue
        c_a = sl.expm((a - tl.times[k]) * _skew(w)) @ tl.c_sn[k]
        rate = np.linalg.norm(w)
        h = b - a
        if rate == 0.0:
            total += c_a * h
            continue
        # int_0^h expm(s [w x]) ds, Rodrigues integrated in closed form.
        u = _skew(w / rate)
        th = rate * h
        integral = (
            h * np.eye(3) + (1 - math.cos(th)) / rate * u + (h - math.sin(th) / rate) * (u @ u)
        )
        total += integral @ c_a
    return total


@pytest.mark.parametrize(
    "scheme", ["four-position", "eight-position", "sixteen-position", "quarter-turns"]
)
@pytest.mark.parametrize("motion", [Motion(), TILTED], ids=["level", "tilted"])
def test_timeline_cycle_integral_equals_the_closed_form(scheme, motion):
    s = _scheme(scheme, 30.0)
    cycle = s.cycle_time
    tl = build_timeline(s.plan(motion, s.first_dwell + cycle), motion, s.first_dwell + cycle)
    got = _timeline_cycle_integral(tl, s.first_dwell, s.first_dwell + cycle)
    want = cycle_integrals(s, motion).full
    # Both exact; quantized rates (1e-13 rad/s over ~1000 s) and roundoff: ~1e-9 s.
    assert np.allclose(got, want, rtol=0, atol=1e-7)


def _rot(axis: int, angle: float) -> np.ndarray:
    """Right-hand turn about a coordinate axis (Rodrigues, no inserr rotation code)."""
    e = np.zeros(3)
    e[axis] = 1.0
    return _rodrigues(e, np.array([angle]))[0]


def test_isolation_angle_points_the_imu_y_axis_at_the_target_heading():
    # Random tilted vehicle attitudes, inner angles, an off-axis mounting and targets: the
    # returned outer angle a must put the IMU y axis, C_b^n rot_z(a) rot_x(b) C_s^t e_y,
    # at the target heading (clockwise from north) with a positive horizontal projection.
    from inserr.schemes.turntable import imu_heading_offset, isolation_angle

    rng = np.random.default_rng(7)
    mounting = _rot(0, 0.02) @ _rot(1, -0.03) @ _rot(2, 0.05)
    for mount in (None, mounting):
        m = np.eye(3) if mount is None else mount
        c_bn = np.array(
            [
                _rot(2, rng.uniform(-3, 3))
                @ _rot(0, rng.normal(0, 0.05))
                @ _rot(1, rng.normal(0, 0.05))
                for _ in range(6)
            ]
        )
        b = rng.choice([0.0, math.pi], size=6) + rng.normal(0, 0.01, size=6)
        target = rng.uniform(-math.pi, math.pi, size=6)
        a = isolation_angle(c_bn, b, mount, target)
        for k in range(6):
            y_n = c_bn[k] @ _rot(2, a[k]) @ _rot(0, b[k]) @ m @ np.array([0.0, 1.0, 0.0])
            heading = math.atan2(y_n[0], y_n[1])
            # A closed-form root: roundoff only.
            assert math.remainder(heading - target[k], 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
        # imu_heading_offset is the same geometry for a vehicle at heading 0.
        tilt = _rot(0, 0.04) @ _rot(1, -0.02)
        off = imu_heading_offset(tilt, a, b, mount)
        for k in range(6):
            y_n = tilt @ _rot(2, a[k]) @ _rot(0, b[k]) @ m @ np.array([0.0, 1.0, 0.0])
            assert off[k] == pytest.approx(math.atan2(y_n[0], y_n[1]), abs=1e-12)


def _rodrigues(w: np.ndarray, s: np.ndarray) -> np.ndarray:
    """expm(s [w x]) for every s, written out (Rodrigues), shape (len(s), 3, 3)."""
    rate = np.linalg.norm(w)
    if rate == 0.0:
        return np.broadcast_to(np.eye(3), (len(s), 3, 3))
    k = _skew(w / rate)
    th = (rate * s)[:, None, None]
    return np.eye(3) + np.sin(th) * k + (1 - np.cos(th)) * (k @ k)


def _cycle_moments(tl, t0: float, t1: float, w_table_n):
    """Numerical cycle integrals from the timeline, Gauss-Legendre per interval.

    Returns (U(t1) - U(t0), mean over [t0, t1] of U(t) = int_0^t C dt, and the same two
    for the rate terms C e_r (C^T w)_c of every unit error e_r e_c^T, w the table's rate).
    """
    x, wts = np.polynomial.legendre.leggauss(30)
    u = np.zeros((3, 3))
    u_rate = np.zeros((3, 3, 3))  # [:, r, c]: int C e_r (C^T w)_c dt
    s_u = np.zeros((3, 3))
    s_rate = np.zeros((3, 3, 3))
    u_at_t0 = None
    u_rate_at_t0 = None
    for k, w in enumerate(tl.omega_n):
        a, b = tl.times[k], min(tl.times[k + 1], t1)
        if b <= a:
            continue
        h = b - a
        s = 0.5 * h * (x + 1.0)
        ws = 0.5 * h * wts
        c = _rodrigues(w, s) @ tl.c_sn[k]
        w_n = w_table_n(k)
        ws_imu = np.einsum("jab,a->jb", c, w_n)  # C^T w, (J, 3)
        rate = np.einsum("jar,jc->jarc", c, ws_imu)  # (J, 3, 3, 3)
        if a >= t0:
            if u_at_t0 is None:
                u_at_t0, u_rate_at_t0 = u.copy(), u_rate.copy()
            # int over the interval of U(t) = U(a) h + int_0^h (h - s) C(a + s) ds
            s_u += u * h + np.einsum("j,jab->ab", ws * (h - s), c)
            s_rate += u_rate * h + np.einsum("j,jarc->arc", ws * (h - s), rate)
        u = u + np.einsum("j,jab->ab", ws, c)
        u_rate = u_rate + np.einsum("j,jarc->arc", ws, rate)
    cycle = t1 - t0
    return u - u_at_t0, s_u / cycle, u_rate - u_rate_at_t0, s_rate / cycle


@pytest.mark.parametrize("scheme", ["two-position", "four-position-modified", "quarter-turns"])
def test_cycle_integrals_running_means_and_rate_terms_match_the_timeline(scheme):
    """Every closed-form cycle quantity against quadrature of the timeline: the integral of
    C_s^n, the cycle mean of its running integral from t = 0 (first stop included), and
    the scale-factor and misalignment x table-rate integrals and their means."""
    from inserr.core.imu import MISALIGNMENT_INDEX, MISALIGNMENTS

    motion = TILTED
    s = _scheme(scheme, 30.0)
    t0, t1 = s.first_dwell, s.first_dwell + s.cycle_time
    tl = build_timeline(s.plan(motion, t1), motion, t1)

    def w_table_n(k):  # the table's own rate resolved in n (Earth rate excluded)
        return tl.omega_n[k]  # static base: the IMU's rate relative to n is the table's

    u, mean_u, u_rate, mean_rate = _cycle_moments(tl, t0, t1, w_table_n)
    ci = cycle_integrals(s, motion)
    # 30-point Gauss-Legendre on intervals of at most half a turn: ~1e-13 relative; the
    # quantities reach ~1e3 s (U) and ~1 rad (rate terms).
    assert np.allclose(ci.full, u, rtol=0, atol=1e-8)
    assert np.allclose(ci.mean_excursion, mean_u, rtol=0, atol=1e-8)
    sf = np.stack([u_rate[:, i, i] for i in range(3)], axis=1)
    mis = np.stack([u_rate[:, r, c] for r, c in (MISALIGNMENT_INDEX[n] for n in MISALIGNMENTS)], 1)
    assert np.allclose(ci.scale_factor, sf, rtol=0, atol=1e-10)
    assert np.allclose(ci.misalignment, mis, rtol=0, atol=1e-10)
    sf_mean = np.stack([mean_rate[:, i, i] for i in range(3)], axis=1)
    mis_mean = np.stack(
        [mean_rate[:, r, c] for r, c in (MISALIGNMENT_INDEX[n] for n in MISALIGNMENTS)], 1
    )
    assert np.allclose(ci.mean_excursion_scale_factor, sf_mean, rtol=0, atol=1e-10)
    assert np.allclose(ci.mean_excursion_misalignment, mis_mean, rtol=0, atol=1e-10)


@pytest.mark.parametrize(
    "scheme, options, starts",
    [
        # A start is a turn after a stop or a reversal (docs/schemes.md).
        ("two-position", {}, 4),
        ("four-position", {}, 4),
        ("eight-position", {}, 8),
        ("continuous", {}, 0),  # one endless turn: started once, before the cycle
        ("continuous", {"reversal": 120.0}, 2),
    ],
)
def test_motor_starts_per_cycle(scheme, options, starts):
    s = build_scheme(scheme, 6 * DEG, 30.0, **options)
    assert cycle_integrals(s).motor_starts == starts
    assert cycle_integrals(s).motor_starts_per_hour == pytest.approx(
        starts * 3600.0 / s.cycle_time, rel=1e-12
    )


# --- the continuous schedule history (fast engine's input) ---------------------------
def _rz(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _rx(b: float) -> np.ndarray:
    c, s = math.cos(b), math.sin(b)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


#: An off-axis IMU mounting on the inner gimbal (heading 20, pitch -35, roll 50 deg):
#: its y axis is far from the gimbal's, so any step that ignores it shows.
MOUNTING = sl.expm(_skew(np.array([0.87, -0.61, 0.35])))
SWING_TILTED = YawSwing(heading=0.3, pitch=2 * DEG, roll=-3 * DEG, amplitude=6 * DEG, period=90.0)


@pytest.mark.parametrize(
    "scheme, options",
    [("quarter-turns", {}), ("two-position", {"mounting": MOUNTING}),
     ("heading-isolation", {"mounting": MOUNTING}), ("heading-isolation", {})],
)  # fmt: skip
def test_schedule_history_is_the_gimbal_attitude_and_its_rate_the_derivative(scheme, options):
    # C_s^n = C_b^n rot_z(a) rot_x(b) C_s^t with the rotations written here, and w_ns^n
    # the derivative of that attitude: vee(log(C(t + h) C(t - h)^T)) / 2h, central, whose
    # error is O(h^2 |w| |dw/dt|) ~ 1e-12 rad/s at h = 1 ms (rates 0.1 rad/s, changing on
    # the 90 s swing) plus round-off eps / h ~ 1e-13: 1e-9 rad/s is a millionth of the
    # table rate. The quarter turns put the inner gimbal at 180 deg with the outer one at
    # 90 deg, where a lost inner angle or a mis-resolved inner rate shows; the mounting
    # moves the IMU y axis off the gimbal's (the isolation law steers that axis).
    from inserr.schemes.composition import ScheduleHistory

    dur = 400.0
    base = QUARTER if scheme == "quarter-turns" else build_scheme(scheme, 6 * DEG, 20.0, **options)
    table = base.plan(SWING_TILTED, dur)
    hist = ScheduleHistory(table, SWING_TILTED, dur)
    breaks = hist.pieces().breaks
    h = 1e-3
    rng = np.random.default_rng(5)
    mid = 0.5 * (breaks[:-1] + breaks[1:])
    t = np.concatenate([mid, rng.uniform(0.0, dur, 300)])
    piece = np.searchsorted(breaks, t, side="right") - 1
    inside = (t - breaks[piece] > 2 * h) & (breaks[piece + 1] - t > 2 * h)
    t, piece = t[inside], piece[inside]
    c, w = hist.evaluate(t, piece)
    a, b = table.angles_at(t, SWING_TILTED)
    m = np.eye(3) if table.mounting is None else table.mounting
    c_bn = SWING_TILTED.attitude(t)
    expected = np.array([cb @ _rz(ai) @ _rx(bi) @ m for cb, ai, bi in zip(c_bn, a, b, strict=True)])
    assert np.abs(c - expected).max() < 1e-12
    assert np.any(np.abs(b) > 1.0) == (scheme == "quarter-turns")
    # The table's own products: C_s^b, and the IMU heading (of its y axis, in [0, 2 pi)).
    c_sb = np.array([_rz(ai) @ _rx(bi) @ m for ai, bi in zip(a, b, strict=True)])
    assert np.abs(table.dcm_at(t, SWING_TILTED) - c_sb).max() < 1e-12
    y = expected[:, :, 1]
    heading = np.mod(np.arctan2(y[:, 0], y[:, 1]), 2 * np.pi)
    got = table.imu_heading(t, SWING_TILTED)
    assert np.abs(np.angle(np.exp(1j * (got - heading)))).max() < 1e-12
    assert np.all((got >= 0.0) & (got < 2 * np.pi))
    c_plus, _ = hist.evaluate(t + h, piece)
    c_minus, _ = hist.evaluate(t - h, piece)
    r = c_plus @ np.swapaxes(c_minus, 1, 2)
    v = 0.5 * np.stack(
        [r[:, 2, 1] - r[:, 1, 2], r[:, 0, 2] - r[:, 2, 0], r[:, 1, 0] - r[:, 0, 1]], 1
    )
    s = np.linalg.norm(v, axis=1, keepdims=True)
    numeric = v / np.where(s > 0, s, 1.0) * np.arcsin(np.minimum(s, 1.0)) / (2 * h)
    assert np.abs(w - numeric).max() < 1e-9
    assert np.abs(w).max() > 0.05  # the table turns within the samples
    # The vehicle part alone (C_b^n and w_nb^n): the motion's own attitude and rate.
    cv, wv = hist.evaluate_vehicle(t)
    assert np.abs(cv - c_bn).max() < 1e-15 and np.array_equal(wv, SWING_TILTED.rate_n(t))


def _y_axis_n(c_tilt: np.ndarray, a: np.ndarray, m: np.ndarray) -> np.ndarray:
    """The IMU y axis in n, C_tilt rot_z(a) C_s^t e_y, for outer angles a (rows E, N, U)."""
    u = m @ np.array([0.0, 1.0, 0.0])
    ru = np.stack([np.cos(a) * u[0] - np.sin(a) * u[1], np.sin(a) * u[0] + np.cos(a) * u[1],
                   np.full_like(a, u[2])], 1)  # fmt: skip
    return ru @ c_tilt.T


@pytest.mark.parametrize(
    "pitch, roll, mount",
    [(3.0, -2.0, None), (25.0, 40.0, (0.3, -0.5, 0.2)), (10.0, -15.0, (1.2, 0.0, 0.0))],
)
def test_outer_axis_heading_against_the_sampled_geometry(pitch, roll, mount):
    # The IMU y axis v(a) = C_tilt rot_z(a) C_s^t e_y written here: the phasor is
    # (v_N + i v_E) / |v_h| for scalars and arrays; min_horizontal is the least |v_h|
    # over all angles (a tight bound: the tilt and the mounting can line up); the
    # curvature bound holds for the second difference of the heading on a 1e-3 rad grid
    # (its O(h^2) error is ~1e-7 here).
    from inserr.schemes.turntable import OuterAxisHeading

    c_tilt = _rot(0, math.radians(pitch)) @ _rot(1, math.radians(roll))
    m = np.eye(3) if mount is None else _rot(0, mount[0]) @ _rot(1, mount[1]) @ _rot(2, mount[2])
    geo = OuterAxisHeading(c_tilt, None if mount is None else m)
    a = np.linspace(0.0, 2 * math.pi, 6284)
    v = _y_axis_n(c_tilt, a, m)
    h = np.hypot(v[:, 0], v[:, 1])
    want = (v[:, 1] + 1j * v[:, 0]) / h
    assert np.abs(geo.phasor(a) - want).max() < 1e-13
    assert abs(geo.phasor(float(a[1000])) - want[1000]) < 1e-13
    assert h.min() - 1e-6 <= geo.min_horizontal() <= h.min()
    heading = np.unwrap(np.arctan2(v[:, 0], v[:, 1]))
    step = a[1] - a[0]
    curvature = np.abs(np.diff(heading, 2)) / step**2
    assert curvature.max() <= geo.curvature_bound() * (1 + 1e-6)
    lo, hi = geo.slope_bounds()
    slope = -np.diff(heading) / step
    assert lo - 1e-6 <= slope.min() and slope.max() <= hi + 1e-6
    # The bounds are the closed forms of their derivation (docstrings), from the outer
    # axis's tilt theta and the bound s = |u_z| cos theta + |u_h| sin theta of |v_U|, which
    # the sampled y axis attains; widened by 1e-12 (relative and absolute) at most.
    k_up = c_tilt[2, 2]
    sin_t = math.sqrt(1.0 - k_up**2)
    u = m @ np.array([0.0, 1.0, 0.0])
    s = abs(u[2]) * abs(k_up) + math.hypot(u[0], u[1]) * sin_t
    assert abs(v[:, 2]).max() == pytest.approx(s, abs=1e-6)
    d = 1.0 - s * s
    curvature_form = (sin_t**2 + s * sin_t) / d + 2.0 * (s * sin_t) ** 2 / d**2
    assert curvature_form <= geo.curvature_bound() <= curvature_form * (1 + 3e-12) + 3e-12
    eps = s * sin_t / math.sqrt(d)
    assert k_up - eps - 3e-12 <= lo <= k_up - eps and k_up + eps <= hi <= k_up + eps + 3e-12
    # imu_heading_offset with its default inner angle (0) is this heading.
    from inserr.schemes.turntable import imu_heading_offset

    off = imu_heading_offset(c_tilt, a[:50], mounting=None if mount is None else m)
    assert np.abs(off - np.arctan2(v[:50, 0], v[:50, 1])).max() < 1e-12


def test_outer_axis_heading_with_the_y_axis_along_the_outer_axis_has_no_bounds():
    # Mounted with its y axis up on a level vehicle, the IMU heading is undefined:
    # no finite slope or curvature bound, no horizontal part.
    from inserr.schemes.turntable import OuterAxisHeading

    geo = OuterAxisHeading(np.eye(3), _rot(0, math.pi / 2))
    assert geo.curvature_bound() == math.inf
    assert geo.slope_bounds() == (-math.inf, math.inf)
    assert geo.min_horizontal() < 1e-6
    # Any outer angle holds such a heading: the isolation angle is still a number.
    from inserr.schemes.turntable import isolation_angle

    y_up = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # exactly
    assert np.all(np.isfinite(isolation_angle(np.eye(3)[None], 0.0, y_up, 0.3)))


def test_isolation_angle_on_inverted_and_strongly_tilted_vehicles():
    # Upside down (roll near 180 deg) the outer gimbal turns the IMU the other way: the
    # root with the positive projection on the target is then the other one. Random
    # targets, attitudes and inner angles (one inner angle given as a one-element
    # array). A target the y axis cannot reach (tilted up 80 deg by its mounting on a
    # vehicle tilted 30 deg): the angle brings it closest, |E cos H - N sin H| least
    # (checked against 20 000 angles).
    from inserr.schemes.turntable import isolation_angle

    rng = np.random.default_rng(11)
    m = _rot(2, 0.3) @ _rot(0, 0.2)
    for roll in (math.pi, 0.6, -2.8):
        c_bn = np.array([_rot(2, rng.uniform(-3, 3)) @ _rot(1, roll + rng.normal(0, 0.1))
                         @ _rot(0, rng.normal(0, 0.3)) for _ in range(8)])  # fmt: skip
        b = rng.normal(0, 0.3, size=8)
        target = rng.uniform(-math.pi, math.pi, size=8)
        a = isolation_angle(c_bn, b, m, target)
        for k in range(8):
            y_n = c_bn[k] @ _rot(2, a[k]) @ _rot(0, b[k]) @ m @ np.array([0.0, 1.0, 0.0])
            assert math.remainder(math.atan2(y_n[0], y_n[1]) - target[k], 2 * math.pi) == (
                pytest.approx(0.0, abs=1e-9)
            )
        one = isolation_angle(c_bn[:1], b[:1], m, target[:1])
        assert one.shape == (1,) and one[0] == pytest.approx(a[0], abs=1e-12)
    # 300 random attitudes (any roll), mountings and targets: where the y axis can point
    # at the target (a turn of the outer gimbal, sampled every 1/8 deg, brings its heading
    # within 2e-3 rad of it), the returned angle points it there.
    n = 300
    c_bn = np.array([_rot(2, rng.uniform(-3, 3)) @ _rot(1, rng.uniform(-3, 3))
                     @ _rot(0, rng.uniform(-1.2, 1.2)) for _ in range(n)])  # fmt: skip
    mounts = [_rot(0, rng.uniform(-1.4, 1.4)) @ _rot(2, rng.uniform(-3, 3)) for _ in range(n)]
    target = rng.uniform(-math.pi, math.pi, size=n)
    grid = np.linspace(-math.pi, math.pi, 2881)
    reached = 0
    for k in range(n):
        a = float(isolation_angle(c_bn[k][None], 0.0, mounts[k], target[k])[0])
        sweep = _y_axis_n(c_bn[k], grid, mounts[k])
        off = np.angle(np.exp(1j * (np.arctan2(sweep[:, 0], sweep[:, 1]) - target[k])))
        if np.abs(off).min() < 2e-3:
            reached += 1
            y_n = _y_axis_n(c_bn[k], np.array([a]), mounts[k])[0]
            miss = math.remainder(math.atan2(y_n[0], y_n[1]) - target[k], 2 * math.pi)
            assert abs(miss) < 1e-8, k
    assert reached > 200
    up = _rot(0, math.radians(80.0))
    tilt = _rot(0, math.radians(30.0))
    for target in (0.0, math.pi / 2, math.pi, -math.pi / 2, 2.0, -2.5):
        a = float(isolation_angle(tilt[None], 0.0, up, target)[0])
        grid = np.linspace(-math.pi, math.pi, 20001)
        across = np.array([math.cos(target), -math.sin(target), 0.0])  # E cos H - N sin H
        miss_a = abs(float(_y_axis_n(tilt, np.array([a]), up)[0] @ across))
        assert np.isfinite(a) and miss_a <= np.abs(_y_axis_n(tilt, grid, up) @ across).min() + 1e-9


def test_motor_starts_and_isolation_segments_as_documented():
    # A start for a turn after a stop or a reversal (not for a turn continuing in the
    # same sense), one for an isolation entered from a stop, plus the scheme's recorded
    # isolation reversals; an isolation segment moves the outer gimbal with no constant
    # rate, and is kept however short.
    from inserr.schemes.turntable import ScheduleBuilder

    b = ScheduleBuilder()
    b.stop(10.0)
    b.rotate("outer", math.pi / 2, 0.1)  # start 1
    b.rotate("outer", math.pi / 2, 0.1)  # continues
    b.rotate("inner", math.pi / 2, 0.1)  # same sense: continues
    b.rotate("outer", -math.pi / 2, 0.1)  # reversal: start 2
    b.stop(10.0)
    b.isolate(0.5, 0.0, 0.0, 0.0)  # from a stop: start 3
    b.isolate(30.0, 0.0, 0.0, 0.0)
    b.isolate(0.0, 0.0, 0.0, 0.0)  # nothing
    b.meta["isolation_reversals"] = 2
    table = b.build()
    assert table.motor_starts() == 3 + 2
    iso = [k for k, kind in enumerate(table.kind) if kind == "isolate"]
    assert len(iso) == 2 and table.duration[iso[0]] == 0.5
    assert all(table.gimbal[k] == "outer" and table.rate[k] == 0.0 for k in iso)
    assert table.labels[iso[0]] == "isolate"
    # Stops and turns: no gimbal label on a stop, no heading target or rate outside an
    # isolation; the inner gimbal's angle carries into the next segment; the builder
    # starts at angles 0 and keeps its mounting.
    mounting = _rot(1, 0.3)
    c = ScheduleBuilder(mounting=mounting)
    c.stop(0.5)
    c.rotate("inner", -0.5, 0.1)
    c.stop(2.0)
    built = c.build()
    assert built.mounting is mounting and built.a0[0] == 0.0 and built.b0[0] == 0.0
    assert built.kind == ("stop", "rotate", "stop") and built.b0[2] == pytest.approx(-0.5)
    assert built.gimbal[0] == "" and np.all(built.target_rate == 0.0)
    assert np.all(np.isnan(built.target_heading))
    first = ScheduleBuilder()
    first.isolate(5.0, 0.0, 0.0, 0.0)  # the run starts from rest: a start
    first.rotate("outer", 0.0, 0.1)  # no turn: nothing
    first.rotate("outer", 1.0, 0.1)  # after an isolation: a start (a 1 rad turn, 10 s)
    built = first.build()
    assert built.motor_starts() == 2 and built.kind == ("isolate", "rotate")
    assert built.duration[1] == pytest.approx(10.0)


def test_outer_angle_is_continuous_through_isolation_segments():
    # angles_at returns continuous angles (not wrapped): through heading-isolation holds
    # and compensated turns on a swinging vehicle heading 170 deg, the outer angle moves
    # by at most (swing rate + turn rate) dt between samples 0.1 s apart, and each
    # isolation segment starts at its recorded start angle.
    motion = YawSwing(heading=170 * DEG, pitch=2 * DEG, roll=-1 * DEG, amplitude=6 * DEG,
                      period=90.0)  # fmt: skip
    table = build_scheme("heading-isolation", 6 * DEG, 20.0).plan(motion, 600.0)
    t = np.arange(0.0, 600.0, 0.1)
    a, _ = table.angles_at(t, motion)
    assert np.abs(np.diff(a)).max() < (6 * DEG + 6 * DEG) * 0.1 * 1.5
    iso = np.array(table.kind) == "isolate"
    start, _ = table.angles_at(table.t0[iso], motion)
    assert np.abs(start - table.a0[iso]).max() < 1e-6
