"""The notebook front door of the calibration chapter: ``inserr.calibrate``, ``inserr.imu_budget``.

* :func:`calibrate` runs the multi-position calibration study of a scenario (as
  ``inserr calibrate``) and returns a :class:`CalibrationStudy`;
* :func:`imu_budget` fits the noise terms of a static recording (as ``inserr
  imu-budget``) and returns a :class:`NoiseBudget`.

Both have the common interface (:class:`~inserr.output.results.StudyResult`):
``metrics()``, ``to_dataframe()``, ``budget()``, ``plot()`` and a Jupyter summary.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from inserr.calibration.allan import (
    ADEV_UNITS,
    AXES,
    SENSORS,
    TERM_POWERS,
    TERMS,
    NoiseFit,
    Recording,
    fit_recording,
    in_units,
    read_recording,
    summary,
)
from inserr.output.results import TOTAL_LABEL, StudyResult, rss
from inserr.scenario.schema import Scenario, as_scenario

if TYPE_CHECKING:  # pragma: no cover - typing only
    import pandas as pd
    from matplotlib.figure import Figure


# --- the noise budget of a recording ----------------------------------------------------
def imu_budget(
    recording: str | Path | Recording,
    rate: float | None = None,
    *,
    gyro_unit: str | None = None,
    accel_unit: str | None = None,
    confidence: float = 0.95,
) -> NoiseBudget:
    """Noise terms of a static IMU recording from its Allan deviation (``inserr.imu_budget``).

    Parameters
    ----------
    recording : str, Path or Recording
        A CSV file (see :func:`inserr.calibration.allan.read_recording`) or a
        :class:`~inserr.calibration.allan.Recording` already in SI.
    rate : float, Hz
        Sample rate (needed for a file).
    gyro_unit, accel_unit : str, optional
        Units of the file's columns when its header does not declare them.
    confidence : float
        Level of the intervals.

    Returns
    -------
    NoiseBudget
    """
    from inserr.core.errors import InputError

    if not isinstance(recording, Recording):
        if rate is None:
            raise InputError("rate", "a recording file needs its sample rate", "pass rate=HZ")
        recording = read_recording(recording, rate, gyro_unit=gyro_unit, accel_unit=accel_unit)
    return NoiseBudget(fit_recording(recording, confidence))


@dataclass
class NoiseBudget(StudyResult):
    """The fitted noise terms of a recording (see :mod:`inserr.calibration.allan`).

    Attributes
    ----------
    fit : NoiseFit
    """

    fit: NoiseFit

    @property
    def title(self) -> str:  # type: ignore[override]
        return f"inserr IMU noise budget: {Path(self.fit.recording.source).name}"

    def metrics(self) -> dict[str, Any]:
        """Every term of every axis with its interval (:func:`.allan.summary`)."""
        return summary(self.fit)

    def imu_section(self) -> str:
        """The ready ``[imu]`` scenario section (TOML text)."""
        return summary(self.fit)["imu_section"]

    def terms(self) -> pd.DataFrame:
        """One row per sensor, term and axis: value, interval, unit, resolved."""
        import pandas as pd

        rows = []
        for sensor in SENSORS:
            for name in TERM_POWERS:
                label, unit, _ = TERMS[sensor][name]
                for axis in AXES:
                    t = self.fit.term(sensor, axis, name)
                    rows.append(
                        {
                            "sensor": sensor,
                            "term": label,
                            "axis": axis,
                            "value": in_units(sensor, name, t.value),
                            "low": in_units(sensor, name, t.low),
                            "high": in_units(sensor, name, t.high),
                            "unit": unit,
                            "resolved": t.resolved,
                        }
                    )
        return pd.DataFrame(rows)

    def to_dataframe(self) -> pd.DataFrame:
        """The Allan deviation of every axis: averaging time (s), deviations with units."""
        import pandas as pd

        first = self.fit.axes[("gyro", "x")].curve
        cols: dict[str, Any] = {"tau (s)": first.tau, "clusters": first.clusters}
        for sensor in SENSORS:
            unit, si = ADEV_UNITS[sensor]
            for axis in AXES:
                c = self.fit.axes[(sensor, axis)].curve
                cols[f"{sensor} {axis} Allan deviation ({unit})"] = c.adev / si
        return pd.DataFrame(cols)

    def budget(self, sensor: str = "gyro", tau: float = 100.0) -> pd.DataFrame:
        """What each term contributes to the Allan deviation at ``tau``, per axis.

        The Allan variances of independent noises add, so the root-sum-square total
        of the rows is the fitted Allan deviation at ``tau``.

        Parameters
        ----------
        sensor : {"gyro", "accel"}
        tau : float, s
            Averaging time.

        Returns
        -------
        pandas.DataFrame
            Index ``source`` (the terms, then the total); columns x, y, z, named with
            the unit (deg/h for the gyro, micro-g for the accelerometer).
        """
        import pandas as pd

        unit, si = ADEV_UNITS[sensor]
        labels = [TERMS[sensor][name][0] for name in TERM_POWERS]
        data = {}
        for axis in AXES:
            f = self.fit.axes[(sensor, axis)]
            vals = [float(f.term_line(name, np.array([tau]))[0]) / si for name in TERM_POWERS]
            data[f"{axis} ({unit} at tau = {tau:g} s)"] = vals + [rss(vals)]
        return pd.DataFrame(data, index=pd.Index([*labels, TOTAL_LABEL], name="source"))

    def plot(self) -> Figure:
        """The Allan deviation of every axis with the fitted terms and intervals."""
        from inserr.calibration.figures import allan_figure

        return allan_figure(self.fit)

    def report(self, out_dir: str | Path) -> Path:
        """Write the report directory (as ``inserr imu-budget --out``)."""
        from inserr.calibration.report import build_noise_report

        return build_noise_report(self.fit).write(out_dir)

    def _summary_metrics(self) -> list[tuple[str, Any]]:
        rec = self.fit.recording
        rows: list[tuple[str, Any]] = [
            ("samples", rec.samples),
            ("sample rate (Hz)", rec.rate),
            ("duration (h)", rec.duration / 3600.0),
        ]
        for sensor in SENSORS:
            for name in TERM_POWERS:
                label, unit, _ = TERMS[sensor][name]
                value = max(self.fit.term(sensor, a, name).value for a in AXES)
                rows.append(
                    (f"{sensor} {label}, largest axis ({unit})", in_units(sensor, name, value))
                )
        return rows


# --- the calibration study --------------------------------------------------------------
def calibrate(scenario: Scenario | str | Path | dict | None = None) -> CalibrationStudy:
    """The multi-position calibration study of a scenario (``inserr.calibrate``).

    Parameters
    ----------
    scenario : Scenario, str, Path, dict or None
        A ``calibration`` scenario (file, dict or Scenario); None: the study's defaults
        (P1's set-up).

    Returns
    -------
    CalibrationStudy
    """
    from inserr.calibration.inputs import calibration_inputs
    from inserr.calibration.summary import calibration_summary
    from inserr.core.errors import InputError

    scen = as_scenario({} if scenario is None else scenario, "calibration")
    inp = calibration_inputs(scen)
    if inp.design:
        raise InputError(
            "calibration.design",
            "the front door runs one position set",
            "set calibration.design = false (the designer runs from the inserr calibrate command)",
        )
    summ, results = calibration_summary(inp.position_set, inp.site, inp.truth, inp.config)
    return CalibrationStudy(scen, summ, results)


def parameter_label(sensor: str, name: str) -> str:
    """Readable name of a calibration parameter, its symbol in brackets.

    Parameters
    ----------
    sensor : {"gyro", "accel"}
    name : str
        From :data:`inserr.calibration.estimation.PARAMETER_NAMES` (``sf_x``,
        ``mis_xy``, ``bias_z``, ...).

    Returns
    -------
    str
        E.g. ``"gyro misalignment, x axis sensing y (mis_xy)"``: the drift budget's
        name of the same error (:func:`inserr.drift.budget.source_label`; ``mis_ij``
        is the sensitivity of the i sensor to the j input in both chapters).
    """
    from inserr.drift.budget import source_label

    kind, _, axes = name.partition("_")
    what = {"sf": "scale_factor", "mis": "misalignment", "bias": "bias"}[kind]
    return f"{source_label(f'{sensor}_{what}_{axes}')} ({name})"


#: Columns of the calibration budget (per parameter, in its unit).
CALIBRATION_BUDGET = (
    "sensor noise 1-sigma (CRLB)",
    "table positioning 1-sigma",
)


@dataclass
class CalibrationStudy(StudyResult):
    """A calibration Monte Carlo: summary (engineering units) and raw results.

    Attributes
    ----------
    scenario : Scenario
    summary : dict
        :func:`inserr.calibration.summary.calibration_summary`'s summary.
    results : dict
        ``"gyro"``, ``"accel"`` -> :class:`~inserr.calibration.estimation.SensorResult`.
    """

    scenario: Scenario
    summary: dict[str, Any]
    results: dict[str, Any]

    @property
    def title(self) -> str:  # type: ignore[override]
        return f"inserr calibration: {self.summary['method']}"

    def metrics(self) -> dict[str, Any]:
        """The study's summary (as ``inserr calibrate --json``)."""
        return self.summary

    def _blocks(self):
        yield "gyro", self.summary
        yield "accel", self.summary["accel"]

    def to_dataframe(self) -> pd.DataFrame:
        """The per-run table: estimate minus truth of every parameter in every run.

        Index ``run``; columns ``<parameter> error (<unit>)``, the parameter by its
        readable name (:func:`parameter_label`).
        """
        import pandas as pd

        from inserr.calibration.estimation import PARAMETER_NAMES, parameter_unit

        cols: dict[str, Any] = {}
        for sensor, result in self.results.items():
            dev = result.deviations
            for k, name in enumerate(PARAMETER_NAMES):
                unit, factor = parameter_unit(name, sensor)
                cols[f"{parameter_label(sensor, name)} error ({unit})"] = dev[:, k] / factor
        frame = pd.DataFrame(cols)
        frame.index.name = "run"
        return frame

    def budget(self) -> pd.DataFrame:
        """Per parameter: 1 sigma from sensor noise and from table positioning, and total.

        The two sources are independent, so the total is their root-sum-square (the
        predicted standard deviation); the Monte Carlo standard deviation is beside it.
        """
        import pandas as pd

        rows, index = [], []
        for sensor, block in self._blocks():
            for name, p in block["parameters"].items():
                noise = p["crlb_sigma"]
                pos = p["positioning_sigma"]
                vals = [np.nan if v is None else float(v) for v in (noise, pos)]
                total = rss(v for v in vals if np.isfinite(v)) if any(np.isfinite(vals)) else np.nan
                rows.append([p["unit"], *vals, total, p["std"]])
                index.append(parameter_label(sensor, name))
        return pd.DataFrame(
            rows,
            index=pd.Index(index, name="parameter"),
            columns=["unit", *CALIBRATION_BUDGET, TOTAL_LABEL, "Monte Carlo std"],
        )

    def plot(self) -> Figure:
        """P1-style repeatability figure of the gyro parameters."""
        from inserr.calibration.figures import std_figure

        return std_figure({self.summary["method"]: self.results}, "gyro", self.title)

    def _summary_metrics(self) -> list[tuple[str, Any]]:
        s = self.summary
        return [
            ("positions", s["n_positions"]),
            ("total time (s)", s["total_time_s"]),
            ("gyro rank (of 12)", s["rank"]),
            ("accel rank (of 12)", s["accel"]["rank"]),
            ("gyro condition number", s["condition_number"]),
            ("runs", s["settings"]["runs"]),
        ]
