"""The nulling two-position rule: its defining property, its costs and its static-base cycle."""

from __future__ import annotations

import math

import numpy as np
import pytest

from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.schemes.catalogue import build_scheme
from inserr.schemes.cycle_integrals import cycle_integrals
from inserr.schemes.nulling import (
    HISTORY_STOPS,
    PHASE_FRACTIONS,
    PHASE_MODULUS,
    TURNS,
    NullingTwoPosition,
    error_integrals,
    heading_maxima,
    heading_period,
    step_dwell,
    synchronous_dwell,
    yaw_rate_reversals,
)
from inserr.schemes.open_loop import Step, TableScheme
from inserr.schemes.vehicle_motion import HeadingHistory, Motion, Turn, YawSwing

DEG = math.pi / 180.0
RATE = 6 * DEG
TS = 300.0
SITE = Site(34.246 * DEG, 108.91 * DEG, 380.0)
# P0 experiment 2: tilted vehicle, yaw rate 6 cos(pi t / 30) deg/s.
HISTORY_TIME = HISTORY_STOPS * TS  # the rule's yaw-rate history, s
P0_EXP2 = YawSwing(heading=15 * DEG, pitch=1 * DEG, roll=-2 * DEG, amplitude=6 * DEG, period=60.0)


def _steps(table):
    """(turn angle, following dwell) pairs of a schedule, after the first stop."""
    out = []
    for k in range(1, len(table) - 1):
        if table.kind[k] == "rotate" and table.kind[k + 1] == "stop":
            out.append((table.rate[k] * table.duration[k], table.duration[k + 1]))
    return out


def test_tilt_coupled_integral_stays_bounded_where_the_traditional_one_grows():
    """Defining property: on P0's experiment-2 swing the rate-coupled integral stays bounded.

    The integral is the heading-channel (U) error per unit x-gyro misalignment to z,
    ``integral of (C_s^n e_x)_U w_z^s dt``; on a vehicle tilted by theta it picks up
    a kick of at most ``2 theta h`` per step (h: heading half-range, 1 rad here,
    theta = 2.24 deg), i.e. 0.08. With the golden phase advance the kick sums are
    geometric series at least 21 deg from resonance for harmonics 1..3 (a factor
    1 / (2 sin 10.6 deg) = 2.7), so a few kicks at most: the bound 0.5 rad/rad is
    stated with that margin. The
    traditional cycle's step (330 s = 5.5 swing periods) is resonant and the
    integral grows linearly.
    """
    dur = 4 * 3600.0
    t_out = np.arange(0.0, dur + 1, 600.0)
    runs = {}
    for scheme in (build_scheme("two-position", RATE, TS), NullingTwoPosition(RATE, TS)):
        table = scheme.plan(P0_EXP2, dur)
        runs[scheme.name] = error_integrals(table, P0_EXP2, SITE.earth_rate_n, dur, t_out=t_out)
    lam = np.abs(runs["nulling-two-position"]["mis_xz"][:, 2])
    trad = np.abs(runs["two-position"]["mis_xz"][:, 2])
    assert lam.max() < 0.5
    assert trad[-1] > 2.0 and trad[-1] > 1.8 * trad[len(trad) // 2]
    # The horizontal projection integral (biases) stays within one long step as well.
    p = np.linalg.norm(runs["nulling-two-position"]["bias_x"][:, :2], axis=1)
    assert p.max() < 2 * (TS + TS)


def test_every_step_advances_the_swing_phase_by_the_target():
    table = NullingTwoPosition(RATE, TS).plan(P0_EXP2, 3 * 3600.0)
    steps = _steps(table)
    assert len(steps) > 20
    for angle, dwell in steps[8:]:  # once eight stops of yaw history exist
        step = dwell + abs(angle) / RATE
        frac = (step / P0_EXP2.period) % PHASE_MODULUS
        assert min(abs(frac - x) for x in PHASE_FRACTIONS) < 2e-3


@pytest.mark.parametrize("period", [20.0, 60.0, 120.0, 330.0, 1200.0])
def test_motor_starts_never_exceed_the_traditional_cycle(period):
    motion = YawSwing(pitch=1 * DEG, roll=-2 * DEG, amplitude=6 * DEG, period=period)
    dur = 12 * 3600.0
    trad = build_scheme("two-position", RATE, TS).plan(motion, dur)
    null = NullingTwoPosition(RATE, TS).plan(motion, dur)
    rate_trad = trad.motor_starts() / trad.end
    rate_null = null.motor_starts() / null.end
    assert rate_null <= rate_trad * (1 + 1e-9)
    assert all(abs(abs(a) - math.pi) < 1e-12 for a, _ in _steps(null))
    assert all(d >= TS - 1e-9 for _, d in _steps(null))


def test_static_base_gives_the_cancelling_mean_zero_cycle():
    motion = Motion(heading=15 * DEG, pitch=1 * DEG, roll=-2 * DEG)
    table = NullingTwoPosition(RATE, TS).plan(motion, 6 * 3600.0)
    steps = _steps(table)
    assert all(d == TS for _, d in steps)
    assert [math.copysign(1, a) for a, _ in steps[:8]] == list(TURNS) * 2
    assert np.all(np.abs(table.a0) <= math.pi + 1e-12)
    cycle = TableScheme("custom", tuple(Step("outer", a, d) for a, d in steps[:4]), RATE, TS)
    ci = cycle_integrals(cycle, motion)
    assert np.max(np.abs(ci.horizontal)) < 1e-9
    assert np.max(np.abs(ci.scale_factor)) < 1e-12  # net table angle zero over the cycle


def _turn_midpoints(table):
    return np.array(
        [
            table.t0[k] + 0.5 * table.duration[k]
            for k in range(len(table))
            if table.kind[k] == "rotate"
        ]
    )


@pytest.mark.parametrize("period", [20.0, 60.0, 330.0, 866.0, 1200.0])
def test_synchronous_turns_are_centred_on_heading_maxima_a_whole_number_of_periods_apart(period):
    # Once the period is known (three reversals in the history), every turn's middle is
    # a heading maximum of the swing (heading = A sin(w t): maxima at T/4 + n T), so
    # consecutive turns are whole periods apart; every stop lasts at least Ts and at
    # most Ts plus one period; turns are 180 deg in the mean-zero order.
    motion = YawSwing(pitch=1 * DEG, roll=-2 * DEG, amplitude=3 * DEG, period=period)
    dur = 12 * 3600.0
    table = NullingTwoPosition(RATE, TS, phase="synchronous").plan(motion, dur)
    mid = _turn_midpoints(table)
    settled = mid[mid > HISTORY_TIME + period]
    assert len(settled) > 10
    # The maxima come from yaw-rate reversals sampled at 100 Hz (interpolated zero):
    # within a small fraction of a sample.
    phase = (settled - period / 4.0) / period
    assert np.max(np.abs(phase - np.round(phase))) * period < 1e-3
    steps = _steps(table)
    assert all(abs(abs(a) - math.pi) < 1e-12 for a, _ in steps)
    assert [math.copysign(1, a) for a, _ in steps[:8]] == list(TURNS) * 2
    dwell = np.array([d for _, d in steps[:-1]])
    assert np.all(dwell >= TS - 1e-9) and np.all(dwell <= TS + period + 1e-6)
    trad = build_scheme("two-position", RATE, TS).plan(motion, dur)
    assert table.motor_starts() / table.end <= trad.motor_starts() / trad.end * (1 + 1e-9)


def test_synchronous_turns_cancel_the_projection_and_the_tilt_coupled_kicks():
    # Every two-turn cycle sees the same swing with opposite table signs, so what is
    # linear in the table's sign cancels cycle by cycle: the bias projection and the
    # tilt x yaw-rate integral stay within one cycle's worth (no growth), on a swing
    # (P0 experiment 2's 60 s period at a 330 s + 30 s cycle) where the traditional
    # cycle resonates and both grow linearly.
    dur = 12 * 3600.0
    t_out = np.arange(0.0, dur + 1, 600.0)
    sync = NullingTwoPosition(RATE, TS, phase="synchronous").plan(P0_EXP2, dur)
    ints = error_integrals(sync, P0_EXP2, SITE.earth_rate_n, dur, t_out=t_out)
    tilt = np.abs(ints["mis_xz"][:, 2])
    half = len(tilt) // 2
    # Bounded: the second half of the run no larger than the first (a growing sum
    # would double); and cancelled, not only bounded: within 0.05, where the golden
    # rule's kicks stay within a few (0.167 here) and a fixed 360 s cycle reaches 0.091.
    assert tilt[half:].max() <= 1.05 * tilt[: half + 1].max() and tilt.max() < 0.05
    proj = np.linalg.norm(ints["bias_x"][:, :2], axis=1)
    assert proj[half:].max() <= 1.05 * proj[: half + 1].max() and proj.max() < 2 * (TS + 60.0)


def test_synchronous_dwell_edge_cases():
    # No period or no maximum yet: Ts. The wait ends on the first maximum the turn can
    # be centred on after Ts; an extension too short for it falls back (None).
    assert synchronous_dwell(TS, 30.0, 1000.0, None, 900.0, None) == TS
    assert synchronous_dwell(TS, 30.0, 1000.0, 120.0, None, None) == TS
    # last maximum 990 s, period 120 s: the turn (30 s) must start at or after 1300 s,
    # so it centres on 990 + 3 * 120 = 1350 s and starts at 1335 s: dwell 335 s.
    assert synchronous_dwell(TS, 30.0, 1000.0, 120.0, 990.0, None) == pytest.approx(335.0)
    assert synchronous_dwell(TS, 30.0, 1000.0, 120.0, 990.0, 35.0) == pytest.approx(335.0)
    assert synchronous_dwell(TS, 30.0, 1000.0, 120.0, 990.0, 34.0) is None
    # A maximum exactly at the earliest centre is taken (no extra period), also far into
    # a run, where the times carry round-off of their sums (~1e-11 s at 3e5 s).
    assert synchronous_dwell(TS, 30.0, 1000.0, 100.0, 915.0, None) == TS
    for start in (281550.1, 3.0e6 + 0.3):
        last = start + TS + 15.0 - 6 * 60.0
        assert synchronous_dwell(TS, 30.0, start, 60.0, last, None) == TS
        last_late = last + 1e-3  # a millisecond later: that maximum, 1 ms of waiting
        assert synchronous_dwell(TS, 30.0, start, 60.0, last_late, None) == pytest.approx(
            TS + 1e-3, abs=1e-6
        )
    # Inputs the rule never passes are refused, not turned into a wrong dwell.
    for period, last in ((0.0, 990.0), (-100.0, 990.0), (float("nan"), 990.0), (120.0, 1010.0)):
        with pytest.raises(ValueError):
            synchronous_dwell(TS, 30.0, 1000.0, period, last, None)


def test_heading_maxima_in_holds_at_the_peaks():
    # A trapezoid swing from a heading file (ramps of 20 s, holds of 10 s at 0 and 30
    # deg, period 60 s): the rate is zero through each hold, where the reversal sits.
    # The maxima are the middles of the top holds (25 s + k 60 s); the synchronous rule
    # then centres its turns on them (lengthening its stops), as on a smooth swing.
    period = 60.0
    t = np.arange(0.0, 6 * 3600.0 + 1.0, 5.0)
    phase = np.mod(t, period)
    h = np.interp(phase, [0.0, 20.0, 30.0, 50.0, 60.0], [0.0, 30.0, 30.0, 0.0, 0.0]) * DEG
    motion = HeadingHistory(pitch=1 * DEG, roll=-2 * DEG, times=t, headings=h)
    rev = yaw_rate_reversals(motion, 2 * 3600.0, 100.0)
    peaks = heading_maxima(motion, rev)
    assert len(peaks) == 120
    # The reversal in a hold is the middle of the last and first non-zero samples at
    # 100 Hz around it (19.99 s and 30 s): within one sample of the hold's middle.
    np.testing.assert_allclose(np.mod(peaks, period), 25.0, atol=0.01)
    table = NullingTwoPosition(RATE, TS, phase="synchronous").plan(motion, 6 * 3600.0)
    assert table.meta["lengthened"] > 40 and table.meta["fallbacks"] == 0
    mid = _turn_midpoints(table)
    settled = mid[mid > HISTORY_TIME + period]
    assert np.max(np.abs(np.mod(settled - 25.0 + 30.0, period) - 30.0)) < 0.01


def test_synchronous_phase_on_a_static_base_is_the_mean_zero_cycle():
    motion = Motion(heading=15 * DEG, pitch=1 * DEG, roll=-2 * DEG)
    a = NullingTwoPosition(RATE, TS, phase="synchronous").plan(motion, 6 * 3600.0)
    b = NullingTwoPosition(RATE, TS).plan(motion, 6 * 3600.0)
    np.testing.assert_array_equal(a.t0, b.t0)
    np.testing.assert_array_equal(a.a0, b.a0)
    with pytest.raises(InputError, match="scheme.phase"):
        NullingTwoPosition(RATE, TS, phase="resonant")


def test_without_oscillation_every_stop_lasts_ts():
    for motion in (Motion(), Turn(rate=2 * DEG), YawSwing(amplitude=1e-6 * DEG, period=60.0)):
        table = NullingTwoPosition(RATE, TS).plan(motion, 4 * 3600.0)
        assert all(d == TS for _, d in _steps(table))
        assert table.meta["lengthened"] == 0


def test_plan_is_deterministic():
    a = NullingTwoPosition(RATE, TS).plan(P0_EXP2, 2 * 3600.0)
    b = NullingTwoPosition(RATE, TS).plan(P0_EXP2, 2 * 3600.0)
    for field in ("t0", "duration", "rate", "a0"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
    assert a.labels == b.labels


def test_period_estimate_from_yaw_rate_reversals():
    motion = YawSwing(amplitude=3 * DEG, period=47.3)
    rev = yaw_rate_reversals(motion, 3600.0, 100.0)
    assert heading_period(rev, 3600.0, 2400.0) == pytest.approx(47.3, rel=1e-4)
    assert heading_period(rev, 30.0, 2400.0) is None  # fewer than three reversals yet


def test_step_dwell_edge_cases():
    assert step_dwell(TS, 30.0, None, TS) == TS
    d = step_dwell(TS, 30.0, 120.0, TS)
    assert TS <= d < TS + 120.0 * PHASE_MODULUS
    frac = ((d + 30.0) / 120.0) % PHASE_MODULUS
    assert min(abs(frac - x) for x in PHASE_FRACTIONS) == pytest.approx(0.0, abs=1e-12)
    # A slow swing needs more lengthening than allowed: the caller falls back to Ts.
    assert step_dwell(TS, 30.0, 4000.0, TS) is None
    assert step_dwell(TS, 30.0, 4000.0, 500.0) == pytest.approx(4000.0 * PHASE_FRACTIONS[0] - 30.0)


def test_scheme_catalogue_and_bad_options():
    s = build_scheme("nulling-two-position", RATE, TS, delta=0.01, variant="threshold", f=100.0)
    assert isinstance(s, NullingTwoPosition)
    with pytest.raises(InputError):
        NullingTwoPosition(RATE, TS, variant="crossing")
    with pytest.raises(InputError):
        NullingTwoPosition(RATE, TS, f=0.0)


def test_reversals_through_a_hold_are_found():
    """Turn right 10 s, hold 10 s (rate exactly 0), turn left 10 s, hold, right again.

    The rate never changes sign between two adjacent samples, only across the holds:
    the reversals are the middles of the holds, 15 s and 35 s (exact for this
    piecewise-linear heading; the samples fall on the hold edges).
    """
    from inserr.schemes.vehicle_motion import HeadingHistory

    times = np.array([0.0, 10.0, 20.0, 30.0, 40.0, 50.0])
    headings = np.radians([0.0, 10.0, 10.0, 0.0, 0.0, 10.0])
    rev = yaw_rate_reversals(HeadingHistory(times=times, headings=headings), 50.0, 10.0)
    np.testing.assert_allclose(rev, [15.0, 35.0], atol=0.06)


@pytest.mark.parametrize("phase", [0, 1])
def test_design_family_decodes_the_phase_rule_into_a_scenario_table_that_plans_the_same(phase):
    # The nulling design family's phase variable (0 golden, 1 synchronous) reaches the
    # scheme, and the [scheme] table it writes (what chosen_scheme.toml holds and
    # `inserr run` reads) plans the same schedule on the scenario's swing.
    from pathlib import Path

    from inserr.design.families import build_family
    from inserr.scenario.schema import load_scenario

    root = Path(__file__).resolve().parents[1]
    scen = load_scenario(root / "analyses" / "design_p0" / "scenario.toml").with_changes(
        {"scenario.duration": "6 h"}
    )
    fam = build_family(scen, "nulling")
    assert [v.name for v in fam.variables()][:3] == ["stop", "extension", "phase"]
    assert fam.start()[2] == 0.0  # the catalogue's golden rule seeds the search
    dec = fam.decode([320.0, 1500.0, float(phase)])
    want = ("golden", "synchronous")[phase]
    assert dec.scheme.phase == want and dec.table["phase"] == want
    changes = {f"scheme.{k}": v for k, v in dec.table.items()}
    written = scen.with_changes(changes)
    a = dec.scheme.plan(scen.motion, scen.duration)
    b = written.scheme().plan(written.motion, written.duration)
    np.testing.assert_array_equal(a.t0, b.t0)
    np.testing.assert_array_equal(a.a0, b.a0)
