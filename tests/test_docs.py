"""The documentation cannot rot: the site builds in strict mode and the tutorials' code runs."""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
TUTORIALS = sorted((DOCS / "tutorials").glob("*.md"))
FENCE = re.compile(
    r"^(?P<indent>[ \t]*)```python[^\n]*\n(?P<body>.*?)^(?P=indent)```[ \t]*$",
    re.MULTILINE | re.DOTALL,
)


def python_blocks(markdown: str) -> list[str]:
    """The ```python fenced blocks of a page, in order (indented fences in lists included)."""
    return [textwrap.dedent(m.group("body")) for m in FENCE.finditer(markdown)]


def load_docs_module(name: str):
    spec = importlib.util.spec_from_file_location(f"docs_{name}", DOCS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_python_blocks_are_found_with_their_indentation():
    page = (
        "text\n```python\na = 1\n```\n\n* item\n\n  ```python\n  b = a + 1\n  ```\n"
        "```bash\nls\n```\n"
    )
    assert python_blocks(page) == ["a = 1\n", "b = a + 1\n"]


@pytest.mark.skipif(not TUTORIALS, reason="no tutorials yet")
@pytest.mark.parametrize("page", TUTORIALS, ids=lambda p: p.name)
def test_tutorial_code_runs(page, tmp_path, monkeypatch):
    """Every ```python block of the page, in order, in one namespace (as a reader would)."""
    blocks = python_blocks(page.read_text(encoding="utf-8"))
    monkeypatch.chdir(tmp_path)  # blocks that write files write them here
    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.setenv("INSERR_NO_PROGRESS", "1")
    namespace: dict = {"__name__": f"tutorial_{page.stem}"}
    for i, code in enumerate(blocks, 1):
        try:
            exec(compile(code, f"{page.name}[block {i}]", "exec"), namespace)
        except Exception as exc:  # name the block: the traceback alone points at "<string>"
            raise AssertionError(f"{page.name}, python block {i} failed: {exc!r}\n{code}") from exc


def test_site_builds_in_strict_mode(tmp_path):
    site = tmp_path / "site"
    env = {**os.environ, "MPLBACKEND": "Agg"}
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "mkdocs",
            "build",
            "--strict",
            "-f",
            str(ROOT / "mkdocs.yml"),
            "-d",
            str(site),
        ],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stderr[-4000:]
    from inserr.cli.main import available_commands
    from inserr.schemes.catalogue import SCHEMES

    for name in SCHEMES:  # one generated figure per scheme
        assert (site / "figures" / "schemes" / f"{name}.png").stat().st_size > 1000
    cli = (site / "cli" / "index.html").read_text(encoding="utf-8")
    for command in available_commands():
        assert f'id="inserr-{command}"' in cli
    assert "--scheduler" in cli and "--param" in cli
    api = (site / "api" / "index.html").read_text(encoding="utf-8")
    for module in (
        "inserr.scenario.schema",
        "inserr.drift.study",
        "inserr.sweep.grid",
        "inserr.core.units",
    ):
        assert f'id="{module}"' in api
    assert "<!-- inserr:" not in cli + api  # the markers were replaced
    hooks = load_docs_module("hooks")
    import yaml

    nav = yaml.safe_load((ROOT / "mkdocs.yml").read_text(encoding="utf-8"))
    for _, src in hooks.nav_pages(nav["nav"]):  # every nav page exists and was rendered
        assert (ROOT / "docs" / src).is_file(), src
        page = src[: -len(".md")]
        html = site / ("index.html" if page == "index" else f"{page}/index.html")
        assert html.stat().st_size > 2000, src


def test_nav_pages_are_found_at_every_depth():
    hooks = load_docs_module("hooks")
    nav = [
        {"Home": "index.md"},
        {"Group": [{"A": "a.md"}, {"Sub": [{"B": "sub/b.md"}]}]},
        "c.md",
        {"Link": "https://example.org"},
    ]
    assert hooks.nav_pages(nav) == [
        ("Home", "index.md"),
        ("A", "a.md"),
        ("B", "sub/b.md"),
        ("c", "c.md"),
    ]


def test_cli_reference_follows_the_parsers():
    text = load_docs_module("gen_cli").command_reference("sweep")
    assert text.startswith("## `inserr sweep`")
    for option in (
        "`--param` (repeatable)",  # or sweep.parameters in the scenario file
        "`--scheduler`",
        "`--workers`",
        "`--out`",
        "`--gyro-bias`",
        "`--json`",
    ):
        assert option in text


def test_readme_example_runs(capsys):
    """The README's Python example runs as written (shortened to 1 h to stay fast)."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    code = text.split("```python\n", 1)[1].split("```", 1)[0]
    assert len(code.strip().splitlines()) <= 10
    short = code.replace('"imu": {', '"scenario": {"duration": "1 h"}, "imu": {', 1)
    assert short != code
    exec(compile(short, "README.md", "exec"), {})
    lines = capsys.readouterr().out.strip().splitlines()
    assert [ln.split()[0] for ln in lines] == ["none", "two-position", "flexible-two-position"]


def test_scenario_reference_lists_every_scheme():
    from inserr.schemes.catalogue import SCHEMES

    text = (ROOT / "docs" / "scenarios.md").read_text(encoding="utf-8")
    assert [n for n in SCHEMES if f"`{n}`" not in text] == []
