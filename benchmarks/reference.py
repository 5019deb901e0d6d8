"""Wall time of the linear analysis against the nonlinear reference on the same 72 h scenario.

The linear analysis is :func:`inserr.drift.study.run_scheme` (deterministic response
at the scenario's output step, per-source responses, RMS and worst case over signs,
noise covariance: everything ``inserr drift`` computes). The nonlinear reference is
:func:`inserr.reference.strapdown.simulate` with one deterministic run at the IMU rate
(100 Hz, P0's), timed on a slice of the same scenario's attitude history and
extrapolated linearly in time: its cost per sample is constant (every chunk does the
same work), and numba's one-off compilation is excluded by a warm-up run. Two
scenarios, both printed:

* ``done-when``: two-position indexing, static, latitude 34 deg, gyro bias 0.02 deg/h,
  accelerometer bias 100 ug, 72 h;
* ``p0-exp1``: P0 experiment 1 (yaw swing 6 cos(pi t / 60) deg/s, full budget),
  two-position, 72 h: the swinging base that issue 13 is about.

The last two lines are ``linear_vs_nonlinear_speedup_p0_exp1: <ratio>`` and
``linear_vs_nonlinear_speedup: <ratio>`` (static case); the target is 2000 for both.
Each linear time is the best of three; timings share the machine with whatever else
runs on it.

Usage: ``python benchmarks/reference.py [--slice-hours 1] [--rate 100]``
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

SCENARIOS = {
    "done-when": {
        "scenario": {"duration": "72 h"},
        "site": {"latitude": "34 deg"},
        "imu": {"gyro_bias": "0.02 deg/h", "accel_bias": "100 ug"},
        "scheme": {"name": "two-position"},
    },
    "p0-exp1": ROOT / "analyses" / "p0_swinging_base" / "scenario.toml",
}


def _scenario(spec):
    from inserr.scenario.schema import load_scenario, scenario_from_dict

    if isinstance(spec, Path):
        return load_scenario(spec).with_changes(
            {"scheme.name": "two-position", "compare.schemes": []}
        )
    return scenario_from_dict(spec)


def measure(name: str, spec, slice_hours: float, rate: float) -> dict:
    """Wall times (s) of the linear analysis and of the extrapolated nonlinear reference."""
    from inserr.core.units import HOUR
    from inserr.drift.study import run_scheme
    from inserr.reference.strapdown import attitude_history, deterministic_run, simulate

    scen = _scenario(spec)
    lin_times = []
    for _ in range(3):
        t0 = time.perf_counter()
        lin = run_scheme(scen)
        lin_times.append(time.perf_counter() - t0)
    t_lin = min(lin_times)
    attitude = attitude_history(lin.timeline)
    run = [deterministic_run(scen.imu, scen.init, scen.dt_out)]
    t0 = time.perf_counter()
    simulate(scen.site, attitude, slice_hours * HOUR, run, rate=rate, vertical=scen.vertical)
    t_slice = time.perf_counter() - t0
    t_nl = t_slice * scen.duration / (slice_hours * HOUR)
    return {
        "scenario": name,
        "hours": scen.duration / HOUR,
        "linear_s": t_lin,
        "nonlinear_slice_s": t_slice,
        "nonlinear_s": t_nl,
        "speedup": t_nl / t_lin,
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--slice-hours", type=float, default=1.0, help="nonlinear slice timed, h")
    p.add_argument("--rate", type=float, default=100.0, help="IMU sample rate, Hz (default 100)")
    args = p.parse_args(argv)

    import numpy as np

    from inserr.core.earth import Site
    from inserr.core.errors import InputError
    from inserr.core.imu import ImuErrors, InitialErrors
    from inserr.reference.strapdown import RunSpec, require_pyins, simulate

    try:
        require_pyins()
    except InputError as exc:
        print(f"benchmark needs the reference extra: {exc}", file=sys.stderr)
        return 2
    # Warm-up: numba compiles pyins's integrator on first use (~10 s), not part of the cost.
    simulate(
        Site(0.6),
        lambda t: np.broadcast_to(np.eye(3), (len(np.atleast_1d(t)), 3, 3)),
        10.0,
        [RunSpec(ImuErrors(), InitialErrors(), noise=False)],
        rate=10.0,
    )

    results = [measure(n, s, args.slice_hours, args.rate) for n, s in SCENARIOS.items()]
    print(f"IMU rate {args.rate:g} Hz; nonlinear timed on {args.slice_hours:g} h and extrapolated")
    print(f"{'scenario':>10} {'hours':>6} {'linear s':>9} {'nonlinear s':>12} {'speedup':>8}")
    for r in results:
        print(
            f"{r['scenario']:>10} {r['hours']:>6g} {r['linear_s']:>9.2f} {r['nonlinear_s']:>12.1f} "
            f"{r['speedup']:>8.0f}"
        )
    # The nonlinear reference costs the same per simulated hour whatever the motion; the
    # linear analysis costs somewhat more on a swinging base. Both ratios are printed.
    for r in results[1:]:
        print(f"linear_vs_nonlinear_speedup_{r['scenario'].replace('-', '_')}: {r['speedup']:.0f}")
    print(f"linear_vs_nonlinear_speedup: {results[0]['speedup']:.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
