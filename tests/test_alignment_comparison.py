"""Tests of the alignment scheme comparison (:mod:`inserr.alignment.comparison`, the study
behind ``analyses/alignment_observability``). The whole study and its write-up run in
``tests/test_analyses.py`` (the script's quick mode).

Independent truth: the schedule of a stop-and-turn scheme written out by hand (a stop,
then 180 deg at the table rate, ...), closed-form sigma curves (exponential decay, so the
time to reach a level is tau ln(sigma0 / level)), the degree-of-observability thresholds
as defined, and the textbook observability of static alignment (zero-velocity updates
cannot tell a horizontal accelerometer bias from a tilt, nor the east gyro bias from
heading; two headings 180 deg apart can).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from inserr.alignment.comparison import (
    NOT,
    WELL,
    classic,
    classify,
    costs,
    observability,
    stop_sweep,
)
from inserr.alignment.filter import STATES, UNITS, Prior, Settings, static_floors
from inserr.alignment.study import SHOWN, Base, alignment_timeline
from inserr.core.earth import Site
from inserr.core.imu import ImuErrors
from inserr.core.units import ARCMIN, DEG, DEG_PER_HOUR, MICRO_G
from inserr.schemes.vehicle_motion import Motion

SITE = Site(34.0 * DEG)
MOTION = Motion(heading=15 * DEG, pitch=1 * DEG, roll=-2 * DEG)
RATE = 6 * DEG  # rad/s
TURN = math.pi / RATE  # s: one 180 deg turn


def _standin(t: np.ndarray, sigma: np.ndarray):
    """A filter result with only what :func:`costs` and :func:`classify` read."""
    return SimpleNamespace(
        t=t,
        sigma=sigma,
        observability_degree=lambda: sigma[0] / sigma[-1],
    )


def test_costs_count_turning_time_and_stops_from_the_schedule():
    """Two-position, 60 s stops, 3 min: stop [0, 60], turn [60, 90], stop [90, 150],
    turn [150, 180]: 60 s turning (a third), two stops."""
    stop, duration = 60.0, 180.0
    tl = alignment_timeline(Base(SITE, MOTION, RATE, stop), "two-position", duration)
    t = np.arange(0.0, duration + 0.5, 1.0)
    sigma = np.ones((len(t), len(STATES)))
    c = costs(_standin(t, sigma), tl, {"phi_u": 0.5}, np.ones(len(STATES)))
    assert TURN == pytest.approx(30.0, rel=1e-12)
    assert c["turning_s"] == pytest.approx(2 * TURN, rel=1e-9)
    assert c["turning_fraction"] == pytest.approx(2 * TURN / duration, rel=1e-9)
    assert c["stops"] == 2
    # sigma never falls: the times to reach a level are undefined (NaN, never a number).
    assert math.isnan(c["time_to_static_heading_floor_s"])
    assert math.isnan(c["time_to_accel_xy_10pct_s"])
    # The unindexed scheme never turns and makes one stop.
    tl0 = alignment_timeline(Base(SITE, MOTION, RATE, stop), "none", duration)
    c0 = costs(_standin(t, sigma), tl0, {"phi_u": 0.5}, np.ones(len(STATES)))
    assert (c0["turning_s"], c0["stops"]) == (0.0, 1)


def test_costs_times_follow_closed_form_sigma_curves():
    """sigma(t) = s0 exp(-t / tau) reaches a level L at tau ln(s0 / L); the reported time is
    the first output sample at or after it (1 s grid)."""
    duration, tau = 600.0, 50.0
    tl = alignment_timeline(Base(SITE, MOTION, RATE, 60.0), "two-position", duration)
    t = np.arange(0.0, duration + 0.5, 1.0)
    prior = np.ones(len(STATES))
    sigma = np.exp(-t[:, None] / tau) * prior[None, :]
    floor = 0.2
    c = costs(_standin(t, sigma), tl, {"phi_u": floor}, prior)
    assert c["time_to_static_heading_floor_s"] == math.ceil(tau * math.log(1 / floor))
    assert c["time_to_accel_xy_10pct_s"] == math.ceil(tau * math.log(10.0))
    # Heading sigma at 2, 5 and 10 min, in the state's engineering unit (arcmin).
    assert UNITS["phi_u"][1] == pytest.approx(ARCMIN, rel=1e-12)
    for m in (2, 5):
        assert c["heading_sigma_arcmin_at_min"][str(m)] == pytest.approx(
            math.exp(-60 * m / tau) / ARCMIN, rel=1e-12
        )
    # Against a static run whose sigma decays twice as slowly, the scheme is better from
    # the first sample after t = 0 (ratio exp(-t/(2 tau)) < 1 for t > 0).
    static = _standin(t, np.exp(-t[:, None] / (2 * tau)) * prior[None, :])
    c2 = costs(_standin(t, sigma), tl, {"phi_u": floor}, prior, static)
    assert c2["time_heading_better_than_static_s"] == 0.0


def test_classify_uses_the_degree_of_observability_thresholds():
    t = np.array([0.0, 1.0])
    final = {"phi_e": 1 / (WELL * 1.01), "phi_n": 1 / (NOT * 0.99), "phi_u": 1 / 3.0}
    sigma = np.ones((2, len(STATES)))
    for s, v in final.items():
        sigma[1, STATES.index(s)] = v
    cls = classify(_standin(t, sigma))
    assert "phi_e" in cls["well"]
    assert "phi_n" in cls["not"]
    assert "phi_u" in cls["partly"]
    assert sorted(cls["well"] + cls["partly"] + cls["not"]) == sorted(SHOWN)


def test_classic_picture_one_heading_rank_seven_two_headings_full():
    c = classic(SITE, 15 * DEG)
    assert (c["one_heading"]["rank"], c["one_heading"]["n_states"]) == (7, 10)
    assert len(c["one_heading"]["unobservable"]) == 3
    assert (c["two_headings"]["rank"], c["two_headings"]["unobservable"]) == (10, [])


def test_static_alignment_cannot_separate_tilts_heading_and_horizontal_biases():
    """Static, zero-velocity updates: the tilt/accelerometer-bias and heading/east-gyro-bias
    pairs are not separately observable; indexing with position fixes makes every shown
    state observable (the two-heading result of the classic picture, with the position
    error pinned)."""
    ob = observability(
        SITE, Base(SITE, MOTION, RATE, 60.0), ["none", "two-position"], 300.0, "free"
    )
    static = ob["none"]["zupt"]["separately_observable"]
    for s in ("phi_e", "phi_n", "phi_u", "accel_bias_x", "accel_bias_y"):
        assert not static[s]
    assert ob["none"]["zupt"]["rank"] < ob["none"]["zupt"]["n_states"]
    indexed = ob["two-position"]["zupt_position"]
    assert indexed["rank"] == indexed["n_states"]
    assert all(indexed["separately_observable"].values())


def test_stop_sweep_counts_stops_from_the_schedule():
    """Two-position for 120 s: stop 20 s -> stops at 0, 50 and 100 s, turning [20, 50] and
    [70, 100]; stop 50 s -> stops at 0 and 80 s, turning [50, 80]. The static floor is the
    textbook tilt limit accel bias / g (diffuse prior, IMU near level: the 1 and 2 deg
    tilts move it by < 0.1 %, the mixing of the equal horizontal biases by a few %)."""
    accel = 30 * MICRO_G
    imu = ImuErrors(gyro_bias=np.full(3, 0.003 * DEG_PER_HOUR), accel_bias=np.full(3, accel))
    c_sn = alignment_timeline(Base(SITE, MOTION, RATE, 60.0), "none", 1.0).c_sn[0]
    floors = static_floors(SITE, imu.gyro_bias, imu.accel_bias, c_sn)
    assert floors["phi_e"] == pytest.approx(accel / SITE.g, rel=0.05)
    rows, runs = stop_sweep(
        SITE, MOTION, RATE, "two-position", (20.0, 50.0), 120.0, imu, Prior(), Settings(), floors
    )
    assert [r["stop_s"] for r in rows] == [20.0, 50.0]
    assert [r["stops_in_run"] for r in rows] == [3, 2]
    assert rows[0]["turning_fraction"] == pytest.approx(2 * TURN / 120.0, rel=1e-9)
    assert rows[1]["turning_fraction"] == pytest.approx(TURN / 120.0, rel=1e-9)
    assert list(runs) == ["20 s", "50 s"]
