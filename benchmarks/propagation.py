"""Speed of the drift engine against an honest naive 100 Hz loop, in one process.

Machines here are noisy, so every figure is a ratio against a baseline timed in the
same process, back to back, and every inserr time is the best of three warm runs.

The naive baseline is what one would write without inserr's structure: at 100 Hz,
``x <- Phi x + Gamma(t) u`` for the nine navigation errors, with ``Phi`` (the
0.01 s transition of the navigation block) computed once and the input ``Gamma(t) u``
built every sample from the true IMU attitude of the scheme and the vehicle (the same
composed schedule inserr uses): one column for the signed errors plus one per error
source, and the covariance step ``P <- Phi P Phi^T + Q`` for ARW/VRW. It is timed on a
slice of 20,000 samples and scaled to the run (its cost per sample is constant).

inserr's time is :func:`inserr.drift.study.run_scheme` (planning the scheme
included) with the outputs the report uses: deterministic response at 1 s, per-source
responses, RMS and worst case over unknown signs and noise covariance at 60 s.

Printed, in order: every catalogue scheme on the static and on P0's swinging base
(72 h; on the engine's threads and on one, ``INSERR_THREADS=1``), the cost at 6, 72 and
720 h, the peak memory of a 72 h and a 720 h swinging-base ``inserr drift`` (separate
processes), and last::

    speedup_vs_naive_100hz: <static base, two-position>
    moving_base_speedup_vs_naive_100hz: <P0 swing, flexible rule>

Run: ``python benchmarks/propagation.py`` (about a minute; ``--quick`` skips 720 h).
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import scipy.linalg as sl

ROOT = Path(__file__).resolve().parents[1]
P0 = ROOT / "analyses" / "p0_swinging_base" / "scenario.toml"
RATE_HZ = 100.0
SLICE = 20_000  # naive samples actually timed (200 s of 100 Hz data)
OUTPUTS = {"output.step": "1 s", "output.covariance_step": "60 s"}


def _scenario(static: bool, hours: float = 72.0):
    from inserr.scenario.schema import load_scenario

    changes = {**OUTPUTS, "scenario.duration": f"{hours:g} h"}
    if static:
        # The swing's own keys back at their defaults: a static base reads neither.
        changes.update({"motion.type": "static", "motion.amplitude": "0 deg/s",
                        "motion.period": "60 s"})  # fmt: skip
    return load_scenario(P0).with_changes(changes)


def best_of(fn, runs: int = 3) -> float:
    """Best wall time of ``runs`` calls of ``fn`` (after one warm-up call)."""
    fn()
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def naive_seconds(scen, scheme: str) -> float:
    """Seconds the naive 100 Hz loop would take for the whole run (timed on a slice)."""
    from inserr.model.error_sources import constant_sources
    from inserr.model.psi_model import ErrorModel

    site, imu = scen.site, scen.imu
    f = ErrorModel(site, vertical=scen.vertical).nav_matrix
    dt = 1.0 / RATE_HZ
    phi = sl.expm(f * dt)
    q = np.zeros((9, 9))
    q[0:3, 0:3] = np.eye(3) * imu.arw**2 * dt
    q[3:5, 3:5] = np.eye(2) * imu.vrw**2 * dt
    sources = constant_sources(imu, scen.init, scen.vertical)
    n = len(sources) + 1
    hist = scen.history(scheme)
    t = 1000.0 + np.arange(SLICE) * dt
    piece = np.searchsorted(hist.pieces().breaks, t, side="right") - 1
    c_all, w_all = hist.evaluate(t, piece)
    kg, ka = imu.gyro_error_matrix, imu.accel_error_matrix
    earth, f_n = site.earth_rate_n, site.specific_force_n
    x = np.zeros((9, n))
    p = np.zeros((9, 9))
    t0 = time.perf_counter()
    for c, w in zip(c_all, w_all, strict=True):
        w_is = c.T @ (earth + w)
        f_s = c.T @ f_n
        u = np.zeros((9, n))
        # Signed column, then one column per IMU error source (unit input of each).
        u[0:3, 0] = -c @ (imu.gyro_bias + kg @ w_is)
        u[3:6, 0] = c @ (imu.accel_bias + ka @ f_s)
        u[0:3, 1:4] = -c
        u[3:6, 4:7] = c
        u[0:3, 7:16] = -np.einsum("ai,j->aij", c, w_is).reshape(3, 9)
        u[3:6, 16:25] = np.einsum("ai,j->aij", c, f_s).reshape(3, 9)
        x = phi @ x + u * dt
        p = phi @ p @ phi.T + q
    return (time.perf_counter() - t0) / SLICE * scen.duration * RATE_HZ


#: Run in the child: ``inserr`` with the given arguments, then report the child's own peak
#: resident memory. VmHWM belongs to the process image, so it starts afresh at exec;
#: ``RUSAGE_CHILDREN`` would also count the benchmark's own pages copied at fork.
_CHILD = (
    "import sys\n"
    "from inserr.cli.main import main\n"
    "code = main(sys.argv[1:])\n"
    "for line in open('/proc/self/status'):\n"
    "    if line.startswith('VmHWM:'):\n"
    "        print('peak_kb', int(line.split()[1]), file=sys.stderr)\n"
    "sys.exit(code)\n"
)


def peak_memory_mb(hours: float, scheme: str) -> float:
    """Peak resident memory (MB) of ``inserr drift`` on P0's swinging base, own process."""
    args = [
        "drift", str(P0), "--duration", f"{hours:g}h", "--scheme", scheme,
        "--step", "1", "--covariance-step", "60", "--json",
    ]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.run(
        [sys.executable, "-c", _CHILD, *args], check=True, capture_output=True, env=env, text=True
    )
    for line in proc.stderr.splitlines():
        if line.startswith("peak_kb"):
            return int(line.split()[1]) / 1024.0
    # No /proc (not Linux): the children's peak, an upper bound.
    return resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0


class _one_thread:
    """The engine on one thread inside the block (``INSERR_THREADS=1``)."""

    def __enter__(self):
        self.before = os.environ.get("INSERR_THREADS")
        os.environ["INSERR_THREADS"] = "1"

    def __exit__(self, *exc):
        if self.before is None:
            os.environ.pop("INSERR_THREADS", None)
        else:
            os.environ["INSERR_THREADS"] = self.before


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip the 720 h run and its memory")
    args = ap.parse_args(argv)
    from inserr.drift.study import run_scheme
    from inserr.model.fast_propagation import engine_threads
    from inserr.schemes.catalogue import SCHEMES

    static, swing = _scenario(True), _scenario(False)
    threads = engine_threads()
    print(
        f"72 h per scheme, P0 budget, outputs 1 s / 60 s (best of 3 warm runs), on "
        f"{threads} engine thread(s) and on one (INSERR_THREADS=1):"
    )
    print(f"{'scheme':>26} {'static s':>9} {'swing s':>9} {'1 thread':>9} {'1 thread':>9}")
    for name in SCHEMES:
        if name == "custom":
            continue
        ts = best_of(lambda n=name: run_scheme(static, n))
        tw = best_of(lambda n=name: run_scheme(swing, n))
        with _one_thread():
            ts1 = best_of(lambda n=name: run_scheme(static, n))
            tw1 = best_of(lambda n=name: run_scheme(swing, n))
        print(f"{name:>26} {ts:>9.3f} {tw:>9.3f} {ts1:>9.3f} {tw1:>9.3f}")

    print("cost against the horizon (P0 swing, two-position):")
    hours = (6.0, 72.0) if args.quick else (6.0, 72.0, 720.0)
    for h in hours:
        scen = _scenario(False, h)
        th = best_of(lambda s=scen: run_scheme(s, "two-position"), runs=1 if h > 100 else 3)
        print(f"  {h:>5g} h: {th:.3f} s ({th / h * 1e3:.2f} ms per simulated hour)")

    mem_hours = (72.0,) if args.quick else (72.0, 720.0)
    for h in mem_hours:
        mb = peak_memory_mb(h, "two-position")
        print(f"peak memory, {h:g} h swinging-base inserr drift: {mb:.0f} MB")

    t_static = best_of(lambda: run_scheme(static, "two-position"))
    n_static = naive_seconds(static, "two-position")
    t_moving = best_of(lambda: run_scheme(swing, "flexible-two-position"))
    n_moving = naive_seconds(swing, "flexible-two-position")
    print(
        f"static two-position 72 h: inserr {t_static:.3f} s, naive 100 Hz loop {n_static:.0f} s "
        f"(scaled from {SLICE} samples)"
    )
    print(
        f"P0 swing, flexible rule 72 h: inserr {t_moving:.3f} s, naive 100 Hz loop "
        f"{n_moving:.0f} s (scaled from {SLICE} samples)"
    )
    print(f"speedup_vs_naive_100hz: {n_static / t_static:.0f}")
    print(f"moving_base_speedup_vs_naive_100hz: {n_moving / t_moving:.0f}")


if __name__ == "__main__":
    main()
