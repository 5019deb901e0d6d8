"""Closed-loop planners against their definitions, computed sample by sample in the tests.

The planners skip the samples that provably cannot change a decision (closed-form stop
sums, bounds on how fast the IMU heading moves, the times where a rate can reverse).
These tests recompute each rule's decisions from every sample, with the IMU heading
from full DCMs, and check the schedules the planners give against them, on motions
chosen to stress the shortcuts: a fast swing whose yaw rate touches the table rate
(the heading hovers near a stop test's band), a large swing, an off-axis mounting, a
level vehicle, heading histories (kinks, holds, bursts of swinging).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

from inserr.core.rotations import heading_of, rot_x, rot_z
from inserr.core.units import DEG
from inserr.schemes.catalogue import build_scheme
from inserr.schemes.closed_loop import (
    _TWO_PI_BITS,
    _TWO_PI_INT,
    _ExactPhase,
    _stop_sums,
)
from inserr.schemes.nulling import HISTORY_STOPS, heading_period, yaw_rate_reversals
from inserr.schemes.turntable import OuterAxisHeading, table_dcm
from inserr.schemes.vehicle_motion import (
    HeadingHistory,
    Motion,
    Turn,
    YawSwing,
    heading_accel_bound,
    heading_rate_bound,
    heading_rate_breaks,
)

RATE = 6 * DEG
TS = 300.0
F = 100.0
TILT = dict(heading=15 * DEG, pitch=1 * DEG, roll=-2 * DEG)
MOUNT = rot_z(0.3) @ rot_x(0.05)


def _smooth_history(duration: float, step: float = 1.0) -> HeadingHistory:
    """A heading history at 1 Hz: two swings and a drift, linear between samples."""
    t = np.arange(0.0, duration + step, step)
    h = (
        15 * DEG
        + 40 * DEG * np.sin(2 * np.pi * t / 97.0)
        + 10 * DEG * np.sin(2 * np.pi * t / 613.0)
    )
    return HeadingHistory(times=t, headings=h + 1e-5 * t, pitch=1 * DEG, roll=-2 * DEG)


def _holds_history(duration: float) -> HeadingHistory:
    """Right 10 deg in 10 s, hold 10 s, back, hold, ...: rate reversals through exact zeros."""
    t = np.arange(0.0, duration + 10.0, 10.0)
    pattern = np.array([0.0, 10.0, 10.0, 0.0]) * DEG
    return HeadingHistory(
        times=t, headings=15 * DEG + pattern[np.arange(len(t)) % 4], pitch=1 * DEG, roll=-2 * DEG
    )


SWINGS = {
    # P0 experiment 2: the yaw rate reaches the table rate, so during one turn in two
    # the IMU heading stands still for seconds, near the band or in it.
    "p0-exp2": (YawSwing(amplitude=RATE, period=60.0, **TILT), None),
    "p0-exp1-mounted": (YawSwing(amplitude=RATE, period=120.0, **TILT), MOUNT),
    "large-swing": (YawSwing(amplitude=20 * DEG, period=300.0, **TILT), None),
    "level": (YawSwing(amplitude=RATE, period=120.0), None),
    "history": (_smooth_history(3 * 3600.0), None),
    "turn": (Turn(rate=0.5 * DEG, **TILT), None),
}


# ---------------------------------------------------------------------------------------
# Flexible rule
# ---------------------------------------------------------------------------------------
def _true_heading(motion, t, a, mounting):
    """IMU heading from full DCMs (independent of the planner's closed forms)."""
    return heading_of(motion.attitude(t) @ table_dcm(a, np.zeros_like(a), mounting))


def _replay(table, motion, mounting, variant):
    """Replay the flexible rule on a planned schedule, every sample, full DCMs.

    Yields ``(kind, data)``: ``("turn", (expr, passes, n, fallback))`` for each
    variable turn (the expression and the test at every sample of a full 360 deg turn,
    the sample the table stopped at), and finally ``("sums", sums)``.
    """
    sums = np.zeros(2)
    per_turn = math.ceil(2 * math.pi / RATE * F)
    j = np.arange(1, per_turn + 1)
    for k, lab in enumerate(table.labels):
        t0, dur = table.t0[k], table.duration[k]
        if table.kind[k] == "stop":
            kk = np.arange(math.ceil(t0 * F - 1e-9), math.ceil((t0 + dur) * F - 1e-9))
            h = _true_heading(motion, kk / F, np.full(len(kk), table.a0[k]), mounting)
            sums += [math.fsum(np.cos(h)), math.fsum(np.sin(h))]
        elif lab.startswith("variable"):
            which = 0 if table.rate[k] > 0 else 1
            h = _true_heading(motion, t0 + j / F, table.a0[k] + table.rate[k] * j / F, mounting)
            main, other = (np.cos(h), np.sin(h)) if which == 0 else (np.sin(h), np.cos(h))
            expr = main + sums[which] / (F * TS)
            s_other = np.sign(sums[1 - which]) * (abs(sums[1 - which]) > 1e-9 * F * TS)
            sign_ok = (np.sign(other) == -s_other) | (s_other == 0)
            if variant == "threshold":
                passes = (np.abs(expr) < 0.01) & sign_ok
            else:
                prev = np.concatenate([[expr[0]], expr[:-1]])
                passes = (np.sign(expr) != np.sign(prev)) & sign_ok
            n = round(dur * F)
            yield "turn", (expr, passes, sign_ok, n, lab.endswith("(fallback)"))
    yield "sums", sums


@pytest.mark.parametrize("variant", ["threshold", "crossing"])
@pytest.mark.parametrize("case", sorted(SWINGS))
def test_flexible_stops_at_the_first_passing_sample(case, variant):
    """Defining property: each variable turn stops at the first sample passing the test.

    Every sample of a full turn is tested here (the planner tests only those its
    bounds cannot rule out); the sample the table stopped at must pass and no earlier
    one may. A fallback turn has no passing sample and stops at the best one.
    """
    motion, mounting = SWINGS[case]
    scheme = build_scheme("flexible-two-position", RATE, TS, variant=variant, mounting=mounting)
    table = scheme.plan(motion, 2 * 3600.0)
    turns = 0
    for kind, data in _replay(table, motion, mounting, variant):
        if kind == "sums":
            # Both sides sum the same cosines and sines: each within a few ulp of the
            # heading's size (< 3 rad here, 40 rad for the turn), 3.9e5 samples in
            # 13 stops, so 1e-13 per sample and radian is a wide bound.
            n_samples = 2 * 3600.0 * F
            scale = 1.0 + float(np.max(np.abs(motion.heading_at(np.array([0.0, 7200.0])))))
            assert np.allclose(
                table.meta["stop_sums"], data, rtol=0, atol=1e-13 * n_samples * scale
            )
            continue
        expr, passes, sign_ok, n, fallback = data
        turns += 1
        if not fallback:
            assert passes[n - 1] and not passes[: n - 1].any()
            continue
        assert not passes.any()
        pool = sign_ok if sign_ok.any() else np.ones_like(sign_ok)
        score = np.abs(expr)
        short = RATE * np.arange(1, len(expr) + 1) / F < 2 * math.pi - 1e-9
        assert pool[n - 1] and score[n - 1] <= score[pool & short].min() + 1e-9
    assert turns >= 10


@pytest.mark.parametrize(
    "motion",
    [
        YawSwing(amplitude=RATE, period=120.0, **TILT),
        YawSwing(amplitude=RATE, period=60.0, **TILT),
        YawSwing(amplitude=3 * DEG, period=47.3, **TILT),  # 4730 samples a period
        YawSwing(amplitude=4 * DEG, period=100.0 / 3.0, **TILT),  # no whole number of samples
        YawSwing(amplitude=20 * DEG, period=300.0, **TILT),  # heading amplitude 16.7 rad
        Turn(rate=RATE, **TILT),
        Turn(rate=-0.5 * DEG, **TILT),
        _smooth_history(73 * 3600.0),
        HeadingHistory(times=np.array([0.0, 3e5]), headings=np.array([0.2, 3e5 * RATE])),
    ],
    ids=[
        "swing120",
        "swing60",
        "swing47.3",
        "swing33.3",
        "big-swing",
        "turn6",
        "turn-0.5",
        "history",
        "long-piece",
    ],
)
def test_stop_sums_are_the_sums_over_the_samples(motion):
    """Closed-form stop sums equal the sums over every sample, late in a 72 h run too."""
    geo = OuterAxisHeading(motion.tilt, MOUNT)
    sums = _stop_sums(motion, F, geo)
    for k0 in (0, 1_234_567, 25_900_000):
        k1 = k0 + 30_000
        for a in (0.0, 2.7, -5.1):
            h = motion.heading_at(np.arange(k0, k1) / F) + geo.offset(a)
            ref = (math.fsum(np.cos(h)), math.fsum(np.sin(h)))
            # Each sampled term is within a few ulp of the heading's size of its exact
            # value, and so is each closed form's phase: 1e-13 per sample and radian.
            size = 1.0 + float(np.max(np.abs(h)))
            assert np.allclose(sums(k0, k1, a), ref, rtol=0, atol=1e-13 * (k1 - k0) * size)


def test_exact_phase_is_exact():
    rng = np.random.default_rng(7)
    two_pi = Fraction(_TWO_PI_INT, 2**_TWO_PI_BITS)
    for _ in range(200):
        h, r, t = rng.normal(0.0, 100.0), rng.normal(0.0, 0.3), rng.uniform(0.0, 1e5)
        k = int(rng.integers(0, 10**8))
        x = Fraction(h) + Fraction(r) * (Fraction(k) / Fraction(F) - Fraction(t))
        expected = float(x - math.floor(x / two_pi) * two_pi)
        assert _ExactPhase(h, r, t, F)(k) == expected
    # The integer 2 pi agrees with math.pi to the last bit.
    assert float(two_pi) == 2 * math.pi


# ---------------------------------------------------------------------------------------
# Geometry and motion bounds the planners rely on
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "tilt, mounting",
    [((1.0, -2.0), None), ((20.0, 30.0), rot_z(0.3) @ rot_x(0.4)), ((40.0, 10.0), rot_x(0.3))],
)
def test_heading_offset_bounds_hold(tilt, mounting):
    """Slope and curvature bounds of the offset against finite differences."""
    from inserr.core.rotations import body_to_nav

    geo = OuterAxisHeading(body_to_nav(0.0, tilt[0] * DEG, tilt[1] * DEG), mounting)
    a = np.linspace(-math.pi, math.pi, 400_001)
    step = a[1] - a[0]
    off = np.unwrap(geo.offset(a))
    slope = -np.gradient(off, step)
    curve = np.diff(off, 2) / step**2
    lo, hi = geo.slope_bounds()
    # Central differences err by step^2 |off'''| / 6 (< 1e-12 here) plus the offset's
    # round-off over the step, 4e-16 / 1.6e-5 = 3e-11: 1e-9 covers both; the second
    # differences' round-off, 4e-16 / step^2 = 2e-6, sets their margin.
    assert lo - 1e-9 <= slope.min() and slope.max() <= hi + 1e-9
    assert np.abs(curve).max() <= geo.curvature_bound() + 1e-5
    assert np.allclose(geo.phasor(a), np.exp(1j * geo.offset(a)), rtol=0, atol=1e-14)
    assert abs(geo.phasor(0.4) - np.exp(1j * geo.offset(0.4))) < 1e-14
    # For a plain tilt (no mounting) the upper bound is attained and the bounds span
    # at most twice the true range: they are not needlessly loose.
    if mounting is None:
        assert hi - slope.max() < 1e-9
        assert hi - lo <= 2.0 * (slope.max() - slope.min()) + 1e-9


def test_heading_rate_breaks_split_the_run_where_the_rate_crosses_a_level():
    swing = YawSwing(amplitude=RATE, period=60.0, **TILT)
    t = np.linspace(0.0, 600.0, 600_001)
    for level in (0.0, 0.5 * RATE, -RATE, RATE, 1.5 * RATE):
        br = heading_rate_breaks(swing, level, 600.0)
        d = swing.heading_rate(t) - level
        piece = np.searchsorted(br, t)
        for p in np.unique(piece):
            s = np.sign(d[(piece == p) & (np.abs(d) > 1e-12)])
            assert len(np.unique(s)) <= 1, (level, p)
        assert np.allclose(swing.heading_rate(br), level, atol=1e-12)
    history = _holds_history(100.0)
    assert np.array_equal(heading_rate_breaks(history, 0.0, 55.0), [10.0, 20.0, 30.0, 40.0, 50.0])
    assert len(heading_rate_breaks(Turn(rate=RATE), RATE, 1e5)) == 0
    assert (
        heading_rate_bound(swing) == RATE
        and heading_accel_bound(swing) == RATE * 2 * math.pi / 60.0
    )
    assert heading_rate_bound(history) == pytest.approx(1 * DEG)
    assert heading_accel_bound(history) is None and heading_accel_bound(Motion()) == 0.0


# ---------------------------------------------------------------------------------------
# Heading isolation
# ---------------------------------------------------------------------------------------
def _sampled_reversals(table, motion, duration, rate_hz):
    """The definition: sign changes of the outer angle's change between neighbouring
    samples at rate_hz, within each hour, changes of at most 1e-9 rad left out."""
    signs = []
    for t0 in np.arange(0.0, duration, 3600.0):
        a, _ = table.angles_at(np.arange(t0, min(t0 + 3600.0, duration), 1.0 / rate_hz), motion)
        d = np.diff(a)
        signs.append(np.sign(d[np.abs(d) > 1e-9]))
    s = np.concatenate(signs)
    return int(np.count_nonzero(np.diff(s)))


@pytest.mark.parametrize(
    "case, motion, mounting",
    [
        ("p0-exp1", YawSwing(amplitude=RATE, period=120.0, **TILT), None),
        ("p0-exp2", YawSwing(amplitude=RATE, period=60.0, **TILT), None),
        ("mounted", YawSwing(amplitude=RATE, period=120.0, **TILT), MOUNT),
        ("turn", Turn(rate=0.5 * DEG, **TILT), None),
        ("turn-at-table-rate", Turn(rate=RATE, **TILT), None),
        ("static", Motion(**TILT), None),
        ("holds", _holds_history(4 * 3600.0), None),
        ("history", _smooth_history(4 * 3600.0), None),
    ],
)
def test_isolation_reversals_are_the_sampled_count(case, motion, mounting):
    duration = 3 * 3600.0 + 1234.5  # a part hour at the end
    for rate_hz in (4.0, 3.0):  # 1/3 s is not exact in binary: counted sample by sample
        scheme = build_scheme("heading-isolation", RATE, TS, mounting=mounting)
        scheme = type(scheme)(RATE, TS, mounting=mounting, count_rate=rate_hz)
        table = scheme.plan(motion, duration)
        expected = _sampled_reversals(table, motion, duration, rate_hz)
        assert table.meta["isolation_reversals"] == expected, (case, rate_hz)
    if case in ("p0-exp1", "p0-exp2"):
        assert expected > 100  # the count is not trivially zero


def test_isolation_segment_ends_hold_the_target_heading():
    """Each segment ends with the IMU on its target heading (full DCMs), angles continuous."""
    motion = YawSwing(amplitude=RATE, period=60.0, **TILT)
    table = build_scheme("heading-isolation", RATE, TS, mounting=MOUNT).plan(motion, 4 * 3600.0)
    ends = table.t0 + table.duration
    target = table.target_heading + table.target_rate * table.duration
    for k in range(len(table) - 1):
        a, b = table.angles_at(np.array([ends[k] - 1e-7, ends[k] + 1e-7]), motion)
        assert abs(a[1] - a[0]) < 1e-5  # continuous across the boundary
        assert a[1] == pytest.approx(table.a0[k + 1], abs=1e-5)
        h = _true_heading(motion, np.array([ends[k]]), np.array([table.a0[k + 1]]), MOUNT)
        assert abs(math.remainder(float(h[0]) - target[k], 2 * math.pi)) < 1e-9


# ---------------------------------------------------------------------------------------
# Nulling rule
# ---------------------------------------------------------------------------------------
def test_yaw_rate_reversals_are_the_true_zeros_over_72_h():
    swing = YawSwing(amplitude=RATE, period=60.0, **TILT)
    duration = 72 * 3600.0
    rev = yaw_rate_reversals(swing, duration, F)
    # A cos(2 pi t / T) = 0 at t = (n + 1/2) T / 2; the zero interpolated between two
    # samples 10 ms apart errs by ~ (dt / 2)^2 |r''| / (2 |r'|) = 1e-6 s at most.
    truth = (np.arange(len(rev)) + 0.5) * 30.0
    assert len(rev) == math.floor(duration / 30.0 - 0.5) + 1
    assert np.abs(rev - truth).max() < 2e-6
    assert len(yaw_rate_reversals(Turn(rate=RATE), duration, F)) == 0
    assert len(yaw_rate_reversals(Motion(), duration, F)) == 0


@pytest.mark.parametrize("motion", [_holds_history(7200.0), _smooth_history(7200.0)])
def test_yaw_rate_reversals_of_histories_are_those_of_every_sample(motion):
    t = np.arange(0, 7200 * 100 + 1) / F
    r = motion.heading_rate(t)
    nz = np.flatnonzero(r != 0.0)
    tn, rn = t[nz], r[nz]
    k = np.flatnonzero(np.sign(rn[1:]) != np.sign(rn[:-1]))
    adjacent = np.isclose(tn[k + 1] - tn[k], 1.0 / F)
    zero = np.where(
        adjacent,
        tn[k] + rn[k] / (rn[k] - rn[k + 1]) * (tn[k + 1] - tn[k]),
        0.5 * (tn[k] + tn[k + 1]),
    )
    assert np.array_equal(yaw_rate_reversals(motion, 7200.0, F), np.unique(zero))


def test_nulling_swing_test_at_every_stop():
    """Each stop uses the period seen before it, unless the heading swing is below delta.

    Every 2 h, 30 min of P0's swing (6 deg/s, 60 s) and then 90 min of a swing too
    small to count (0.003 rad): the yaw rate still reverses, but over a whole
    history window (40 min) the swing is below delta. The swing test passes and fails
    in turn, so the planner's guesses go wrong and it must restart; the periods it
    used must still be those of testing stop by stop.
    """
    t = np.arange(0.0, 8 * 3600.0 + 1.0, 0.5)
    size = np.where((t % 7200.0) < 1800.0, RATE * 60 / (2 * np.pi), 0.003)
    h = size * np.sin(2 * np.pi * t / 60.0)
    motion = HeadingHistory(times=t, headings=h, pitch=1 * DEG, roll=-2 * DEG)
    table = build_scheme("nulling-two-position", RATE, TS).plan(motion, 8 * 3600.0)
    stops = [k for k in range(len(table)) if table.kind[k] == "stop"]
    periods = table.meta["period_estimates_s"]
    assert len(periods) == len(stops)
    reversals = yaw_rate_reversals(motion, 8 * 3600.0, F)
    history = HISTORY_STOPS * TS
    seen = []
    for k, used in zip(stops, periods, strict=True):
        t0 = table.t0[k]
        period = heading_period(reversals, t0 - 1 / F, history) if t0 > 0 else None
        swing = np.ptp(motion.heading_at(np.linspace(max(0.0, t0 - history), t0, 512)))
        if period is not None:
            seen.append(swing >= 0.01)
        expected = period if period is not None and swing >= 0.01 else None
        if expected is None:
            assert math.isnan(used)
        else:
            assert used == expected
    assert any(seen) and not all(seen)  # both outcomes occur


@pytest.mark.parametrize("case", sorted(SWINGS))
def test_fallback_best_sample_in_closed_form_equals_every_sample(case):
    """The fallback's best sample, found from the closed form plus the samples that can
    decide it, is the one the sampled rule picks from every sample of the turn.

    Random turn starts (time, table angle, direction, expression, sign condition) on
    the stress motions; the reference is the same search with its round-off bound
    removed, which computes every sample with the rule's own operations. Offsets ``c``
    near +-1 make the score flat at its minimum (ties) and the sign condition hover.
    """
    from inserr.schemes.closed_loop import _TurnSearch

    motion, mounting = SWINGS[case]
    scheme = build_scheme("flexible-two-position", RATE, TS, mounting=mounting)
    fast = _TurnSearch(scheme, motion, 6 * 3600.0)
    assert fast.roundoff is not None
    slow = _TurnSearch(scheme, motion, 6 * 3600.0)
    slow.roundoff = None
    rng = np.random.default_rng(7)
    looked = []
    for _ in range(150):
        args = (
            float(rng.uniform(0, 6 * 3600.0)),
            float(rng.uniform(-4 * np.pi, 4 * np.pi)),
            float(rng.choice([1.0, -1.0])),
            int(rng.integers(2)),
            float(rng.choice([rng.uniform(-1.2, 1.2), 1.0, -1.0, 0.0])),
            float(rng.choice([1.0, -1.0, 0.0])),
        )
        assert fast.best_sample(*args) == slow.best_sample(*args), args
        tol = fast.roundoff + 1e-12 * abs(args[1])
        found = fast._stretches(args[0], np.exp(1j * args[1]), *args[2:], tol)
        looked.append(fast.n_short if found is None else len(found[0]))
    # The bounds did their job: most turns were looked at in a few stretches only.
    assert np.median(looked) < fast.n_short / 4


@pytest.mark.parametrize("mounting", [None, MOUNT], ids=["aligned", "off-axis"])
def test_static_turns_from_a_recurring_angle_stop_where_the_search_stops(mounting):
    """On a static base a turn from an angle seen before is answered from its kept,
    sorted samples (two binary searches); it must stop where the bounded search stops.

    Start angles from a small set (as a static run's are), both directions and tests,
    offsets ``c`` spread over the band's reach and placed right at samples' band edges
    (``|main + c|`` within an ulp or so of delta), every sign condition.
    """
    from inserr.schemes.closed_loop import _TurnSearch

    motion = Motion(**TILT)
    scheme = build_scheme("flexible-two-position", RATE, TS, mounting=mounting)
    kept = _TurnSearch(scheme, motion, 6 * 3600.0)
    searched = _TurnSearch(scheme, motion, 6 * 3600.0)
    searched.heading = None  # the bounded search every time
    searched.static_phasor = {}
    rng = np.random.default_rng(21)
    angles = [0.0, 0.00942477796076938, 3.0997047516, -2.5, 6.2412974, 40.1]
    answered = 0
    for _ in range(600):
        a0 = float(rng.choice(angles))
        direction = float(rng.choice([1.0, -1.0]))
        which = int(rng.integers(2))
        s_other = float(rng.choice([1.0, -1.0, 0.0]))
        main, _ = kept.values(0.0, a0, direction, which, kept.j)
        edge = float(main[rng.integers(len(main))])
        c = float(rng.choice([rng.uniform(-1.05, 1.05), -edge + 0.01, -edge - 0.01,
                              np.nextafter(-edge + 0.01, 0.0), -edge]))  # fmt: skip
        t0 = float(rng.uniform(0.0, 6 * 3600.0))
        got = kept.first_pass(t0, a0, direction, which, c, s_other)
        assert got == searched.first_pass(t0, a0, direction, which, c, s_other)
        answered += (a0, direction, which) in kept._recurring and s_other in kept._recurring[
            (a0, direction, which)
        ]
    assert answered > 400  # most were answered from the kept samples


@pytest.mark.parametrize(
    "motion",
    [
        Motion(**TILT),
        YawSwing(amplitude=0.0, period=100.0, **TILT),
        Turn(rate=0.0, **TILT),
        HeadingHistory(
            times=np.array([0.0, 50.0, 4e5]),
            headings=np.full(3, 0.7),
            pitch=TILT["pitch"],
            roll=TILT["roll"],
        ),  # fmt: skip
    ],
    ids=["still", "swing-of-zero", "turn-of-zero", "history-of-one-heading"],
)
@pytest.mark.parametrize("mounting", [None, MOUNT], ids=["aligned", "off-axis"])
def test_static_stop_sums_are_the_sampled_sums_to_the_bit(motion, mounting):
    # On a static base every sample of a stop has one heading: the static sums take the
    # repeated cosine (sine) once and sum it as numpy sums the rule's array. The rule's
    # own sums (every sample computed) must come out identical, not merely close: the
    # crossing test can fall exactly on a sample, where round-off decides.
    from inserr.schemes.closed_loop import _SampledStopSums, _StaticStopSums

    geo = OuterAxisHeading(motion.tilt, mounting)
    static, sampled = _StaticStopSums(motion, F, geo), _SampledStopSums(motion, F, geo)
    rng = np.random.default_rng(31)
    for _ in range(150):
        k0 = int(rng.integers(0, 3 * 10**7))
        n = int(rng.choice([1, 7, 128, 129, 30000, 30001, int(rng.integers(1, 60000))]))
        a = float(rng.uniform(-30.0, 30.0))
        assert static(k0, k0 + n, a) == sampled(k0, k0 + n, a)
