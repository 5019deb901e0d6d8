"""Running a scenario under its schemes, and the drift results as tables and JSON.

The report directory of these runs is built by :mod:`inserr.drift.report`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.core.units import ARCSEC, DEG, HOUR, MICRO_G, PPM
from inserr.drift.analysis import DriftResult, analyze_drift
from inserr.model.timeline import Timeline
from inserr.scenario.schema import Scenario
from inserr.schemes.composition import ScheduleHistory
from inserr.schemes.turntable import TableSchedule


@dataclass
class SchemeRun:
    """One scheme run on a scenario: its attitude history and drift result.

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
    """

    name: str
    history: ScheduleHistory
    result: DriftResult
    site: Site
    substep: float = 1.0

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
        if table.cycle:
            m["cycle_time_s"] = table.cycle
            ratio = table.cycle / self.schuler_period_s
            m["cycle_to_schuler_ratio"] = ratio
            k = max(1, round(ratio))
            if abs(ratio - k) < 0.15 * k:
                m["warnings"].append(
                    f"cycle {table.cycle:.0f} s is close to {k} x the Schuler period "
                    f"({self.schuler_period_s:.0f} s): forcing at the cycle frequency excites the "
                    "Schuler loop near resonance; shorten the stops or change the cycle"
                )
        return m

    @property
    def schuler_period_s(self) -> float:
        from inserr.model.psi_model import ErrorModel, modes

        return modes(ErrorModel(self.site)).schuler_period_s


def run_scheme(scen: Scenario, name: str | None = None) -> SchemeRun:
    """Drift analysis of ``scen`` under its scheme (or ``name``)."""
    name = name or scen.scheme_name
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
    return SchemeRun(name, hist, res, scen.site, scen.substep)


def describe(scen: Scenario) -> list[tuple[str, str]]:
    """Key facts of a scenario as (label, value) rows for reports."""
    imu = scen.imu
    return [
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
        ("gyro bias (x,y,z)", ", ".join(f"{v / (DEG / HOUR):g}" for v in imu.gyro_bias) + " deg/h"),
        ("accel bias (x,y,z)", ", ".join(f"{v / MICRO_G:g}" for v in imu.accel_bias) + " ug"),
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
        ("vertical channel", scen.vertical),
    ]


def _axes(values) -> str:
    """Per-axis values as text, one number when they are all equal."""
    v = [float(x) for x in values]
    return f"{v[0]:g}" if all(x == v[0] for x in v) else ", ".join(f"{x:g}" for x in v)


def metrics_table(runs: list[SchemeRun]) -> tuple[list[str], list[list]]:
    """Header and rows of the comparison table."""
    header = [
        "scheme",
        "max horiz (nmi)",
        "final horiz (nmi)",
        "RMS unknown signs (nmi)",
        "worst signs (nmi)",
        "noise 1-sigma (nmi)",
        "final heading (deg)",
        "motor starts/h",
    ]
    rows = []
    for r in runs:
        m = r.metrics()
        rows.append(
            [
                r.name,
                m["max_horizontal_error_nmi"],
                m["final_horizontal_error_nmi"],
                m["rms_horizontal_error_nmi"],
                m["worst_case_horizontal_error_nmi"],
                m["final_horizontal_1sigma_nmi"],
                m["final_heading_error_deg"],
                m["motor_starts_per_hour"],
            ]
        )
    return header, rows


def compared_schemes(scen: Scenario) -> tuple[str, ...]:
    """The schemes of ``compare.schemes`` (validated with the scenario), or InputError."""
    if not scen.compare:
        raise InputError("compare.schemes", "no schemes to compare", "give a list of schemes")
    return tuple(scen.compare)
