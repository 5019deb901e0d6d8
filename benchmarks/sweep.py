"""Benchmark: a 1000-point design sweep of P0's swinging base on 1 and on 2 local workers.

Every point is a 72 h drift analysis of P0 experiment 1
(``analyses/p0_swinging_base/scenario.toml``: P0's full budget, yaw swing, outputs
at 10 s and 60 s) with one change per swept parameter::

    scheme   two-position, four-position, four-position-modified,
             flexible-two-position, nulling-two-position          (5)
    stop     60, 120, 180, 240, 300 s                              (5)
    rate     3, 6, 10, 20 deg/s                                    (4)
    period   20, 30, 45, 60, 90, 120, 165, 240, 480, 1200 s        (10)

The sweep runs once in this process (1 worker, Dask's synchronous scheduler) and
once on 2 worker processes; the two ``results.csv`` must be identical (the sweep is
deterministic whatever the engine). Printed: both wall times, the CPU time they used
(how many cores the run really got on a shared machine), and last::

    sweep_points_per_second: <points per second on 2 workers>

Usage::

    python benchmarks/sweep.py              # the 1000 points (target: <= 120 s on 2 workers)
    python benchmarks/sweep.py --points 40  # a subset (every k-th point), for a quick check
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "analyses" / "p0_swinging_base" / "scenario.toml"
PARAMS = [
    "scheme=two-position,four-position,four-position-modified,"
    "flexible-two-position,nulling-two-position",
    "stop=60,120,180,240,300",
    "rate=3,6,10,20",
    "motion.period=20 s,30 s,45 s,60 s,90 s,120 s,165 s,240 s,480 s,1200 s",
]


def timed(grid, out: Path, label: str, **engine) -> tuple[float, str]:
    """Wall time of one sweep and the text of its results.csv (CPU time printed too)."""
    from inserr.sweep.runner import run_sweep

    cpu0, t0 = os.times(), time.perf_counter()
    res = run_sweep(grid, out, plots=False, **engine)
    wall = time.perf_counter() - t0
    cpu = sum(os.times()[:4]) - sum(cpu0[:4])
    assert res.counts == {"ok": len(grid.points)}, res.counts
    print(
        f"{label:>11}: {wall:7.2f} s wall, {cpu:7.2f} s CPU ({cpu / wall:.2f} cores), "
        f"{len(grid.points) / wall:.2f} points/s",
        flush=True,
    )
    return wall, (out / "results.csv").read_text()


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=None, help="run every k-th point only")
    args = ap.parse_args(argv)
    os.environ.setdefault("INSERR_NO_PROGRESS", "1")
    from inserr.scenario.schema import load_scenario
    from inserr.sweep.grid import build_grid

    params = list(PARAMS)
    grid = build_grid(load_scenario(SCENARIO), params)
    if args.points:
        keep = grid.points[:: max(1, len(grid.points) // args.points)][: args.points]
        grid = dataclasses.replace(grid, points=tuple(keep))
    print(
        f"{len(grid.points)} points of 72 h, {os.cpu_count()} CPUs, "
        f"load average {os.getloadavg()[0]:.2f}"
    )
    # Imports first (not timed): the first import reads everything from disk.
    import inserr.drift.study  # noqa: F401

    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        _, csv1 = timed(grid, root / "one", "1 worker", workers=1)
        two, csv2 = timed(grid, root / "two", "2 workers", workers=2, scheduler="processes")
    assert csv1 == csv2, "results differ between 1 and 2 workers"
    print("results.csv identical for 1 and 2 workers")
    print(f"sweep_points_per_second: {len(grid.points) / two:.2f}")


if __name__ == "__main__":  # the guard matters: worker processes are spawned
    main()
