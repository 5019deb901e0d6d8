"""Speed of the propagation engine against a naive per-sample 100 Hz loop, same process.

Two cases, each printed as a ratio (machines here are noisy, so both sides run in
this process, back to back):

1. The 72 h ``none`` scenario (15 states: psi, dv, dr, gyro and accel biases):
   deterministic response at 1 s output plus ARW/VRW covariance at 60 s, against
   filterpy ``KalmanFilter.predict()`` (x and P) at 100 Hz, timed on a slice and
   extrapolated to 72 h.
2. The 72 h closed-loop P0 case (flexible two-position rule on a yawing, tilted
   vehicle, full budget with scale factors and misalignments, 33 states): plan,
   timeline and analysis, against a 100 Hz loop that rebuilds the time-varying
   system matrix from the true attitude every sample and steps x and P with it.

Run: ``python benchmarks/propagation.py``. The last line is
``speedup_vs_naive_100hz: <ratio>`` (case 1; target >= 100).
"""

from __future__ import annotations

import time

import numpy as np
from filterpy.kalman import KalmanFilter

from inserr.core.earth import Site
from inserr.core.imu import ImuErrors, InitialErrors
from inserr.core.units import (
    ARCSEC,
    DEG,
    DEG_PER_HOUR,
    DEG_PER_SQRT_HOUR,
    MICRO_G,
    MICRO_G_PER_SQRT_HZ,
    PPM,
)
from inserr.drift.analysis import analyze_drift
from inserr.model.discretization import Discretizer
from inserr.model.psi_model import ErrorModel, Layout
from inserr.model.timeline import Timeline
from inserr.schemes.catalogue import build_scheme
from inserr.schemes.composition import build_timeline
from inserr.schemes.vehicle_motion import YawSwing

HOURS = 72.0
RATE_HZ = 100.0
SLICE = 20_000  # naive samples actually timed (200 s of 100 Hz data)


def naive_static(site: Site, imu: ImuErrors) -> float:
    """Seconds per 72 h for filterpy predict() at 100 Hz on the 15-state model."""
    model = ErrorModel(site, Layout())
    disc = Discretizer(model, model.noise_intensity(imu.arw, imu.vrw))
    dt = 1.0 / RATE_HZ
    kf = KalmanFilter(dim_x=model.layout.n, dim_z=1)
    kf.F = disc.transition(np.zeros(3), dt)
    kf.Q = disc.noise(np.zeros(3), dt)
    kf.x = np.zeros((model.layout.n, 1))
    kf.x[model.layout["eps"], 0] = imu.gyro_bias
    kf.P = np.zeros((model.layout.n,) * 2)
    t0 = time.perf_counter()
    for _ in range(SLICE):
        kf.predict()
    return (time.perf_counter() - t0) / SLICE * HOURS * 3600 * RATE_HZ


def naive_time_varying(site: Site, imu: ImuErrors, timeline: Timeline) -> float:
    """Seconds per 72 h for a 100 Hz loop rebuilding A(C_s^n(t)) every sample."""
    model = ErrorModel(site, Layout(scale_misalignment=True))
    lay = model.layout
    q = model.noise_input() @ model.noise_intensity(imu.arw, imu.vrw) @ model.noise_input().T
    dt = 1.0 / RATE_HZ
    x = np.zeros(lay.n)
    p = np.zeros((lay.n, lay.n))
    t = np.arange(SLICE) * dt + 1000.0
    c_all = timeline.attitude_at(t)
    w_all = timeline.omega_n[timeline.interval_index(t)]
    t0 = time.perf_counter()
    for c, w in zip(c_all, w_all, strict=True):
        # Naive: IMU-frame biases with input matrix C_s^n(t), Euler transition I + A dt.
        a = model.matrix(w)
        tr = model.imu_transform(c)
        a = np.linalg.solve(tr, a) @ tr  # back to IMU-frame parameters each sample
        phi = np.eye(lay.n) + a * dt
        x = phi @ x
        p = phi @ p @ phi.T + q * dt
    return (time.perf_counter() - t0) / SLICE * HOURS * 3600 * RATE_HZ


def main() -> None:
    site = Site.from_degrees(34.0)
    imu = ImuErrors(
        gyro_bias=np.full(3, 0.02 * DEG_PER_HOUR),
        accel_bias=np.full(3, 100 * MICRO_G),
        arw=0.001 * DEG_PER_SQRT_HOUR,
        vrw=10 * MICRO_G_PER_SQRT_HZ,
    )
    # Warm-up (imports, python-control's first call).
    analyze_drift(site, imu, InitialErrors(), Timeline.static(np.eye(3), 3600.0))
    t0 = time.perf_counter()
    analyze_drift(
        site,
        imu,
        InitialErrors(),
        Timeline.static(np.eye(3), HOURS * 3600),
        dt_out=1.0,
        dt_cov=60.0,
    )
    ours = time.perf_counter() - t0
    naive = naive_static(site, imu)
    print(
        f"case 1, 72 h none scenario: inserr {ours:.2f} s, "
        f"naive 100 Hz filterpy predict() {naive:.0f} s "
        f"(extrapolated from {SLICE} samples)"
    )

    p0_site = Site.from_degrees(34.246, height=380.0)
    p0_imu = ImuErrors(
        gyro_bias=np.full(3, 0.003 * DEG_PER_HOUR),
        accel_bias=np.full(3, 30 * MICRO_G),
        gyro_scale_factor=np.full(3, 10 * PPM),
        accel_scale_factor=np.full(3, 10 * PPM),
        gyro_misalignment=np.full(6, 10 * ARCSEC),
        accel_misalignment=np.full(6, 10 * ARCSEC),
        arw=0.0005 * DEG_PER_SQRT_HOUR,
        vrw=5 * MICRO_G_PER_SQRT_HZ,
    )
    motion = YawSwing(
        heading=15 * DEG, pitch=1 * DEG, roll=-2 * DEG, amplitude=6 * DEG, period=120.0
    )
    t0 = time.perf_counter()
    table = build_scheme("flexible-two-position", 6 * DEG, 300.0).plan(motion, HOURS * 3600)
    tl = build_timeline(table, motion, HOURS * 3600)
    analyze_drift(p0_site, p0_imu, InitialErrors(), tl)
    closed = time.perf_counter() - t0
    naive_tv = naive_time_varying(p0_site, p0_imu, tl)
    print(
        f"case 2, 72 h flexible rule on a swinging base: inserr {closed:.2f} s "
        "(plan + timeline + analysis), "
        f"naive 100 Hz loop {naive_tv:.0f} s (extrapolated)"
    )
    print(f"closed_loop_speedup_vs_naive_100hz: {naive_tv / closed:.0f}")
    print(f"speedup_vs_naive_100hz: {naive / ours:.0f}")


if __name__ == "__main__":
    main()
