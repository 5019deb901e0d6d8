"""Scenario files (TOML with explicit units) and the one validation path for all inputs.

A scenario is a nested table of sections. The drift engine reads ``scenario``,
``site``, ``imu``, ``initial``, ``motion``, ``scheme``, ``output`` and ``compare``;
the studies built on the same inputs read those too and have one section each for
what is theirs alone (``alignment``, ``observability``, ``calibration``,
``northfinder``, ``validate``, ``sweep``, ``design``). Physical values are strings carrying
their unit (``gyro_bias = "0.02 deg/h"``, ``"0.01,0.02,0.03 deg/h"`` for the three
IMU axes). CLI flags are translated into the same nested table
(:mod:`inserr.scenario.flags`) and go through :func:`scenario_from_dict` too, so a
flag and a scenario key are validated by the same code.

A key that is absent takes its default: the study's own (:data:`STUDY_DEFAULTS`,
e.g. 60 s stops and a 10-minute run for an alignment) where the study has one,
else the schema's (:data:`SCHEMA`). An analysis script keeps its own settings (sweep
grids) in ``[analysis.NAME]`` tables, which it declares and which are validated by
the same code (:func:`load_scenario`). Reference: ``docs/scenarios.md``.
"""

from __future__ import annotations

import copy
import math
import os
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import Any, NamedTuple

import numpy as np

from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.core.imu import ImuErrors, InitialErrors
from inserr.core.units import DAY, DEG, DEG_PER_HOUR, DEG_PER_SQRT_HOUR, MICRO_G, parse_quantity
from inserr.schemes.nulling import PHASES
from inserr.schemes.open_loop import SCHEME_STARTS
from inserr.schemes.vehicle_motion import (
    HEADING_CONVENTIONS,
    HeadingHistory,
    Motion,
    Turn,
    YawSwing,
    heading_sign,
)

#: Largest number of samples (or sub-step segments) one run keeps in memory.
MAX_SAMPLES = 3_000_000


class Key(NamedTuple):
    """One scenario key.

    Attributes
    ----------
    kind : str
        A physical kind of :data:`inserr.core.units.UNITS` (the value is a string with
        its unit), or ``"str"``, ``"bool"``, ``"int"``, ``"float"``, ``"list"`` (of
        names), ``"int-list"``, ``"float-list"``, ``"table-list"`` (array of tables).
    size : int, "list" or None
        For physical kinds: None = one value, 3 = IMU axes (one value means all
        three), 6 = misalignments, ``"list"`` = any number of values.
    default : Any
        The value when the key is absent (as a file would hold it), unless the study
        has its own (:data:`STUDY_DEFAULTS`). None = not set.
    doc : str
        One line for the reference (``docs/scenarios.md``).
    """

    kind: str
    size: int | str | None
    default: Any
    doc: str = ""


_K = Key

#: Schema: section -> key -> :class:`Key`.
SCHEMA: dict[str, dict[str, Key]] = {
    "scenario": {
        "name": _K("str", None, "scenario", "title of reports; names the default sweep directory"),
        "duration": _K("time", None, "72 h", "length of the run (of each run for studies)"),
        "seed": _K("int", None, 0, "seed of every random draw (>= 0)"),
        "runs": _K("int", None, 1, "Monte Carlo runs (validate: 1 = no Monte Carlo)"),
    },
    "site": {
        "latitude": _K("angle", None, "34 deg", "geodetic latitude, |latitude| < 90 deg"),
        "longitude": _K("angle", None, "0 deg", "longitude"),
        "height": _K("length", None, "0 m", "height above the WGS84 ellipsoid"),
        "earth": _K("str", None, "ellipsoid", "Earth shape"),
    },
    "imu": {
        "gyro_bias": _K("angular_rate", 3, "0 deg/h", "gyro bias, IMU x, y, z"),
        "accel_bias": _K("acceleration", 3, "0 ug", "accelerometer bias"),
        "gyro_scale_factor": _K("ratio", 3, "0 ppm", "gyro scale-factor error"),
        "accel_scale_factor": _K("ratio", 3, "0 ppm", "accelerometer scale-factor error"),
        "gyro_misalignment": _K("angle", 6, "0 arcsec", "gyro misalignment xy,xz,yx,yz,zx,zy"),
        "accel_misalignment": _K("angle", 6, "0 arcsec", "accelerometer misalignment"),
        "arw": _K("arw", None, "0 deg/sqrt(h)", "gyro angle random walk"),
        "vrw": _K("vrw", None, "0 ug/sqrt(Hz)", "accelerometer velocity random walk"),
        "gyro_bias_instability": _K(
            "angular_rate", None, "0 deg/h", "first-order Gauss-Markov gyro bias, 1 sigma"
        ),
        "accel_bias_instability": _K(
            "acceleration", None, "0 ug", "first-order Gauss-Markov accelerometer bias, 1 sigma"
        ),
        "gyro_correlation_time": _K("time", None, "1 h", "correlation time of the gyro one"),
        "accel_correlation_time": _K("time", None, "1 h", "correlation time of the accel one"),
        "sample_rate": _K("frequency", None, "100 Hz", "sample rate of simulated IMU data"),
    },
    "initial": {
        "attitude": _K("angle", 3, "0 arcsec", "attitude error phi_E, phi_N (tilts), phi_U"),
        "velocity": _K("velocity", 3, "0 m/s", "velocity error E, N, U"),
        "position": _K("length", 3, "0 m", "position error E, N, U"),
    },
    "motion": {
        "type": _K("str", None, "static", "static | yaw-swing | turn | heading-history"),
        "heading_convention": _K(
            "str",
            None,
            "clockwise-from-north",
            "sense of heading, heading rates, heading history and mounting heading",
        ),
        "heading": _K("angle", None, "0 deg", "vehicle heading from north (heading_convention)"),
        "pitch": _K("angle", None, "0 deg", "vehicle pitch"),
        "roll": _K("angle", None, "0 deg", "vehicle roll"),
        "amplitude": _K("angular_rate", None, "0 deg/s", "yaw-swing: peak heading rate"),
        "period": _K("time", None, "60 s", "yaw-swing: period"),
        "rate": _K("angular_rate", None, "0 deg/s", "turn: constant heading rate"),
        "file": _K("str", None, "", "heading-history: CSV file time_s, heading_deg"),
    },
    "scheme": {
        "name": _K("str", None, "none", "indexing scheme"),
        "rate": _K("angular_rate", None, "6 deg/s", "table rate"),
        "stop": _K("time", None, "300 s", "stop (dwell) time at each position"),
        "start": _K("str", None, "stop", "opening phase: stop (at the first position) | turn"),
        "reversal": _K("time", None, "0 s", "continuous: reversal period (0 = never)"),
        "delta": _K("float", None, 0.01, "flexible-two-position: stop threshold"),
        "variant": _K("str", None, "threshold", "flexible-two-position: threshold | crossing"),
        "decision_rate": _K("frequency", None, "100 Hz", "closed-loop schemes: decision rate"),
        "mounting": _K("angle", 3, "0 deg", "IMU on the inner gimbal: heading, pitch, roll"),
        "steps": _K("table-list", None, [], "custom: [[scheme.steps]] rotation table"),
        "extension": _K(
            "time", None, None, "nulling-two-position: longest lengthening of a stop (absent: stop)"
        ),
        "phase": _K(
            "str", None, "golden", "nulling-two-position: golden | synchronous (turns on maxima)"
        ),
    },
    "output": {
        "step": _K("time", None, "1 s", "output step of the deterministic run"),
        "covariance_step": _K("time", None, "60 s", "output step of covariance results"),
        "export_step": _K(
            "time", None, "60 s", "row step of timeseries.csv and to_dataframe (x output.step)"
        ),
        "substep": _K("time", None, "1 s", "sub-step of continuous motion (exact engine)"),
        "vertical": _K("str", None, "clamped", "vertical channel"),
        "engine": _K("str", None, "fast", "drift engine: fast | exact (step by step)"),
    },
    "compare": {
        "schemes": _K("list", None, [], "schemes to run side by side"),
    },
    "alignment": {
        "zupt_rate": _K("frequency", None, "1 Hz", "zero-velocity update rate"),
        "zupt_sigma": _K("velocity", None, "0.001 m/s", "zero-velocity measurement 1 sigma"),
        "position_sigma": _K(
            "length", None, None, "position updates with this 1 sigma (absent: none)"
        ),
    },
    "observability": {
        "headings": _K(
            "angle", "list", [], "one stop of scheme.stop per heading (instead of a scheme)"
        ),
        "model": _K("str", None, "auto", "auto (alignment10 with headings, else full)"),
        "position_updates": _K("bool", None, False, "full model: position measurements too"),
    },
    "calibration": {
        "method": _K(
            "str", None, "offaxis-four-position", "built-in position set or a .toml set file"
        ),
        "settle": _K("time", None, "0 s", "settling time after every move"),
        "positioning_error": _K(
            "angle", None, "3 arcsec", "half-width of the uniform positioning error at a stop"
        ),
        "positioning_model": _K("str", None, "three-axis", "what the positioning error turns"),
        "per_sample": _K("bool", None, False, "simulate every sample (default: dwell averages)"),
        "design": _K("bool", None, False, "rank candidate position sets instead"),
        "design_sizes": _K("int-list", None, [4, 5, 6], "design: numbers of positions to try"),
        "design_sensors": _K("str", None, "gyro", "design: what must be identifiable"),
        "design_step": _K("angle", None, "90 deg", "design: gimbal step"),
        "top": _K("int", None, 10, "design: candidate sets shown"),
    },
    "northfinder": {
        "filter_period": _K("time", None, "1 s", "Kalman filter period"),
        "gyro_tilt": _K("angle", None, "0 deg", "gyro tilt toward the rotation axis"),
        "accel_azimuth": _K("angle", None, "0 deg", "accelerometer azimuth from the gyro axis"),
        "accel_tilt": _K("angle", None, "0 deg", "accelerometer tilt toward the rotation axis"),
        "latitude_known": _K("bool", None, False, "give the estimator the true latitude"),
        "hemisphere": _K("str", None, "north", "hemisphere declared to the estimator"),
    },
    "validate": {
        "chunk": _K("time", None, "1 h", "chunk length of the nonlinear reference"),
        "confidence": _K("float", None, 0.99, "confidence of the chi-square consistency test"),
        "random_constants": _K(
            "bool", None, False, "the Monte Carlo also draws the constant errors"
        ),
    },
    "sweep": {
        "parameters": _K("list", None, [], "swept parameters, each NAME=V1,V2,..."),
    },
    "design": {
        "family": _K("str", None, "single-axis", "schedules searched"),
        "stops": _K("int", None, 8, "single-axis, dual-axis: stops per cycle"),
        "angle_step": _K("angle", None, "90 deg", "single-axis: table positions are multiples"),
        "stop_range": _K(
            "time", "list", None, "shortest, longest stop (absent: scheme.stop, 2 scheme.stop)"
        ),
        "rate_range": _K("angular_rate", "list", None, "table rates tried (absent: scheme.rate)"),
        "extension_range": _K(
            "time", "list", None, "nulling: lengthening allowed (absent: 0 s, 2 scheme.stop)"
        ),
        "delta_range": _K("float-list", None, [0.001, 0.1], "flexible: stop threshold tried"),
        "stretch_range": _K(
            "float-list", None, [1.2, 2.0], "single-axis-golden: cycle B's stops / cycle A's"
        ),
        "motions": _K("str", None, "grid", "the motion set designed for"),
        "periods": _K(
            "time", "list", "20,30,45,60,90,120,165,240,330,480,660,1200 s", "grid: swing periods"
        ),
        "amplitudes": _K("angular_rate", "list", "1,3,6 deg/s", "grid: peak yaw rates"),
        "headings": _K("angle", "list", [], "grid: vehicle headings (absent: motion.heading)"),
        "draws": _K("int", None, 36, "random, grid+draws: motions drawn (training stream)"),
        "period_range": _K("time", "list", "20,1200 s", "random, held-out: swing period"),
        "amplitude_range": _K(
            "angular_rate", "list", "1,6 deg/s", "random, held-out: peak yaw rate"
        ),
        "heading_range": _K(
            "angle", "list", [], "random, held-out: vehicle heading (absent: motion.heading)"
        ),
        "pitch_range": _K(
            "angle", "list", [], "random, held-out: vehicle pitch (absent: motion.pitch)"
        ),
        "roll_range": _K(
            "angle", "list", [], "random, held-out: vehicle roll (absent: motion.roll)"
        ),
        "files": _K("list", None, [], "files: heading-history CSV files (time_s, heading_deg)"),
        "held_out": _K("int", None, 0, "random motions drawn for the robustness check"),
        "exclude": _K("list", None, ["gyro_bias_z"], "error sources left out of the objective"),
        "max_starts": _K(
            "float", None, None, "motor starts per hour (absent: the two-position cycle's)"
        ),
        "max_turning": _K("float", None, 0.25, "largest fraction of the time spent turning"),
        "table_range": _K("angle", None, "360 deg", "largest |gimbal angle| (no slip ring)"),
        "budget": _K("int", None, 600, "feasible candidates the optimizer evaluates"),
        "population": _K("int", None, 30, "optimizer population"),
        "screen_duration": _K(
            "time", None, None, "horizon of the search (absent: scenario.duration)"
        ),
        "screen_step": _K("time", None, "600 s", "output step of the search's RMS"),
        "verify": _K("int", None, 8, "candidates re-evaluated at the full horizon"),
    },
}

#: Physical range of each quantity key: dotted key -> (low, high, unit shown, why), in
#: SI; every component must lie in [low, high]. Values outside are not errors an
#: instrument could have, or lie where the model or the memory of one run cannot
#: follow; ``docs/scenarios.md`` lists them. (Latitude: strictly inside +-90 deg,
#: checked by :class:`~inserr.core.earth.Site`.)
RANGES: dict[str, tuple[float, float, str, str]] = {
    "scenario.duration": (1.0, 366 * DAY, "s", "1 s to one year"),
    "site.longitude": (-360 * DEG, 360 * DEG, "deg", "one turn either way"),
    "site.height": (-11_000.0, 100_000.0, "m", "ocean floor to the edge of space"),
    "imu.gyro_bias": (-1e4 * DEG_PER_HOUR, 1e4 * DEG_PER_HOUR, "deg/h", "MEMS grade and better"),
    "imu.accel_bias": (-1e5 * MICRO_G, 1e5 * MICRO_G, "ug", "0.1 g at most"),
    "imu.gyro_scale_factor": (-0.1, 0.1, "ppm", "10 % at most"),
    "imu.accel_scale_factor": (-0.1, 0.1, "ppm", "10 % at most"),
    "imu.gyro_misalignment": (-10 * DEG, 10 * DEG, "arcsec", "10 deg at most"),
    "imu.accel_misalignment": (-10 * DEG, 10 * DEG, "arcsec", "10 deg at most"),
    "imu.arw": (0.0, 100 * DEG_PER_SQRT_HOUR, "deg/sqrt(h)", "non-negative, MEMS grade"),
    "imu.vrw": (0.0, 1e5 * MICRO_G, "ug/sqrt(Hz)", "non-negative, MEMS grade"),
    "imu.gyro_bias_instability": (0.0, 1e4 * DEG_PER_HOUR, "deg/h", "non-negative"),
    "imu.accel_bias_instability": (0.0, 1e5 * MICRO_G, "ug", "non-negative"),
    "imu.gyro_correlation_time": (1e-3, 1e9, "s", "positive"),
    "imu.accel_correlation_time": (1e-3, 1e9, "s", "positive"),
    "imu.sample_rate": (1e-3, 1e5, "Hz", "positive, at most 100 kHz"),
    "initial.attitude": (-10 * DEG, 10 * DEG, "arcsec", "small angles: 10 deg at most"),
    "initial.velocity": (-1000.0, 1000.0, "m/s", "1 km/s at most"),
    "initial.position": (-1e6, 1e6, "m", "1000 km at most"),
    "motion.heading": (-360 * DEG, 360 * DEG, "deg", "one turn either way"),
    "motion.pitch": (-90 * DEG, 90 * DEG, "deg", "+-90 deg"),
    "motion.roll": (-180 * DEG, 180 * DEG, "deg", "+-180 deg"),
    "motion.amplitude": (-100 * DEG, 100 * DEG, "deg/s", "100 deg/s at most"),
    "motion.period": (1.0, 366 * DAY, "s", "1 s to one year"),
    "motion.rate": (-100 * DEG, 100 * DEG, "deg/s", "100 deg/s at most"),
    "scheme.rate": (-1000 * DEG, 1000 * DEG, "deg/s", "1000 deg/s at most"),
    "scheme.stop": (0.0, 366 * DAY, "s", "non-negative, one year at most"),
    "scheme.reversal": (0.0, 366 * DAY, "s", "non-negative, one year at most"),
    "scheme.decision_rate": (1e-3, 1e5, "Hz", "positive, at most 100 kHz"),
    "scheme.mounting": (-360 * DEG, 360 * DEG, "deg", "one turn either way"),
    "output.step": (1e-3, DAY, "s", "1 ms to 1 day"),
    "output.covariance_step": (1e-3, DAY, "s", "1 ms to 1 day"),
    "output.substep": (1e-3, DAY, "s", "1 ms to 1 day"),
    "alignment.zupt_rate": (1e-3, 1e5, "Hz", "positive"),
    "alignment.zupt_sigma": (1e-9, 1e3, "m/s", "positive"),
    "alignment.position_sigma": (1e-6, 1e7, "m", "positive"),
    "calibration.settle": (0.0, DAY, "s", "non-negative, one day at most"),
    "calibration.positioning_error": (0.0, 10 * DEG, "arcsec", "non-negative, 10 deg at most"),
    "northfinder.filter_period": (1e-3, DAY, "s", "positive, one day at most"),
    "validate.chunk": (1.0, 366 * DAY, "s", "1 s to one year"),
}

#: Number keys' ranges, as :data:`RANGES` (no unit).
NUMBER_RANGES: dict[str, tuple[float, float, str]] = {
    "scenario.seed": (0, 2**63 - 1, "0 to 2**63 - 1"),
    "scenario.runs": (1, 1_000_000, "1 to 1e6"),
    "scheme.delta": (1e-9, 1.0, "a fraction in (0, 1]"),
    "validate.confidence": (1e-6, 1 - 1e-6, "a probability in (0, 1)"),
    "calibration.top": (1, 10_000, "1 to 1e4"),
}


def _check_range(fld: str, value: Any) -> Any:
    """``value`` if every component lies in the key's documented range, else InputError."""
    if fld in NUMBER_RANGES:
        lo, hi, text = NUMBER_RANGES[fld]
        if not lo <= value <= hi:
            raise InputError(fld, f"{value!r} is out of range ({text})", f"give {text}")
        return value
    rng = RANGES.get(fld)
    if rng is None or value is None:
        return value
    lo, hi, unit, why = rng
    arr = np.atleast_1d(np.asarray(value, dtype=float))
    bad = arr[(arr < lo) | (arr > hi) | ~np.isfinite(arr)]
    if bad.size:
        from inserr.core.units import UNITS

        scale = UNITS_SCALE.get(unit) or next(u[unit] for u in UNITS.values() if unit in u)
        raise InputError(
            fld,
            f"{bad[0] / scale:.6g} {unit} is out of range ({why})",
            f"give a value from {lo / scale:.6g} to {hi / scale:.6g} {unit}",
        )
    return value


#: Display scales of :data:`RANGES` units that several kinds share.
UNITS_SCALE: dict[str, float] = {"s": 1.0, "m": 1.0, "Hz": 1.0, "m/s": 1.0, "ppm": 1e-6}

#: Keys whose value is one of a few words.
CHOICES: dict[str, tuple[str, ...]] = {
    "site.earth": ("ellipsoid", "spherical"),
    "output.vertical": ("clamped", "free"),
    "output.engine": ("fast", "exact"),
    "scheme.variant": ("threshold", "crossing"),
    "scheme.phase": PHASES,
    "design.family": ("single-axis", "single-axis-golden", "nulling", "flexible", "dual-axis"),
    "design.motions": ("grid", "grid+draws", "random", "scenario", "files"),
    "scheme.start": SCHEME_STARTS,
    "motion.heading_convention": HEADING_CONVENTIONS,
    "observability.model": ("auto", "alignment10", "full"),
    "calibration.positioning_model": ("three-axis", "gimbal"),
    "calibration.design_sensors": ("gyro", "gyro+accel"),
    "northfinder.hemisphere": ("north", "south"),
}

#: Defaults that differ from :data:`SCHEMA`'s on purpose, per study (dotted key -> value
#: as a file would hold it). ``drift`` (also compare, run, validate, sweep, cycle and
#: modes) uses the schema's. Documented with the reasons in ``docs/scenarios.md``.
STUDY_DEFAULTS: dict[str, dict[str, Any]] = {
    "drift": {},
    # Fine alignment after a coarse one: a P0-grade IMU whose biases are the filter's
    # prior 1 sigma (and the true values of the simulated run), a coarse-alignment
    # attitude prior, 60 s stops (several positions in 10 minutes) and a free vertical
    # channel (zero-velocity updates measure vertical velocity too).
    "alignment": {
        "scenario.duration": "10 min",
        "scheme.stop": "60 s",
        "output.vertical": "free",
        "imu.gyro_bias": "0.003 deg/h",
        "imu.accel_bias": "30 ug",
        "initial.attitude": "60, 60, 3600 arcsec",
        "initial.velocity": "0.01 m/s",
        "initial.position": "10 m",
    },
    # P1's set-up: its true gyro errors (the accelerometer's mirror them), a
    # navigation-grade noise, 100 runs and seed 1.
    "calibration": {
        "scenario.runs": 100,
        "scenario.seed": 1,
        "imu.gyro_bias": "2.04173693, 3.01844241, 2.09545751 deg/h",
        "imu.gyro_scale_factor": "100 ppm",
        "imu.gyro_misalignment": "2.145e-5 rad",
        "imu.accel_bias": "50, 80, 100 ug",
        "imu.accel_scale_factor": "100 ppm",
        "imu.accel_misalignment": "2.145e-5 rad",
        "imu.arw": "0.0005 deg/sqrt(h)",
        "imu.vrw": "5 ug/sqrt(Hz)",
    },
    # Issue 7's grade of the single gyro and accelerometer, 3-minute runs, 50 runs.
    "northfinder": {
        "scenario.duration": "3 min",
        "scenario.runs": 50,
        "imu.gyro_bias": "0.05 deg/h",
        "imu.accel_bias": "100 ug",
        "imu.arw": "0.001 deg/sqrt(h)",
        "imu.vrw": "10 ug/sqrt(Hz)",
        "imu.gyro_bias_instability": "0.005 deg/h",
        "imu.gyro_correlation_time": "300 s",
        "imu.accel_correlation_time": "300 s",
    },
}

#: The sections every scenario parses at once (what the drift engine reads).
_CORE_SECTIONS = frozenset(
    {"scenario", "site", "imu", "initial", "motion", "scheme", "output", "compare"}
)
#: Studies that build ``scheme.name`` (and ``compare.schemes``) as an indexing scheme;
#: the north finder's table turns continuously at ``scheme.rate`` (either sign).
_SCHEME_STUDIES = frozenset({"drift", "alignment", "calibration"})
#: Studies whose vehicle motion runs over ``scenario.duration``.
_MOTION_STUDIES = frozenset({"drift", "alignment"})

#: The section of an analysis script's own tables, ``[analysis.NAME]``: kept unread by
#: the studies, validated by the script's declaration (``analysis=`` of :func:`load_scenario`).
ANALYSIS = "analysis"

MOTION_TYPES = ("static", "yaw-swing", "turn", "heading-history")
STEP_KEYS = {
    "gimbal": "str",
    "angle": "angle",
    "dwell": "time",
    "rotation_time": "time",
    "label": "str",
}


def study_default(key: str, study: str = "drift") -> Any:
    """The default of a dotted key for a study (the study's own, else the schema's).

    Parameters
    ----------
    key : str
        Dotted scenario key, e.g. ``"scheme.stop"``.
    study : str
        A key of :data:`STUDY_DEFAULTS`.

    Returns
    -------
    Any
        The default as a scenario file would hold it (``"60 s"``, ``100``, ``False``).
    """
    section, _, name = key.partition(".")
    return STUDY_DEFAULTS[study].get(key, SCHEMA[section][name].default)


@dataclass(frozen=True)
class Scenario:
    """A validated scenario (SI units inside).

    Use :meth:`timeline` to get the IMU attitude history of its scheme (or of any
    scheme name, for comparisons), and :meth:`value` for any key in SI (the study
    sections included).
    """

    name: str
    duration: float
    seed: int
    site: Site
    imu: ImuErrors
    init: InitialErrors
    motion: Motion
    scheme_name: str
    scheme_rate: float
    scheme_stop: float
    scheme_options: dict
    dt_out: float
    dt_cov: float
    substep: float
    vertical: str
    compare: tuple[str, ...]
    engine: str
    raw: dict = field(compare=False, repr=False)
    base_dir: Path | None = field(default=None, compare=False, repr=False)
    study: str = "drift"
    values: Mapping[str, Any] = field(default_factory=dict, compare=False, repr=False)
    analysis: Mapping[str, Mapping[str, Key]] | None = field(
        default=None, compare=False, repr=False
    )

    def value(self, key: str) -> Any:
        """The validated value of a dotted key, SI (e.g. ``value("alignment.zupt_rate")``).

        Raises
        ------
        KeyError
            For a key that is neither in :data:`SCHEMA` nor a declared analysis key.
        """
        if key in self.values:
            return self.values[key]
        section, _, name = key.partition(".")
        if section not in _CORE_SECTIONS and name in SCHEMA.get(section, {}):
            # A study key left at its default: parsed on demand (defaults are valid).
            return _value(SCHEMA[section][name], key, study_default(key, self.study))
        raise KeyError(key)

    @property
    def heading_convention(self) -> str:
        """The declared sense of headings and heading rates (``motion.heading_convention``).

        The motion, the mounting and the observability headings are already turned
        into inserr's clockwise sense; this is for writing them back as declared
        (:meth:`~inserr.schemes.vehicle_motion.Motion.describe`) and for reports.
        """
        return self.value("motion.heading_convention")

    def given(self, key: str) -> bool:
        """Whether the dotted key was written (in the file or by a flag), not defaulted."""
        section, _, name = key.partition(".")
        return name in self.raw.get(section, {})

    def scheme(self, name: str | None = None):
        """The scheme object (``name`` overrides the scenario's scheme)."""
        from inserr.schemes.catalogue import build_scheme

        name = name or self.scheme_name
        opts = dict(self.scheme_options)
        if name != self.scheme_name:
            # Compared schemes share the table's mounting and opening phase only.
            opts = {k: v for k, v in opts.items() if k in ("mounting", "start")}
        return build_scheme(name, self.scheme_rate, self.scheme_stop, **_options_for(name, opts))

    def timeline(self, name: str | None = None):
        """The :class:`~inserr.model.timeline.Timeline` of the scenario's (or ``name``'s) scheme."""
        from inserr.schemes.composition import build_timeline

        table = self.scheme(name).plan(self.motion, self.duration)
        return build_timeline(table, self.motion, self.duration, self.substep)

    def history(self, name: str | None = None):
        """The exact IMU attitude history of the scenario's (or ``name``'s) scheme.

        A :class:`~inserr.schemes.composition.ScheduleHistory`: the table schedule of the
        scheme composed with the vehicle motion, without sub-steps.
        """
        from inserr.schemes.composition import ScheduleHistory

        return ScheduleHistory(
            self.scheme(name).plan(self.motion, self.duration), self.motion, self.duration
        )

    def with_changes(self, changes: dict[str, Any]) -> Scenario:
        """A new scenario with dotted keys replaced (e.g. ``{"scheme.stop": "60 s"}``)."""
        raw = copy.deepcopy(self.raw)
        for key, value in changes.items():
            section, _, name = key.partition(".")
            if section not in SCHEMA or name not in SCHEMA[section]:
                raise InputError(
                    key, "unknown scenario key", f"use one of: {', '.join(all_keys())}"
                )
            raw.setdefault(section, {})[name] = value
        return scenario_from_dict(raw, self.base_dir, study=self.study, analysis=self.analysis)


def all_keys() -> list[str]:
    """Every dotted scenario key."""
    return [f"{s}.{k}" for s, keys in SCHEMA.items() for k in keys]


def _options_for(name: str, opts: dict) -> dict:
    keep = {"mounting", "start"}
    if name == "continuous":
        keep |= {"reversal"}
    if name in ("flexible-two-position", "nulling-two-position"):
        keep |= {"delta", "variant", "f"}
    if name == "nulling-two-position":
        keep |= {"extension", "phase"}
    if name == "custom":
        keep |= {"steps"}
    return {k: v for k, v in opts.items() if k in keep}


def _analysis_tables(table: Any) -> dict[str, dict[str, Any]]:
    if not isinstance(table, dict) or not all(isinstance(v, dict) for v in table.values()):
        raise InputError(ANALYSIS, "must hold tables only", "write [analysis.NAME] tables")
    return {name: dict(t) for name, t in table.items()}


def _analysis_values(
    given: Mapping[str, Mapping[str, Any]], declared: Mapping[str, Mapping[str, Key]]
) -> dict[str, Any]:
    """Validated values of the ``[analysis.NAME]`` tables a script declares."""
    for name, table in given.items():
        if name not in declared:
            raise InputError(
                f"{ANALYSIS}.{name}",
                "unknown analysis table",
                f"use one of: {', '.join(f'{ANALYSIS}.{n}' for n in declared)}",
            )
        for key in table:
            if key not in declared[name]:
                raise InputError(
                    f"{ANALYSIS}.{name}.{key}",
                    "unknown key",
                    f"use one of: {', '.join(declared[name])}",
                )
    out = {}
    for name, keys in declared.items():
        table = given.get(name, {})
        for key, spec in keys.items():
            dotted = f"{ANALYSIS}.{name}.{key}"
            out[dotted] = _value(spec, dotted, table.get(key, spec.default))
    return out


def _is_number(raw: Any) -> bool:
    return isinstance(raw, (int, float)) and not isinstance(raw, bool)


def _value(spec: Key, fld: str, raw: Any) -> Any:
    """One key's value, validated and in SI (``fld`` is its dotted name)."""
    kind, size = spec.kind, spec.size
    if raw is None:  # only a default can be None (TOML has no null): "not set"
        return None
    if kind == "str":
        if not isinstance(raw, str):
            raise InputError(fld, f"expected a string, got {raw!r}")
        choices = CHOICES.get(fld)
        if choices is not None and raw not in choices:
            raise InputError(fld, f"unknown value {raw!r}", f"use one of: {', '.join(choices)}")
        return raw
    if kind == "bool":
        if not isinstance(raw, bool):
            raise InputError(fld, f"expected true or false, got {raw!r}")
        return raw
    if kind == "int":
        if isinstance(raw, bool) or not isinstance(raw, int):
            raise InputError(fld, f"expected an integer, got {raw!r}")
        return _check_range(fld, raw)
    if kind == "float":
        if not _is_number(raw) or not math.isfinite(raw):
            raise InputError(fld, f"expected a finite number, got {raw!r}")
        return _check_range(fld, float(raw))
    if kind == "int-list":
        if not isinstance(raw, list) or not all(
            isinstance(v, int) and not isinstance(v, bool) for v in raw
        ):
            raise InputError(fld, f"expected a list of integers, got {raw!r}")
        return tuple(raw)
    if kind == "float-list":
        if not isinstance(raw, list) or not all(_is_number(v) and math.isfinite(v) for v in raw):
            raise InputError(fld, f"expected a list of finite numbers, got {raw!r}")
        return tuple(float(v) for v in raw)
    if kind == "list":
        if not isinstance(raw, list) or not all(isinstance(v, str) for v in raw):
            raise InputError(fld, f"expected a list of names, got {raw!r}")
        for i, v in enumerate(raw):
            if not v.strip():
                raise InputError(f"{fld}[{i}]", "empty item", "remove it or give a name")
        return tuple(v.strip() for v in raw)
    if kind == "table-list":
        if not isinstance(raw, list) or not all(isinstance(v, dict) for v in raw):
            raise InputError(fld, "expected an array of tables ([[scheme.steps]])")
        return raw
    if size == "list":
        # An array of quantities (["0 deg", "180 deg"]) or one string ("0, 180 deg").
        if isinstance(raw, str):
            if any(not v.strip() for v in raw.split(",")):
                raise InputError(fld, f"empty item in {raw!r}", "remove the extra comma")
            n = len(raw.split(","))
            return tuple(float(v) for v in np.atleast_1d(parse_quantity(raw, kind, fld, size=n)))
        if not isinstance(raw, list):
            raise InputError(fld, f"expected a list of quantities, got {raw!r}")
        return tuple(
            float(_value(Key(kind, None, None), f"{fld}[{i}]", v)) for i, v in enumerate(raw)
        )
    if _is_number(raw) and raw == 0:
        raw = f"0 {_first_unit(kind)}"  # a bare 0 needs no unit
    return _check_range(fld, parse_quantity(raw, kind, fld, size=size))


def _first_unit(kind: str) -> str:
    from inserr.core.units import units_for

    return units_for(kind)[0]


def read_scenario_file(path: str | Path) -> tuple[dict, Path]:
    """The parsed TOML of a scenario file and its directory, not yet validated.

    Raises
    ------
    InputError
        Missing file, not UTF-8, malformed TOML.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"path: expected a scenario file path, got {type(path).__name__}")
    p = Path(path)
    if p.is_dir():
        raise InputError(str(path), "is a directory, not a scenario file", "name a .toml file")
    if not p.is_file():
        raise InputError(str(path), "scenario file not found", "check the path")
    try:
        # utf-8-sig: a byte-order mark (Windows editors write one) is dropped.
        data = tomllib.loads(p.read_text(encoding="utf-8-sig"))
    except UnicodeDecodeError as exc:
        raise InputError(
            str(path),
            f"not a UTF-8 text file (byte {exc.start}: {exc.reason})",
            "save the scenario as UTF-8 TOML",
        ) from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(
            str(path), f"malformed TOML ({exc})", "fix the syntax at that line"
        ) from None
    return data, p.parent


def load_scenario(
    path: str | Path,
    *,
    study: str = "drift",
    analysis: Mapping[str, Mapping[str, Key]] | None = None,
) -> Scenario:
    """Read and validate a scenario TOML file.

    Parameters
    ----------
    path : str or Path
        The TOML file; relative file names inside it are relative to its directory.
    study : str
        Whose defaults fill the absent keys (a key of :data:`STUDY_DEFAULTS`).
    analysis : mapping, optional
        The ``[analysis.NAME]`` tables an analysis script reads (its sweep grids):
        NAME -> key -> :class:`Key`, validated like the schema's and read back with
        :meth:`Scenario.value` (``"analysis.NAME.key"``). Without it those tables are
        kept, unread, so an analysis' scenario file also runs under the CLI.

    Raises
    ------
    InputError
        Missing file, malformed TOML, unknown section/key, wrong unit, bad value.
    """
    data, base_dir = read_scenario_file(path)
    return scenario_from_dict(data, base_dir, study=study, analysis=analysis)


def scenario_from_dict(
    data: dict,
    base_dir: Path | None = None,
    *,
    study: str = "drift",
    analysis: Mapping[str, Mapping[str, Key]] | None = None,
) -> Scenario:
    """Validate a nested dict (parsed TOML or translated CLI flags) into a :class:`Scenario`.

    Parameters
    ----------
    data : dict
        Section -> key -> value, as a TOML file holds them.
    base_dir : Path, optional
        Directory that relative file names are relative to.
    study : str
        Whose defaults fill the absent keys (a key of :data:`STUDY_DEFAULTS`); also
        which cross-checks apply (the drift engine's memory bound, the scheme).
    analysis : mapping, optional
        The ``[analysis.NAME]`` tables the caller reads (see :func:`load_scenario`).

    Returns
    -------
    Scenario
        Every key validated; :meth:`Scenario.value` gives any of them in SI.
    """
    if not isinstance(data, Mapping):
        raise TypeError(f"data: expected a dict of scenario sections, got {type(data).__name__}")
    if study not in STUDY_DEFAULTS:  # a programming error, not bad input
        raise ValueError(f"unknown study {study!r}; use one of {', '.join(STUDY_DEFAULTS)}")
    raw: dict[str, dict[str, Any]] = {}
    for section, table in data.items():
        if section == ANALYSIS:
            raw[section] = _analysis_tables(table)
            continue
        if section not in SCHEMA:
            raise InputError(
                section,
                "unknown scenario section",
                f"use one of: {', '.join([*SCHEMA, ANALYSIS + '.NAME'])}",
            )
        if not isinstance(table, dict):
            raise InputError(section, "must be a table ([section])")
        for key in table:
            if key not in SCHEMA[section]:
                raise InputError(
                    f"{section}.{key}",
                    "unknown scenario key",
                    f"use one of: {', '.join(SCHEMA[section])}",
                )
        raw[section] = dict(table)
    defaults = STUDY_DEFAULTS[study]
    values: dict[str, Any] = {}
    for section, keys in SCHEMA.items():
        given = raw.get(section, {})
        # The study sections are parsed when given (to validate them) and otherwise
        # only when read (Scenario.value): the drift engine does not pay for them.
        core = section in _CORE_SECTIONS
        for key, spec in keys.items():
            if core or key in given:
                dotted = f"{section}.{key}"
                default = defaults.get(dotted, spec.default)
                values[dotted] = _value(spec, dotted, given.get(key, default))
    if analysis is not None:
        values.update(_analysis_values(raw.get(ANALYSIS, {}), analysis))

    def sect(name: str) -> dict[str, Any]:
        return {k: values[f"{name}.{k}"] for k in SCHEMA[name]}

    sc, si, im, ini, mo, sh, out = (
        sect(k) for k in ("scenario", "site", "imu", "initial", "motion", "scheme", "output")
    )
    duration = sc["duration"]
    if duration <= 0:
        raise InputError(
            "scenario.duration", f"must be > 0, got {duration / 3600:g} h", "give e.g. 72 h"
        )
    if sc["seed"] < 0:
        raise InputError("scenario.seed", f"must be >= 0, got {sc['seed']}", "give e.g. 0")
    if sc["runs"] < 1:
        raise InputError("scenario.runs", f"must be >= 1, got {sc['runs']}", "give e.g. 100")
    try:
        site = Site(
            si["latitude"], si["longitude"], si["height"], spherical=si["earth"] == "spherical"
        )
    except InputError as exc:
        raise InputError(f"site.{exc.field}", exc.problem, exc.fix) from None
    try:
        imu = ImuErrors(
            gyro_bias=im["gyro_bias"],
            accel_bias=im["accel_bias"],
            gyro_scale_factor=im["gyro_scale_factor"],
            accel_scale_factor=im["accel_scale_factor"],
            arw=im["arw"],
            vrw=im["vrw"],
            gyro_bias_instability=im["gyro_bias_instability"],
            accel_bias_instability=im["accel_bias_instability"],
            gyro_correlation_time=im["gyro_correlation_time"],
            accel_correlation_time=im["accel_correlation_time"],
            gyro_misalignment=im["gyro_misalignment"],
            accel_misalignment=im["accel_misalignment"],
        )
    except InputError as exc:
        raise InputError(f"imu.{exc.field}", exc.problem, exc.fix) from None
    if im["sample_rate"] <= 0:
        raise InputError("imu.sample_rate", "must be > 0 Hz", "give e.g. 100 Hz")
    init = InitialErrors(ini["attitude"], ini["velocity"], ini["position"])
    motion = _motion(mo, base_dir)
    if study in _MOTION_STUDIES:
        motion.pieces(duration)  # a heading history shorter than the run fails here, early
    if study in _SCHEME_STUDIES:
        if sh["rate"] <= 0:
            raise InputError("scheme.rate", "table rate must be > 0", "give e.g. 6 deg/s")
        if sh["stop"] < 0:
            raise InputError("scheme.stop", "stop time must be >= 0", "give e.g. 300 s")
    for key in ("step", "covariance_step", "substep", "export_step"):
        if out[key] <= 0:
            raise InputError(f"output.{key}", "must be > 0", "give e.g. 1 s")
    ratio = out["export_step"] / out["step"]
    if ratio < 1 - 1e-9 or abs(ratio - round(ratio)) > 1e-9 * ratio:
        # The exported rows are samples of the deterministic run, never interpolations.
        raise InputError(
            "output.export_step",
            f"{out['export_step']:g} s is not a multiple of output.step ({out['step']:g} s)",
            f"use a multiple of it, e.g. {max(round(ratio), 1) * out['step']:g} s",
        )
    if study == "drift":
        # The engine keeps every output sample (and, under continuous motion, every
        # sub-step segment) in memory: about 1.3 MB per hour at 1 s, so 30 days at 1 s
        # is ~1 GB. Refuse beyond that before any work, with the fix.
        grids = [("step", out["step"]), ("covariance_step", out["covariance_step"])]
        if not motion.is_static:
            grids.append(("substep", out["substep"]))
        for key, dt in grids:
            n = duration / dt
            if n > MAX_SAMPLES:
                raise InputError(
                    f"output.{key}",
                    f"{duration / 3600:g} h at {dt:g} s is {n:.3g} samples, more than the "
                    f"{MAX_SAMPLES:.3g} kept in memory",
                    f"use a coarser output.{key} of at least "
                    f"{math.ceil(duration / MAX_SAMPLES * 1000.0) / 1000.0:g} s, "
                    "or a shorter duration",
                )
    opts: dict[str, Any] = {
        "reversal": sh["reversal"],
        "delta": sh["delta"],
        "variant": sh["variant"],
        "f": sh["decision_rate"],
        "start": sh["start"],
        "phase": sh["phase"],
    }
    if np.any(sh["mounting"]):
        from inserr.core.rotations import body_to_nav

        m = sh["mounting"]
        # The mounting heading is a heading: it follows motion.heading_convention.
        opts["mounting"] = body_to_nav(heading_sign(mo["heading_convention"]) * m[0], m[1], m[2])
    if sh["steps"]:
        opts["steps"] = _steps(sh["steps"])
    if sh["extension"] is not None:
        if sh["extension"] < 0:
            raise InputError("scheme.extension", "must be >= 0 s", "give e.g. 300 s")
        opts["extension"] = sh["extension"]
    scen = Scenario(
        name=sc["name"],
        duration=duration,
        seed=sc["seed"],
        site=site,
        imu=imu,
        init=init,
        motion=motion,
        scheme_name=sh["name"],
        scheme_rate=sh["rate"],
        scheme_stop=sh["stop"],
        scheme_options=opts,
        dt_out=out["step"],
        dt_cov=out["covariance_step"],
        substep=out["substep"],
        vertical=out["vertical"],
        compare=values["compare.schemes"],
        engine=out["engine"],
        raw=raw,
        base_dir=base_dir,
        study=study,
        values=MappingProxyType(values),
        analysis=analysis,
    )
    if study in _SCHEME_STUDIES:
        scen.scheme(scen.scheme_name)  # unknown scheme names fail here, before any work
        for name in scen.compare:
            try:
                scen.scheme(name)
            except InputError as exc:
                if "unknown scheme" not in exc.problem:
                    raise
                raise InputError("compare.schemes", exc.problem, exc.fix) from None
        _refuse_ignored_scheme_keys(
            _changed(raw, "scheme", values, defaults), (scen.scheme_name, *scen.compare)
        )
    _refuse_ignored_motion_keys(_changed(raw, "motion", values, defaults), mo)
    return scen


def _changed(
    raw: Mapping[str, Mapping[str, Any]],
    section: str,
    values: Mapping[str, Any],
    defaults: Mapping[str, Any],
) -> set[str]:
    """The keys of ``section`` given with a value other than their default.

    A key given at its default changes nothing, so it is harmless wherever it is
    ignored (the reference example in ``docs/scenarios.md`` lists every key).
    """
    out = set()
    for key in raw.get(section, {}):
        dotted = f"{section}.{key}"
        spec = SCHEMA[section][key]
        default = _value(spec, dotted, defaults.get(dotted, spec.default))
        if not np.array_equal(
            np.asarray(values[dotted], dtype=object), np.asarray(default, dtype=object)
        ):
            out.add(key)
    return out


#: Scheme keys only some schemes read: key -> option name in :func:`_options_for`.
_SCHEME_OPTION_KEYS = {
    "reversal": "reversal",
    "delta": "delta",
    "variant": "variant",
    "phase": "phase",
    "decision_rate": "f",
    "steps": "steps",
}


def _refuse_ignored_scheme_keys(given: set[str], names: tuple[str, ...]) -> None:
    """InputError for a ``[scheme]`` key that none of the schemes run would read."""
    for key, opt in _SCHEME_OPTION_KEYS.items():
        if key in given and not any(opt in _options_for(n, {opt: 1}) for n in names):
            users = [n for n in _SCHEME_KEY_USERS if opt in _options_for(n, {opt: 1})]
            raise InputError(
                f"scheme.{key}",
                f"is ignored by scheme {', '.join(repr(n) for n in names)}",
                f"remove it, or choose a scheme that reads it ({', '.join(users)})",
            )


#: The schemes with options of their own (for the fix of an ignored key).
_SCHEME_KEY_USERS = ("continuous", "flexible-two-position", "nulling-two-position", "custom")

#: Motion keys only one motion type reads.
_MOTION_KEY_TYPES = {
    "amplitude": "yaw-swing",
    "period": "yaw-swing",
    "rate": "turn",
    "file": "heading-history",
}


def _refuse_ignored_motion_keys(given: set[str], mo: Mapping[str, Any]) -> None:
    """InputError for a ``[motion]`` key the motion type ignores, or a yaw swing of 0."""
    kind = mo["type"]
    for key, needs in _MOTION_KEY_TYPES.items():
        if key in given and kind != needs:
            raise InputError(
                f"motion.{key}",
                f"is ignored by motion type {kind!r} (only {needs!r} reads it)",
                f"remove it, or set motion.type = {needs!r}",
            )
    if kind == "heading-history" and "heading" in given:
        raise InputError(
            "motion.heading",
            "is ignored by motion type 'heading-history' (the file gives the heading)",
            "remove it",
        )
    if kind == "yaw-swing" and mo["amplitude"] == 0:
        raise InputError(
            "motion.amplitude", "a yaw swing needs a non-zero amplitude", "give e.g. 2 deg/s"
        )


def _motion(mo: dict, base_dir: Path | None) -> Motion:
    """The vehicle motion of ``[motion]``, headings and rates turned into inserr's sense.

    Under ``heading_convention = "counter-clockwise-from-north"`` the heading, the
    yaw-swing amplitude, the turn rate and the heading history are negated: the
    motion objects always hold headings clockwise from north (the same physical
    motion, written the other way round). Pitch and roll do not depend on it.
    """
    kind = mo["type"]
    k = heading_sign(mo["heading_convention"])
    common = {"heading": k * mo["heading"], "pitch": mo["pitch"], "roll": mo["roll"]}
    if kind == "static":
        return Motion(**common)
    if kind == "yaw-swing":
        if mo["period"] <= 0:
            raise InputError("motion.period", "must be > 0 s")
        return YawSwing(**common, amplitude=k * mo["amplitude"], period=mo["period"])
    if kind == "turn":
        return Turn(**common, rate=k * mo["rate"])
    if kind == "heading-history":
        path = Path(mo["file"])
        if base_dir is not None and not path.is_absolute():
            path = base_dir / path
        if not mo["file"] or not path.is_file():
            raise InputError("motion.file", f"heading history file {str(path)!r} not found")
        try:
            arr = np.loadtxt(path, delimiter=",", comments="#", ndmin=2)
        except ValueError as exc:
            raise InputError(
                "motion.file", f"cannot read {path}: {exc}", "two columns: time_s, heading_deg"
            ) from None
        if arr.shape[1] != 2:
            raise InputError("motion.file", "needs two columns: time_s, heading_deg")
        return HeadingHistory(
            pitch=mo["pitch"],
            roll=mo["roll"],
            times=arr[:, 0],
            headings=np.unwrap(k * arr[:, 1] * DEG),
        )
    raise InputError(
        "motion.type", f"unknown motion {kind!r}", f"use one of: {', '.join(MOTION_TYPES)}"
    )


def _steps(rows: list[dict]):
    from inserr.schemes.open_loop import Step

    steps = []
    for i, row in enumerate(rows):
        fld = f"scheme.steps[{i}]"
        for key in row:
            if key not in STEP_KEYS:
                raise InputError(f"{fld}.{key}", "unknown step key", f"use: {', '.join(STEP_KEYS)}")
        for key in ("gimbal", "angle", "dwell"):
            if key not in row:
                raise InputError(f"{fld}.{key}", "missing")
        gimbal = row["gimbal"]
        if gimbal not in ("outer", "inner"):
            raise InputError(f"{fld}.gimbal", f"unknown gimbal {gimbal!r}", "use outer or inner")
        angle = parse_quantity(row["angle"], "angle", f"{fld}.angle")
        if angle == 0.0:
            raise InputError(
                f"{fld}.angle",
                "a 0 deg turn is not a step",
                "add its dwell to the step before (or to scheme.stop) and remove it",
            )
        dwell = parse_quantity(row["dwell"], "time", f"{fld}.dwell")
        if dwell < 0:
            raise InputError(f"{fld}.dwell", "must be >= 0")
        rt = row.get("rotation_time")
        rt = parse_quantity(rt, "time", f"{fld}.rotation_time") if rt is not None else None
        if rt is not None and rt <= 0:
            raise InputError(f"{fld}.rotation_time", "must be > 0")
        steps.append(Step(gimbal, angle, dwell, rt, str(row.get("label", f"P{i + 1}"))))
    return steps


def as_scenario(obj: Any, study: str = "drift") -> Scenario:
    """A scenario from what a notebook user has at hand: a Scenario, a file or a dict.

    Parameters
    ----------
    obj : Scenario, str, Path or mapping
        A validated scenario (re-read with ``study``'s defaults if it was built for
        another study), the path of a TOML file, or a nested dict as a file holds it.
    study : str
        Whose defaults fill the absent keys (a key of :data:`STUDY_DEFAULTS`).

    Returns
    -------
    Scenario

    Raises
    ------
    InputError
        A bad file or value (as :func:`load_scenario`), or an object of another type.
    """
    if isinstance(obj, Scenario):
        if obj.study == study:
            return obj
        return scenario_from_dict(obj.raw, obj.base_dir, study=study, analysis=obj.analysis)
    if isinstance(obj, (str, Path)):
        return load_scenario(obj, study=study)
    if isinstance(obj, Mapping):
        return scenario_from_dict(dict(obj), study=study)
    raise InputError(
        "scenario",
        f"expected a Scenario, a TOML file path or a dict, got {type(obj).__name__}",
        "pass inserr.load_scenario(path), the path itself, or a dict of sections",
    )


def resolved_scenario(scen: Scenario) -> dict[str, dict[str, Any]]:
    """Every key the scenario's study reads, as written or defaulted, units as text.

    The sections the drift engine reads (:data:`_CORE_SECTIONS`) in full, plus every
    other section the scenario wrote; each value as the file holds it (a string with
    its unit), the default filling each absent key. Together with
    :func:`scenario_digest` this says exactly which inputs produced a report.

    Parameters
    ----------
    scen : Scenario

    Returns
    -------
    dict
        Section -> key -> value (JSON-ready: strings, numbers, booleans, lists).
    """
    out: dict[str, dict[str, Any]] = {}
    for section, keys in SCHEMA.items():
        given = scen.raw.get(section, {})
        if section not in _CORE_SECTIONS and not given:
            continue
        table = {}
        for key in keys:
            value = given[key] if key in given else study_default(f"{section}.{key}", scen.study)
            if value is not None:
                table[key] = copy.deepcopy(value)
        out[section] = table
    if scen.raw.get(ANALYSIS):
        out[ANALYSIS] = copy.deepcopy(scen.raw[ANALYSIS])
    return out


def scenario_digest(scen: Scenario) -> str:
    """SHA-256 (hex) of :func:`resolved_scenario` as canonical JSON (sorted keys).

    The same inputs give the same digest whether written in a file or given by
    flags, and a key written with its default text hashes like an absent one. (A
    heading-history file is named by its path; its content is not hashed.)
    """
    import hashlib
    import json

    text = json.dumps(resolved_scenario(scen), sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()
