"""For the people who use it: the notebook front door, the report read at a glance, the
exports, the CLI and packaging conventions, and the README's examples as printed.

Numbers are checked against independent truth: the budget's root-sum-square total
against the RMS and noise curves the engine computes by other sums; exported rows
against the engine's own samples at those times; the scenario digest against a
second route to the same inputs; the decimated curve against the extremes of the
full one.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import math
import os
import re
import shlex
import subprocess
import sys
import tomllib
from contextlib import redirect_stdout
from pathlib import Path

import numpy as np
import pytest

import inserr
from inserr.cli.main import main
from inserr.core.units import NMI

ROOT = Path(__file__).resolve().parents[1]

SCENARIO = {
    "scenario": {"name": "nb", "duration": "6 h"},
    "imu": {
        "gyro_bias": "0.003 deg/h",
        "accel_bias": "30 ug",
        "gyro_scale_factor": "10 ppm",
        "arw": "0.0005 deg/sqrt(h)",
        "vrw": "5 ug/sqrt(Hz)",
    },
    "initial": {"attitude": "10, 10, 60 arcsec", "velocity": "0.01 m/s"},
    "scheme": {"stop": "120 s"},
    "compare": {"schemes": ["two-position", "sixteen-position"]},
}


@pytest.fixture(scope="module")
def comparison():
    return inserr.compare(SCENARIO)


# --- the front door ----------------------------------------------------------------------
def test_the_front_door_is_on_the_package_and_stays_lazy():
    code = (
        "import sys, inserr\n"
        "heavy = [m for m in sys.modules if m.split('.')[0] in "
        "('matplotlib','scipy','control','dask','pandas','allantools')]\n"
        "assert not heavy, heavy\n"
        "for name in ('load_scenario','drift','compare','align','calibrate','northfind',"
        "'sweep','imu_budget'):\n"
        "    assert callable(getattr(inserr, name)), name\n"
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    # inserr.drift and inserr.sweep are the chapters themselves, and callable.
    assert inserr.drift.__name__ == "inserr.drift" and callable(inserr.drift)
    assert inserr.sweep.__name__ == "inserr.sweep" and callable(inserr.sweep)


def test_drift_accepts_a_scenario_a_file_or_a_dict(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(
        '[scenario]\nduration = "1 h"\n[imu]\ngyro_bias = "0.01 deg/h"\n', encoding="utf-8"
    )
    by_file = inserr.drift(path, "two-position").metrics()
    by_dict = inserr.drift(tomllib.loads(path.read_text()), "two-position").metrics()
    by_scen = inserr.drift(inserr.load_scenario(path), "two-position").metrics()
    assert by_file == by_dict == by_scen
    with pytest.raises(inserr.InputError, match="scenario"):
        inserr.drift(42)


def test_budget_total_is_the_rms_of_constants_and_noise_together(comparison):
    # The total row is the root-sum-square of the per-source rows; the engine's RMS
    # over unknown signs (rms_norm of the source columns) and its noise covariance
    # give the same number by other sums.
    for name, run in comparison.runs.items():
        r = run.result
        expected = math.hypot(r.rms_horizontal[-1], r.noise_horizontal_sigma[-1]) / NMI
        b = run.budget()
        assert b.index[-1] == "total (root-sum-square)"
        assert b.iloc[-1, -1] == pytest.approx(expected, rel=1e-9)
        assert comparison.budget().loc["total (root-sum-square)", name] == pytest.approx(
            expected, rel=1e-9
        )
        labels = list(b.index[:-1])
        assert not any("_" in lab for lab in labels), labels  # readable, not keys
        assert "initial heading error" in labels and "gyro angle random walk (ARW)" in labels


def test_timeseries_rows_are_the_engines_samples_at_the_export_step(comparison):
    run = comparison["two-position"]
    frame = run.to_dataframe()
    r = run.result
    # 6 h every 60 s, both ends included.
    assert len(frame) == 6 * 60 + 1
    assert frame["time (s)"].iloc[1] == 60.0
    for col in frame.columns[1:]:
        assert re.search(r"\((s|h|arcsec|arcmin|m/s|nmi)\)$", col), col
    k = 90  # 5400 s
    i = int(np.searchsorted(r.t, 5400.0))
    assert frame["east position error (nmi)"].iloc[k] == r.nav[i, 6] / NMI
    assert frame["heading error (arcmin)"].iloc[k] == pytest.approx(
        math.degrees(r.attitude[i, 2]) * 60, rel=1e-12
    )
    coarser = run.to_dataframe(step=600.0)
    assert len(coarser) == 6 * 6 + 1
    with pytest.raises(inserr.InputError, match="output.export_step"):
        run.to_dataframe(step=1.5)


def test_comparison_tables_and_figures(comparison):
    table = comparison.to_dataframe()
    assert list(table.index) == ["none", "two-position", "sixteen-position"]
    assert all("error" in c or "motor" in c for c in table.columns)
    series = comparison.timeseries()
    assert set(series["scheme"]) == set(table.index)
    fig = comparison.plot()
    assert type(fig).__name__ == "Figure" and fig.canvas.manager is None
    html = comparison._repr_html_()
    assert "<table>" in html and "total (root-sum-square)" in html
    assert "<table>" in comparison["none"]._repr_html_()


def test_export_step_is_validated_before_any_work():
    bad = {**SCENARIO, "output": {"step": "10 s", "export_step": "25 s"}}
    with pytest.raises(inserr.InputError, match="output.export_step"):
        inserr.scenario_from_dict(bad)


# --- the figures read at a glance ---------------------------------------------------------
def test_minmax_decimation_keeps_every_columns_extremes():
    from inserr.output.figure_style import minmax_decimate

    rng = np.random.default_rng(0)
    x = np.arange(259_201, dtype=float)
    y = np.cumsum(rng.standard_normal(len(x))) + 30 * np.sin(x / 50)
    columns = 1000
    xd, yd = minmax_decimate(x, y, columns)
    assert len(xd) <= 2 * columns + 2 and xd[0] == x[0] and xd[-1] == x[-1]
    assert np.all(np.diff(xd) > 0)  # kept in order
    # Every pixel column (of a 1000-px wide plot) spans the same values.
    edges = np.linspace(x[0], x[-1], columns + 1)
    for lo, hi in zip(edges[:-1:37], edges[1::37], strict=True):
        full = y[(x >= lo) & (x <= hi)]
        thin = yd[(xd >= lo) & (xd <= hi)]
        assert thin.max() <= full.max() and thin.min() >= full.min()
    assert yd.max() == y.max() and yd.min() == y.min()


def test_figures_keep_one_colour_per_scheme_and_legends_outside(comparison):
    from inserr.drift import figures as plots
    from inserr.drift.budget import budget_table
    from inserr.output import figure_style as style

    results = {n: r.result for n, r in comparison.runs.items()}
    horiz = plots.horizontal_error(results)
    att = plots.attitude_errors(results)
    bud = plots.budget_figure(
        budget_table({n: r.result.metrics["error_budget"] for n, r in comparison.runs.items()})
    )
    for fig in (horiz, att, bud):
        assert fig._suptitle is not None or fig.axes[0].get_title()  # titled
    panels = [ax for ax in horiz.axes if ax.get_visible()]
    assert len(att.axes) == 3 * len(results)  # a row per scheme, never overdrawn
    for ax in att.axes:
        assert len(ax.lines) == 1
    for i, name in enumerate(results):
        colour = style.scheme_color(name)
        assert panels[i].lines[0].get_color() == colour
        assert att.axes[3 * i].lines[0].get_color() == colour
        # The statistical curves are never a scheme's colour.
        assert panels[i].lines[1].get_color() not in style.SCHEME_COLORS.values()
        assert panels[i].lines[2].get_color() not in style.SCHEME_COLORS.values()
        assert panels[i].lines[1].get_linestyle() != panels[i].lines[2].get_linestyle()
    # The legends sit outside every axes (drawn, then compared as pixel boxes).
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    for fig in (horiz, bud):
        canvas = FigureCanvasAgg(fig)
        canvas.draw()
        renderer = canvas.get_renderer()
        legend_box = fig.legends[0].get_window_extent(renderer)
        for ax in fig.axes:
            assert not legend_box.overlaps(ax.get_window_extent(renderer))


# --- the report and its exports ------------------------------------------------------------
def test_report_carries_the_whole_scenario_data_files_and_provenance(tmp_path, capsys):
    path = tmp_path / "s.toml"
    text = (
        '[scenario]\nname = "r"\nduration = "2 h"\n'
        '[imu]\ngyro_bias = "0.003 deg/h"\narw = "0.0005 deg/sqrt(h)"\n'
        '[initial]\nattitude = "10, 10, 60 arcsec"\n'
        '[scheme]\nname = "none"\nstop = "120 s"\n[compare]\nschemes = ["two-position"]\n'
    )
    path.write_text(text, encoding="utf-8")
    out = tmp_path / "rep"
    assert main(["run", str(path), "--out", str(out), "--json"]) == 0
    capsys.readouterr()
    md = (out / "report.md").read_text(encoding="utf-8")
    res = json.loads((out / "results.json").read_text())
    assert res["inserr_version"] == inserr.__version__
    assert res["scenario"]["initial"]["attitude"] == "10, 10, 60 arcsec"
    assert res["scenario"]["imu"]["gyro_bias"] == "0.003 deg/h"
    assert res["scenario_file_sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
    # The same inputs by another route (a dict, defaults written out) hash alike;
    # a changed value does not.
    from inserr.scenario.schema import scenario_digest

    same = tomllib.loads(text)
    same["output"] = {"step": "1 s"}  # the default, written out
    assert scenario_digest(inserr.scenario_from_dict(same)) == res["scenario_sha256"]
    same["imu"]["gyro_bias"] = "0.004 deg/h"
    assert scenario_digest(inserr.scenario_from_dict(same)) != res["scenario_sha256"]
    assert inserr.__version__ in md and res["scenario_sha256"][:16] in md
    assert "initial attitude error (east tilt, north tilt, heading) | 10, 10, 60 arcsec" in md
    # Budget table and figure: the same rows, a total, readable names.
    table = [ln for ln in md.splitlines() if ln.startswith("| ") and "(nmi) |" not in ln]
    assert any(ln.startswith("| total (root-sum-square) |") for ln in table)
    assert "gyro_bias" not in md.split("## Error budget")[1]
    # The data files: CSV with units in the header, every scheme, every 60 s.
    rows = list(csv.DictReader(io.StringIO((out / "timeseries.csv").read_text())))
    assert {r["scheme"] for r in rows} == {"none", "two-position"}
    assert len(rows) == 2 * (2 * 60 + 1)
    assert "horizontal position error (nmi)" in rows[0]
    budget = list(csv.DictReader(io.StringIO((out / "budget.csv").read_text())))
    totals = [b for b in budget if b["type"] == "total"]
    assert [t["scheme"] for t in totals] == ["none", "two-position"]
    for t in totals:
        parts = [
            float(b["RMS horizontal position error at the end (nmi)"])
            for b in budget
            if b["scheme"] == t["scheme"] and b["type"] in ("constant", "noise")
        ]
        total = float(t["RMS horizontal position error at the end (nmi)"])
        assert total == pytest.approx(math.sqrt(sum(p * p for p in parts)), rel=1e-8)


@pytest.mark.parametrize(
    ("command", "study", "flags", "section"),
    [
        ("align", "alignment", ["--duration", "5 min"], {"scenario": {"duration": "5 min"}}),
        ("calibrate", "calibration", ["--runs", "5"], {"scenario": {"runs": 5}}),
        ("northfind", "northfinder", ["--runs", "3"], {"scenario": {"runs": 3}}),
    ],
)
def test_every_study_report_names_its_version_and_scenario(
    command, study, flags, section, tmp_path, capsys
):
    from inserr.scenario.schema import as_scenario, scenario_digest

    path = tmp_path / "s.toml"
    path.write_text('[site]\nlatitude = "45 deg"\n', encoding="utf-8")
    out = tmp_path / "rep"
    assert main([command, str(path), *flags, "--out", str(out), "--json"]) == 0
    capsys.readouterr()
    res = json.loads((out / "results.json").read_text())
    assert res["inserr_version"] == inserr.__version__
    assert res["scenario"]["site"]["latitude"] == "45 deg"
    assert res["scenario_file_sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
    # The file plus the flags, rebuilt as a dict, hash alike (a second route).
    same = as_scenario({**section, "site": {"latitude": "45 deg"}}, study)
    assert scenario_digest(same) == res["scenario_sha256"]
    page = (out / "report.md").read_text(encoding="utf-8")
    assert res["scenario_sha256"][:16] in page
    # The declared heading convention is echoed on every study's page (issue 15).
    assert "Heading convention: clockwise-from-north" in page


# --- the command line and packaging --------------------------------------------------------
def test_version_and_python_dash_m(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--version"])
    assert exc.value.code == 0
    assert capsys.readouterr().out.strip() == f"inserr {inserr.__version__}"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.run(
        [sys.executable, "-m", "inserr", "--version"], env=env, capture_output=True, text=True
    )
    assert proc.returncode == 0 and proc.stdout.strip() == f"inserr {inserr.__version__}"


def test_an_empty_budget_is_said_on_stderr(capsys):
    assert main(["drift", "--duration", "1 h", "--json"]) == 0
    captured = capsys.readouterr()
    assert "warning: the error budget is empty" in captured.err
    assert "--gyro-bias" in captured.err
    assert json.loads(captured.out)["max_horizontal_error_nmi"] == 0.0
    assert main(["drift", "--duration", "1 h", "--gyro-bias", "0.01", "--json"]) == 0
    assert "warning" not in capsys.readouterr().err


def test_cycle_prints_round_off_as_zero(capsys):
    assert main(["cycle", "--scheme", "four-position", "--rate", "6", "--stop", "300"]) == 0
    out = capsys.readouterr().out
    assert "e-1" not in out and "-0 " not in out
    assert main(["cycle", "--scheme", "four-position", "--json"]) == 0
    h = json.loads(capsys.readouterr().out)["horizontal_cycle_integral_s"]
    # Four positions 90 deg apart: the off-diagonal terms cancel exactly.
    assert h[0][1] == 0.0 and h[1][0] == 0.0 and h[0][0] > 0


def test_license_and_packaging_metadata():
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert (ROOT / "LICENSE").read_text(encoding="utf-8").startswith("MIT License")
    assert "License :: OSI Approved :: MIT License" in meta["classifiers"]
    deps = meta["dependencies"]
    assert "filterpy>=2.0.0,<3" in deps
    assert any(d.startswith("pandas>=") for d in deps)
    assert any(d.startswith("allantools>=") for d in deps)
    text = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    before = text.split('"filterpy>=2.0.0,<3"')[0].splitlines()[-2:]
    assert any(line.strip().startswith("#") for line in before)  # the reason, in a comment


# --- the README prints what it says ---------------------------------------------------------
_FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.MULTILINE | re.DOTALL)


def readme_blocks() -> list[tuple[str, str]]:
    return [(m[1], m[2]) for m in _FENCE.finditer((ROOT / "README.md").read_text("utf-8"))]


def test_readme_keeps_exactly_its_two_set_up_commands():
    setup = [b for lang, b in readme_blocks() if lang == "" and "python3.11 -m venv" in b]
    assert setup == [
        "python3.11 -m venv .venv && . .venv/bin/activate && pip install . && "
        "inserr run analyses/quickstart/scenario.toml\n",
        'python3.11 -m venv .venv && . .venv/bin/activate && pip install ".[test]" && '
        "python -m pytest\n",
    ]


def _lines(text: str) -> list[str]:
    return [ln.rstrip() for ln in text.strip("\n").splitlines()]


def test_readme_examples_print_what_the_readme_says(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("INSERR_NO_PROGRESS", "1")
    blocks = readme_blocks()
    checked = 0
    namespace: dict = {}
    for (lang, body), (next_lang, expected) in zip(blocks, [*blocks[1:], ("", "")], strict=True):
        out = io.StringIO()
        if lang == "python":
            with redirect_stdout(out):
                exec(compile(body, "README.md", "exec"), namespace)
        elif lang == "" and "inserr " in body and "pytest" not in body:
            command = body.strip().split("&& ")[-1]
            argv = shlex.split(command)[1:]
            if argv[:2] == ["run", "analyses/quickstart/scenario.toml"]:
                argv[1] = str(ROOT / argv[1])  # run from a scratch directory
            with redirect_stdout(out):
                assert main(argv) == 0, command
        else:
            continue
        if next_lang == "text":
            assert _lines(out.getvalue()) == _lines(expected), body
            checked += 1
    assert checked >= 5  # the main job, the Python example, the shell one, cycle, modes
    assert Path("scenario_report/report.html").is_file()


def test_alignment_budget_splits_the_filters_covariance_exactly():
    # One covariance per source through the filter's own transitions and gains adds
    # up to the filter's covariance (filterpy's Joseph form), to round-off.
    from inserr.alignment.filter import STATES, UNITS

    study = inserr.align(
        {
            "scenario": {"duration": "3 min"},
            "imu": {"arw": "0.001 deg/sqrt(h)", "vrw": "10 ug/sqrt(Hz)"},
        },
        ["none", "two-position"],
    )
    budget = study.budget()
    for name, result in study.results.items():
        total = budget[name].loc["total (root-sum-square)"].to_numpy()
        idx = [STATES.index(s) for s in ("phi_e", "phi_n", "phi_u")]
        scale = np.array([UNITS[s][1] for s in ("phi_e", "phi_n", "phi_u")])
        assert total == pytest.approx(result.final_sigma[idx] / scale, rel=1e-9)
    # Static and unindexed, the tilt is limited by the accelerometer bias (nabla / g).
    none = budget["none"]
    tilt = none.columns[0]
    assert none[tilt].drop("total (root-sum-square)").idxmax() == "accelerometer bias (prior)"


def test_the_notebook_walk_through_touches_no_module_path():
    # The page is executed by tests/test_docs.py; here: it uses the front door only
    # (import inserr; inserr.<verb>), never a module path such as inserr.drift.study.
    page = (ROOT / "docs" / "tutorials" / "notebook.md").read_text(encoding="utf-8")
    code = "\n".join(b for lang, b in _FENCE.findall(page) if lang == "python")
    assert "import inserr" in code
    assert not re.search(r"from inserr\b|import inserr\.", code)
    assert not re.search(r"inserr\.[a-z_]+\.[a-z_]+", code)
    for verb in ("load_scenario", "drift", "compare", "to_dataframe", "budget", "plot"):
        assert verb in code, verb


# --- the other studies' front doors --------------------------------------------------------
def _check_common_interface(study, value_unit: str):
    """The five calls every result answers (the walk-through's promise)."""
    from matplotlib.figure import Figure

    metrics = study.metrics()
    assert isinstance(metrics, dict) and metrics
    json.dumps(metrics, default=str)  # plain data
    frame = study.to_dataframe()
    assert len(frame) > 0
    budget = study.budget()
    # The root-sum-square total: a row (sources of one quantity) or, for the
    # calibration's per-parameter budget, a column (the sources of each parameter).
    totals = [str(x) for x in (*budget.index, *budget.columns) if str(x).startswith("total")]
    assert totals
    assert any(value_unit in c for c in budget.columns)
    assert isinstance(study.plot(), Figure)
    assert "<table>" in study._repr_html_()
    return frame, budget


def test_calibrate_front_door_budget_is_the_closed_form_noise_limit():
    from inserr.core.earth import OMEGA_IE
    from inserr.output.results import TOTAL_LABEL

    study = inserr.calibrate({"scenario": {"runs": 20}})
    frame, budget = _check_common_interface(study, "1-sigma")
    # Every parameter by its readable name, the per-run table one error column each.
    label = "gyro scale factor, x axis (sf_x)"
    assert label in budget.index and f"{label} error (ppm)" in frame.columns
    assert "accelerometer misalignment, y axis sensing z (mis_yz)" in budget.index
    assert len(frame) == 20
    # P1's four positions give sf_x from two stops on the north Earth rate:
    # sigma = ARW / (sqrt(T) sqrt(2) W cos L) (docs/tutorials/calibration.md, section 2).
    scen = study.scenario
    arw, lat = scen.value("imu.arw"), scen.value("site.latitude")
    dwell = study.summary["positions"][1]["dwell_s"]  # T: every stop's own dwell
    closed = arw / (math.sqrt(dwell) * math.sqrt(2) * OMEGA_IE * math.cos(lat)) / 1e-6
    # The CRLB is the least-squares covariance of the same noise model, so the two
    # agree to round-off (1e-9 leaves room for the matrix inverse).
    assert budget.loc[label, "sensor noise 1-sigma (CRLB)"] == pytest.approx(closed, rel=1e-9)
    # Independent sources: the total is their root-sum-square.
    row = budget.loc[label]
    assert row[TOTAL_LABEL] == pytest.approx(
        math.hypot(row["sensor noise 1-sigma (CRLB)"], row["table positioning 1-sigma"])
    )


def test_northfind_front_door_without_bias_instability_is_the_white_noise_bound():
    from scipy.stats import chi2

    runs = 20
    scen = {
        "scenario": {"runs": runs, "duration": "3 min"},
        "imu": {"gyro_bias_instability": "0 deg/h", "accel_bias_instability": "0 ug"},
    }
    study = inserr.northfind(scen)
    frame, budget = _check_common_interface(study, "(mil)")
    assert "heading error 1-sigma, Monte Carlo (mil)" in frame.columns
    col = budget.columns[0]
    # Limiting case: no bias instability, so its share is zero and the total is the
    # white-noise Cramer-Rao bound itself.
    assert budget[col].iloc[1] == 0.0
    assert budget[col].iloc[2] == pytest.approx(budget[col].iloc[0], rel=1e-12)
    # The Monte Carlo scatter of an efficient estimator: runs * (s/sigma)^2 follows
    # chi-square with runs - 1 degrees of freedom; 99.9 % two-sided interval.
    ratio = budget[col].iloc[3] / budget[col].iloc[2]
    lo, hi = (math.sqrt(chi2.ppf(q, runs - 1) / runs) for q in (0.0005, 0.9995))
    assert lo < ratio < hi


def test_sweep_front_door_points_are_the_drift_of_each_scenario(tmp_path):
    base = {
        "scenario": {"duration": "6 h"},
        "imu": {"gyro_bias": "0.01 deg/h", "accel_bias": "20 ug"},
        "scheme": {"name": "two-position"},
    }
    stops = ["60 s", "300 s"]
    study = inserr.sweep(base, {"scheme.stop": stops}, out=tmp_path / "sw", workers=1)
    frame, budget = _check_common_interface(study, "(nmi)")
    assert list(frame["scheme.stop"]) == stops and set(frame["status"]) == {"ok"}
    largest = 0.0
    for stop, final in zip(stops, frame["final_horizontal_error_nmi"], strict=True):
        # The same point run directly (in this process, not by a sweep worker).
        direct = inserr.drift({**base, "scheme": {"name": "two-position", "stop": stop}})
        assert float(final) == pytest.approx(direct.metrics()["final_horizontal_error_nmi"])
        largest = max(largest, max(direct.metrics()["error_budget"].values()))
    # One row per dominating source (readable), then the count of points analysed.
    assert budget.iloc[-1, 0] == len(stops)
    assert budget.iloc[:-1, 0].sum() == len(stops)
    assert budget.iloc[:-1, 1].max() == pytest.approx(largest)
    assert all("_" not in name for name in budget.index)
