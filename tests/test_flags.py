"""One input path: one flag table, one spelling per quantity, errors that name the key.

The flag table (``inserr.scenario.flags.FLAGS``) is walked together with the parsers
the commands really build (``inserr <cmd> --help``): every flag comes from the table,
no two flags set the same scenario key, a flag has the same help and unit in every
command, units are spelled one way, and the default a help text states is the default
the command uses (checked by running the command's scenario with and without it).
"""

from __future__ import annotations

import argparse
import ast
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from inserr.cli.main import available_commands, build_parser, main
from inserr.core.errors import InputError
from inserr.core.units import parse_quantity
from inserr.scenario.flags import CONTROLS, FLAGS, RECORDING_FLAGS, help_text, scenario_from_args
from inserr.scenario.schema import (
    CHOICES,
    SCHEMA,
    STUDY_DEFAULTS,
    load_scenario,
    scenario_from_dict,
    study_default,
)

ROOT = Path(__file__).resolve().parents[1]

#: The study each command reads its scenario for.
STUDY = {
    "align": "alignment",
    "observability": "alignment",
    "calibrate": "calibration",
    "northfind": "northfinder",
}

#: The unit words a flag may use for each physical kind, written out here (not taken
#: from the code): micro-g is "ug" and never "µg" or "micro-g", and so on.
CANONICAL = {
    "angle": {"deg", "arcsec"},
    "angular_rate": {"deg/h", "deg/s"},
    "acceleration": {"ug"},
    "ratio": {"ppm"},
    "arw": {"deg/sqrt(h)"},
    "vrw": {"ug/sqrt(Hz)"},
    "time": {"s", "min", "h"},
    "frequency": {"Hz"},
    "length": {"m"},
    "velocity": {"m/s"},
}
#: Spellings no help text may use (the canonical ones above replace them).
FORBIDDEN = ("µg", "micro-g", "deg/hr", "√", "°", "1σ", "arcmin")


def _subparser(command: str) -> argparse.ArgumentParser:
    parser = build_parser(command)
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return sub.choices[command]


def _options(command: str) -> dict[str, argparse.Action]:
    """Flag name (without dashes) -> its argparse action, for one command."""
    return {
        o.removeprefix("--"): a
        for a in _subparser(command)._actions
        if not isinstance(a, argparse._HelpAction)
        for o in a.option_strings
    }


#: The commands that read a scenario (``imu-budget`` reads a recording: its own flags,
#: RECORDING_FLAGS, checked below).
COMMANDS = [c for c in available_commands() if c not in ("run", "imu-budget")]


def test_imu_budget_has_only_its_recording_flags():
    assert set(_options("imu-budget")) == set(RECORDING_FLAGS) | {"out", "json"}


def _without_default(text: str) -> str:
    return re.sub(r" \(default [^()]*(\([^()]*\)[^()]*)*\)$", "", text)


def test_no_two_flags_set_the_same_key_and_every_key_exists():
    seen: dict[str, str] = {}
    for name, flag in FLAGS.items():
        for key in flag.keys:
            section, _, k = key.partition(".")
            assert k in SCHEMA[section], (name, key)
            assert key not in seen, f"--{name} and --{seen.get(key)} both set {key}"
            seen[key] = name
    assert not set(FLAGS) & set(CONTROLS)


@pytest.mark.parametrize("command", [*COMMANDS, "run"])
def test_every_flag_of_every_command_comes_from_the_table(command):
    for name, action in _options(command).items():
        assert name in FLAGS or name in CONTROLS, f"inserr {command} --{name}"
        if name in FLAGS:
            # No flag-level default: an absent flag leaves the scenario's value.
            assert action.default is None, f"inserr {command} --{name}"


def test_one_spelling_per_quantity_across_commands():
    """align, northfind, calibrate and drift (and the rest) agree flag by flag."""
    seen: dict[str, tuple[str, str, str]] = {}
    for command in COMMANDS:
        for name, action in _options(command).items():
            if name not in FLAGS:
                continue
            spelling = (_without_default(action.help), str(action.metavar), command)
            if name in seen:
                assert spelling[:2] == seen[name][:2], (name, command, seen[name][2])
            seen[name] = spelling
    # The quantities the issue found spelled several ways now have one flag each.
    for command in ("align", "northfind", "calibrate", "drift"):
        opts = _options(command)
        assert "gyro-bi" not in opts and "minutes" not in opts and "hours" not in opts
        assert "dwell" not in opts and "imu-rate" not in opts
    for command in ("align", "northfind", "drift"):
        assert "gyro-bias" in _options(command) and "duration" in _options(command)
    assert "gyro-bias-instability" in _options("northfind")


def test_one_unit_word_per_physical_kind():
    for name, flag in FLAGS.items():
        kind = flag.spec.kind
        if name == "yaw-swing":  # AMP,PERIOD: a rate and a time
            assert flag.unit == "deg/s,s"
            continue
        if flag.unit is not None:
            assert flag.unit in CANONICAL[kind], (name, flag.unit)
        # The same physical quantity, the same unit: biases in deg/h and ug, table and
        # motion rates in deg/s, misalignments and attitude errors in arcsec.
        if kind == "angular_rate":
            assert flag.unit == ("deg/h" if "bias" in flag.keys[0] else "deg/s"), name
        if kind == "acceleration":
            assert flag.unit == "ug", name
    for command in COMMANDS:
        for name, action in _options(command).items():
            for word in FORBIDDEN:
                assert word not in (action.help or ""), (command, name, word)
            if name in FLAGS and FLAGS[name].unit and name != "yaw-swing":
                # The unit word in the help is the table's, after the first words.
                assert f", {FLAGS[name].unit}" in action.help, (command, name)


def _stated_default(action: argparse.Action) -> str | None:
    m = re.search(r"\(default (.*)\)$", action.help or "")
    return m.group(1) if m else None


@pytest.mark.parametrize("command", ["drift", "align", "observability", "calibrate", "northfind"])
def test_the_default_a_help_states_is_the_one_the_command_uses(command):
    """Give every flag its stated default: the scenario must not change at all."""
    study = STUDY.get(command, "drift")
    opts = _options(command)
    plain = scenario_from_args(argparse.Namespace(), study)
    checked = 0
    for name, action in opts.items():
        if name not in FLAGS or isinstance(action, argparse._StoreTrueAction):
            continue
        stated = _stated_default(action)
        if stated is None or stated == "none":
            continue
        flag = FLAGS[name]
        ns = argparse.Namespace(**{action.dest: stated})
        given = scenario_from_args(ns, study)
        key = flag.keys[0]
        a, b = plain.value(key), given.value(key)
        if isinstance(a, (np.ndarray, tuple, float)):
            np.testing.assert_array_equal(np.asarray(a), np.asarray(b), err_msg=f"--{name}")
        else:
            assert a == b, name
        checked += 1
    assert checked >= 4


def test_study_defaults_are_the_library_defaults():
    """The scenario's per-study defaults and the library's dataclass defaults agree."""
    from inserr.alignment.filter import Prior, Settings
    from inserr.alignment.inputs import alignment_inputs
    from inserr.calibration.estimation import MonteCarloConfig, p1_truth
    from inserr.calibration.inputs import calibration_inputs
    from inserr.northfinder.inputs import northfinder_inputs
    from inserr.northfinder.instrument import Instrument, SensorGrade

    inp = alignment_inputs(scenario_from_dict({}, study="alignment"))
    prior, settings = Prior(), Settings()
    np.testing.assert_allclose(inp.prior.sigma(), prior.sigma(), rtol=1e-15)
    assert (inp.settings.zupt_rate, inp.settings.zupt_sigma) == (
        settings.zupt_rate,
        settings.zupt_sigma,
    )
    assert inp.settings.vertical == settings.vertical == "free"
    nf = northfinder_inputs(scenario_from_dict({}, study="northfinder"))
    for field in SensorGrade.__dataclass_fields__:
        assert getattr(nf.grade, field) == pytest.approx(getattr(SensorGrade(), field), 1e-15)
    for field in Instrument.__dataclass_fields__:
        assert getattr(nf.instrument, field) == pytest.approx(getattr(Instrument(), field))
    cal = calibration_inputs(scenario_from_dict({}, study="calibration"))
    assert cal.config == MonteCarloConfig()
    truth = p1_truth()
    for field in ("gyro_bias", "accel_bias", "gyro_scale_factor", "gyro_misalignment", "arw"):
        np.testing.assert_allclose(getattr(cal.truth, field), getattr(truth, field), rtol=1e-15)


def test_choices_are_the_library_choices():
    from inserr.calibration.estimation import POSITIONING_MODELS
    from inserr.calibration.position_sets import DESIGN_SENSORS

    assert set(CHOICES["calibration.positioning_model"]) == set(POSITIONING_MODELS)
    assert set(CHOICES["calibration.design_sensors"]) == set(DESIGN_SENSORS)


# --- errors name the key, and the flag only when the value came from one ------------------


@pytest.mark.parametrize(
    "command, flag, value, key, in_file",
    [
        ("drift", "--arw", "-1", "imu.arw", '"-1 deg/sqrt(h)"'),
        ("align", "--zupt-rate", "0", "alignment.zupt_rate", '"0 Hz"'),
        ("northfind", "--filter-period", "0.015", "northfinder.filter_period", '"0.015 s"'),
        ("calibrate", "--positioning-error", "-1", "calibration.positioning_error", '"-1 arcsec"'),
        ("observability", "--headings", "north", "observability.headings", '"north"'),
    ],
)
def test_errors_name_the_flag_only_when_it_was_typed(
    command, flag, value, key, in_file, tmp_path, capsys
):
    out = tmp_path / "never"
    extra = ["--out", str(out)] if "out" in _options(command) else []
    assert main([command, flag, value, *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert f"error: {flag} ({key}): " in err and len(err.splitlines()) == 1
    # The same value from a scenario file: the key alone, no flag.
    section, _, k = key.partition(".")
    scen = tmp_path / "s.toml"
    scen.write_text(f"[{section}]\n{k} = {in_file}\n", encoding="utf-8")
    assert main([command, str(scen), *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert f"error: {key}: " in err and "--" not in err
    assert not out.exists()


def _input_error_texts(path: Path) -> list[tuple[int, str]]:
    """The string parts of every ``InputError(...)`` call in a module."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "InputError":
            for arg in node.args:
                for sub in ast.walk(arg):
                    if isinstance(sub, ast.Constant) and isinstance(sub.value, str):
                        out.append((node.lineno, sub.value))
    return out


def test_library_errors_never_name_a_flag():
    """Below cli/ (and the flag table itself), errors name scenario keys or arguments."""
    offenders = []
    for path in sorted((ROOT / "inserr").rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        if rel.startswith("inserr/cli/") or rel == "inserr/scenario/flags.py":
            continue
        for line, text in _input_error_texts(path):
            if re.search(r"(^|[\s(])--[a-z]", text):
                offenders.append(f"{rel}:{line}: {text!r}")
    assert offenders == []


def test_the_checker_finds_a_flag_in_an_error(tmp_path):
    bad = tmp_path / "m.py"
    bad.write_text('raise InputError(f"--param {name}", "x", "give --runs 2")\n')
    assert [t for _, t in _input_error_texts(bad) if "--" in t] == ["--param ", "give --runs 2"]


# --- one scenario for every command ------------------------------------------------------


def _json(capsys, argv) -> dict:
    assert main(argv) == 0, capsys.readouterr().err
    return json.loads(capsys.readouterr().out)


def test_study_sections_from_a_file_and_flags_over_them(tmp_path, capsys):
    f = tmp_path / "cal.toml"
    f.write_text(
        '[scenario]\nruns = 3\n[calibration]\nmethod = "six-position"\n'
        '[scheme]\nstop = "600 s"\n[imu]\ngyro_scale_factor = "50 ppm"\n',
        encoding="utf-8",
    )
    out = _json(capsys, ["calibrate", str(f), "--json"])
    assert out["n_positions"] == 6 and out["dwell_time_s"] == pytest.approx(6 * 600.0)
    assert out["parameters"]["sf_x"]["true"] == pytest.approx(50.0)
    out = _json(capsys, ["calibrate", str(f), "--stop", "120", "--method", "offaxis-four-position",
                         "--json"])  # fmt: skip
    assert out["n_positions"] == 4 and out["dwell_time_s"] == pytest.approx(4 * 120.0)
    # Truth the calibration model does not have is refused, naming the key.
    f.write_text('[imu]\ngyro_bias_instability = "0.01 deg/h"\n', encoding="utf-8")
    assert main(["calibrate", str(f)]) == 2
    assert "imu.gyro_bias_instability" in capsys.readouterr().err


def test_position_set_file_is_relative_to_the_scenario(tmp_path, capsys):
    (tmp_path / "sets").mkdir()
    (tmp_path / "sets" / "p1.toml").write_text(
        'name = "p1"\ndwell = "300 s"\n[table]\nouter_axis = "up"\ninner_axis = [1, -1, 0]\n'
        '[[positions]]\n[[positions]]\ninner = "180 deg"\n[[positions]]\nouter = "180 deg"\n'
        '[[positions]]\ninner = "0 deg"\n',
        encoding="utf-8",
    )
    f = tmp_path / "s.toml"
    f.write_text('[scenario]\nruns = 2\n[calibration]\nmethod = "sets/p1.toml"\n')
    assert _json(capsys, ["calibrate", str(f), "--json"])["method"] == "p1"


def test_northfinder_reads_a_static_base_and_one_gyro(tmp_path, capsys):
    f = tmp_path / "nf.toml"
    f.write_text('[motion]\ntype = "yaw-swing"\namplitude = "6 deg/s"\nperiod = "120 s"\n')
    assert main(["northfind", str(f)]) == 2
    assert "motion.type" in capsys.readouterr().err
    f.write_text('[imu]\ngyro_misalignment = "10 arcsec"\n')
    assert main(["northfind", str(f)]) == 2
    assert "imu.gyro_misalignment" in capsys.readouterr().err
    # Negative table rate = the other direction (only the north finder allows it).
    out = _json(capsys, ["northfind", "--rate", "-6", "--runs", "2", "--duration", "1min",
                         "--json"])  # fmt: skip
    assert out["runs"] == 2
    assert main(["drift", "--rate", "-6"]) == 2
    assert "--rate (scheme.rate)" in capsys.readouterr().err


def test_observability_from_a_file(tmp_path, capsys):
    f = tmp_path / "obs.toml"
    f.write_text('[observability]\nheadings = "0, 180 deg"\n[site]\nlatitude = "34 deg"\n')
    out = _json(capsys, ["observability", str(f), "--json"])
    assert (out["n_states"], out["rank"]) == (10, 10)
    one = _json(capsys, ["observability", str(f), "--headings", "0", "--json"])
    assert one["rank"] == 7  # the flag replaced the file's list


def test_modes_and_cycle_read_the_scenario(tmp_path, capsys):
    f = tmp_path / "m.toml"
    f.write_text(
        '[site]\nlatitude = "60 deg"\nearth = "spherical"\n[scheme]\nname = "two-position"\n'
    )
    m = _json(capsys, ["modes", str(f), "--json"])
    assert m["latitude_deg"] == pytest.approx(60.0) and m["earth_model"] == "spherical"
    # Foucault period 2 pi / (Omega sin L), independently of inserr's constants.
    omega = 7.292115e-5
    assert m["foucault_period_h"] == pytest.approx(
        2 * math.pi / (omega * math.sin(math.pi / 3)) / 3600, rel=1e-6
    )
    c = _json(capsys, ["cycle", str(f), "--json"])
    assert c["scheme"] == "two-position"
    assert _json(capsys, ["modes", "--json"])["latitude_deg"] == pytest.approx(34.0)  # default


def test_sweep_parameters_from_the_file(tmp_path, capsys):
    from inserr.sweep.grid import build_grid

    f = tmp_path / "s.toml"
    f.write_text(
        '[scenario]\nduration = "1 h"\n[scheme]\nname = "two-position"\n'
        '[sweep]\nparameters = ["stop=60,300"]\n'
    )
    base = load_scenario(f)
    grid = build_grid(base)
    assert [p.name for p in grid.params] == ["stop"] and len(grid.points) == 2
    # The grid's identity does not depend on the [sweep] table (a grown grid resumes).
    plain = scenario_from_dict({k: v for k, v in base.raw.items() if k != "sweep"}, f.parent)
    assert [pt.id for pt in build_grid(plain, ["stop=60,300"]).points] == [
        pt.id for pt in grid.points
    ]
    out = tmp_path / "out"
    res = _json(capsys, ["sweep", str(f), "--workers", "1", "--no-plots", "--out", str(out),
                         "--json"])  # fmt: skip
    assert res["points"] == 2
    assert main(["sweep", str(f), "--param", "stop=6O", "--out", str(tmp_path / "x")]) == 2
    assert "--param (sweep.parameters[stop])" in capsys.readouterr().err
    f.write_text('[scenario]\nduration = "1 h"\n')
    assert main(["sweep", str(f), "--out", str(tmp_path / "y")]) == 2
    assert "sweep.parameters: nothing to sweep" in capsys.readouterr().err


def test_analysis_tables_are_declared_and_validated(tmp_path):
    from inserr.scenario.schema import Key

    f = tmp_path / "a.toml"
    f.write_text('[analysis.grid]\nstops = ["30 s", "1 min"]\n')
    declared = {"grid": {"stops": Key("time", "list", [])}}
    assert load_scenario(f, analysis=declared).value("analysis.grid.stops") == (30.0, 60.0)
    load_scenario(f)  # the commands keep an analysis' tables unread
    for text, field in (
        ('[analysis.grid]\nstop = ["30 s"]\n', "analysis.grid.stop"),
        ('[analysis.grids]\nstops = ["30 s"]\n', "analysis.grids"),
        ('[analysis.grid]\nstops = ["30 m"]\n', "analysis.grid.stops[0]"),
    ):
        f.write_text(text)
        with pytest.raises(InputError) as exc:
            load_scenario(f, analysis=declared)
        assert exc.value.field == field


def test_every_analysis_scenario_runs_under_its_command(capsys):
    """The analyses' scenario files are ordinary scenarios of their study."""
    a = ROOT / "analyses"
    for argv in (
        ["align", str(a / "alignment_observability/scenario.toml"), "--duration", "1min"],
        ["calibrate", str(a / "p1_calibration/scenario.toml"), "--runs", "2"],
        [
            "northfind",
            str(a / "p3_northfinder/scenario.toml"),
            "--runs",
            "2",
            "--duration",
            "1min",
        ],  # fmt: skip
    ):
        assert main([*argv, "--json"]) == 0, argv
        json.loads(capsys.readouterr().out)


# --- the documentation ------------------------------------------------------------------


def test_scenario_reference_lists_every_key_and_every_study_default():
    text = (ROOT / "docs" / "scenarios.md").read_text(encoding="utf-8")
    blocks = "\n".join(re.findall(r"```toml\n(.*?)```", text, re.S))
    for section, keys in SCHEMA.items():
        assert f"[{section}]" in blocks, section
        for key in keys:
            if key != "steps":  # [[scheme.steps]] has its own example
                assert re.search(rf"^{key} = ", blocks, re.M), f"{section}.{key}"
    rows = re.findall(r"^\| [a-z ]+\(`[^|]+\) \| `([a-z_.]+)` \| `([^`]+)` \|", text, re.M)
    documented = {(k, v) for k, v in rows}
    expected = {(k, str(v)) for d in STUDY_DEFAULTS.values() for k, v in d.items()}
    assert documented == expected


def test_help_shows_the_study_default():
    assert help_text("stop", "alignment").endswith("(default 60)")
    assert help_text("stop", "drift").endswith("(default 300)")
    assert help_text("duration", "northfinder").endswith("(default 3 min)")
    assert study_default("scenario.runs", "calibration") == 100
    # Quantities in the study default parse with the flag's unit.
    assert parse_quantity("60", "time", "f", default_unit="s") == 60.0


def test_align_runs_the_scheme_then_the_compared_ones():
    """As ``inserr run``: scheme.name when given (or alone), then compare.schemes."""
    from inserr.alignment.inputs import alignment_inputs

    def names(data):
        return alignment_inputs(scenario_from_dict(data, study="alignment")).schemes

    assert names({}) == ("none",)
    two_four = {"compare": {"schemes": ["two-position", "four-position"]}}
    assert names(two_four) == ("two-position", "four-position")
    assert names({**two_four, "scheme": {"name": "none"}}) == (
        "none",
        "two-position",
        "four-position",
    )
    assert names({**two_four, "scheme": {"name": "two-position"}}) == (
        "two-position",
        "four-position",
    )
