"""Schemes composed with vehicle motion: exactness, isolation, the flexible rule, sub-steps."""

import math

import numpy as np
import pytest

from inserr.drift import analyze_drift
from inserr.earth import Site
from inserr.imu import ImuErrors, InitialErrors
from inserr.motion import Motion, Turn, YawSwing
from inserr.rotations import heading_of
from inserr.schedule import build_timeline
from inserr.schemes import build_scheme
from inserr.units import ARCSEC, DEG, DEG_PER_HOUR, MICRO_G, PPM

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


@pytest.mark.parametrize("variant", ["threshold", "crossing"])
def test_flexible_rule_stops_where_its_test_says(variant):
    f, ts, delta = 100.0, 300.0, 0.01
    scheme = build_scheme("flexible-two-position", RATE, ts, variant=variant)
    table = scheme.plan(P0_MOTION, 2 * 3600.0)
    assert table.meta["fallbacks"] == 0
    sums = np.zeros(2)
    for k, lab in enumerate(table.labels):
        t0, dur = table.t0[k], table.duration[k]
        if table.kind[k] == "stop":
            kk = np.arange(math.ceil(t0 * f - 1e-9), math.ceil((t0 + dur) * f - 1e-9))
            t = kk / f
            h = heading_of(P0_MOTION.attitude(t) @ table.dcm_at(t, P0_MOTION))
            sums += [np.cos(h).sum(), np.sin(h).sum()]
        elif lab.startswith("variable"):
            t_end = np.array([t0 + dur])
            h = heading_of(P0_MOTION.attitude(t_end) @ table.dcm_at(t_end, P0_MOTION))[0]
            forward = table.rate[k] > 0
            main, other = (math.cos(h), math.sin(h)) if forward else (math.sin(h), math.cos(h))
            expr = main + sums[0 if forward else 1] / (f * ts)
            if variant == "threshold":
                assert abs(expr) < delta
            else:
                # Stopped at the first sample past the zero: within one sample's change.
                assert abs(expr) < RATE / f + 6 * DEG / f
            assert np.sign(other) == -np.sign(sums[1 if forward else 0])


def test_motor_starts_of_two_position():
    table = build_scheme("two-position", RATE, 300.0).plan(Motion(), 4 * 1320.0 + 300.0)
    assert table.motor_starts() == 16  # four turns per 1320 s cycle, each from a stop


def test_bad_durations_and_schemes_raise_input_errors():
    from inserr.errors import InputError

    with pytest.raises(InputError, match="duration"):
        build_timeline(build_scheme("none", RATE, 300.0).plan(Motion(), 10.0), Motion(), -5.0)
    with pytest.raises(InputError, match="unknown scheme"):
        build_scheme("three-position", RATE, 300.0)
    with pytest.raises(InputError, match="--rate"):
        build_scheme("two-position", float("nan"), 300.0)
