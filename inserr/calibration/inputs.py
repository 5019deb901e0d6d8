"""What a calibration study reads from a scenario.

``inserr calibrate`` and ``analyses/p1_calibration`` build their inputs here from a
:class:`~inserr.scenario.schema.Scenario` loaded for the ``calibration`` study (whose
defaults are P1's set-up: its true gyro errors, navigation-grade noise, 100 runs,
seed 1; see ``docs/scenarios.md``). Errors name the scenario key.

Keys read
---------
* ``site`` (latitude, height: the inputs are Earth rate and gravity);
* ``[imu]``: the true errors (biases, scale factors, misalignments) and the noise
  (``arw``, ``vrw``) of the sensors being calibrated; ``sample_rate`` for the
  per-sample simulation;
* the table: ``scheme.rate`` (indexing rate) and ``scheme.stop`` (dwell at every
  position; for a position-set file, at the positions that give none);
* ``[calibration]``: the position set (``method``), settling, positioning error and
  model, per-sample simulation, and the position-set designer's settings;
* ``scenario.runs`` and ``scenario.seed`` of the Monte Carlo.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from inserr.calibration.estimation import MonteCarloConfig
from inserr.calibration.two_axis_table import (
    BUILTIN_SETS,
    PositionSet,
    builtin_set,
    load_position_set,
)
from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.core.imu import ImuErrors
from inserr.scenario.schema import Scenario


@dataclass(frozen=True)
class CalibrationInputs:
    """Validated inputs of a calibration study (SI).

    Attributes
    ----------
    site : Site
    truth : ImuErrors
        True errors and noise of the sensors being calibrated.
    dwell : float
        Dwell per position, s.
    rate : float
        Table indexing rate, rad/s.
    settle : float
        Settling time after every move, s.
    position_set : PositionSet or None
        The set of ``calibration.method`` (None when designing).
    config : MonteCarloConfig or None
        Runs, seed, positioning error (None when designing).
    design : bool
        Rank candidate position sets instead of a Monte Carlo.
    design_sizes : tuple of int
    design_sensors : str
    design_step : float
        Gimbal step of the candidates, rad.
    top : int
        Candidates shown.
    """

    site: Site
    truth: ImuErrors
    dwell: float
    rate: float
    settle: float
    position_set: PositionSet | None
    config: MonteCarloConfig | None
    design: bool
    design_sizes: tuple[int, ...]
    design_sensors: str
    design_step: float
    top: int


def method_set(
    method: str, dwell: float, rate: float, settle: float = 0.0, base_dir: Path | None = None
) -> PositionSet:
    """A built-in position set, or a TOML position-set file (relative to ``base_dir``).

    Parameters
    ----------
    method : str
        A key of :data:`~inserr.calibration.two_axis_table.BUILTIN_SETS` or a path.
    dwell : float
        Dwell per position, s (for a file, of the positions that give none).
    rate : float
        Indexing rate, rad/s.
    settle : float
        Settling time after every move, s (for a file without its own).
    base_dir : Path, optional
        Directory of the scenario file.

    Returns
    -------
    PositionSet
    """
    if method in BUILTIN_SETS:
        return builtin_set(method, dwell, rate, settle)
    path = Path(method)
    if base_dir is not None and not path.is_absolute():
        path = Path(base_dir) / path
    if path.suffix.lower() != ".toml" and not path.exists():
        raise InputError(
            "calibration.method",
            f"unknown method {method!r}",
            f"use {', '.join(BUILTIN_SETS)} or the path of a .toml position-set file",
        )
    pset = load_position_set(path, dwell, rate)
    if settle and not pset.table.settle:
        pset = replace(pset, table=replace(pset.table, settle=settle))
    return pset


def calibration_inputs(scen: Scenario) -> CalibrationInputs:
    """The calibration study's inputs from ``scen`` (load it with ``study="calibration"``).

    The position set and the Monte Carlo settings are checked here, before any work.

    Parameters
    ----------
    scen : Scenario

    Returns
    -------
    CalibrationInputs

    Raises
    ------
    InputError
        Naming the scenario key.
    """
    imu = scen.imu
    for key in ("gyro_bias_instability", "accel_bias_instability"):
        if getattr(imu, key) > 0:
            raise InputError(
                f"imu.{key}",
                "the calibration model has constant errors and white noise only",
                "set it to 0",
            )
    dwell, rate = scen.scheme_stop, scen.scheme_rate
    if dwell <= 0:
        raise InputError(
            "scheme.stop", "the dwell at every position must be > 0 s", "give e.g. 300 s"
        )
    settle = scen.value("calibration.settle")
    if settle < 0:
        raise InputError("calibration.settle", f"must be >= 0, got {settle:g} s", "give e.g. 0 s")
    top = scen.value("calibration.top")
    if top < 1:
        raise InputError("calibration.top", f"must be >= 1, got {top}", "give e.g. 10")
    design = scen.value("calibration.design")
    pset = config = None
    if not design:
        config = MonteCarloConfig(
            runs=scen.value("scenario.runs"),
            seed=scen.seed,
            positioning_error=scen.value("calibration.positioning_error"),
            positioning_model=scen.value("calibration.positioning_model"),
            per_sample=scen.value("calibration.per_sample"),
            sample_rate=scen.value("imu.sample_rate"),
        )
        pset = method_set(scen.value("calibration.method"), dwell, rate, settle, scen.base_dir)
    return CalibrationInputs(
        site=scen.site,
        truth=imu,
        dwell=dwell,
        rate=rate,
        settle=settle,
        position_set=pset,
        config=config,
        design=design,
        design_sizes=scen.value("calibration.design_sizes"),
        design_sensors=scen.value("calibration.design_sensors"),
        design_step=scen.value("calibration.design_step"),
        top=top,
    )
