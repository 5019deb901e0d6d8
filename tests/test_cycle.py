"""Closed-form cycle integrals against numerical integration and symmetry properties."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from inserr.cycle import cycle_integrals
from inserr.imu import MISALIGNMENT_INDEX, MISALIGNMENTS
from inserr.motion import Motion
from inserr.schedule import build_timeline
from inserr.schemes import Step, TableScheme, build_scheme
from inserr.units import DEG

RATE = 6 * DEG
PERIODIC = [
    "two-position",
    "four-position",
    "four-position-modified",
    "eight-position",
    "sixteen-position",
]


def _numerical(scheme: TableScheme, motion=None):
    """Gauss-Legendre integral of C_s^n (and the SF/misalignment x rate terms) over one cycle.

    Independent of inserr.cycle: the attitude comes from the schedule/timeline path
    (Rodrigues rotations of the planned table), integrated interval by interval.
    """
    motion = motion or Motion()
    t0 = scheme.first_dwell
    t1 = t0 + scheme.cycle_time
    tl = build_timeline(scheme.plan(motion, t1 + 1.0), motion, t1 + 1.0)
    nodes, weights = np.polynomial.legendre.leggauss(12)
    full = np.zeros((3, 3))
    sf = np.zeros((3, 3))
    mis = np.zeros((3, 6))
    edges = np.union1d(tl.times[(tl.times > t0) & (tl.times < t1)], [t0, t1])
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        t = 0.5 * (b - a) * nodes + 0.5 * (a + b)
        w = 0.5 * (b - a) * weights
        c = tl.attitude_at(t)
        full += np.einsum("k,kij->ij", w, c)
        k = tl.interval_index(np.array([0.5 * (a + b)]))[0]
        w_s = c.transpose(0, 2, 1) @ tl.omega_n[k]  # table rate in the IMU frame
        for i in range(3):
            sf[:, i] += np.einsum("k,ki->i", w * w_s[:, i], c[:, :, i])
        for j, name in enumerate(MISALIGNMENTS):
            r, col = MISALIGNMENT_INDEX[name]
            mis[:, j] += np.einsum("k,ki->i", w * w_s[:, col], c[:, :, r])
    return full, sf, mis


@pytest.mark.parametrize("name", PERIODIC + ["continuous"])
def test_closed_form_equals_numerical_integral(name):
    opts = {"reversal": 120.0} if name == "continuous" else {}
    scheme = build_scheme(name, RATE, 300.0, **opts)
    c = cycle_integrals(scheme)
    full, sf, mis = _numerical(scheme)
    # 12-point Gauss-Legendre on each constant-rate interval (<= 180 deg) is exact to
    # ~1e-12 s; the timeline's attitude carries ~1e-15 relative roundoff per node.
    assert np.allclose(c.full, full, atol=1e-8)
    assert np.allclose(c.scale_factor, sf, atol=1e-10)
    assert np.allclose(c.misalignment, mis, atol=1e-10)


def test_closed_form_on_a_tilted_static_vehicle():
    scheme = build_scheme("four-position", RATE, 60.0)
    motion = Motion(heading=0.4, pitch=0.02, roll=-0.03)
    c = cycle_integrals(scheme, motion)
    full, _, _ = _numerical(scheme, motion)
    assert np.allclose(c.full, full, atol=1e-8)


def test_issue_figures_for_four_position_and_cancelling_schemes():
    four = cycle_integrals(build_scheme("four-position", RATE, 300.0))
    expected = 2 * math.sqrt(2) / RATE  # 27.009 s: the four turns' residual
    assert np.allclose(four.horizontal, np.diag([expected, expected]), atol=1e-9)
    assert expected == pytest.approx(27.009, abs=1e-3)
    for name in ("two-position", "four-position-modified", "eight-position", "sixteen-position"):
        assert np.abs(cycle_integrals(build_scheme(name, RATE, 300.0)).horizontal).max() < 1e-9


def test_reversal_cancels_scale_factor_times_rate():
    one_way = cycle_integrals(build_scheme("continuous", RATE, 0.0))
    both = cycle_integrals(build_scheme("continuous", RATE, 0.0, reversal=120.0))
    # One revolution about up: a unit z scale factor accumulates 2 pi rad of heading error.
    assert one_way.scale_factor[2, 2] == pytest.approx(2 * math.pi, rel=1e-12)
    assert abs(both.scale_factor[2, 2]) < 1e-12


def test_dual_axis_schemes_cancel_all_three_axes():
    eight = cycle_integrals(build_scheme("eight-position", RATE, 300.0))
    sixteen = cycle_integrals(build_scheme("sixteen-position", RATE, 300.0))
    assert np.abs(eight.full).max() < 1e-9  # the up row and column too
    assert np.abs(eight.scale_factor).max() < 1e-12
    assert np.abs(eight.misalignment).max() > 1.0  # eight positions leave misalignment x rate
    assert np.abs(sixteen.full).max() < 1e-9
    assert np.abs(sixteen.misalignment).max() < 1e-12


_turn = st.floats(min_value=-170.0, max_value=170.0).filter(lambda a: abs(a) > 1.0)
_dwell = st.floats(min_value=0.0, max_value=500.0)


def _half_turn_sequence(turns, dwells):
    """Steps whose net outer angle is exactly +180 deg (last turn adjusted)."""
    angles = [a * DEG for a in turns]
    last = math.pi - sum(angles)
    steps = [Step("outer", a, d) for a, d in zip(angles, dwells, strict=False)]
    steps.append(Step("outer", last, dwells[-1]))
    return steps


@settings(max_examples=40, deadline=None)
@given(
    turns=st.lists(_turn, min_size=0, max_size=4),
    dwells=st.lists(_dwell, min_size=5, max_size=5),
    start=st.floats(min_value=-math.pi, max_value=math.pi),
)
def test_symmetric_pairs_cancel(turns, dwells, start):
    # Any history followed by the same history 180 deg further on: every attitude of the
    # first half has its mirror in the second half, stops and turns alike.
    half = _half_turn_sequence(turns, dwells)
    scheme = TableScheme("pairs", tuple(half + half), RATE, 10.0, start=(start, 0.0))
    c = cycle_integrals(scheme)
    assert np.abs(c.horizontal).max() < 1e-9 * max(1.0, c.cycle_time)


@settings(max_examples=40, deadline=None)
@given(
    turns=st.lists(_turn, min_size=0, max_size=4),
    dwells=st.lists(_dwell, min_size=5, max_size=5),
    start=st.floats(min_value=-math.pi, max_value=math.pi),
    extra=st.floats(min_value=1.0, max_value=300.0),
    which=st.integers(min_value=0, max_value=4),
)
def test_breaking_the_symmetry_leaves_exactly_the_extra_stop(turns, dwells, start, extra, which):
    half = _half_turn_sequence(turns, dwells)
    which = min(which, len(half) - 1)
    broken = list(half)
    s = broken[which]
    broken[which] = Step(s.gimbal, s.angle, s.dwell + extra)
    scheme = TableScheme("asym", tuple(half + broken), RATE, 10.0, start=(start, 0.0))
    c = cycle_integrals(scheme)
    # The only unpaired piece is the extra stop, at outer angle a: its horizontal block is
    # extra * [[cos a, -sin a], [sin a, cos a]], never zero (norm extra * sqrt(2)).
    a = start + math.pi + sum(st_.angle for st_ in half[: which + 1])
    expected = extra * np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    assert np.allclose(c.horizontal, expected, atol=1e-9 * max(1.0, c.cycle_time))
    assert np.linalg.norm(c.horizontal) > extra


@pytest.mark.parametrize(
    "name", ["two-position", "four-position", "eight-position", "sixteen-position"]
)
def test_mean_excursion_closed_form_equals_numerical(name):
    # Mean over one cycle of the running integral U(t) = int_0^t C_s^n dt, measured from
    # the start of the run (first stop included), by dense trapezoidal integration.
    from scipy.integrate import cumulative_trapezoid

    scheme = build_scheme(name, RATE, 120.0)
    c = cycle_integrals(scheme)
    t0, tc = scheme.first_dwell, scheme.cycle_time
    tl = build_timeline(scheme.plan(Motion(), t0 + tc + 1.0), Motion(), t0 + tc + 1.0)
    t = np.linspace(0.0, t0 + tc, int((t0 + tc) / 0.02) + 1)
    att = tl.attitude_at(t)
    u = cumulative_trapezoid(att, t, axis=0, initial=0.0)
    in_cycle = t >= t0
    mean = np.trapezoid(u[in_cycle], t[in_cycle], axis=0) / tc
    # Trapezoid error at 0.02 s steps: ~(dt w)^2/12 of the turn contributions, < 1e-4 s.
    assert np.allclose(c.mean_excursion, mean, atol=1e-3)
    w_s = np.einsum("tji,tj->ti", att, tl.omega_n[tl.interval_index(t)])
    sf = cumulative_trapezoid(np.einsum("tij,tj->tij", att, w_s), t, axis=0, initial=0.0)
    sf_mean = np.trapezoid(sf[in_cycle], t[in_cycle], axis=0) / tc
    # Rate terms jump at turn starts/stops: first-order trapezoid error ~ dt * (turn
    # integral) per jump, a few 1e-3 rad at most.
    assert np.allclose(c.mean_excursion_scale_factor, sf_mean, atol=5e-3)
