"""Running a scenario under its schemes, and the drift results as tables, series and JSON.

The report directory of these runs is built by :mod:`inserr.drift.report`; the
notebook front door (``inserr.drift``, ``inserr.compare``) is :mod:`inserr.drift.api`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.core.units import ARCMIN, ARCSEC, DEG, HOUR, MICRO_G, NMI, PPM
from inserr.drift.analysis import DriftResult, analyze_drift
from inserr.drift.budget import BUDGET_COLUMN, budget_rows
from inserr.drift.validity import (
    check_finite,
    check_vertical,
    linear_validity_warnings,
    near_schuler_resonance,
)
from inserr.model.timeline import Timeline
from inserr.output.results import StudyResult, budget_frame
from inserr.scenario.schema import Scenario
from inserr.schemes.composition import ScheduleHistory
from inserr.schemes.turntable import TableSchedule

if TYPE_CHECKING:  # pragma: no cover - typing only
    import pandas as pd
    from matplotlib.figure import Figure


@dataclass
class SchemeRun(StudyResult):
    """One scheme run on a scenario: its attitude history and drift result.

    The notebook interface (:class:`~inserr.output.results.StudyResult`):
    :meth:`metrics` (dict), :meth:`to_dataframe` (the time series, units in the
    column names), :meth:`budget` (sources, readable labels, RSS total), :meth:`plot`
    (horizontal error figure) and the Jupyter summary.

    Attributes
    ----------
    name : str
        Scheme name.
    history : ScheduleHistory
        The table schedule composed with the vehicle motion.
    result : DriftResult
    site : Site
    substep : float, s
        Sub-step used when a piecewise-constant-rate :attr:`timeline` is asked for.
    scenario : Scenario, optional
        The scenario it ran (the export step of :meth:`to_dataframe`, the summary).
    validity : tuple of str
        Warnings of :mod:`inserr.drift.validity` (free vertical channel, linear model
        out of range); :meth:`metrics` lists them under ``warnings``.
    """

    name: str
    history: ScheduleHistory
    result: DriftResult
    site: Site
    substep: float = 1.0
    scenario: Scenario | None = None
    validity: tuple[str, ...] = ()

    @property
    def title(self) -> str:  # type: ignore[override]
        """Heading of the Jupyter summary."""
        where = f" ({self.scenario.name})" if self.scenario is not None else ""
        return f"inserr drift: {self.name}{where}"

    @cached_property
    def timeline(self) -> Timeline:
        """The history as a :class:`~inserr.model.timeline.Timeline` (built on first use)."""
        return self.history.timeline(self.substep)

    @property
    def table(self) -> TableSchedule:
        """The scheme's table schedule."""
        return self.history.table

    @property
    def motor_starts_per_hour(self) -> float:
        return self.table.motor_starts() * HOUR / self.history.duration

    def metrics(self) -> dict:
        """Headline metrics plus the scheme name, motor starts per hour and warnings."""
        m = {"scheme": self.name}
        m.update(self.result.metrics)
        m["motor_starts_per_hour"] = self.motor_starts_per_hour
        table = self.table
        if "fallbacks" in table.meta:
            m["fallbacks"] = table.meta["fallbacks"]
        m["warnings"] = []
        if not m["error_budget"]:
            m["warnings"].append(EMPTY_BUDGET)
        if table.cycle:
            m["cycle_time_s"] = table.cycle
            ratio = table.cycle / self.schuler_period_s
            m["cycle_to_schuler_ratio"] = ratio
            k = near_schuler_resonance(table.cycle, self.schuler_period_s, self.history.duration)
            if k is not None:
                m["warnings"].append(
                    f"cycle {table.cycle:.0f} s is close to {k} x the Schuler period "
                    f"({self.schuler_period_s:.0f} s): forcing at the cycle frequency excites the "
                    "Schuler loop near resonance; shorten the stops or change the cycle"
                )
        m["warnings"].extend(self.validity)
        return m

    @property
    def schuler_period_s(self) -> float:
        from inserr.model.psi_model import ErrorModel, modes

        return modes(ErrorModel(self.site)).schuler_period_s

    # --- the notebook interface ------------------------------------------------------
    def to_dataframe(self, step: float | None = None) -> pd.DataFrame:
        """The time series of this run (:func:`timeseries_columns`) as a DataFrame.

        Parameters
        ----------
        step : float, s, optional
            Row step, a multiple of the run's output step; default the scenario's
            ``output.export_step`` (60 s unless set).

        Returns
        -------
        pandas.DataFrame
            One row per output time; columns ``scheme``, ``time (s)``, ``time (h)``
            and the errors, each with its unit in its name.
        """
        import pandas as pd

        return pd.DataFrame(timeseries_columns(self, step))

    def budget(self) -> pd.DataFrame:
        """Every error source (readable label, constant or noise) and the RSS total.

        Returns
        -------
        pandas.DataFrame
            Index ``source``; columns ``type`` and
            ``"RMS horizontal position error at the end (nmi)"``; largest first, the
            root-sum-square total last (see :mod:`inserr.drift.budget`).
        """
        rows = budget_rows(self.result.metrics["error_budget"], top=None)[:-1]
        return budget_frame(((r.label, r.kind, r.value) for r in rows), BUDGET_COLUMN)

    def plot(self) -> Figure:
        """Horizontal position error of this run (signs as given, RMS, worst, noise)."""
        from inserr.drift.figures import horizontal_error

        return horizontal_error({self.name: self.result}, title=self.title)

    def _summary_metrics(self) -> list[tuple[str, object]]:
        return list(zip(METRIC_COLUMNS, metric_values(self), strict=True))


#: Warning of a run without any error source (every number it reports is zero).
EMPTY_BUDGET = (
    "the error budget is empty (every [imu] and [initial] error is zero), so every error "
    'reported is zero; set at least one, e.g. imu.gyro_bias = "0.01 deg/h"'
)


#: The headline numbers of a run as people read them (label with unit), in table order.
METRIC_COLUMNS = (
    "max horizontal position error (nmi)",
    "final horizontal position error (nmi)",
    "max RMS horizontal error, unknown signs (nmi)",
    "max horizontal error, worst signs (nmi)",
    "final noise 1-sigma horizontal error (nmi)",
    "final heading error (arcmin)",
    "motor starts (per hour)",
)


def metric_values(run: SchemeRun) -> list[float]:
    """The values of :data:`METRIC_COLUMNS` for one run (their units)."""
    m = run.metrics()
    return [
        m["max_horizontal_error_nmi"],
        m["final_horizontal_error_nmi"],
        m["rms_horizontal_error_nmi"],
        m["worst_case_horizontal_error_nmi"],
        m["final_horizontal_1sigma_nmi"],
        m["final_heading_error_deg"] * DEG / ARCMIN,
        m["motor_starts_per_hour"],
    ]


#: Columns of the time series (:func:`timeseries_columns`), with units.
SERIES_COLUMNS = (
    "scheme",
    "time (s)",
    "time (h)",
    "east tilt error (arcsec)",
    "north tilt error (arcsec)",
    "heading error (arcmin)",
    "east velocity error (m/s)",
    "north velocity error (m/s)",
    "east position error (nmi)",
    "north position error (nmi)",
    "horizontal position error (nmi)",
    "RMS horizontal error, unknown signs (nmi)",
    "horizontal error, worst signs (nmi)",
    "noise 1-sigma horizontal error (nmi)",
)


def export_step(run: SchemeRun, step: float | None = None) -> float:
    """The row step of a run's exported series: ``step``, else the scenario's, else 60 s."""
    if step is not None:
        return float(step)
    if run.scenario is not None:
        return float(run.scenario.value("output.export_step"))
    return 60.0


def timeseries_columns(run: SchemeRun, step: float | None = None) -> dict[str, np.ndarray]:
    """A run's time series, decimated to ``step``: name (with unit) -> column.

    The deterministic columns (signs as given) are the engine's own samples at the
    rows' times (the step is a multiple of the run's output step). The RMS over
    unknown signs, the worst sign pattern and the noise 1 sigma live on the
    covariance grid; they are exact at its times and interpolated linearly between
    them (at the default steps every row is on both grids).

    Parameters
    ----------
    run : SchemeRun
    step : float, s, optional
        Row step (default: :func:`export_step`).

    Returns
    -------
    dict
        :data:`SERIES_COLUMNS` -> array (``scheme`` repeated).

    Raises
    ------
    InputError
        ``output.export_step`` not a positive multiple of the output step.
    """
    from inserr.drift.analysis import output_grid

    r = run.result
    dt = float(r.t[1] - r.t[0]) if len(r.t) > 1 else float(r.t[-1] or 1.0)
    step = export_step(run, step)
    ratio = step / dt
    if step <= 0 or ratio < 1 - 1e-9 or abs(ratio - round(ratio)) > 1e-9 * ratio:
        raise InputError(
            "output.export_step",
            f"{step:g} s is not a multiple of the output step {dt:g} s",
            f"use a multiple of output.step, e.g. {max(round(ratio), 1) * dt:g} s",
        )
    te = output_grid(float(r.t[-1]), step)
    # Every export time is a fine-grid time (a multiple of dt, or the final time).
    i = np.minimum(np.searchsorted(r.t, te - 1e-6 * dt), len(r.t) - 1)
    h = r.horizontal

    def coarse(values: np.ndarray) -> np.ndarray:
        return np.interp(te, r.t_cov, values)

    return {
        "scheme": np.full(len(te), run.name, dtype=object),
        "time (s)": r.t[i],
        "time (h)": r.t[i] / HOUR,
        "east tilt error (arcsec)": r.attitude[i, 0] / ARCSEC,
        "north tilt error (arcsec)": r.attitude[i, 1] / ARCSEC,
        "heading error (arcmin)": r.attitude[i, 2] / ARCMIN,
        "east velocity error (m/s)": r.nav[i, 3],
        "north velocity error (m/s)": r.nav[i, 4],
        "east position error (nmi)": r.nav[i, 6] / NMI,
        "north position error (nmi)": r.nav[i, 7] / NMI,
        "horizontal position error (nmi)": h[i] / NMI,
        "RMS horizontal error, unknown signs (nmi)": coarse(r.rms_horizontal) / NMI,
        "horizontal error, worst signs (nmi)": coarse(r.worst_horizontal) / NMI,
        "noise 1-sigma horizontal error (nmi)": coarse(r.noise_horizontal_sigma) / NMI,
    }


def timeseries_csv(runs: list[SchemeRun], step: float | None = None) -> str:
    """The time series of several runs as CSV text (one block of rows per run).

    Written without pandas (the report path stays light); the header is
    :data:`SERIES_COLUMNS`, numbers with 10 significant digits.
    """
    lines = [",".join(f'"{c}"' if "," in c else c for c in SERIES_COLUMNS)]
    for run in runs:
        cols = timeseries_columns(run, step)
        numeric = np.column_stack([cols[c] for c in SERIES_COLUMNS[1:]])
        # One %-format per row of Python floats: a third of the time of a per-value
        # f-string over numpy scalars (the quick-start CSV has 18,000 rows).
        row_fmt = run.name.replace("%", "%%") + "," + ",".join(["%.10g"] * numeric.shape[1])
        lines += [row_fmt % tuple(row) for row in numeric.tolist()]
    return "\n".join(lines) + "\n"


def budget_csv(runs: list[SchemeRun]) -> str:
    """Every run's full budget as CSV: scheme, source, key, type, value (nmi), totals last."""
    lines = [f'scheme,source,key,type,"{BUDGET_COLUMN}"']
    for run in runs:
        for row in budget_rows(run.result.metrics["error_budget"], top=None):
            label = f'"{row.label}"' if "," in row.label else row.label
            lines.append(f"{run.name},{label},{row.key},{row.kind},{row.value:.10g}")
    return "\n".join(lines) + "\n"


def run_scheme(scen: Scenario, name: str | None = None) -> SchemeRun:
    """Drift analysis of ``scen`` under its scheme (or ``name``)."""
    if not isinstance(scen, Scenario):
        raise TypeError(
            f"scen: expected a Scenario (load_scenario or scenario_from_dict), "
            f"got {type(scen).__name__}"
        )
    if name is None:
        name = scen.scheme_name
    elif not isinstance(name, str):
        raise TypeError(f"scheme.name: expected a scheme name (str), got {type(name).__name__}")
    elif not name.strip():
        raise InputError("scheme.name", "empty scheme name", "give a scheme name or None")
    vertical_warnings = check_vertical(scen.site, scen.duration, scen.vertical)
    hist = scen.history(name)
    res = analyze_drift(
        scen.site,
        scen.imu,
        scen.init,
        hist,
        dt_out=scen.dt_out,
        dt_cov=scen.dt_cov,
        vertical=scen.vertical,
        engine=scen.engine,
        substep=scen.substep,
    )
    check_finite(res, name)
    warnings = (*vertical_warnings, *linear_validity_warnings(res, scen.site))
    return SchemeRun(name, hist, res, scen.site, scen.substep, scen, warnings)


def describe(scen: Scenario) -> list[tuple[str, str]]:
    """The whole scenario as (item, value with unit) rows for the reports' set-up table.

    Every input the drift engine reads is listed, initial errors and output steps
    included, each in the unit it is usually quoted in.
    """
    imu, init = scen.imu, scen.init
    rows = [
        (
            "site",
            f"lat {math.degrees(scen.site.lat):.4f} deg, "
            f"lon {math.degrees(scen.site.lon):.4f} deg, "
            f"h {scen.site.height:g} m ({'spherical' if scen.site.spherical else 'WGS84'} Earth)",
        ),
        ("duration", f"{scen.duration / HOUR:g} h"),
        ("motion", scen.motion.describe(scen.heading_convention)),
        ("heading convention", f"{scen.heading_convention} (table angles: right hand about up)"),
        ("table", f"rate {scen.scheme_rate / DEG:g} deg/s, stop {scen.scheme_stop:g} s"),
        ("gyro bias (x,y,z)", f"{_axes(imu.gyro_bias / (DEG / HOUR))} deg/h"),
        ("accel bias (x,y,z)", f"{_axes(imu.accel_bias / MICRO_G)} ug"),
        (
            "gyro / accel scale factor (x,y,z)",
            f"{_axes(imu.gyro_scale_factor / PPM)} / {_axes(imu.accel_scale_factor / PPM)} ppm",
        ),
        (
            "gyro / accel misalignment (xy,xz,yx,yz,zx,zy)",
            f"{_axes(imu.gyro_misalignment / ARCSEC)} / "
            f"{_axes(imu.accel_misalignment / ARCSEC)} arcsec",
        ),
        ("ARW / VRW", f"{imu.arw / (DEG / 60):g} deg/sqrt(h) / {imu.vrw / MICRO_G:g} ug/sqrt(Hz)"),
    ]
    if imu.gyro_bias_instability > 0 or imu.accel_bias_instability > 0:
        rows.append(
            (
                "bias instability, gyro / accel (1 sigma, correlation time)",
                f"{imu.gyro_bias_instability / (DEG / HOUR):g} deg/h, "
                f"{imu.gyro_correlation_time:g} s / "
                f"{imu.accel_bias_instability / MICRO_G:g} ug, "
                f"{imu.accel_correlation_time:g} s",
            )
        )
    rows += [
        (
            "initial attitude error (east tilt, north tilt, heading)",
            f"{_axes(init.attitude / ARCSEC, merge=False)} arcsec",
        ),
        ("initial velocity error (E,N,U)", f"{_axes(init.velocity)} m/s"),
        ("initial position error (E,N,U)", f"{_axes(init.position)} m"),
        (
            "output steps (deterministic / covariance / export)",
            f"{scen.dt_out:g} s / {scen.dt_cov:g} s / {scen.value('output.export_step'):g} s",
        ),
        ("vertical channel", scen.vertical),
        ("engine", scen.engine),
    ]
    return rows


def _axes(values, merge: bool = True) -> str:
    """Per-axis values as text, one number when they are all equal (and ``merge``)."""
    v = [float(x) for x in values]
    if merge and all(x == v[0] for x in v):
        return f"{v[0]:g}"
    return ", ".join(f"{x:g}" for x in v)


def metrics_table(runs: list[SchemeRun]) -> tuple[list[str], list[list]]:
    """Header and rows of the comparison table (:data:`METRIC_COLUMNS`, one row per run)."""
    return ["scheme", *METRIC_COLUMNS], [[r.name, *metric_values(r)] for r in runs]


def compared_schemes(scen: Scenario) -> tuple[str, ...]:
    """The schemes of ``compare.schemes`` (validated with the scenario), or InputError."""
    if not scen.compare:
        raise InputError("compare.schemes", "no schemes to compare", "give a list of schemes")
    return tuple(scen.compare)
