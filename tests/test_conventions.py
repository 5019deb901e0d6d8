"""Declared heading conventions, negative CLI values and the opening phase of a scheme.

The truths used here are independent of inserr's code: the geometry of a heading
written either way (where the forward axis points, what a level gyro reads of the
Earth rate), the definition of the two conventions (one is the other with every
heading and heading rate negated: the mirror identity), and the schedules a turn-first
opening must give (the stop-first schedule with its opening stop cut out).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from inserr.cli.main import main
from inserr.core.earth import OMEGA_IE
from inserr.core.errors import InputError
from inserr.drift.study import describe, run_scheme
from inserr.scenario.schema import scenario_from_dict
from inserr.schemes.vehicle_motion import HEADING_CONVENTIONS, heading_sign

CW, CCW = HEADING_CONVENTIONS
EAST, NORTH, UP = np.eye(3)

#: P0's IMU budget (every error source non-zero, so every response is compared).
P0_IMU = {
    "gyro_bias": "0.003, 0.004, 0.005 deg/h",
    "accel_bias": "30, 20, 10 ug",
    "gyro_scale_factor": "10, 20, 30 ppm",
    "accel_scale_factor": "10 ppm",
    "gyro_misalignment": "10, 20, 30, 40, 50, 60 arcsec",
    "accel_misalignment": "10 arcsec",
    "arw": "0.0005 deg/sqrt(h)",
    "vrw": "5 ug/sqrt(Hz)",
}


def _scenario(convention: str, motion: dict, scheme: dict | None = None, **sections):
    data = {
        "scenario": {"duration": "2 h"},
        "site": {"latitude": "34.246 deg"},
        "imu": P0_IMU,
        "initial": {"attitude": "10, 10, 60 arcsec", "velocity": "0.01 m/s", "position": "10 m"},
        "motion": {"heading_convention": convention, **motion},
        "scheme": {"name": "two-position", "stop": "300 s", **(scheme or {})},
        "output": {"step": "60 s", "covariance_step": "300 s"},
        **sections,
    }
    return scenario_from_dict(data)


def _arrays(run) -> dict[str, np.ndarray]:
    r = run.result
    return {
        "nav": r.nav,
        "attitude": r.attitude,
        "source_horizontal": r.source_horizontal,
        "source_heading": r.source_heading,
        **{f"noise_{k}": v for k, v in r.noise_cov.items()},
    }


def _assert_same(a: dict, b: dict) -> None:
    assert a.keys() == b.keys()
    for k in a:
        # 1e-12 of the largest value: the two runs must be the same computation (a
        # convention applied to some input but not another differs at first order).
        scale = max(float(np.max(np.abs(a[k]))), 1e-300)
        assert np.max(np.abs(a[k] - b[k])) <= 1e-12 * scale, k


def _far_apart(a: dict, b: dict) -> bool:
    x, y = a["source_horizontal"], b["source_horizontal"]
    return float(np.max(np.abs(x - y))) > 1e-3 * float(np.max(np.abs(x)))


SWING = {"type": "yaw-swing", "pitch": "1 deg", "roll": "-2 deg", "period": "120 s"}
MIRROR_CASES = {
    "yaw swing, two-position": (
        {**SWING, "heading": "15 deg", "amplitude": "6 deg/s"},
        {**SWING, "heading": "-15 deg", "amplitude": "-6 deg/s"},
        {},
    ),
    "yaw swing, flexible rule": (
        {**SWING, "heading": "15 deg", "amplitude": "6 deg/s"},
        {**SWING, "heading": "-15 deg", "amplitude": "-6 deg/s"},
        {"name": "flexible-two-position"},
    ),
    "yaw swing, nulling rule": (
        {**SWING, "heading": "40 deg", "amplitude": "3 deg/s"},
        {**SWING, "heading": "-40 deg", "amplitude": "-3 deg/s"},
        {"name": "nulling-two-position"},
    ),
    "turn, heading isolation": (
        {"type": "turn", "heading": "30 deg", "rate": "0.5 deg/s", "roll": "1 deg"},
        {"type": "turn", "heading": "-30 deg", "rate": "-0.5 deg/s", "roll": "1 deg"},
        {"name": "heading-isolation"},
    ),
    "static, off-axis mounting": (
        {"heading": "70 deg", "pitch": "2 deg"},
        {"heading": "-70 deg", "pitch": "2 deg"},
        {"name": "four-position", "mounting": "25, 10, 0 deg"},
    ),
}


@pytest.mark.parametrize("case", list(MIRROR_CASES))
def test_mirror_identity(case):
    """Counter-clockwise values == the clockwise run with every heading and rate negated."""
    ccw_motion, cw_motion, scheme = MIRROR_CASES[case]
    cw_scheme = dict(scheme)
    if "mounting" in scheme:  # the mounting heading is a heading too
        h, p, r = scheme["mounting"].replace(" deg", "").split(",")
        cw_scheme["mounting"] = f"{-float(h)}, {p}, {r} deg"
    ccw = _arrays(run_scheme(_scenario(CCW, ccw_motion, scheme)))
    mirrored = _arrays(run_scheme(_scenario(CW, cw_motion, cw_scheme)))
    _assert_same(ccw, mirrored)
    # The convention is not a no-op: the same numbers read clockwise are another run.
    same_numbers_cw = _arrays(run_scheme(_scenario(CW, ccw_motion, scheme)))
    assert _far_apart(ccw, same_numbers_cw)


def test_mirror_identity_heading_history(tmp_path):
    rows = [(0.0, 10.0), (600.0, 40.0), (1800.0, -20.0), (7200.0, 5.0)]
    (tmp_path / "ccw.csv").write_text("".join(f"{t},{h}\n" for t, h in rows))
    (tmp_path / "cw.csv").write_text("".join(f"{t},{-h}\n" for t, h in rows))
    runs = {}
    for conv, name in ((CCW, "ccw.csv"), (CW, "cw.csv")):
        data = {
            "scenario": {"duration": "2 h"},
            "imu": P0_IMU,
            "motion": {"heading_convention": conv, "type": "heading-history", "file": name},
            "scheme": {"name": "two-position"},
            "output": {"step": "60 s", "covariance_step": "300 s"},
        }
        runs[conv] = _arrays(run_scheme(scenario_from_dict(data, tmp_path)))
    _assert_same(runs[CCW], runs[CW])


def _level(convention: str, heading: str):
    return _scenario(convention, {"heading": heading}, {"name": "none"})


def test_heading_90_points_the_forward_axis_east_or_west():
    """Body/IMU y is the forward axis: 90 deg clockwise is east, counter-clockwise west."""
    for conv, forward, right in ((CW, EAST, -NORTH), (CCW, -EAST, NORTH)):
        c_sn = _level(conv, "90 deg").timeline().c_sn[0]
        assert np.allclose(c_sn @ [0.0, 1.0, 0.0], forward, atol=1e-15), conv
        assert np.allclose(c_sn @ [1.0, 0.0, 0.0], right, atol=1e-15), conv  # x: right
        assert np.allclose(c_sn @ [0.0, 0.0, 1.0], UP, atol=1e-15), conv


@pytest.mark.parametrize("heading_deg", [0.0, 30.0, 90.0, 135.0, 250.0])
def test_level_gyros_read_the_earth_rate_of_the_declared_heading(heading_deg):
    """Forward axis at psi from north reads W_N cos psi in both conventions; the right axis
    (cos psi, -sin psi, 0) in ENU if psi is clockwise, (cos psi, sin psi, 0) if
    counter-clockwise, reads -W_N sin psi or +W_N sin psi."""
    lat = 34.246 * math.pi / 180
    w_n = np.array([0.0, OMEGA_IE * math.cos(lat), OMEGA_IE * math.sin(lat)])
    psi = math.radians(heading_deg)
    for conv, sign in ((CW, -1.0), (CCW, 1.0)):
        c_sn = _level(conv, f"{heading_deg} deg").timeline().c_sn[0]
        w_s = c_sn.T @ w_n
        expected = [sign * w_n[1] * math.sin(psi), w_n[1] * math.cos(psi), w_n[2]]
        assert np.allclose(w_s, expected, rtol=0, atol=1e-18), conv


def test_heading_rates_follow_the_convention():
    """A positive counter-clockwise rate turns the body about +Up (right hand), clockwise -Up."""
    for conv, sign in ((CW, -1.0), (CCW, 1.0)):
        turn = _scenario(conv, {"type": "turn", "rate": "2 deg/s"}).motion
        assert turn.rate_n(0.0)[0] == pytest.approx([0, 0, sign * math.radians(2)], abs=1e-18)
        swing = _scenario(conv, {**SWING, "amplitude": "6 deg/s", "heading": "0 deg"}).motion
        # A quarter period in, the heading has swung by A T / (2 pi) in the declared sense.
        half_range = math.radians(6) * 120 / (2 * math.pi)
        c_bn = swing.attitude(30.0)[0]
        forward = c_bn @ [0.0, 1.0, 0.0]
        az_cw = math.atan2(forward[0], forward[1])  # from north towards east
        # Pitch and roll leave the forward axis' azimuth alone (rot_y fixes y, rot_x keeps it
        # in the vertical plane through the heading), so the match is exact to round-off.
        assert az_cw == pytest.approx(-sign * half_range, abs=1e-12)


def test_table_angles_are_right_handed_under_both_conventions():
    """A +90 deg custom step turns the IMU counter-clockwise seen from above, either way:
    at vehicle heading 0 its forward axis then points west (IMU heading -90 deg written
    clockwise, +90 deg written counter-clockwise), and the schedule is the same."""
    steps = [
        {"gimbal": "outer", "angle": "90 deg", "dwell": "100 s"},
        {"gimbal": "outer", "angle": "-90 deg", "dwell": "100 s"},
    ]
    tables = {}
    for conv in (CW, CCW):
        scen = _scenario(
            conv, {"heading": "0 deg"}, {"name": "custom", "stop": "100 s", "steps": steps}
        )
        table = scen.scheme().plan(scen.motion, scen.duration)
        t = np.array([150.0])  # at rest after the turn (100 s stop, 15 s turn)
        c_sn = scen.motion.attitude(t)[0] @ table.dcm_at(t)[0]
        assert np.allclose(c_sn @ [0.0, 1.0, 0.0], -EAST, atol=1e-15), conv
        tables[conv] = table
    assert np.array_equal(tables[CW].a0, tables[CCW].a0)


def test_mounting_heading_and_observability_headings_follow_the_convention(capsys):
    out = {}
    for conv, headings in ((CCW, "0,90"), (CW, "0,-90")):
        argv = ["observability", "--headings", headings, "--heading-convention", conv, "--json"]
        assert main(argv) == 0
        out[conv] = json.loads(capsys.readouterr().out)
    assert out[CCW]["headings_deg"] == [0.0, 90.0]  # echoed as declared
    assert "headings 0, 90 deg counter-clockwise" in out[CCW]["model"]
    a, b = dict(out[CCW]), dict(out[CW])
    for k in ("headings_deg", "model"):
        a.pop(k), b.pop(k)
    assert a == b


def test_heading_sign_and_unknown_convention():
    assert heading_sign(CW) == 1.0 and heading_sign(CCW) == -1.0
    with pytest.raises(InputError) as exc:
        _scenario("north-by-west", {"heading": "0 deg"})
    assert exc.value.field == "motion.heading_convention"


def test_set_up_table_states_the_convention_and_the_declared_values():
    rows = dict(describe(_scenario(CCW, {**SWING, "heading": "15 deg", "amplitude": "6 deg/s"})))
    assert rows["heading convention"].startswith("counter-clockwise-from-north")
    assert "yaw swing 6 deg/s peak" in rows["motion"]
    rows = dict(describe(_scenario(CW, {"heading": "15 deg"})))
    assert rows["heading convention"].startswith("clockwise-from-north")
    assert "heading 15 deg" in rows["motion"]


# --- negative values on the command line ------------------------------------------------
DRIFT = ["drift", "--duration", "1h", "--gyro-bias", "0.01", "--accel-bias", "20", "--json"]


def test_negative_values_need_no_equals_sign(capsys):
    assert main([*DRIFT, "--yaw-swing=-6,60", "--heading=-15", "--roll=-2"]) == 0
    with_equals = json.loads(capsys.readouterr().out)
    assert main([*DRIFT, "--yaw-swing", "-6,60", "--heading", "-15", "--roll", "-2"]) == 0
    assert json.loads(capsys.readouterr().out) == with_equals
    assert main([*DRIFT, "--yaw-swing", "6,60"]) == 0  # and the sign matters
    assert json.loads(capsys.readouterr().out) != with_equals


def test_negative_duration_gets_the_range_error_not_an_argparse_error(capsys):
    assert main(["drift", "--duration", "-3min"]) == 2
    err = capsys.readouterr().err.strip()
    # The range check's own line (the value read as -180 s), not argparse's "expected
    # one argument".
    assert err.startswith("inserr drift: error: --duration (scenario.duration): -180 s")
    assert "out of range" in err and "expected one argument" not in err
    assert len(err.splitlines()) == 1


def test_a_flag_is_never_taken_for_a_value(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["drift", "--heading", "--lat", "34"])
    assert exc.value.code == 2
    assert "--heading: expected one argument" in capsys.readouterr().err


# --- opening phase ------------------------------------------------------------------------
def _table(name: str, start: str, motion: dict | None = None, **scheme):
    scen = _scenario(CW, motion or {"heading": "0 deg"}, {"name": name, "start": start, **scheme})
    return scen.scheme().plan(scen.motion, scen.duration)


@pytest.mark.parametrize("name", ["two-position", "four-position-modified", "eight-position"])
def test_turn_first_is_the_stop_first_schedule_without_its_opening_stop(name):
    stop_first, turn_first = _table(name, "stop"), _table(name, "turn")
    assert stop_first.kind[0] == "stop" and turn_first.kind[0] == "rotate"
    first = stop_first.duration[0]
    n = min(len(turn_first), len(stop_first) - 1) - 1  # the last segments may differ (run end)
    assert turn_first.kind[:n] == stop_first.kind[1 : n + 1]
    assert np.allclose(turn_first.t0[:n], stop_first.t0[1 : n + 1] - first, atol=1e-9)
    for field in ("duration", "rate", "a0", "b0"):
        a, b = getattr(turn_first, field)[:n], getattr(stop_first, field)[1 : n + 1]
        assert np.array_equal(a, b), field


def test_p2_cycle_written_turn_first_ends_at_a():
    t = _table("four-position", "turn")
    assert t.labels[:8] == (
        "outer +180 -> C",
        "stop C",
        "outer +90 -> D",
        "stop D",
        "outer -180 -> B",
        "stop B",
        "outer -90 -> A",
        "stop A",
    )
    assert t.a0[0] == pytest.approx(math.radians(-135))


def test_custom_table_with_zero_first_stop_is_two_position_turn_first():
    steps = [
        {"gimbal": "outer", "angle": f"{a} deg", "dwell": "300 s"} for a in (180, 180, -180, -180)
    ]
    custom = _scenario(CW, {"heading": "0 deg"}, {"name": "custom", "stop": "0 s", "steps": steps})
    c = custom.scheme().plan(custom.motion, custom.duration)
    t = _table("two-position", "turn")
    assert c.kind == t.kind
    for field in ("t0", "duration", "rate", "a0"):
        assert np.array_equal(getattr(c, field), getattr(t, field)), field


def test_closed_loop_rules_open_with_their_first_turn():
    swing = {**SWING, "heading": "15 deg", "amplitude": "6 deg/s"}
    flex = _table("flexible-two-position", "turn", swing)
    assert flex.kind[0] == "rotate" and flex.t0[0] == 0.0 and flex.rate[0] > 0
    # The first variable turn stops where the test on empty sums passes: |cos psi| < delta.
    scen = _scenario(CW, swing)
    t_end = flex.t0[1]
    psi = flex.imu_heading(np.array([t_end]), scen.motion)[0]
    assert abs(math.cos(psi)) < 0.01
    null = _table("nulling-two-position", "turn", swing)
    assert null.kind[:2] == ("rotate", "stop") and null.a0[1] == pytest.approx(math.pi)
    iso = _table("heading-isolation", "turn", swing)
    assert iso.kind[0] == "isolate" and iso.target_rate[0] != 0.0
    stop_first = _table("heading-isolation", "stop", swing)
    assert stop_first.target_rate[0] == 0.0


def test_unknown_opening_phase_names_the_key():
    with pytest.raises(InputError) as exc:
        _table("two-position", "spin")
    assert exc.value.field == "scheme.start"
