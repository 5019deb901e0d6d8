"""The layering holds: import order, no cycles, no CLI in the library, no import-time effects.

The import graph is read from the source (``ast``), not from ``sys.modules``, so an
import inside a function counts as much as one at the top of a module: every
``import`` and ``from ... import`` statement anywhere in a file (module level, in a
function or method, under ``if TYPE_CHECKING``) is an edge. Cycles are searched in
that graph of all imports; it contains the graph of module-level imports, so a cycle
of either kind fails the test. What the tests check:

* nothing outside ``inserr/cli`` (library, analyses, benchmarks) imports ``inserr.cli``;
* every import between two subpackages goes down the layer order :data:`LAYERS`
  (written down in ``docs/architecture.md``); subpackages on the same layer are
  independent of each other;
* the module import graph has no cycle;
* the lazy re-export table of every subpackage points into that subpackage only, so
  it cannot smuggle an import past the layer check;
* no file calls ``matplotlib.use`` or imports ``matplotlib.pyplot``;
* importing every module leaves the matplotlib backend alone, ``import inserr``
  imports neither matplotlib, scipy, control nor dask, and only the figure modules
  import matplotlib at all.
"""

from __future__ import annotations

import ast
import importlib
import os
import re
import subprocess
import sys
import textwrap
from collections import defaultdict
from pathlib import Path

import pytest

import inserr

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "inserr"

#: The layer order, lowest first; a subpackage may import only from lower layers.
#: The same order, written as one line, is in docs/architecture.md.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("core",),
    ("output",),
    ("model",),
    ("schemes",),
    ("scenario",),
    ("drift",),
    ("reference", "alignment", "calibration", "northfinder"),
    ("sweep",),
    ("cli",),
)
LAYER_LINE = (
    "core < output < model < schemes < scenario < drift < "
    "{reference, alignment, calibration, northfinder} < sweep < cli"
)
RANK = {pkg: rank for rank, layer in enumerate(LAYERS) for pkg in layer}
HEAVY = ("matplotlib", "scipy", "control", "dask")


# --- the import graph -------------------------------------------------------------------
def module_name(path: Path, root: Path = ROOT) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def library_modules() -> dict[str, Path]:
    """Every module of the inserr package by dotted name."""
    return {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def imports_of(path: Path, name: str, known: set[str]) -> list[tuple[str, int]]:
    """(imported module, line) for every import statement of a file, wherever it is.

    ``from a.b import c`` counts as an import of ``a.b.c`` when that is a module, else
    of ``a.b``; relative imports are resolved against ``name``'s package.
    """
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    is_pkg = path.name == "__init__.py"
    out: list[tuple[str, int]] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(a.name, node.lineno) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                pkg = name.split(".") if is_pkg else name.split(".")[:-1]
                pkg = pkg[: len(pkg) - (node.level - 1)]
                base = ".".join(pkg + ([base] if base else []))
            for a in node.names:
                full = f"{base}.{a.name}"
                out.append((full if full in known else base, node.lineno))
    return out


def graph() -> dict[str, list[tuple[str, int]]]:
    """Module -> the inserr modules it imports (with the line of the statement)."""
    mods = library_modules()
    known = set(mods)
    return {
        name: [(t, line) for t, line in imports_of(path, name, known) if t.startswith("inserr")]
        for name, path in mods.items()
    }


def subpackage(module: str) -> str | None:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else None


def cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (or a self-import)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    counter = [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1 or v in edges.get(v, ()):
                found.append(sorted(comp))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return found


# --- the checker checks itself ----------------------------------------------------------
def test_cycle_finder_finds_a_planted_cycle_and_no_false_one():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"a"}}) == [["a"]]
    assert cycles({"a": {"b", "c"}, "b": {"c"}, "c": set()}) == []


def test_import_reader_sees_function_level_and_relative_imports(tmp_path):
    src = tmp_path / "inserr" / "drift" / "x.py"
    src.parent.mkdir(parents=True)
    src.write_text(
        textwrap.dedent(
            """
            import inserr.core.units
            from . import study
            def f():
                from inserr.cli.main import main
            """
        )
    )
    known = {"inserr.drift.study", "inserr.cli.main", "inserr.core.units"}
    got = {t for t, _ in imports_of(src, "inserr.drift.x", known)}
    assert got == {"inserr.core.units", "inserr.drift.study", "inserr.cli.main"}


# --- the rules --------------------------------------------------------------------------
def test_every_subpackage_has_a_layer():
    on_disk = {p.parent.name for p in PACKAGE.glob("*/__init__.py")}
    assert on_disk == set(RANK), "place a new subpackage in LAYERS and docs/architecture.md"
    assert tuple(inserr.SUBPACKAGES) == tuple(p for layer in LAYERS for p in layer)


def test_layer_order_is_the_documented_one():
    doc = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    assert LAYER_LINE in doc


def test_imports_go_down_the_layers_and_never_into_the_cli():
    bad = []
    for module, targets in graph().items():
        if module == "inserr.__main__":
            continue  # ``python -m inserr`` is the command itself, like the installed script
        src = subpackage(module)
        for target, line in targets:
            dst = subpackage(target)
            if target == "inserr":
                # The root package imports nothing at import time (test below), so
                # reading inserr.__version__ is allowed from anywhere.
                continue
            if dst == "cli" and src != "cli":
                bad.append(f"{module}:{line} imports the CLI ({target})")
            elif src is None or dst is None or src == dst:
                continue
            elif RANK[dst] >= RANK[src]:
                bad.append(f"{module}:{line} imports {target}: {src} may not import {dst}")
    assert not bad, "\n".join(bad)


def test_the_root_package_imports_nothing_at_import_time():
    tree = ast.parse((PACKAGE / "__init__.py").read_text(encoding="utf-8"))
    top = [n for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom))]
    names = {a.name for n in top if isinstance(n, ast.Import) for a in n.names} | {
        n.module for n in top if isinstance(n, ast.ImportFrom)
    }
    assert names <= {"__future__", "importlib"}


def test_no_import_cycles_among_module_and_function_level_imports():
    edges = defaultdict(set)
    known = set(library_modules())
    for module, targets in graph().items():
        edges[module] |= {t for t, _ in targets if t in known and t != "inserr"}
    assert cycles(edges) == []


def test_lazy_re_exports_stay_inside_their_subpackage():
    for pkg in inserr.SUBPACKAGES:
        module = importlib.import_module(f"inserr.{pkg}")
        targets = set(module.__getattr__.exports.values())
        assert targets, pkg
        assert all(t.startswith(f"inserr.{pkg}.") for t in targets), (pkg, targets)


def test_nothing_outside_the_cli_imports_it():
    bad = []
    for folder in ("analyses", "benchmarks"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            for target, line in imports_of(path, module_name(path), set()):
                if target == "inserr.cli" or target.startswith("inserr.cli."):
                    bad.append(f"{path.relative_to(ROOT)}:{line} imports {target}")
    assert not bad, "\n".join(bad)


def _python_files():
    for folder in ("inserr", "analyses", "benchmarks", "tools", "docs"):
        yield from sorted((ROOT / folder).rglob("*.py"))


def test_no_pyplot_and_no_backend_switch_anywhere():
    bad = []
    for path in _python_files():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
            if any(n in ("matplotlib.pyplot", "pylab") for n in names):
                bad.append(f"{path.relative_to(ROOT)}:{node.lineno} imports pyplot")
            if (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Attribute)
                and node.func.attr == "use"
                and isinstance(node.func.value, ast.Name)
                and node.func.value.id == "matplotlib"
            ):
                bad.append(f"{path.relative_to(ROOT)}:{node.lineno} calls matplotlib.use")
    assert not bad, "\n".join(bad)


# --- what importing does ----------------------------------------------------------------
def _python(code: str, **env: str) -> subprocess.CompletedProcess:
    environ = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
    environ["PYTHONPATH"] = os.pathsep.join(
        p for p in (str(ROOT), os.environ.get("PYTHONPATH", "")) if p
    )
    environ.update(env)
    return subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, env=environ, capture_output=True, text=True
    )


WALK = (
    "import matplotlib; b = matplotlib.get_backend(); import inserr, pkgutil, importlib; "
    "[importlib.import_module(m.name) for m in pkgutil.walk_packages(inserr.__path__, "
    "'inserr.')]; assert matplotlib.get_backend() == b"
)


@pytest.mark.parametrize("backend", [None, "svg"])
def test_importing_every_module_keeps_the_matplotlib_backend(backend):
    # The command as written, and under the non-interactive "svg" backend:
    # on a headless machine the default backend resolves to Agg, which a stray
    # matplotlib.use("Agg") would not change, so only a backend other than Agg lets
    # this test fail on such a call.
    env = {} if backend is None else {"MPLBACKEND": backend}
    proc = _python(WALK, **env)
    assert proc.returncode == 0, proc.stderr[-2000:]


def test_import_inserr_is_light_and_its_entry_points_resolve():
    code = textwrap.dedent(
        f"""
        import sys
        import inserr
        heavy = sorted(m for m in sys.modules if m.split(".")[0] in {HEAVY!r})
        assert not heavy, heavy
        assert [m for m in sys.modules if m.startswith("inserr.")] == []
        """
    )
    proc = _python(code)
    assert proc.returncode == 0, proc.stderr[-2000:]
    from inserr.core.errors import InputError
    from inserr.drift.analysis import analyze_drift
    from inserr.drift.study import run_scheme
    from inserr.scenario.schema import load_scenario, scenario_from_dict

    assert inserr.load_scenario is load_scenario
    assert inserr.scenario_from_dict is scenario_from_dict
    assert inserr.run_scheme is run_scheme
    assert inserr.analyze_drift is analyze_drift
    assert inserr.InputError is InputError
    assert re.fullmatch(r"\d+\.\d+\.\d+", inserr.__version__)
    for name in inserr.__all__:
        assert getattr(inserr, name) is not None
    assert set(inserr.__all__) <= set(dir(inserr))
    with pytest.raises(AttributeError):
        inserr.no_such_name  # noqa: B018


def test_every_subpackage_export_resolves_to_its_module():
    for pkg in inserr.SUBPACKAGES:
        module = importlib.import_module(f"inserr.{pkg}")
        assert module.__all__, pkg
        for name in module.__all__:
            value = getattr(module, name)
            defining = getattr(value, "__module__", None)
            if defining is not None and callable(value):
                assert defining.startswith(f"inserr.{pkg}."), (pkg, name, defining)


def test_only_figure_modules_import_matplotlib():
    # Importing every module except the figure modules (and the CLI, which imports
    # its studies when a command runs) must not load matplotlib: figures stay apart.
    names = sorted(
        n
        for n in library_modules()
        if not n.endswith(".figures") and not n.startswith("inserr.cli")
    )
    code = "import sys, importlib\n"
    code += "".join(f"importlib.import_module({n!r})\n" for n in names)
    code += "assert 'matplotlib' not in sys.modules, 'matplotlib imported'\n"
    proc = _python(code)
    assert proc.returncode == 0, proc.stderr[-2000:]


# --- the map ----------------------------------------------------------------------------
def test_the_map_lists_every_subpackage_in_reading_order():
    doc = inserr.__doc__
    positions = [doc.index(f":mod:`inserr.{p}`") for p in inserr.SUBPACKAGES]
    assert positions == sorted(positions)
    arch = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    positions = [arch.index(f"`inserr.{p}`") for p in inserr.SUBPACKAGES]
    assert positions == sorted(positions)
    for convention in ("ENU", "right-front-up", "clockwise from north", "computed minus true"):
        assert convention in doc and convention in arch, convention


@pytest.mark.parametrize("pkg", inserr.SUBPACKAGES)
def test_every_subpackage_docstring_lists_its_modules(pkg):
    module = importlib.import_module(f"inserr.{pkg}")
    on_disk = {p.stem for p in (PACKAGE / pkg).glob("*.py") if p.stem != "__init__"}
    listed = set(re.findall(r"^\* ``(\w+)``", module.__doc__, flags=re.MULTILINE))
    assert listed == on_disk
