"""The generated P0 and P2 write-ups say what their results say, in the right units.

Truths written here: the papers' own figures (typed from the papers, not from inserr),
the definition of the micro-g (1e-6 standard gravity, so 1e-4 g is exactly 100 ug),
and the scenario files' text.
"""

from __future__ import annotations

import json
import re
import tomllib
from pathlib import Path

import pytest

from inserr.core.units import G0, MICRO_G
from inserr.scenario.schema import load_scenario

ROOT = Path(__file__).resolve().parents[1]
P0 = ROOT / "analyses" / "p0_swinging_base"
P2 = ROOT / "analyses" / "p2_four_position"

#: P0's maximum horizontal error over 72 h, nmi: none / traditional / flexible.
P0_PAPER = {"exp1": (8.57, 3.70, 2.97), "exp2": (16.13, 12.90, 1.98)}


def _table_after(text: str, heading: str) -> list[list[str]]:
    """The first Markdown table after ``heading``: its body rows, cells stripped."""
    part = text.split(heading, 1)[1]
    lines = [ln for ln in part.splitlines() if ln.startswith("|")]
    rows, started = [], False
    for ln in part.splitlines():
        if ln.startswith("|"):
            started = True
            rows.append([c.strip() for c in ln.strip("|").split("|")])
        elif started:
            break
    assert lines, f"no table after {heading!r}"
    return rows[2:]  # header and separator


def test_p2_accelerometer_bias_is_1e_4_g_and_reported_as_100_ug():
    scen = load_scenario(P2 / "scenario.toml")
    # 1e-4 g with g the standard gravity 9.80665 m/s^2 (the definition, typed here).
    assert scen.imu.accel_bias == pytest.approx([1e-4 * 9.80665] * 3, rel=1e-15)
    # inserr's micro-g is 1e-6 standard gravity, so the same bias is 100 ug exactly.
    assert scen.imu.accel_bias[0] / MICRO_G == pytest.approx(100.0, rel=1e-14)
    text = (P2 / "results" / "REPORT.md").read_text(encoding="utf-8")
    m = re.search(r"1e-4 g is ([0-9.]+) ug", text)
    assert m and float(m.group(1)) == 100.0
    assert "98.0665" not in text
    row = next(r for r in _table_after(text, "## Set-up") if r[0].startswith("accel bias"))
    # The report writer prints three equal components once ("(x,y,z)" in the row's name).
    assert row[1] == "100 ug"
    res = json.loads((P2 / "results" / "results.json").read_text(encoding="utf-8"))
    assert res["choices"]["accel_bias_ug"] == pytest.approx(100.0, rel=1e-12)
    assert res["choices"]["accel_bias_g"] == pytest.approx(1e-4, rel=1e-12)
    assert res["choices"]["g0_m_s2"] == G0 == 9.80665


def test_p2_azimuth_claim_is_judged_for_both_opening_phases():
    res = json.loads((P2 / "results" / "results.json").read_text(encoding="utf-8"))
    az = [c for c in res["claims"] if "azimuth" in c["claim"]]
    assert {c["start"] for c in az} == {"stop", "turn"}
    text = (P2 / "results" / "REPORT.md").read_text(encoding="utf-8")
    rows = _table_after(text, "## Against the paper")
    word = {True: "holds", False: "fails", None: "partly"}
    for c in res["claims"]:
        row = next(r for r in rows if r[0] == c["claim"])
        assert row[1 if c["start"] == "stop" else 2] == word[c["holds"]]


@pytest.mark.parametrize("name", ["scenario.toml", "scenario_exp2.toml"])
def test_p0_scenarios_declare_their_heading_convention(name):
    raw = tomllib.loads((P0 / name).read_text(encoding="utf-8"))
    assert raw["motion"]["heading_convention"] in (
        "clockwise-from-north",
        "counter-clockwise-from-north",
    )
    assert load_scenario(P0 / name).heading_convention == raw["motion"]["heading_convention"]


def test_p0_against_the_paper_table_quotes_the_paper_and_the_results():
    text = (P0 / "results" / "REPORT.md").read_text(encoding="utf-8")
    res = json.loads((P0 / "results" / "results.json").read_text(encoding="utf-8"))
    comps = res["against_the_paper"]["comparisons"]
    rows = _table_after(text, "## Against the paper")
    assert len(rows) == 6
    for exp, paper in P0_PAPER.items():
        mine = [r for r in rows if r[0] == exp]
        assert [float(r[2]) for r in mine] == list(paper)
        for r in mine:
            detail = comps[exp]["detail"][r[1]]
            readings = list(detail)
            assert len(readings) == 2  # one per convention, at the stated set-up
            for j, reading in enumerate(readings):
                d = detail[reading]
                cells = r[3 + 5 * j : 8 + 5 * j]
                for cell, key in zip(cells[:3], ("all-positive", "RMS", "worst"), strict=True):
                    assert cell == f"{d[key]:.2f}"
                assert cells[3] == f"{d['lowest']:.2f}-{d['highest']:.2f}"
                assert cells[4] == d["reach"]
                # The figures lie inside the range over sign patterns (the all-positive
                # and worst are patterns; the RMS is an average over them).
                for key in ("all-positive", "worst"):
                    assert d["lowest_bound"] - 1e-9 <= d[key] <= d["highest"] + 1e-9
                assert d["worst"] == pytest.approx(d["highest"], rel=1e-9)


#: docs/design.md's P0 figures: row label -> (study, "chosen" or a catalogue label, key).
_S, _N, _ST = "p0_vehicle", "p0_vehicle_nulling", "static_base"
_C, _NU, _TP = "chosen", "nulling-two-position", "two-position"
_DA, _NR = "designed single-axis cycle: ", "nulling rule (catalogue): "
DESIGN_FIGURES = {
    _DA + "worst on P0's 36-case grid": (_S, _C, "grid_worst_nmi"),
    _DA + "worst on the whole training set (grid and 24 draws)": (_S, _C, "worst_nmi"),
    _DA + "worst on the 36 held-out swings": (_S, _C, "held_out_worst_nmi"),
    _DA + "motor starts per hour": (_S, _C, "starts_per_hour"),
    _NR + "worst on the grid": (_S, _NU, "grid_worst_nmi"),
    _NR + "worst on the whole training set": (_S, _NU, "worst_nmi"),
    _NR + "worst on the held-out swings": (_S, _NU, "held_out_worst_nmi"),
    "traditional two-position cycle: worst on the grid": (_S, _TP, "grid_worst_nmi"),
    "traditional two-position cycle: motor starts per hour": (_S, _TP, "starts_per_hour"),
    "designed nulling parameters: worst on the grid": (_N, _C, "grid_worst_nmi"),
    "designed nulling parameters: worst on the whole training set": (_N, _C, "worst_nmi"),
    "designed nulling parameters: worst on the held-out swings": (_N, _C, "held_out_worst_nmi"),
    "designed nulling parameters: motor starts per hour": (_N, _C, "starts_per_hour"),
    "static base: designed cycle": (_ST, _C, "worst_nmi"),
    "static base: nulling rule": (_ST, _NU, "worst_nmi"),
}


def test_design_doc_quotes_the_design_study_results():
    # The figures of docs/design.md section 5 are hand-placed in prose; each must be the
    # study's results.json value to the digits printed (4 significant digits, as REPORT.md).
    text = (ROOT / "docs" / "design.md").read_text()
    rows = _table_after(text, "<!-- inserr:design-p0-figures -->")
    results = json.loads((ROOT / "analyses" / "design_p0" / "results" / "results.json").read_text())
    quoted = {label: value for label, value in rows}
    assert set(quoted) == set(DESIGN_FIGURES)
    for label, (study, who, key) in DESIGN_FIGURES.items():
        r = results[study]
        entry = (
            r["chosen"] if who == "chosen" else next(e for e in r["catalogue"] if e["label"] == who)
        )
        assert quoted[label] == f"{entry[key]:.4g}", label


def test_design_study_verdict_on_issue_17_is_strict_and_complete():
    # analyses/design_p0/run.py decides which design meets issue 17's done-when: strictly
    # below every catalogue scheme on the grid and on the held-out set, and no more motor
    # starts than the traditional cycle. Checked on the committed results (the closed-loop
    # design meets it, the open-loop one does not) and on altered copies: a tie on the
    # grid, a tie on the held-out set and one start too many each fail it.
    import copy
    import importlib.util
    from types import SimpleNamespace

    spec = importlib.util.spec_from_file_location(
        "design_p0_run", ROOT / "analyses" / "design_p0" / "run.py"
    )
    run = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(run)
    results = json.loads((ROOT / "analyses" / "design_p0" / "results" / "results.json").read_text())

    def outcome(res):
        return SimpleNamespace(results=res, settings=SimpleNamespace(grid=36))

    closed, open_loop = results["p0_vehicle_nulling"], results["p0_vehicle"]
    assert run.meets_issue_17(outcome(closed)) and not run.meets_issue_17(outcome(open_loop))
    best = {
        key: min(c[key] for c in closed["catalogue"])
        for key in ("grid_worst_nmi", "held_out_worst_nmi")
    }
    trad = next(c for c in closed["catalogue"] if c["label"] == "two-position")
    for key, value in (
        ("grid_worst_nmi", best["grid_worst_nmi"]),
        ("held_out_worst_nmi", best["held_out_worst_nmi"]),
        ("starts_per_hour", trad["starts_per_hour"] + 1e-9),
    ):
        altered = copy.deepcopy(closed)
        altered["chosen"][key] = value
        assert not run.meets_issue_17(outcome(altered)), key
    text = run.summary([("open", outcome(open_loop)), ("closed", outcome(closed))])
    assert "is met by the closed, not by the open." in text
