"""One report writer for every study, one figure style for every figure.

Every command that writes a report directory runs here in-process with the
writer spied on: the report must be written once, by
:meth:`inserr.output.report.Report.write`, and every directory must have the same
layout (``report.md``, ``report.html`` with the figures embedded, one PNG per
figure, ``results.json``, the marker), the same heading style and figures in the
inserr style. The Markdown-to-HTML renderer and the style module are tested on
their own below.
"""

from __future__ import annotations

import base64
import json
import re
import struct
from pathlib import Path

import pytest

from inserr.cli.main import main
from inserr.output import figure_style as style
from inserr.output.report import (
    MARKER,
    Report,
    check_report_dir,
    dumps,
    inline_html,
    markdown_to_html,
)

SCENARIO = """
[scenario]
name = "writer test"
duration = "1 h"

[imu]
gyro_bias = "0.01 deg/h"
accel_bias = "50 ug"
arw = "0.002 deg/sqrt(h)"

[scheme]
name = "none"
stop = "120 s"

[compare]
schemes = ["none", "two-position"]
"""

#: command -> its arguments (small runs; each writes a report with --out)
COMMANDS = {
    "drift": ["drift", "--scheme", "two-position", "--duration", "1 h", "--gyro-bias", "0.01"],
    "compare": ["compare", "--duration", "1 h", "--schemes", "none,two-position", "--arw", "0.002"],
    "run": ["run", "{scenario}"],
    "align": ["align", "--schemes", "none,two-position", "--duration", "2 min"],
    "calibrate": ["calibrate", "--runs", "3"],
    "northfind": [
        "northfind",
        "--lat",
        "34",
        "--heading",
        "30",
        "--runs",
        "2",
        "--duration",
        "1 min",
    ],
    "validate": [
        "validate",
        "--duration",
        "0.2 h",
        "--gyro-bias",
        "0.02",
        "--scheme",
        "two-position",
        "--sample-rate",
        "10",
    ],
}


def png_dpi(data: bytes) -> float:
    """Resolution stored in a PNG's pHYs chunk (pixels per metre), in dots per inch."""
    i = data.index(b"pHYs")
    x, y, unit = struct.unpack(">IIB", data[i + 4 : i + 13])
    assert unit == 1 and x == y
    return x * 0.0254


@pytest.fixture
def spied(monkeypatch):
    """Record every Report.write and Report.figure call (and still do the work)."""
    calls = {"write": [], "figures": []}
    write, figure = Report.write, Report.figure

    def spy_write(self, out_dir, markdown_name="report.md"):
        calls["write"].append((self, Path(out_dir)))
        return write(self, out_dir, markdown_name)

    def spy_figure(self, fig, name, caption="", **options):
        calls["figures"].append(fig)
        return figure(self, fig, name, caption, **options)

    monkeypatch.setattr(Report, "write", spy_write)
    monkeypatch.setattr(Report, "figure", spy_figure)
    return calls


@pytest.mark.parametrize("command", list(COMMANDS))
def test_every_study_report_goes_through_the_one_writer(command, spied, tmp_path, capsys):
    if command == "validate":
        pytest.importorskip("pyins")
    scenario = tmp_path / "scenario.toml"
    scenario.write_text(SCENARIO, encoding="utf-8")
    out = tmp_path / "report"
    argv = [a.format(scenario=scenario) for a in COMMANDS[command]]
    assert main([*argv, "--out", str(out), "--json"]) == 0
    capsys.readouterr()

    # Written once, by the one writer, to the directory asked for.
    assert [p for _, p in spied["write"]] == [out]
    rep = spied["write"][0][0]
    figures = [b.payload[0] for b in rep.blocks if b.kind == "figure"]
    assert figures, "every study's report has figures"
    attached = {b.payload[0] for b in rep.blocks if b.kind == "file"}

    # The same layout for every study (plus the data files a study attaches).
    files = {p.name for p in out.iterdir()}
    assert files == {"report.md", "report.html", "results.json", MARKER} | attached | {
        f"{name}.png" for name in figures
    }
    for name in attached:  # linked from both pages
        assert f"]({name})" in (out / "report.md").read_text(encoding="utf-8")
        assert f"href='{name}'" in (out / "report.html").read_text(encoding="utf-8")
    md = (out / "report.md").read_text(encoding="utf-8")
    page = (out / "report.html").read_text(encoding="utf-8")
    assert md.startswith(f"# {rep.title}\n")
    # One title; every other heading is a section (## or deeper).
    assert [line for line in md.splitlines() if re.match(r"#\s", line)] == [f"# {rep.title}"]
    embedded = re.findall(r"src='data:image/png;base64,([A-Za-z0-9+/=]+)'", page)
    assert len(embedded) == len(figures)
    for name, data in zip(figures, embedded, strict=True):
        png = (out / f"{name}.png").read_bytes()
        assert md.count(f"]({name}.png)") == 1
        assert base64.b64decode(data) == png  # the HTML embeds exactly the file
        assert png_dpi(png) == pytest.approx(style.DPI, abs=0.01)  # pHYs is rounded to 1/m
    assert json.loads((out / "results.json").read_text()) == json.loads(dumps(rep.results))

    # The figures: built without pyplot, finished in the inserr style.
    assert len(spied["figures"]) == len(figures)
    for fig in spied["figures"]:
        assert type(fig).__name__ == "Figure" and fig.canvas.manager is None
        for ax in fig.axes:
            if ax.get_title():
                assert ax.title.get_fontsize() == style.FONT["title"]
            if ax.get_xlabel():
                assert ax.xaxis.label.get_fontsize() == style.FONT["label"]
            legend = ax.get_legend()
            if legend is not None:
                assert {t.get_fontsize() for t in legend.get_texts()} == {style.FONT["legend"]}


def test_write_into_writes_the_same_files_and_leaves_others_alone(tmp_path):
    rep = _sample_report()
    whole = rep.write(tmp_path / "whole")
    shared = tmp_path / "shared"
    shared.mkdir()
    (shared / "NOTES.md").write_text("the user's", encoding="utf-8")
    rep.write_into(shared, markdown_name="REPORT.md")
    written = {p.name for p in whole.iterdir()} - {MARKER}
    assert {p.name for p in shared.iterdir()} == (written - {"report.md"}) | {
        "REPORT.md",
        "NOTES.md",
    }
    assert (shared / "NOTES.md").read_text(encoding="utf-8") == "the user's"
    for name in written - {"report.md"}:
        assert (shared / name).read_bytes() == (whole / name).read_bytes()
    assert (shared / "REPORT.md").read_bytes() == (whole / "report.md").read_bytes()


def test_the_writer_refuses_a_directory_it_did_not_write(tmp_path):
    user = tmp_path / "mine"
    user.mkdir()
    (user / "thesis.tex").write_text("x", encoding="utf-8")
    with pytest.raises(Exception, match="not an inserr report"):
        _sample_report().write(user)
    assert [p.name for p in user.iterdir()] == ["thesis.tex"]
    assert check_report_dir(tmp_path / "new") == (tmp_path / "new").resolve()


def _sample_report() -> Report:
    rep = Report("Sample <report>")
    rep.heading("Section")
    rep.paragraph("A **bold** claim with `code` and a [link](https://example.org).")
    rep.table(["a", "b"], [[1.0, "x"], [2.5, "y*z"]])
    rep.markdown_text("## Raw\n\n- one\n- two\n\n| h |\n|---|\n| c |\n")
    fig, ax = style.subplots(1, 1, height=2.0)
    ax.plot([0, 1], [0, 1], color=style.scheme_color("two-position"), label="line")
    ax.set_title("t")
    ax.legend()
    rep.figure(fig, "line", "A line")
    rep.results = {"x": 1.0}
    return rep


# --- Markdown to HTML -------------------------------------------------------------------
def test_inline_markdown_is_rendered_and_everything_else_escaped():
    assert inline_html("**b** and *i* and `a<b`") == (
        "<strong>b</strong> and <em>i</em> and <code>a&lt;b</code>"
    )
    assert inline_html("<script>x</script>") == "&lt;script&gt;x&lt;/script&gt;"
    # Stars that do not hug a word are arithmetic, not emphasis.
    assert inline_html("a * b * c") == "a * b * c"
    assert inline_html("[t](https://x.org/a)") == '<a href="https://x.org/a">t</a>'
    # Markdown inside a code span stays literal.
    assert inline_html("`**x**`") == "<code>**x**</code>"


def test_markdown_blocks_become_html_blocks():
    text = (
        "## Title *x*\n\nfirst line\nsecond line\n\n- item one\n  continued\n- item two\n\n"
        "| h1 | h2 |\n|---|---|\n| a | `b` |\n| c | d |\n\n```\n<raw> **x**\n```\n"
    )
    got = markdown_to_html(text)
    assert got.split("\n")[0] == "<h2>Title <em>x</em></h2>"
    assert "<p>first line\nsecond line</p>" in got
    assert "<ul><li>item one continued</li><li>item two</li></ul>" in got
    assert got.count("<tr>") == 3 and got.count("<th>") == 2 and got.count("<td>") == 4
    assert "<td><code>b</code></td>" in got
    assert "<pre><code>&lt;raw&gt; **x**</code></pre>" in got


def test_markdown_text_is_copied_verbatim_into_the_markdown_file():
    raw = "## Raw\n\n| h |\n|---|\n| c |\n\n- one\n- two"
    rep = Report("T")
    rep.markdown_text(raw + "\n\n")
    assert rep.markdown() == f"# T\n\n{raw}\n"


# --- the figure style -------------------------------------------------------------------
def test_every_catalogue_scheme_has_its_own_colour():
    from matplotlib.colors import to_rgb

    from inserr.schemes.catalogue import SCHEMES

    assert set(style.SCHEME_COLORS) == set(SCHEMES)
    colours = [to_rgb(c) for c in style.SCHEME_COLORS.values()]
    assert len(set(colours)) == len(colours)
    # A scheme's colour never doubles as the "worst sign pattern" or the black reference.
    assert to_rgb(style.ROLE_COLORS["worst"]) not in colours
    assert to_rgb(style.ROLE_COLORS["reference"]) not in colours
    # Unknown names fall back to the series palette by position.
    assert style.scheme_color("my scheme", 3) == style.series_color(3)
    assert style.scheme_color("two-position", 3) == style.SCHEME_COLORS["two-position"]


def test_finish_applies_the_fonts_and_is_idempotent():
    fig, axes = style.subplots(1, 2)
    for ax in axes:
        ax.plot([0, 1], label="x")
        ax.set_title("a", fontsize=20)
        ax.set_xlabel("b", fontsize=3)
        ax.legend(fontsize=15)
    for _ in range(2):
        style.finish(fig)
        for ax in axes:
            assert ax.title.get_fontsize() == style.FONT["title"]
            assert ax.xaxis.label.get_fontsize() == style.FONT["label"]
            assert ax.get_legend().get_texts()[0].get_fontsize() == style.FONT["legend"]
    assert fig.canvas.manager is None
    assert png_dpi(style.png_bytes(fig)) == pytest.approx(style.DPI, abs=0.01)
