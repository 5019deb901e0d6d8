"""Rotation-modulation north finder (P3): Monte Carlo repeatability beside the bound.

Runs are simulated in chunks (each run has its own seed stream, see
:func:`inserr.northfinder.run_seed`, so chunking never changes the numbers), filtered
together (one filterpy filter, one state column per run) and solved after every
filter period, giving error histories for heading, latitude, pitch and roll.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from inserr.errors import InputError
from inserr.northfinder import (
    Instrument,
    Pose,
    SensorGrade,
    n_filter_periods,
    simulate,
)
from inserr.northfinder_bounds import Bound, crlb
from inserr.northfinder_filter import period_measurements, run_filter, solve, wrap_angle
from inserr.progress import progress
from inserr.units import MIL

#: Heading tolerance and run fraction of the convergence time (issue #7).
CONVERGENCE_TOLERANCE = 0.5 * MIL
CONVERGENCE_FRACTION = 0.68


@dataclass(frozen=True)
class MonteCarloResult:
    """Error histories of a Monte Carlo study and the bound beside them.

    Attributes
    ----------
    times : ndarray (n_periods,)
        End of each filter period, s.
    heading_error, lat_error, pitch_error, roll_error : ndarray (n_periods, n_runs)
        Estimate minus truth, rad (heading wrapped to [-pi, pi); ``lat_error`` is
        all zero when latitude is known).
    ambiguous : ndarray (n_periods, n_runs) of bool
        Whether the hemisphere could not pick the root (see
        :class:`inserr.northfinder_filter.Solution`).
    bound : Bound
        Cramér-Rao bound, white noise.
    bound_bi : Bound
        Asymptotic bound including the bias instability.
    latitude_known : bool
    """

    times: np.ndarray
    heading_error: np.ndarray
    lat_error: np.ndarray
    pitch_error: np.ndarray
    roll_error: np.ndarray
    ambiguous: np.ndarray
    bound: Bound
    bound_bi: Bound
    latitude_known: bool

    @property
    def n_runs(self) -> int:
        """Number of Monte Carlo runs."""
        return self.heading_error.shape[1]

    def heading_sigma(self) -> np.ndarray:
        """Heading repeatability (1 sigma about the mean over runs) per period, rad."""
        return _std(self.heading_error)

    def heading_bias(self) -> np.ndarray:
        """Mean heading error over runs per period, rad."""
        return self.heading_error.mean(axis=1)

    def lat_sigma(self) -> np.ndarray:
        """Latitude repeatability per period, rad (NaN when latitude is known)."""
        if self.latitude_known:
            return np.full(len(self.times), np.nan)
        return _std(self.lat_error)

    def lat_bias(self) -> np.ndarray:
        """Mean latitude error per period, rad (NaN when latitude is known)."""
        if self.latitude_known:
            return np.full(len(self.times), np.nan)
        return self.lat_error.mean(axis=1)

    def fraction_within(self, tolerance: float = CONVERGENCE_TOLERANCE) -> np.ndarray:
        """Fraction of runs whose ``|heading error| <= tolerance`` (rad) per period."""
        return np.mean(np.abs(self.heading_error) <= tolerance, axis=1)

    def convergence_time(
        self,
        tolerance: float = CONVERGENCE_TOLERANCE,
        fraction: float = CONVERGENCE_FRACTION,
    ) -> float | None:
        """Time (s) from which the heading error stays within ``tolerance`` in at least
        ``fraction`` of the runs until the end; None if that never happens."""
        ok = self.fraction_within(tolerance) >= fraction
        if not ok[-1]:
            return None
        bad = np.flatnonzero(~ok)
        first = 0 if bad.size == 0 else bad[-1] + 1
        return float(self.times[first])

    def summary(self) -> dict[str, float | int | None]:
        """Final-time figures in engineering units (mil, deg, s), for JSON and reports."""
        deg = 180.0 / math.pi
        lat_sigma = self.lat_sigma()[-1]
        lat_bias = self.lat_bias()[-1]
        return {
            "heading_error_1sigma_mil": float(self.heading_sigma()[-1] / MIL),
            "heading_bias_mil": float(self.heading_bias()[-1] / MIL),
            "latitude_error_1sigma_deg": None if self.latitude_known else float(lat_sigma * deg),
            "latitude_bias_deg": None if self.latitude_known else float(lat_bias * deg),
            "crlb_heading_mil": float(self.bound.heading[-1] / MIL),
            "crlb_heading_with_bias_instability_mil": float(self.bound_bi.heading[-1] / MIL),
            "crlb_latitude_deg": None if self.latitude_known else float(self.bound.lat[-1] * deg),
            "heading_sigma_over_crlb": float(self.heading_sigma()[-1] / self.bound.heading[-1]),
            "convergence_time_s": self.convergence_time(),
            "pitch_error_1sigma_deg": float(_std(self.pitch_error)[-1] * deg),
            "roll_error_1sigma_deg": float(_std(self.roll_error)[-1] * deg),
            "ambiguous_fraction": float(self.ambiguous[-1].mean()),
            "runs": self.n_runs,
            "duration_s": float(self.times[-1]),
        }


def _std(err: np.ndarray) -> np.ndarray:
    """Sample standard deviation over runs (axis 1); NaN for a single run."""
    if err.shape[1] < 2:
        return np.full(err.shape[0], np.nan)
    return err.std(axis=1, ddof=1)


def monte_carlo(
    pose: Pose,
    instrument: Instrument,
    grade: SensorGrade,
    duration: float,
    *,
    n_runs: int,
    seed: int = 0,
    latitude_known: bool = False,
    hemisphere: int | None = None,
    estimator: Instrument | None = None,
    model: str = "exact",
    chunk_size: int = 10,
    desc: str = "northfind",
) -> MonteCarloResult:
    """Monte Carlo study of the north finder against truth and the Cramér-Rao bound.

    Parameters
    ----------
    pose, instrument, grade
        Truth used to simulate.
    duration : float
        s.
    n_runs : int
        Monte Carlo runs (>= 1; >= 2 for a standard deviation).
    seed : int
        Master seed; run i uses :func:`inserr.northfinder.run_seed` (seed, i).
    latitude_known : bool
        Give the estimator the true latitude.
    hemisphere : +1, -1 or None
        Hemisphere told to the estimator when latitude is unknown; None = the true
        one (the only piece of position the finder needs, see the tutorial).
    estimator : Instrument, optional
        The estimator's (calibrated) idea of the instrument; default the truth.
    model : "exact" or "p3"
        Inversion model, see :func:`inserr.northfinder_filter.solve`.
    chunk_size : int
        Runs simulated and filtered together (memory ~ 32 bytes x samples x chunk).
    desc : str
        Progress-bar label.

    Returns
    -------
    MonteCarloResult
    """
    if int(n_runs) < 1:
        raise InputError("runs", f"need at least one run, got {n_runs}", "give runs >= 1")
    if int(seed) < 0:
        raise InputError("seed", f"must be >= 0, got {seed}", "give a non-negative integer")
    est = estimator if estimator is not None else instrument
    hemi = hemisphere if hemisphere is not None else (1 if pose.lat >= 0 else -1)
    n_periods = n_filter_periods(instrument, duration)
    errs = np.empty((5, n_periods, int(n_runs)))
    starts = range(0, int(n_runs), int(chunk_size))
    for start in progress(starts, total=len(starts), desc=desc):
        stop = min(start + int(chunk_size), int(n_runs))
        data = simulate(
            pose, instrument, grade, duration, n_runs=stop - start, seed=seed, first_run=start
        )
        out = run_filter(period_measurements(data, est), est, grade)
        sol = solve(
            np.moveaxis(out.x, 1, 0),
            est,
            lat=pose.lat if latitude_known else None,
            hemisphere=hemi,
            height=pose.height,
            model=model,
        )
        errs[0, :, start:stop] = wrap_angle(sol.heading - pose.heading)
        errs[1, :, start:stop] = sol.lat - pose.lat
        errs[2, :, start:stop] = sol.pitch - pose.pitch
        errs[3, :, start:stop] = sol.roll - pose.roll
        errs[4, :, start:stop] = sol.ambiguous
    bound = crlb(pose, instrument, grade, duration, latitude_known=latitude_known)
    bound_bi = crlb(
        pose, instrument, grade, duration, latitude_known=latitude_known, bias_instability=True
    )
    return MonteCarloResult(
        times=bound.times,
        heading_error=errs[0],
        lat_error=errs[1],
        pitch_error=errs[2],
        roll_error=errs[3],
        ambiguous=errs[4].astype(bool),
        bound=bound,
        bound_bi=bound_bi,
        latitude_known=latitude_known,
    )
