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
from inserr.schemes.vehicle_motion import Motion, YawSwing


def _skew(w: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def _max_interval_mismatch(tl) -> float:
    worst = 0.0
    for k, w in enumerate(tl.omega_n):
        dt = tl.times[k + 1] - tl.times[k]
        carried = sl.expm(dt * _skew(w)) @ tl.c_sn[k]
        worst = max(worst, float(np.abs(carried - tl.c_sn[k + 1]).max()))
    return worst


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


def _scheme(name: str, stop: float):
    return QUARTER if name == "quarter-turns" else build_scheme(name, 6 * DEG, stop)


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
    ],
    ids=lambda p: p if isinstance(p, str) else type(p).__name__ + ("-tilted" if p.pitch else ""),
)
def test_interval_rates_carry_each_node_attitude_into_the_next(scheme, motion):
    s = _scheme(scheme, 20.0)
    duration = 1.5 * (s.cycle_time or 200.0)
    tl = build_timeline(s.plan(motion, duration), motion, duration)
    # Exact intervals (stops, turns on a static base): w is the exact rate, error ~1e-15
    # per interval. Sub-steps of a swinging base: w is the geodesic rate between exact
    # nodes, so the nodes are carried exactly too. Wrong gimbal order, axis or frame
    # of a rate: an O(rate x dt) ~ 0.1 error.
    assert _max_interval_mismatch(tl) < 1e-9


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
