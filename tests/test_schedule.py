"""Schemes composed with vehicle motion: exactness, isolation, the flexible rule, sub-steps."""

import math

import numpy as np
import pytest

from inserr.core.earth import Site
from inserr.core.imu import ImuErrors, InitialErrors
from inserr.core.rotations import heading_of
from inserr.core.units import ARCSEC, DEG, DEG_PER_HOUR, MICRO_G, PPM
from inserr.drift.analysis import analyze_drift
from inserr.schemes.catalogue import build_scheme
from inserr.schemes.composition import build_timeline
from inserr.schemes.open_loop import Step
from inserr.schemes.turntable import table_dcm
from inserr.schemes.vehicle_motion import Motion, Turn, YawSwing

RATE = 6 * DEG
P0_MOTION = YawSwing(
    heading=15 * DEG, pitch=1 * DEG, roll=-2 * DEG, amplitude=6 * DEG, period=120.0
)


def test_static_vehicle_schedules_are_exact_single_intervals():
    scheme = build_scheme("four-position", RATE, 300.0)
    table = scheme.plan(Motion(heading=0.3, pitch=0.01), 7200.0)
    tl = build_timeline(table, Motion(heading=0.3, pitch=0.01), 7200.0)
    assert tl.meta["exact_intervals"] == len(tl.omega_n)
    assert len(tl.omega_n) == np.count_nonzero(table.t0 < 7200.0)
    # Propagating the attitude with the interval rates reproduces the exact node attitudes.
    mid = tl.attitude_at(tl.times[1:] - 1e-9)
    assert np.allclose(mid, tl.c_sn[1:], atol=1e-9)


def test_table_turn_on_level_turning_vehicle_is_exact():
    motion = Turn(heading=0.0, rate=2 * DEG)
    tl = build_timeline(
        build_scheme("two-position", RATE, 100.0).plan(motion, 1000.0), motion, 1000.0
    )
    assert tl.meta["exact_intervals"] == len(tl.omega_n)
    # IMU heading = vehicle heading - table angle (level vehicle, right-hand table angle).
    t = np.array([50.0, 115.0, 400.0])
    a, _ = tl.meta["table"].angles_at(t)
    assert np.allclose(
        np.unwrap(heading_of(tl.attitude_at(t))),
        np.unwrap(np.mod(motion.heading_at(t) - a, 2 * math.pi)),
    )


def test_yaw_swing_substeps_converge():
    # Geodesic sub-steps: halving the step should change a 1 h drift by O(h^2), i.e. tiny.
    site = Site.from_degrees(34.246)
    imu = ImuErrors(
        gyro_bias=np.full(3, 0.003 * DEG_PER_HOUR),
        accel_bias=np.full(3, 30 * MICRO_G),
        gyro_scale_factor=np.full(3, 10 * PPM),
        gyro_misalignment=np.full(6, 10 * ARCSEC),
    )
    table = build_scheme("two-position", RATE, 300.0).plan(P0_MOTION, 3600.0)
    runs = []
    for h in (2.0, 1.0, 0.5):
        tl = build_timeline(table, P0_MOTION, 3600.0, substep=h)
        runs.append(analyze_drift(site, imu, InitialErrors(), tl, dt_out=60.0).nav)
    e1 = np.abs(runs[0] - runs[2]).max()
    e2 = np.abs(runs[1] - runs[2]).max()
    scale = np.abs(runs[2]).max()
    assert e2 < 1e-3 * scale  # 1 s sub-steps: better than 0.1 % of the error itself
    assert e2 < 0.5 * e1  # and the error falls as the step shrinks (second order: ~1/4)


def test_heading_isolation_holds_the_imu_heading():
    scheme = build_scheme("heading-isolation", RATE, 300.0)
    table = scheme.plan(P0_MOTION, 3000.0)
    holds = [k for k, lab in enumerate(table.labels) if lab.startswith("hold")]
    assert holds
    for k in holds:
        t = table.t0[k] + np.linspace(0.0, table.duration[k], 50)
        t = t[t < 3000.0]
        h = heading_of(P0_MOTION.attitude(t) @ table.dcm_at(t, P0_MOTION))
        # Exact geometry (full DCMs), independent of the closed-form isolation angle.
        assert np.allclose(np.angle(np.exp(1j * (h - table.target_heading[k]))), 0.0, atol=1e-9)
    # Each swing period reverses the compensating table rate twice.
    assert table.meta["isolation_reversals"] == pytest.approx(2 * 3000.0 / 120.0, abs=3)


F, TS, DELTA = 100.0, 300.0, 0.01


def _imu_heading_true(motion, t, a):
    """IMU heading from full DCMs (independent of the planner's closed-form offset)."""
    return heading_of(motion.attitude(t) @ table_dcm(a, np.zeros_like(a)))


def _variable_turns(table, motion):
    """Each variable turn with the stop sums before it and its criterion over a full turn.

    Yields ``(k, expr, sign_ok, n)``: segment index, the stop expression at samples
    1..N of a full 360 deg turn from the turn's start (N = ceil(360 deg / rate * f)),
    the sign condition there, and the sample the table actually stopped at.
    """
    sums = np.zeros(2)
    per_turn = math.ceil(2 * math.pi / RATE * F)
    j = np.arange(1, per_turn + 1)
    for k, lab in enumerate(table.labels):
        t0, dur = table.t0[k], table.duration[k]
        if table.kind[k] == "stop":
            kk = np.arange(math.ceil(t0 * F - 1e-9), math.ceil((t0 + dur) * F - 1e-9))
            h = _imu_heading_true(motion, kk / F, table.angles_at(kk / F, motion)[0])
            sums += [np.cos(h).sum(), np.sin(h).sum()]
        elif lab.startswith("variable"):
            forward = table.rate[k] > 0
            which = 0 if forward else 1
            t = t0 + j / F
            h = _imu_heading_true(motion, t, table.a0[k] + table.rate[k] * j / F)
            main, other = (np.cos(h), np.sin(h)) if forward else (np.sin(h), np.cos(h))
            expr = main + sums[which] / (F * TS)
            s_other = np.sign(sums[1 - which]) * (abs(sums[1 - which]) > 1e-9 * F * TS)
            sign_ok = (np.sign(other) == -s_other) | (s_other == 0)
            yield k, expr, sign_ok, round(dur * F)


def _passes(variant, expr, sign_ok):
    if variant == "threshold":
        return (np.abs(expr) < DELTA) & sign_ok
    prev = np.concatenate([[expr[0]], expr[:-1]])
    return (np.sign(expr) != np.sign(prev)) & sign_ok


@pytest.mark.parametrize("variant", ["threshold", "crossing"])
def test_flexible_rule_stops_where_its_test_says(variant):
    scheme = build_scheme("flexible-two-position", RATE, TS, variant=variant)
    table = scheme.plan(P0_MOTION, 2 * 3600.0)
    assert table.meta["fallbacks"] == 0
    turns = list(_variable_turns(table, P0_MOTION))
    assert len(turns) >= 4
    for _, expr, sign_ok, n in turns:
        passes = _passes(variant, expr, sign_ok)
        # Stopped at the first sample that passes the test (the sample at the stop passes).
        assert passes[n - 1] and not passes[: n - 1].any()
        if variant == "threshold":
            assert abs(expr[n - 1]) < DELTA
        else:
            # Stopped at the first sample past the zero: within one sample's change.
            assert abs(expr[n - 1]) < RATE / F + 6 * DEG / F


@pytest.mark.parametrize("variant", ["threshold", "crossing"])
@pytest.mark.parametrize("turn_rate", [6.0, -6.0])
def test_flexible_fallback_stops_at_the_best_sample_of_one_turn(variant, turn_rate):
    # A vehicle turning at the table rate freezes the IMU heading during the table's
    # turns in one direction: no stop angle passes the test, the fallback must act.
    motion = Turn(heading=15 * DEG, pitch=1 * DEG, roll=-2 * DEG, rate=turn_rate * DEG)
    scheme = build_scheme("flexible-two-position", RATE, TS, variant=variant)
    table = scheme.plan(motion, 3 * 3600.0)
    fallback_segments = [k for k, lab in enumerate(table.labels) if "(fallback)" in lab]
    assert table.meta["fallbacks"] == len(fallback_segments) >= 5
    checked = 0
    for k, expr, sign_ok, n in _variable_turns(table, motion):
        passes = _passes(variant, expr, sign_ok)
        if k not in fallback_segments:
            assert passes[n - 1] and not passes[: n - 1].any()
            continue
        checked += 1
        # Documented fallback: no sample of a full turn passes the test ...
        assert not passes.any()
        # ... and the table stops within that turn (never a whole revolution or more) ...
        assert 1 <= n <= len(expr) and abs(table.rate[k] * table.duration[k]) < 2 * math.pi
        # ... at the smallest |expression| among the sign-admissible samples (all if
        # none is), the earliest of equal values.
        pool = sign_ok if sign_ok.any() else np.ones_like(sign_ok)
        score = np.abs(expr)
        assert pool[n - 1]
        assert score[n - 1] <= score[pool].min() + 1e-9
        assert np.all(score[: n - 1][pool[: n - 1]] > score[n - 1] - 1e-9)
    assert checked == len(fallback_segments)
    # The table angle no longer runs away by whole revolutions (it used to reach 20 turns).
    assert np.abs(table.a0).max() < 8 * math.pi


def test_every_scheme_starts_with_a_stop_at_its_first_position():
    from inserr.schemes.catalogue import SCHEMES
    from inserr.schemes.open_loop import TableScheme

    custom = [Step("outer", 90 * DEG, 60.0, label="B"), Step("outer", -90 * DEG, 60.0)]
    for name in SCHEMES:
        opts = {"steps": custom} if name == "custom" else {}
        scheme = build_scheme(name, RATE, 300.0, **opts)
        table = scheme.plan(P0_MOTION, 3600.0)
        assert table.t0[0] == 0.0, name
        if name == "heading-isolation":
            # Its stop is a hold of the IMU heading (see HeadingIsolation's docstring).
            assert table.kind[0] == "isolate" and table.target_rate[0] == 0.0
            assert table.labels[0].startswith("hold")
        else:
            assert table.kind[0] == "stop" and table.labels[0].startswith("stop"), name
        assert table.duration[0] >= 300.0, name
        start = scheme.start if isinstance(scheme, TableScheme) else (0.0, 0.0)
        assert (table.a0[0], table.b0[0]) == pytest.approx(start), name
    # On a vehicle that does not yaw, heading isolation's opening hold is a literal stop.
    static = Motion(heading=0.3, pitch=0.01, roll=-0.02)
    table = build_scheme("heading-isolation", RATE, 300.0).plan(static, 1000.0)
    a, b = table.angles_at(np.linspace(0.0, 300.0, 31), static)
    assert np.allclose(a, a[0], atol=1e-12) and np.allclose(b, 0.0)


def test_motor_starts_of_two_position():
    table = build_scheme("two-position", RATE, 300.0).plan(Motion(), 4 * 1320.0 + 300.0)
    assert table.motor_starts() == 16  # four turns per 1320 s cycle, each from a stop


def test_bad_durations_and_schemes_raise_input_errors():
    from inserr.core.errors import InputError

    with pytest.raises(InputError, match="duration"):
        build_timeline(build_scheme("none", RATE, 300.0).plan(Motion(), 10.0), Motion(), -5.0)
    with pytest.raises(InputError, match="unknown scheme"):
        build_scheme("three-position", RATE, 300.0)
    with pytest.raises(InputError, match="scheme.rate"):
        build_scheme("two-position", float("nan"), 300.0)
