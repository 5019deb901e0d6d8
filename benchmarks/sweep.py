"""Benchmark: a 16-point design sweep with 1 and with 2 local workers.

Each point is a 72 h drift analysis of a full navigation-grade budget (biases,
scale factors, misalignments, noise) on P0's swinging base, a few seconds of CPU,
so that Dask's scheduling and the start-up of the worker processes (each imports
numpy, scipy and inserr, and starts with a cold discretization cache: one to two
seconds) do not dominate. The two runs must give identical
``results.csv`` files (determinism); the last line printed is
``sweep_speedup_2_workers: <ratio>``.

Usage::

    python benchmarks/sweep.py            # 1 worker (in-process) vs 2 worker processes
    python benchmarks/sweep.py --threads  # also 2 threads in one process
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from inserr.scenario.schema import scenario_from_dict
from inserr.sweep.grid import build_grid
from inserr.sweep.runner import run_sweep

BASE = {  # P0's navigation-grade budget and yaw swing, 72 h at P0's site latitude
    "scenario": {"name": "bench", "duration": "72 h"},
    "site": {"latitude": "34.246 deg"},
    "motion": {
        "type": "yaw-swing",
        "amplitude": "6 deg/s",
        "period": "120 s",
        "pitch": "1 deg",
        "roll": "-2 deg",
    },
    "imu": {
        "gyro_bias": "0.003 deg/h",
        "accel_bias": "30 ug",
        "gyro_scale_factor": "10 ppm",
        "accel_scale_factor": "10 ppm",
        "gyro_misalignment": "10 arcsec",
        "accel_misalignment": "10 arcsec",
        "arw": "0.0005 deg/sqrt(h)",
        "vrw": "5 ug/sqrt(Hz)",
        "gyro_bias_instability": "0.001 deg/h",
    },
}
#: 2 x 4 x 2 = 16 points; short stops, the expensive end of a stop-time study.
PARAMS = ["scheme=two-position,four-position", "stop=20,30,45,60", "rate=6,10"]


def timed(grid, root: Path, label: str, **engine) -> tuple[float, str]:
    """Wall time of one sweep, and its results.csv; prints the CPU time used too.

    The CPU time (this process and its finished worker processes) over the wall
    time shows how many cores the run really got: on a shared machine, other
    jobs take their share and the speed-up drops with it.

    Parameters
    ----------
    grid : Grid
        The grid to run (every point must succeed).
    root : Path
        Directory for the run's output directory ``root/label``.
    label : str
        Name of the run, printed and used as the directory name.
    **engine
        ``scheduler`` and ``workers`` for :func:`inserr.sweep.runner.run_sweep`.

    Returns
    -------
    wall : float
        Wall time of the sweep (s).
    results : str
        The text of its ``results.csv``.
    """
    out = root / label
    cpu0, t0 = os.times(), time.perf_counter()
    res = run_sweep(grid, out, plots=False, **engine)
    wall = time.perf_counter() - t0
    cpu1 = os.times()
    cpu = sum(cpu1[:4]) - sum(cpu0[:4])
    assert res.counts == {"ok": len(grid.points)}, res.counts
    print(
        f"{label:>11}: {wall:6.2f} s wall, {cpu:6.2f} s CPU ({cpu / wall:.2f} cores) {res.engine}",
        flush=True,
    )
    return wall, (out / "results.csv").read_text()


def main() -> None:
    """Time the sweep of :data:`PARAMS` with 1 and 2 workers and print the speed-up.

    Raises
    ------
    AssertionError
        A point did not succeed, or the results differ between worker counts.
    """
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--threads", action="store_true", help="also time 2 threads")
    args = parser.parse_args()
    os.environ.setdefault("INSERR_NO_PROGRESS", "1")
    grid = build_grid(scenario_from_dict(BASE), PARAMS)
    print(
        f"{len(grid.points)} points of {BASE['scenario']['duration']}, {os.cpu_count()} CPUs, "
        f"load average {os.getloadavg()[0]:.2f}"
    )
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        # Imports first (not timed): on a freshly installed environment the first
        # import reads everything from disk, which would be charged to the 1-worker
        # run alone. Nothing is computed, so both runs start with cold caches.
        import control  # noqa: F401
        import filterpy.kalman  # noqa: F401

        import inserr.drift.analysis  # noqa: F401
        import inserr.drift.study  # noqa: F401

        one, csv1 = timed(grid, root, "1 worker", workers=1)
        two, csv2 = timed(grid, root, "2 processes", workers=2, scheduler="processes")
        assert csv1 == csv2, "results differ between 1 and 2 workers"
        if args.threads:
            threads, csv3 = timed(grid, root, "2 threads", workers=2, scheduler="threads")
            assert csv3 == csv1, "results differ with threads"
            print(f"sweep_speedup_2_threads: {one / threads:.2f}")
    print("results.csv identical for 1 and 2 workers")
    print(f"sweep_speedup_2_workers: {one / two:.2f}")


if __name__ == "__main__":  # the guard matters: worker processes are spawned
    main()
