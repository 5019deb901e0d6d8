"""What a north-finder study reads from a scenario.

``inserr northfind`` and ``analyses/p3_northfinder`` build their inputs here from a
:class:`~inserr.scenario.schema.Scenario` loaded for the ``northfinder`` study (whose
defaults are issue 7's sensor grade, 3-minute runs and 50 runs; see
``docs/scenarios.md``). Errors name the scenario key.

Keys read
---------
* the truth simulated: ``site.latitude`` (never given to the estimator unless
  ``northfinder.latitude_known``), ``site.height``, and the base's
  ``motion.heading``, ``pitch`` and ``roll`` (a static base);
* the table: ``scheme.rate`` (continuous rotation, sign = direction) and the mounting
  ``northfinder.gyro_tilt``, ``accel_azimuth``, ``accel_tilt``;
* the single gyro and accelerometer from ``[imu]``: ``gyro_bias`` and ``accel_bias``
  (one value each), ``arw``, ``vrw``, the bias instabilities and their correlation
  times, ``sample_rate``; no scale factors or misalignments (the instrument's model
  has none);
* ``northfinder.filter_period``, ``latitude_known``, ``hemisphere`` (declared, never
  derived from the latitude), ``scenario.duration``, ``runs`` and ``seed``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from inserr.core.errors import InputError
from inserr.northfinder.instrument import Instrument, Pose, SensorGrade, n_filter_periods
from inserr.scenario.schema import Scenario
from inserr.schemes.vehicle_motion import Motion

#: Field names of the north-finder dataclasses -> the scenario key they come from.
#: Most samples one north-finder run simulates (~32 bytes each: about 2 GB).
MAX_NORTHFINDER_SAMPLES = 6e7

FIELD_KEYS = {
    "lat": "site.latitude",
    "height": "site.height",
    "heading": "motion.heading",
    "pitch": "motion.pitch",
    "roll": "motion.roll",
    "duration": "scenario.duration",
    "table_rate": "scheme.rate",
    "sample_rate": "imu.sample_rate",
    "filter_period": "northfinder.filter_period",
    "gyro_tilt": "northfinder.gyro_tilt",
    "accel_azimuth": "northfinder.accel_azimuth",
    "accel_tilt": "northfinder.accel_tilt",
    "gyro_arw": "imu.arw",
    "gyro_bias": "imu.gyro_bias",
    "gyro_bias_instability": "imu.gyro_bias_instability",
    "gyro_correlation_time": "imu.gyro_correlation_time",
    "accel_vrw": "imu.vrw",
    "accel_bias": "imu.accel_bias",
    "accel_bias_instability": "imu.accel_bias_instability",
    "accel_correlation_time": "imu.accel_correlation_time",
}


@dataclass(frozen=True)
class NorthfinderInputs:
    """Validated inputs of a north-finder Monte Carlo (SI).

    Attributes
    ----------
    pose : Pose
        The simulated truth.
    instrument : Instrument
    grade : SensorGrade
    duration : float
        Length of each run, s.
    runs : int
    seed : int
    latitude_known : bool
        Give the estimator the true latitude.
    hemisphere : int
        Declared hemisphere, +1 north or -1 south.
    """

    pose: Pose
    instrument: Instrument
    grade: SensorGrade
    duration: float
    runs: int
    seed: int
    latitude_known: bool
    hemisphere: int


def _single(scen: Scenario, key: str, what: str) -> float:
    v = np.asarray(scen.value(key), dtype=float)
    if not np.all(v == v[0]):
        raise InputError(key, f"the north finder has a single {what}", "give one value")
    return float(v[0])


def northfinder_inputs(scen: Scenario) -> NorthfinderInputs:
    """The north finder's inputs from ``scen`` (load it with ``study="northfinder"``).

    Parameters
    ----------
    scen : Scenario

    Returns
    -------
    NorthfinderInputs

    Raises
    ------
    InputError
        Naming the scenario key: a moving base, per-axis or modelled-away IMU errors,
        a pole, a table at rest, a filter period the run cannot hold, no white noise.
    """
    if type(scen.motion) is not Motion:
        raise InputError(
            "motion.type", "the north finder stands on a static base", "use motion.type static"
        )
    for key in (
        "gyro_scale_factor",
        "accel_scale_factor",
        "gyro_misalignment",
        "accel_misalignment",
    ):
        if np.any(scen.value(f"imu.{key}")):
            raise InputError(
                f"imu.{key}",
                "the north finder's sensor model has biases, noise and bias instability only",
                "set it to 0",
            )
    gyro_bias = _single(scen, "imu.gyro_bias", "gyro")
    accel_bias = _single(scen, "imu.accel_bias", "accelerometer")
    imu = scen.imu
    try:
        pose = Pose(
            scen.site.lat,
            scen.motion.heading,
            scen.motion.pitch,
            scen.motion.roll,
            scen.site.height,
        )
        instrument = Instrument(
            table_rate=scen.scheme_rate,
            sample_rate=scen.value("imu.sample_rate"),
            filter_period=scen.value("northfinder.filter_period"),
            gyro_tilt=scen.value("northfinder.gyro_tilt"),
            accel_azimuth=scen.value("northfinder.accel_azimuth"),
            accel_tilt=scen.value("northfinder.accel_tilt"),
        )
        grade = SensorGrade(
            gyro_arw=imu.arw,
            gyro_bias=gyro_bias,
            gyro_bias_instability=imu.gyro_bias_instability,
            gyro_correlation_time=imu.gyro_correlation_time,
            accel_vrw=imu.vrw,
            accel_bias=accel_bias,
            accel_bias_instability=imu.accel_bias_instability,
            accel_correlation_time=imu.accel_correlation_time,
        )
        n_filter_periods(instrument, scen.duration)
    except InputError as exc:
        raise InputError(FIELD_KEYS.get(exc.field, exc.field), exc.problem, exc.fix) from None
    if grade.gyro_arw <= 0 or grade.accel_vrw <= 0:
        raise InputError(
            "imu.arw" if grade.gyro_arw <= 0 else "imu.vrw",
            "the filter and the bound need non-zero white noise",
            "give a positive noise density",
        )
    # The simulation holds the sample grid of a whole run (8-byte indices and times,
    # ~32 bytes per sample with the sensor outputs): refuse a run whose grid alone
    # would pass ~2 GB, before any work, with the fix.
    n_samples = scen.duration * instrument.sample_rate
    if n_samples > MAX_NORTHFINDER_SAMPLES:
        need_gb = 32.0 * n_samples / 1e9
        raise InputError(
            "scenario.duration",
            f"{scen.duration:g} s at {instrument.sample_rate:g} Hz is {n_samples:.3g} samples "
            f"(~{need_gb:.3g} GB), more than the {MAX_NORTHFINDER_SAMPLES:.3g} one run may hold",
            f"give a duration of at most {MAX_NORTHFINDER_SAMPLES / instrument.sample_rate:g} s "
            "or a lower imu.sample_rate",
        )
    hemisphere = 1 if scen.value("northfinder.hemisphere") == "north" else -1
    return NorthfinderInputs(
        pose=pose,
        instrument=instrument,
        grade=grade,
        duration=scen.duration,
        runs=scen.value("scenario.runs"),
        seed=scen.seed,
        latitude_known=scen.value("northfinder.latitude_known"),
        hemisphere=hemisphere,
    )
