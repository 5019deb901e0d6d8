"""One evaluation: a schedule on one motion, and the task the Dask engines run.

The figure of merit of a schedule on a motion is the RMS horizontal position error
over unknown signs (every constant error a random constant of 1 sigma its
magnitude, :func:`inserr.drift.unknown_signs.rms_norm`), maximum over the run, of
the scenario's IMU budget without the sources of ``design.exclude`` (by default the
z-gyro bias, which no rotation about the up axis modulates). It comes from the fast
engine's per-source responses on the output grid ``0, step, 2 step, ..., duration``
(:func:`inserr.model.fast_propagation.constant_error_response`), exactly what
``inserr drift`` reports as ``rms_horizontal_error_nmi`` for the same budget and
covariance step; the noise sources are not part of it. The design's objective is
the worst (largest) of these over the motion set.

The constraints are properties of the planned table schedule over the run
(:func:`schedule_metrics`): motor starts per hour (as ``inserr drift`` counts them),
the fraction of the time the table turns, and the largest gimbal angle.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from inserr.core.units import DEG, HOUR, NMI
from inserr.design.motions import build_motion, canonical
from inserr.drift.analysis import output_grid
from inserr.drift.unknown_signs import rms_norm
from inserr.scenario.schema import Scenario, scenario_from_dict
from inserr.schemes.turntable import TableSchedule

#: Objective value of a candidate that breaks a rule or a constraint: above any error
#: (nmi), plus the total violation so that the optimizer is led back to the feasible set.
PENALTY = 1.0e3


@dataclass(frozen=True)
class Horizon:
    """Where the RMS is read: a run of ``duration`` s, outputs every ``step`` s.

    Attributes
    ----------
    duration : float, s
    step : float, s
    exclude : tuple of str
        Error sources left out.
    """

    duration: float
    step: float
    exclude: tuple[str, ...]

    def as_dict(self) -> dict[str, Any]:
        return {"duration": self.duration, "step": self.step, "exclude": list(self.exclude)}


def error_model_key(scen: Scenario) -> dict[str, Any]:
    """Everything of the scenario the RMS depends on besides the schedule and the motion.

    Site, the constant IMU errors, the initial errors and the vertical channel, SI.
    """
    site, imu, ini = scen.site, scen.imu, scen.init
    return {
        "site": [site.lat, site.lon, site.height, bool(site.spherical)],
        "imu": [
            np.asarray(v, dtype=float).tolist()
            for v in (
                imu.gyro_bias,
                imu.accel_bias,
                imu.gyro_scale_factor,
                imu.accel_scale_factor,
                imu.gyro_misalignment,
                imu.accel_misalignment,
            )
        ],
        "initial": [
            np.asarray(v, dtype=float).tolist() for v in (ini.attitude, ini.velocity, ini.position)
        ],
        "vertical": scen.vertical,
    }


def schedule_metrics(table: TableSchedule, duration: float, motion=None) -> dict[str, float]:
    """Motor starts per hour, fraction of the time turning, largest gimbal angle.

    Parameters
    ----------
    table : TableSchedule
        A planned schedule (it may run a little past ``duration``).
    duration : float, s
        Length of the run.
    motion : Motion, optional
        Needed for heading-isolation segments (their angle follows the vehicle).

    Returns
    -------
    dict
        ``starts_per_hour`` (``table.motor_starts()`` per hour of the run, as
        ``inserr drift`` reports it), ``turning_fraction`` (time in rotation or
        isolation segments within the run / duration) and ``range_deg`` (largest
        |outer| or |inner| gimbal angle reached by the segments that start within the run).
    """
    start = table.t0
    end = table.t0 + table.duration
    inside = start < duration
    moving = np.array([k != "stop" for k in table.kind])
    overlap = np.clip(np.minimum(end, duration) - start, 0.0, None)
    turning = float(np.sum(overlap[moving & inside])) / duration
    outer = np.array([g == "outer" for g in table.gimbal])
    a_end = table.a0 + np.where(outer, table.rate * table.duration, 0.0)
    b_end = table.b0 + np.where(~outer & (table.rate != 0), table.rate * table.duration, 0.0)
    extent = np.max(np.abs(np.concatenate([table.a0, a_end, table.b0, b_end])[np.tile(inside, 4)]))
    iso = [k for k in range(len(table)) if table.kind[k] == "isolate" and inside[k]]
    if iso:
        t = np.concatenate([np.linspace(start[k], min(end[k], duration), 33) for k in iso])
        a, _ = table.angles_at(t, motion)
        extent = max(extent, float(np.max(np.abs(a))))
    return {
        "starts_per_hour": table.motor_starts() * HOUR / duration,
        "turning_fraction": turning,
        "range_deg": float(extent) / DEG,
    }


@dataclass(frozen=True)
class Limits:
    """The constraints: motor starts per hour, turning fraction, table range (deg)."""

    max_starts: float
    max_turning: float
    table_range_deg: float

    def violation(self, metrics: dict[str, float]) -> dict[str, float]:
        """Relative excess of each constraint (only the ones broken)."""
        out = {}
        # Tolerances: the counts are exact; the range and times carry float round-off.
        if metrics["starts_per_hour"] > self.max_starts * (1 + 1e-12):
            out["starts"] = metrics["starts_per_hour"] / self.max_starts - 1.0
        if metrics["turning_fraction"] > self.max_turning * (1 + 1e-12):
            out["turning"] = metrics["turning_fraction"] / self.max_turning - 1.0
        if metrics["range_deg"] > self.table_range_deg + 1e-6:
            out["range"] = metrics["range_deg"] / self.table_range_deg - 1.0
        return out

    def as_dict(self) -> dict[str, float]:
        return {
            "max_starts": self.max_starts,
            "max_turning": self.max_turning,
            "table_range_deg": self.table_range_deg,
        }


class ErrorBudget:
    """The sources of the objective and the error model, built once per scenario.

    Parameters
    ----------
    scen : Scenario
    exclude : tuple of str
        Source names left out.
    """

    def __init__(self, scen: Scenario, exclude: tuple[str, ...]):
        from inserr.model.error_sources import constant_sources, layout_for, source_set
        from inserr.model.psi_model import ErrorModel

        imu = scen.imu.without_noise()
        self.model = ErrorModel(scen.site, layout_for(imu), vertical=scen.vertical)
        self.sources = [
            s for s in constant_sources(imu, scen.init, scen.vertical) if s.name not in exclude
        ]
        self.source_set = source_set(self.model, self.sources)

    def _horizontal(self, table: TableSchedule, motion, horizon: Horizon):
        """Output times (s) and per-source horizontal position errors (Mc, N, 2), m."""
        from inserr.model.fast_propagation import constant_error_response
        from inserr.model.psi_model import DR
        from inserr.schemes.composition import ScheduleHistory

        hist = ScheduleHistory(table, motion, horizon.duration)
        t = output_grid(horizon.duration, horizon.step)
        resp = constant_error_response(self.model, hist, self.source_set, t, t)
        return t, np.moveaxis(resp.coarse[:, DR, :][:, :2, :], 1, 2)  # E and N

    def rms_nmi(self, table: TableSchedule, motion, horizon: Horizon) -> float:
        """Maximum over the run of the RMS horizontal error over unknown signs, nmi."""
        if not self.sources:
            return 0.0
        _, v = self._horizontal(table, motion, horizon)
        return float(rms_norm(v).max() / NMI)

    def breakdown(
        self, table: TableSchedule, motion, horizon: Horizon
    ) -> tuple[float, float, list[tuple[str, float]]]:
        """Where the RMS peaks and what makes it: the per-source budget at that time.

        Returns
        -------
        time : float, s
            Output time of the largest RMS.
        rms : float, nmi
            The RMS there (:meth:`rms_nmi`).
        sources : list of (name, nmi)
            Each source's horizontal error magnitude at that time, largest first (their
            root sum of squares is the RMS: the signs are unknown and independent).
        """
        t, v = self._horizontal(table, motion, horizon)
        total = rms_norm(v)
        k = int(np.argmax(total))
        mag = np.linalg.norm(v[k], axis=-1) / NMI
        order = np.argsort(-mag, kind="stable")
        return (
            float(t[k]),
            float(total[k] / NMI),
            [(self.sources[i].name, float(mag[i])) for i in order],
        )


def source_names(scen: Scenario) -> list[str]:
    """Names of the constant error sources any budget can have (to check ``design.exclude``)."""
    from inserr.core.imu import AXES, MISALIGNMENTS

    names = []
    for group in ("gyro_bias", "accel_bias", "gyro_scale_factor", "accel_scale_factor"):
        names += [f"{group}_{a}" for a in AXES]
    for group in ("gyro_misalignment", "accel_misalignment"):
        names += [f"{group}_{m}" for m in MISALIGNMENTS]
    for group in ("initial_attitude", "initial_velocity", "initial_position"):
        names += [f"{group}_{c}" for c in ("e", "n", "u")]
    return names


# --- the worker task --------------------------------------------------------------------
@lru_cache(maxsize=4)
def _scenario(text: str, base_dir: str | None) -> Scenario:
    """The scenario of a payload, parsed once per worker process."""
    return scenario_from_dict(json.loads(text), Path(base_dir) if base_dir else None)


@lru_cache(maxsize=8)
def _budget(text: str, base_dir: str | None, exclude: tuple[str, ...]) -> ErrorBudget:
    return ErrorBudget(_scenario(text, base_dir), exclude)


def candidate_scheme(candidate: dict[str, Any], scen: Scenario):
    """The scheme of a candidate description (a family member or a catalogue scheme)."""
    if "catalogue" in candidate:
        return scen.scheme(candidate["catalogue"])
    from inserr.design.families import family_from_spec

    return family_from_spec(candidate["family"]).decode(candidate["vars"]).scheme


def evaluate_task(payload: str) -> dict[str, Any]:
    """Worker side: plan a candidate on some motions, check the limits, then the RMS.

    The payload (JSON) holds the scenario (``scenario``: the validated file's tables,
    ``base_dir``), the candidate (``candidate``: ``{"family": spec, "vars": [...]}``
    or ``{"catalogue": name}``), the ``horizon`` (:class:`Horizon`), the ``limits``
    (:class:`Limits` or null), the ``motions`` (specs, in the order to evaluate),
    ``partial`` (the worst RMS already known for this candidate from other motions,
    nmi) and ``threshold`` (null, or stop as soon as the worst exceeds it: the
    optimizer rejects the candidate anyway).

    Every motion is planned first; if a schedule breaks a limit, no RMS is computed.
    Otherwise the RMS is computed motion by motion in the order given.

    Returns
    -------
    dict
        ``status`` ("ok" or "failed"), ``error``, ``index`` (the payload's, echoed: what
        the motions are in the caller's set), ``plans`` (position in ``motions`` ->
        schedule metrics), ``rms`` (position -> RMS, nmi) and ``elapsed_s``. Never raises.
    """
    t0 = time.perf_counter()
    try:
        p = json.loads(payload)
        text = canonical(p["scenario"])
        scen = _scenario(text, p["base_dir"])
        horizon = Horizon(
            p["horizon"]["duration"], p["horizon"]["step"], tuple(p["horizon"]["exclude"])
        )
        scheme = candidate_scheme(p["candidate"], scen)
        limits = Limits(**p["limits"]) if p["limits"] else None
        plans, tables = {}, {}
        shared = None  # an open-loop table does not depend on the motion: plan it once
        for i, spec in enumerate(p["motions"]):
            motion = build_motion(spec)
            if shared is not None:
                table = shared
            else:
                table = scheme.plan(motion, horizon.duration)
                if table.cycle is not None:
                    shared = table
            tables[i] = (table, motion)
            plans[i] = schedule_metrics(table, horizon.duration, motion)
        broken = limits is not None and any(limits.violation(m) for m in plans.values())
        rms: dict[int, float] = {}
        if not broken:
            budget = _budget(text, p["base_dir"], horizon.exclude)
            worst = p.get("partial") or 0.0
            threshold = p.get("threshold")
            for i in range(len(p["motions"])):
                table, motion = tables[i]
                rms[i] = budget.rms_nmi(table, motion, horizon)
                worst = max(worst, rms[i])
                if threshold is not None and worst > threshold:
                    break
        result = {"status": "ok", "error": "", "index": p.get("index"), "plans": plans, "rms": rms}
    except Exception as exc:  # noqa: BLE001 - reported to the design, which stops with it
        result = {"status": "failed", "error": f"{type(exc).__name__}: {exc}"}
    result["elapsed_s"] = time.perf_counter() - t0
    return result
