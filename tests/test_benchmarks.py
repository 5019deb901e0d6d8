"""The benchmark scripts still read their scenarios (no timing here: timed tests are
not allowed, and the benchmarks print ratios themselves).

A change of the input rules once broke ``benchmarks/propagation.py`` unnoticed (a
static base given the swing's keys); these checks build every scenario and grid the
scripts use, the cheap part of each run, so such a break fails the suite.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _load(name: str):
    spec = importlib.util.spec_from_file_location(
        f"bench_{name}", ROOT / "benchmarks" / f"{name}.py"
    )
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize("static", [True, False])
def test_propagation_benchmark_scenarios_load(static):
    mod = _load("propagation")
    scen = mod._scenario(static, 6.0)
    assert scen.motion.is_static is static
    assert scen.duration == pytest.approx(6 * 3600.0)


def test_reference_benchmark_scenarios_load():
    mod = _load("reference")
    for spec in mod.SCENARIOS.values():
        scen = mod._scenario(spec)
        assert scen.scheme_name == "two-position"


def test_sweep_benchmark_grid_has_its_thousand_points():
    from inserr.scenario.schema import load_scenario
    from inserr.sweep.grid import build_grid

    mod = _load("sweep")
    grid = build_grid(load_scenario(mod.SCENARIO), list(mod.PARAMS))
    assert len(grid.points) == 5 * 5 * 4 * 10  # schemes x stops x rates x periods
