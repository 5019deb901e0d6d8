"""Every analysis in ``analyses/`` runs from its scenario file (reduced where it has a
``--quick`` mode) and writes its generated write-up and results.

These are smoke tests of the scripts as a user runs them (a subprocess, the bundled
scenario file, an output directory of the test's own); the physics of each study is
tested in the module tests. The full runs and their committed reports are in
``analyses/*/results/``.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: (script, extra arguments, a heading the write-up must contain)
CASES = [
    ("alignment_observability/run.py", ["--quick"], "## What the unmodelled errors cost"),
    ("p1_calibration/run.py", ["--quick"], "# "),
    ("p2_four_position/run.py", [], "# "),
    ("p0_swinging_base/run.py", ["--quick"], "## Verdicts"),
    ("p3_northfinder/run.py", ["--quick"], "# "),
    ("design_p0/run.py", ["--quick"], "## Verdicts (issue 17)"),
]


@pytest.mark.parametrize(("script", "extra", "heading"), CASES, ids=[c[0] for c in CASES])
def test_analysis_runs_from_its_scenario_file(script, extra, heading, tmp_path):
    out = tmp_path / "out"
    env = {**os.environ, "MPLBACKEND": "Agg"}
    proc = subprocess.run(
        [sys.executable, str(ROOT / "analyses" / script), *extra, "--out", str(out)],
        cwd=tmp_path,
        env=env,
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    report = out / "REPORT.md"
    assert report.is_file()
    text = report.read_text(encoding="utf-8")
    assert heading in text
    assert "nan" not in text.lower().split()  # no missing figure leaked into the prose
    json.loads((out / "results.json").read_text(encoding="utf-8"))
    pngs = sorted(out.glob("*.png"))
    assert pngs
    # Written by the one report writer (inserr.output.report): the HTML page beside the
    # Markdown embeds every figure the write-up links.
    page = (out / "report.html").read_text(encoding="utf-8")
    linked = set(re.findall(r"\]\(([\w.-]+\.png)\)", text))
    assert linked <= {p.name for p in pngs}
    assert page.count("src='data:image/png;base64,") == len(linked)
