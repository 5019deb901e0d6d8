"""Running a scenario under its schemes, and the drift results as tables and JSON.

The report directory of these runs is built by :mod:`inserr.drift.report`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from inserr.core.earth import Site
from inserr.core.units import ARCSEC, DEG, HOUR, MICRO_G, PPM
from inserr.drift.analysis import DriftResult, analyze_drift
from inserr.model.timeline import Timeline
from inserr.scenario.schema import Scenario


@dataclass
class SchemeRun:
    """One scheme run on a scenario: its timeline and drift result."""

    name: str
    timeline: Timeline
    result: DriftResult
    site: Site

    @property
    def motor_starts_per_hour(self) -> float:
        return self.timeline.motor_starts * HOUR / self.timeline.duration

    def metrics(self) -> dict:
        """Headline metrics plus the scheme name, motor starts per hour and warnings."""
        m = {"scheme": self.name}
        m.update(self.result.metrics)
        m["motor_starts_per_hour"] = self.motor_starts_per_hour
        table = self.timeline.meta.get("table")
        if table is not None and "fallbacks" in table.meta:
            m["fallbacks"] = table.meta["fallbacks"]
        m["warnings"] = []
        if table is not None and table.cycle:
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
    tl = scen.timeline(name)
    res = analyze_drift(
        scen.site,
        scen.imu,
        scen.init,
        tl,
        dt_out=scen.dt_out,
        dt_cov=scen.dt_cov,
        vertical=scen.vertical,
    )
    return SchemeRun(name, tl, res, scen.site)


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
        ("motion", scen.motion.describe()),
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
