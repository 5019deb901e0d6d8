"""The open-loop rotation tables are the ones their documentation states.

Each expectation is copied from a docstring or ``docs/schemes.md`` (positions, turn
signs, dwells, labels, names), never from the code's output: P0's two-position cycle
+180, +180, -180, -180; P2's four-position A(-135) -> C(+45) -> D(+135) -> B(-45) -> A
with stops of ``stop + 2/rate`` at A and D when modified; continuous rotation reversing
every ``reversal`` seconds rounded to whole revolutions; the eight- and sixteen-position
gimbal orders; the PSINS sixteen-position table translated to gimbal turns.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from inserr.core.units import DEG
from inserr.schemes.catalogue import SCHEMES, build_scheme
from inserr.schemes.vehicle_motion import Motion

RATE = 6 * DEG
STOP = 100.0
OPEN_LOOP = (
    "none",
    "continuous",
    "two-position",
    "four-position",
    "four-position-modified",
    "eight-position",
    "sixteen-position",
    "sixteen-position-inserr",
)


def _plan(name: str, duration: float, **options):
    return build_scheme(name, RATE, STOP, **options).plan(Motion(), duration)


@pytest.mark.parametrize("name", OPEN_LOOP)
def test_every_open_loop_scheme_carries_its_catalogue_name(name):
    assert name in SCHEMES
    assert build_scheme(name, RATE, STOP).name == name


def test_two_position_is_p0s_plus_plus_minus_minus_cycle():
    s = build_scheme("two-position", RATE, STOP)
    table = s.plan(Motion(), s.first_dwell + 2 * s.cycle_time)
    turns = [
        (g, round(r / RATE))
        for k, g, r in zip(table.kind, table.gimbal, table.rate, strict=True)
        if k == "rotate"
    ]
    assert turns == [("outer", 1), ("outer", 1), ("outer", -1), ("outer", -1)] * 2
    stops = [lab for k, lab in zip(table.kind, table.labels, strict=True) if k == "stop"]
    assert stops[:5] == ["stop 0", "stop 180", "stop 360", "stop 180", "stop 0"]
    # Four 180 deg turns at 6 deg/s (30 s each) and four stops per cycle.
    assert s.cycle_time == pytest.approx(4 * (30.0 + STOP))


@pytest.mark.parametrize("modified", [False, True])
def test_four_position_visits_a_c_d_b_with_p2s_longer_stops_when_modified(modified):
    name = "four-position-modified" if modified else "four-position"
    s = build_scheme(name, RATE, STOP)
    table = s.plan(Motion(), s.first_dwell + 2 * s.cycle_time)
    stops = [
        (lab, round(math.degrees(a)), d)
        for k, lab, a, d in zip(table.kind, table.labels, table.a0, table.duration, strict=True)
        if k == "stop"
    ]
    extra = 2.0 / RATE if modified else 0.0  # P2: stop + 2 / rate (rate in rad/s) at A and D
    want = [
        ("stop A", -135, STOP + extra),
        ("stop C", 45, STOP),
        ("stop D", 135, STOP + extra),
        ("stop B", -45, STOP),
        ("stop A", -135, STOP + extra),
    ]
    for (lab, ang, dur), (wl, wa, wd) in zip(stops, want, strict=False):
        assert (lab, ang) == (wl, wa)
        assert dur == pytest.approx(wd, rel=1e-12)
    # Turns of 180, 90, 180, 90 deg at 6 deg/s: 90 s of turning per cycle.
    assert s.cycle_time == pytest.approx(90.0 + 4 * STOP + 2 * extra, rel=1e-12)


@pytest.mark.parametrize("reversal_revs", [None, 1, 3])
def test_continuous_turns_whole_revolutions_and_reverses_every_reversal_time(reversal_revs):
    rev_time = 2 * math.pi / RATE  # 60 s
    options = {} if reversal_revs is None else {"reversal": reversal_revs * rev_time}
    table = _plan("continuous", STOP + 12 * rev_time, **options)
    assert table.kind[0] == "stop" and table.labels[0] == "stop start"
    assert table.duration[0] == STOP
    # After the opening stop: only whole-revolution turns, no dwell between them.
    assert set(table.kind[1:]) == {"rotate"}
    assert np.allclose(table.duration[1:], rev_time, rtol=1e-12)
    signs = np.sign(table.rate[1:13]).astype(int).tolist()
    labels = list(table.labels[1:13])
    if reversal_revs is None:
        assert signs == [1] * 12
        assert labels == ["outer +360 -> +rev"] * 12
    else:
        n = reversal_revs
        block = [1] * n + [-1] * n
        assert signs == (block * 12)[:12]
        assert labels == [f"outer {s * 360:+d} -> {'+' if s > 0 else '-'}rev" for s in signs]


def test_any_positive_reversal_time_reverses_at_least_every_revolution():
    # A reversal time below one revolution still reverses (after one whole revolution).
    table = _plan("continuous", STOP + 240.0, reversal=1.0)
    assert np.sign(table.rate[1:5]).astype(int).tolist() == [1, -1, 1, -1]


@pytest.mark.parametrize(
    "name, gimbals, labels",
    [
        (
            "eight-position",
            "o+ i+ o+ i+ o- i- o- i-",
            [f"P{i}" for i in range(1, 9)],
        ),
        (
            "sixteen-position-inserr",
            "o+ i+ o+ i+ o- i- o- i- i+ o+ i+ o+ i- o- i- o-",
            [f"P{i}" for i in range(1, 9)] + [f"Q{i}" for i in range(1, 9)],
        ),
        (
            # PSINS rows 1-16 in gimbal turns, as the docstring of sixteen_position lists.
            "sixteen-position",
            "o+ i- o- i- i- o- i- o+ o- i+ o+ i+ i+ o+ i+ o-",
            [f"P{i}" for i in range(1, 17)],
        ),
    ],
)
def test_dual_axis_gimbal_orders_and_position_labels(name, gimbals, labels):
    s = build_scheme(name, RATE, STOP)
    table = s.plan(Motion(), s.first_dwell + s.cycle_time)
    turns = [
        ("o" if g == "outer" else "i") + ("+" if r > 0 else "-")
        for k, g, r in zip(table.kind, table.gimbal, table.rate, strict=True)
        if k == "rotate"
    ]
    assert turns == gimbals.split()
    rotate_durations = [d for k, d in zip(table.kind, table.duration, strict=True) if k == "rotate"]
    assert np.allclose(rotate_durations, 30.0, rtol=1e-12)  # 180 deg at 6 deg/s
    stops = [lab for k, lab in zip(table.kind, table.labels, strict=True) if k == "stop"]
    assert stops == ["stop P0"] + [f"stop {lab}" for lab in labels]
    assert s.cycle_time == pytest.approx(len(labels) * (30.0 + STOP), rel=1e-12)


def test_none_holds_the_start_position_for_the_whole_run():
    table = _plan("none", 5000.0)
    assert table.kind == ("stop",) and table.labels == ("stop start",)
    assert table.duration[0] == 5000.0 and table.a0[0] == 0.0 and table.b0[0] == 0.0
    assert build_scheme("none", RATE, STOP).cycle_time is None


def test_builders_default_to_the_plain_schemes():
    # Called without options, the builders give the plain schemes their docstrings
    # describe: continuous rotation that never reverses (every row turns the same way),
    # and P2's four-position cycle without the modified stops (all four stops equal).
    from inserr.schemes.open_loop import continuous, four_position

    rate = 6 * DEG
    c = continuous(rate, 300.0)
    assert len({math.copysign(1.0, s.angle) for s in c.steps}) == 1
    f = four_position(rate, 300.0)
    assert f.name == "four-position"
    assert {s.dwell for s in f.steps} == {300.0}
    assert f.first_dwell == 300.0


def test_opening_phase_and_the_end_of_a_plan():
    # with_start: "turn" drops the opening stop (the plan starts turning at t = 0),
    # "stop" and a scheme without steps are returned as they are.
    from inserr.schemes.open_loop import none_scheme, two_position, with_start

    rate = 6 * DEG
    two = two_position(rate, 300.0)
    assert with_start(two, "stop") is two
    none = none_scheme(rate, 300.0)
    assert with_start(none, "turn") is none
    turned = with_start(two, "turn")
    assert turned.first_dwell == 0.0 and turned.steps == two.steps
    table = turned.plan(Motion(), 1000.0)
    assert table.kind[0] == "rotate" and table.t0[0] == 0.0
    # A run ending exactly at a segment boundary (stop, turn, stop: 300 + 30 + 300 s)
    # plans no segment that starts at or after the end.
    table = two.plan(Motion(), 630.0)
    assert np.all(table.t0 < 630.0)
    assert table.t0[-1] + table.duration[-1] == pytest.approx(630.0, abs=1e-9)


def test_cycle_integrals_name_an_object_without_a_name():
    from inserr.core.errors import InputError
    from inserr.schemes.cycle_integrals import cycle_integrals

    with pytest.raises(InputError, match="not a scheme has no fixed cycle"):
        cycle_integrals("not a scheme")


def test_a_step_that_does_not_turn_is_refused_by_the_library_too():
    # A 0 deg step would have a zero turn time (|angle| / rate) and a 0 / 0 turn rate.
    from inserr.schemes.open_loop import Step

    for angle in (0.0, -0.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="must turn"):
            Step("outer", angle, 10.0)
    assert Step("outer", 1e-9, 10.0).angle == 1e-9  # any turn, however small, is a step
