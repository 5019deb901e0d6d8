"""Rotation-modulation north finder (P3): Monte Carlo repeatability beside the bound.

Runs are simulated in chunks (each run has its own seed stream, see
:func:`inserr.northfinder.instrument.run_seed`, so chunking never changes the numbers), filtered
(one filterpy filter per run) and solved after every filter period, giving error
histories for heading, latitude, pitch and roll. :func:`diagnose` then says where the
numbers should not be read at face value: inside the polar or equatorial band, where
the latitude is not resolved, where the declared hemisphere selects the mirror root,
and whenever the Monte Carlo sigma leaves 0.8-1.2 times the bound.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from inserr.core import earth
from inserr.core.errors import InputError
from inserr.core.units import DEG, MIL
from inserr.northfinder.bounds import Bound, crlb
from inserr.northfinder.filter import (
    hemisphere_name,
    hemisphere_sign,
    period_measurements,
    run_filter,
    solve,
    wrap_angle,
)
from inserr.northfinder.instrument import (
    Instrument,
    Pose,
    SensorGrade,
    body_vectors,
    mirror_pose,
    n_filter_periods,
    simulate,
)
from inserr.output.progress import progress

#: Heading tolerance and run fraction of the convergence time (issue #7).
CONVERGENCE_TOLERANCE = 0.5 * MIL
CONVERGENCE_FRACTION = 0.68

#: Bands of degraded observability (``docs/tutorials/northfinding.md`` section 8). Each
#: bound is inversely proportional to the Earth-rate component that carries its
#: quantity: heading to the horizontal rate ``Omega cos L`` (bound ~ sec L), latitude
#: and the choice of root to the component along the table normal ``Omega sin E``
#: (bound ~ 1 / |sin E|; E is the elevation of the Earth-rate vector above the table
#: plane, E = L on a level table). A band is where that component is below this
#: fraction of Omega, i.e. where the bound is more than ten times its best value.
OBSERVABILITY_FRACTION = 0.1
#: |latitude| beyond which heading observability has degraded: cos L < 0.1 (84.26 deg).
POLAR_BAND = math.acos(OBSERVABILITY_FRACTION)
#: |latitude| (or |E|) below which latitude observability has degraded: 5.74 deg.
EQUATORIAL_BAND = math.asin(OBSERVABILITY_FRACTION)
#: The data resolve the latitude (and so the side of the table plane the Earth-rate
#: vector lies on) when |E| is at least this many latitude bounds; below, the solver's
#: hemisphere constraint ``sign(lambda) = hemisphere`` clips a noticeable fraction of
#: runs and the estimator is biased, so the unbiased bound does not describe it.
RESOLVED_IN_BOUNDS = 3.0
#: Accepted range of Monte Carlo heading sigma / CRLB (the 20 % of issue #7).
RATIO_RANGE = (0.8, 1.2)
#: Unknown-latitude heading bound / known-latitude heading bound above which the
#: latitude-heading coupling through the table tilt is reported.
COUPLING_LIMIT = 1.1
#: Heading bound beyond which the bound's small-error (linear) approximation is poor, rad.
SMALL_ERROR_LIMIT = 0.1
#: A heading bias is reported when it exceeds this many standard errors of the mean.
BIAS_IN_STANDARD_ERRORS = 4.0


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
        :class:`inserr.northfinder.filter.Solution`).
    bound : Bound
        Cramér-Rao bound, white noise.
    bound_bi : Bound
        Asymptotic bound including the bias instability.
    latitude_known : bool
        Whether the estimator was given the latitude.
    hemisphere : int
        Hemisphere declared to the estimator, +1 north or -1 south (unused when the
        latitude is known).
    warnings : tuple of str
        Diagnostics from :func:`diagnose` (empty when nothing needs saying).
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
    hemisphere: int = 1
    warnings: tuple[str, ...] = ()

    @property
    def n_runs(self) -> int:
        """Number of Monte Carlo runs.

        Returns
        -------
        int
        """
        return self.heading_error.shape[1]

    def heading_sigma(self) -> np.ndarray:
        """Heading repeatability per filter period.

        Returns
        -------
        ndarray (n_periods,)
            Sample standard deviation of the heading error over runs, rad (NaN for a
            single run).
        """
        return _std(self.heading_error)

    def heading_bias(self) -> np.ndarray:
        """Mean heading error per filter period.

        Returns
        -------
        ndarray (n_periods,)
            Mean over runs, rad.
        """
        return self.heading_error.mean(axis=1)

    def lat_sigma(self) -> np.ndarray:
        """Latitude repeatability per filter period.

        Returns
        -------
        ndarray (n_periods,)
            Sample standard deviation over runs, rad (NaN when latitude is known).
        """
        if self.latitude_known:
            return np.full(len(self.times), np.nan)
        return _std(self.lat_error)

    def lat_bias(self) -> np.ndarray:
        """Mean latitude error per filter period.

        Returns
        -------
        ndarray (n_periods,)
            Mean over runs, rad (NaN when latitude is known).
        """
        if self.latitude_known:
            return np.full(len(self.times), np.nan)
        return self.lat_error.mean(axis=1)

    def fraction_within(self, tolerance: float = CONVERGENCE_TOLERANCE) -> np.ndarray:
        """Fraction of runs whose heading error is within a tolerance, per filter period.

        Parameters
        ----------
        tolerance : float
            rad (default 0.5 mil).

        Returns
        -------
        ndarray (n_periods,)
            Fraction of runs with ``|heading error| <= tolerance`` (0-1).
        """
        return np.mean(np.abs(self.heading_error) <= tolerance, axis=1)

    def convergence_time(
        self,
        tolerance: float = CONVERGENCE_TOLERANCE,
        fraction: float = CONVERGENCE_FRACTION,
    ) -> float | None:
        """Time from which the heading error stays within a tolerance in enough runs.

        Parameters
        ----------
        tolerance : float
            rad (default 0.5 mil).
        fraction : float
            Fraction of runs that must be within ``tolerance`` (default 0.68).

        Returns
        -------
        float or None
            s: the earliest period end from which the condition holds until the end of
            the record; None if it does not hold at the end.
        """
        ok = self.fraction_within(tolerance) >= fraction
        if not ok[-1]:
            return None
        bad = np.flatnonzero(~ok)
        first = 0 if bad.size == 0 else bad[-1] + 1
        return float(self.times[first])

    def summary(self) -> dict:
        """Final-time figures in engineering units, for JSON and reports.

        Returns
        -------
        dict
            Heading sigma and bias (mil), latitude sigma and bias (deg), the bounds
            (mil, deg), sigma / CRLB, convergence time (s), pitch/roll sigma (deg),
            the ambiguous fraction (0-1), runs, duration (s), the declared hemisphere
            (``"north"``/``"south"``) and the list of warnings (str).
        """
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
            # With the latitude given, no hemisphere is declared (none is used).
            "hemisphere_declared": None
            if self.latitude_known
            else hemisphere_name(self.hemisphere),
            "warnings": list(self.warnings),
        }


def _std(err: np.ndarray) -> np.ndarray:
    """Sample standard deviation over runs (axis 1); NaN for a single run."""
    if err.shape[1] < 2:
        return np.full(err.shape[0], np.nan)
    return err.std(axis=1, ddof=1)


def table_elevation(pose: Pose) -> float:
    """Elevation of the Earth-rate vector above the table plane.

    ``E = asin(w^b_z / Omega)``: the angle between the Earth's axis and the table
    plane, positive when the north celestial pole is above it. On a level table
    ``E = L``; a tilt of the table moves it by up to the tilt. The gyro senses only
    the Earth rate in the table plane, so ``Omega sin E`` (which carries the latitude
    and the choice between the two roots) is known only up to its sign.

    Parameters
    ----------
    pose : Pose
        Latitude, heading, pitch and roll (rad).

    Returns
    -------
    float
        rad, in [-pi/2, pi/2].
    """
    w_b, _ = body_vectors(pose.lat, pose.heading, pose.pitch, pose.roll, pose.gravity)
    return math.asin(max(-1.0, min(1.0, float(w_b[2]) / earth.OMEGA_IE)))


def diagnose(
    result: MonteCarloResult, pose: Pose, instrument: Instrument, grade: SensorGrade
) -> list[str]:
    """Warnings on a Monte Carlo result: observability bands, root choice, sigma / CRLB.

    The simulation knows the truth, so the checks may use it; the estimator never
    does. Checked at the end of the record (constants above, tutorial section 8):

    * polar band: ``|L| > POLAR_BAND`` (84.3 deg; heading bound > 10 x equatorial);
    * equatorial band (latitude unknown): ``|L|`` or ``|E|`` below ``EQUATORIAL_BAND``
      (5.7 deg; latitude bound > 10 x its best);
    * latitude not resolved (latitude unknown): ``|E| < 3`` latitude bounds;
    * latitude-heading coupling: unknown-latitude heading bound > 1.1 x known;
    * roots: the mirror root in the declared hemisphere in some runs, or the
      declaration selecting the mirror root outright;
    * heading bound > 0.1 rad (small-error approximation poor);
    * heading sigma / CRLB outside 0.8-1.2, or a bias beyond 4 standard errors, with
      the likely cause.

    Parameters
    ----------
    result : MonteCarloResult
        The study (its bounds, declared hemisphere and error histories).
    pose, instrument, grade
        The truth the study simulated (rad, rad/s, SI noise levels).

    Returns
    -------
    list of str
        One sentence per finding, each starting with a short tag; empty if none.
    """
    out: list[str] = []
    lat, elev = pose.lat, table_elevation(pose)
    crlb_h = float(result.bound.heading[-1])
    unknown = not result.latitude_known
    deg = 1.0 / DEG

    if abs(lat) > POLAR_BAND:
        out.append(
            f"polar band: |latitude| {abs(lat) * deg:.4g} deg is beyond "
            f"{POLAR_BAND * deg:.1f} deg, where the horizontal Earth rate Omega cos L that "
            f"carries heading is below {OBSERVABILITY_FRACTION:g} Omega: the heading bound "
            f"grows as sec L ({1 / math.cos(lat):.3g} x its equatorial value, here "
            f"{crlb_h / MIL:.3g} mil) and north is undefined at the pole"
        )

    sigma_lat = float(result.bound.lat[-1])
    unresolved = unknown and not abs(elev) >= RESOLVED_IN_BOUNDS * sigma_lat
    if unknown and min(abs(lat), abs(elev)) < EQUATORIAL_BAND:
        out.append(
            f"equatorial band: latitude {lat * deg:.3g} deg, Earth-rate vector "
            f"{elev * deg:.3g} deg above the table plane (band: within "
            f"{EQUATORIAL_BAND * deg:.2f} deg, where Omega sin E, which carries the latitude "
            f"and the choice of root, is below {OBSERVABILITY_FRACTION:g} Omega): the "
            f"latitude bound grows as 1/|sin E| (here {sigma_lat * deg:.3g} deg); give the "
            "latitude (northfinder.latitude_known) if it is known"
        )
    if unresolved:
        out.append(
            f"latitude not resolved: the Earth-rate vector is {elev * deg:.3g} deg from the "
            f"table plane, less than {RESOLVED_IN_BOUNDS:g} latitude bounds "
            f"({RESOLVED_IN_BOUNDS * sigma_lat * deg:.3g} deg), so the data cannot tell on "
            "which side of the plane it lies; the declared hemisphere then clips the "
            "root in many runs, the estimator is biased and the unbiased Cramér-Rao bound "
            "does not describe it. Give the latitude (northfinder.latitude_known), level the table "
            "or measure longer"
        )
    if unknown:
        known_h = float(
            crlb(pose, instrument, grade, result.times[-1], latitude_known=True).heading[-1]
        )
        if crlb_h > COUPLING_LIMIT * known_h:
            tilt = math.acos(max(-1.0, min(1.0, math.cos(pose.pitch) * math.cos(pose.roll))))
            rise = crlb_h / known_h
            rise_text = f"{rise:.3g}-fold" if rise >= 2 else f"by {100 * (rise - 1):.0f} %"
            out.append(
                f"latitude-heading coupling: not knowing the latitude raises the heading "
                f"bound {rise_text} ({crlb_h / MIL:.3g} mil "
                f"against {known_h / MIL:.3g} mil with the latitude known): near the "
                f"equator the table's {tilt * deg:.2g} deg tilt mixes the poorly known "
                "normal Earth-rate component into the heading; give the latitude or level "
                "the table"
            )

    wrong_root = False
    if unknown:
        ambiguous = float(result.ambiguous[-1].mean())
        name = hemisphere_name(result.hemisphere)
        mirror_h, mirror_l = mirror_pose(pose)
        off = f"heading {wrap_angle(mirror_h - pose.heading) / MIL:+.3g} mil, latitude " + (
            f"{mirror_l * deg:.3g} deg instead of {lat * deg:.3g} deg"
        )
        declared_ok = lat == 0.0 or math.copysign(1, lat) == result.hemisphere
        wrong_root = elev != 0.0 and math.copysign(1, elev) != result.hemisphere
        if wrong_root and not declared_ok:
            out.append(
                f"hemisphere: the estimator was told '{name}' but the simulated site is at "
                f"{lat * deg:.3g} deg; the instrument cannot tell the two hemispheres apart, "
                f"so the finder returns the mirror solution ({off})"
            )
        elif wrong_root:
            out.append(
                f"mirror root: the table is tilted toward the equator by more than "
                f"|latitude|, so the {name} celestial pole lies below the table plane and "
                f"the declared hemisphere selects the mirror solution ({off})"
            )
        elif not declared_ok:
            out.append(
                f"hemisphere: the estimator was told '{name}' but the simulated site is at "
                f"{lat * deg:.3g} deg; the table's tilt happens to put the {name} celestial "
                "pole above the table plane, so the root is still the simulated one"
            )
        elif ambiguous > 0:
            out.append(
                f"ambiguous root: in {100 * ambiguous:.0f} % of runs the mirror solution "
                "lies in the declared hemisphere too (|latitude| below about twice the "
                "table's tilt toward the equator), so the declaration cannot confirm the "
                "root; had the tilt toward the equator exceeded |latitude| the finder would "
                "have returned the mirror"
            )

    nonlinear = crlb_h > SMALL_ERROR_LIMIT
    if nonlinear:
        out.append(
            f"large errors: the heading bound {crlb_h / MIL:.3g} mil exceeds "
            f"{SMALL_ERROR_LIMIT:g} rad ({SMALL_ERROR_LIMIT / MIL:.0f} mil), beyond which "
            "the bound's small-error approximation is poor; read the Monte Carlo sigma "
            "and bias as indicative"
        )

    n = result.n_runs
    if n >= 2:
        sigma = float(result.heading_sigma()[-1])
        bias = float(result.heading_bias()[-1])
        ratio = sigma / crlb_h
        spread = 1.0 / math.sqrt(2.0 * (n - 1))  # relative 1 sigma of a sample std
        if not RATIO_RANGE[0] <= ratio <= RATIO_RANGE[1]:
            causes = _ratio_causes(
                ratio, result, instrument, unresolved=unresolved, wrong_root=wrong_root
            )
            if nonlinear:
                causes.append("the errors are too large for the small-error bound")
            if abs(ratio - 1.0) < 3.0 * spread:
                causes.append(
                    f"sampling spread: with {n} runs sigma is known to +-{100 * spread:.0f} % "
                    "(1 sigma); use more runs (scenario.runs)"
                )
            if not causes:
                causes.append("none of the modelled ones; investigate")
            out.append(
                f"sigma/CRLB: the Monte Carlo heading sigma is {ratio:.3g} x the bound, "
                f"outside {RATIO_RANGE[0]:g}-{RATIO_RANGE[1]:g}; likely cause: " + "; ".join(causes)
            )
        standard_error = sigma / math.sqrt(n)
        if abs(bias) > BIAS_IN_STANDARD_ERRORS * standard_error:
            if wrong_root:
                cause = "the mirror root (see above)"
            elif unresolved:
                cause = "the hemisphere constraint on an unresolved latitude (see above)"
            elif nonlinear:
                cause = "errors too large for a linear estimate"
            else:
                cause = "none of the modelled ones; investigate"
            out.append(
                f"heading bias: {bias / MIL:.3g} mil, {abs(bias) / standard_error:.0f} "
                f"standard errors of the mean from zero; likely cause: {cause}"
            )
    return out


def _ratio_causes(
    ratio: float,
    result: MonteCarloResult,
    instrument: Instrument,
    *,
    unresolved: bool,
    wrong_root: bool,
) -> list[str]:
    """Modelled reasons for a heading sigma / CRLB outside the accepted range."""
    causes = []
    if unresolved:
        causes.append(
            "the latitude is not resolved, and the hemisphere constraint makes the "
            "estimator biased, which the unbiased bound does not cover"
        )
    if wrong_root:
        causes.append("the estimator solved for the mirror root, not the simulated one")
    if ratio > 1.0:
        half_turn = 0.5 * instrument.table_rate * instrument.filter_period
        sinc = math.sin(half_turn) / half_turn
        if 1.0 / sinc > 1.05:
            causes.append(
                f"the filter's {instrument.filter_period:g} s period sums keep only "
                f"sinc(wT/2) = {sinc:.3f} of the signal (expect sigma/CRLB near "
                f"{1 / sinc:.3f}); shorten the filter period"
            )
        inflation = float(result.bound_bi.heading[-1] / result.bound.heading[-1])
        if inflation > 1.05:
            causes.append(
                f"bias instability, which the white-noise bound leaves out, raises the "
                f"bound by {100 * (inflation - 1):.0f} %"
            )
    return causes


def monte_carlo(
    pose: Pose,
    instrument: Instrument,
    grade: SensorGrade,
    duration: float,
    *,
    n_runs: int,
    seed: int = 0,
    latitude_known: bool = False,
    hemisphere: int | str = "north",
    estimator: Instrument | None = None,
    model: str = "exact",
    chunk_size: int = 10,
    desc: str = "northfind",
) -> MonteCarloResult:
    """Monte Carlo study of the north finder against truth and the Cramér-Rao bound.

    Parameters
    ----------
    pose, instrument, grade
        Truth used to simulate (rad; rad/s, Hz, s; SI noise levels).
    duration : float
        s.
    n_runs : int
        Monte Carlo runs (>= 1; >= 2 for a standard deviation).
    seed : int
        Master seed; run i uses :func:`inserr.northfinder.instrument.run_seed` (seed, i).
    latitude_known : bool
        Give the estimator the true latitude.
    hemisphere : "north", "south", +1 or -1
        The hemisphere the user declares to the estimator (used when the latitude is
        unknown). Default north, as ``inserr northfind``. It is never read from
        ``pose``: the instrument cannot tell the hemispheres apart (the two roots fit
        the data exactly), so a declaration that contradicts ``pose`` returns the
        mirror solution, and :func:`diagnose` says so.
    estimator : Instrument, optional
        The estimator's (calibrated) idea of the instrument; default the truth.
    model : "exact" or "p3"
        Inversion model, see :func:`inserr.northfinder.filter.solve`.
    chunk_size : int
        Runs simulated together (memory ~ 32 bytes x samples x chunk).
    desc : str
        Progress-bar label.

    Returns
    -------
    MonteCarloResult
        Errors in rad, bounds in rad, times in s, and the warnings of :func:`diagnose`.
    """
    if int(n_runs) < 1:
        raise InputError("runs", f"need at least one run, got {n_runs}", "give runs >= 1")
    if int(seed) < 0:
        raise InputError("seed", f"must be >= 0, got {seed}", "give a non-negative integer")
    est = estimator if estimator is not None else instrument
    hemi = hemisphere_sign(hemisphere)
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
    result = MonteCarloResult(
        times=bound.times,
        heading_error=errs[0],
        lat_error=errs[1],
        pitch_error=errs[2],
        roll_error=errs[3],
        ambiguous=errs[4].astype(bool),
        bound=bound,
        bound_bi=bound_bi,
        latitude_known=latitude_known,
        hemisphere=hemi,
    )
    return replace(result, warnings=tuple(diagnose(result, pose, instrument, grade)))
