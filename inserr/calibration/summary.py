"""Calibration results for people: JSON-ready summaries and tables.

Engineering units throughout (this is an edge of the package): scale factors in ppm,
misalignments in arcsec, gyro biases in deg/h, accelerometer biases in micro-g, inputs
in deg/h and g, times in s; sensitivities to the table's positioning error in those
units per arcsec (ppm/arcsec, arcsec/arcsec, (deg/h)/arcsec, ug/arcsec). The P1-style
figures are in :mod:`inserr.calibration.figures`, the report in
:mod:`inserr.calibration.report`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from inserr.calibration.estimation import (
    PARAMETER_NAMES,
    CalibrationDesign,
    MonteCarloConfig,
    SensorResult,
    gimbal_sensitivity,
    monte_carlo,
    parameter_unit,
)
from inserr.calibration.two_axis_table import PositionSet
from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.core.imu import ImuErrors
from inserr.core.units import ARCSEC, DEG_PER_HOUR, DEG_PER_SQRT_HOUR, G0, MICRO_G_PER_SQRT_HZ


def positions_summary(pset: PositionSet, site: Site) -> list[dict[str, Any]]:
    """Per-stop description of a position set with its ideal sensor inputs.

    Parameters
    ----------
    pset : PositionSet
        The stops.
    site : Site
        Latitude (Earth rate) and gravity of the calibration site.

    Returns
    -------
    list of dict
        One dict per stop, in visiting order: ``name``, ``outer_deg`` and ``inner_deg``
        (gimbal angles, deg), ``dwell_s`` (s), ``up_axis`` (signed IMU axis pointing
        up), ``gyro_input_deg_h`` (ideal Earth-rate input in IMU axes, deg/h, (3,)
        array) and ``accel_input_g`` (ideal specific force in IMU axes, g, (3,) array).
    """
    rows = pset.describe()
    for row, c in zip(rows, pset.attitudes, strict=True):
        for key, ref, unit in (
            ("gyro_input_deg_h", site.earth_rate_n, DEG_PER_HOUR),
            ("accel_input_g", site.specific_force_n, G0),
        ):
            u = c.T @ ref
            # Nominal zeros come out of the DCM products as ~1e-16 of the reference;
            # shown as exact zeros so the table reads like P1's.
            u[np.abs(u) < 1e-12 * np.linalg.norm(ref)] = 0.0
            row[key] = u / unit
    return rows


def sensor_summary(result: SensorResult) -> dict[str, Any]:
    """Rank, condition number, identifiability messages and per-parameter table of one triad.

    Parameters
    ----------
    result : SensorResult
        Monte Carlo result of one sensor triad (SI).

    Returns
    -------
    dict
        ``rank`` (int, of 12), ``condition_number`` (dimensionless, ``inf`` when rank
        deficient), ``unidentifiable`` (parameter names), ``identifiability_messages``
        (sentences) and ``parameters`` (:meth:`SensorResult.table`: per parameter
        ``true``, ``mean_deviation``, ``std``, ``variance``, ``crlb_sigma``,
        ``positioning_sigma``, ``predicted_std`` in ppm, arcsec, deg/h or micro-g).
    """
    ident = result.identifiability
    return {
        "rank": ident.rank,
        "condition_number": ident.condition_number,
        "unidentifiable": ident.unidentifiable,
        "identifiability_messages": list(ident.messages),
        "parameters": result.table(),
    }


# --- sensitivity to the table's positioning error ---------------------------------------

#: Axes of the positioning-error sensitivity, as they appear in the JSON keys
#: (``about_<axis>_<unit>``), with their meaning.
SENSITIVITY_AXES: dict[str, str] = {
    "east": "small rotation of the IMU about the local east axis",
    "north": "small rotation of the IMU about the local north axis",
    "up": "small rotation of the IMU about the local up axis",
    "outer_gimbal": "error of the outer gimbal angle (rotation about the outer axis)",
    "inner_gimbal": "error of the inner gimbal angle (rotation about the inner axis at the stop)",
}
#: The axes each positioning-error model (``calibration.positioning_model``) perturbs.
MODEL_AXES: dict[str, tuple[str, ...]] = {
    "three-axis": ("east", "north", "up"),
    "gimbal": ("outer_gimbal", "inner_gimbal"),
}
_AXIS_SHORT = {
    "east": "E",
    "north": "N",
    "up": "U",
    "outer_gimbal": "outer",
    "inner_gimbal": "inner",
}
# Sensitivities below this fraction of the parameter's natural scale (1 per rad for scale
# factors and misalignments, |reference input| per rad for biases) are the ~1e-16
# rounding of structural zeros; real sensitivities are > 1e-6 of that scale.
_ZERO_RTOL = 1e-12


def sensitivity_unit(name: str, sensor: str) -> tuple[str, str, float]:
    """Unit of a parameter's sensitivity to positioning error: parameter unit per arcsec.

    Parameters
    ----------
    name : str
        Parameter name (:data:`inserr.calibration.estimation.PARAMETER_NAMES`).
    sensor : str
        "gyro" or "accel".

    Returns
    -------
    label : str
        For tables: ``"ppm/arcsec"``, ``"arcsec/arcsec"``, ``"(deg/h)/arcsec"`` or
        ``"ug/arcsec"``.
    key : str
        For JSON keys: ``"ppm_per_arcsec"``, ``"arcsec_per_arcsec"``,
        ``"deg_h_per_arcsec"`` or ``"ug_per_arcsec"``.
    si_per_unit : float
        SI value (parameter SI unit per rad) of one such unit.
    """
    unit, f = parameter_unit(name, sensor)
    label = "(deg/h)/arcsec" if unit == "deg/h" else f"{unit}/arcsec"
    key = f"{unit.replace('/', '_')}_per_arcsec"
    return label, key, f / ARCSEC


def _position_keys(pset: PositionSet) -> list[str]:
    """Position names, made unique (``"p1 (3)"`` = third stop, named p1) if repeated."""
    names = [p.name for p in pset.positions]
    return [n if names.count(n) == 1 else f"{n} ({k + 1})" for k, n in enumerate(names)]


def positioning_sensitivity_summary(
    pset: PositionSet, site: Site, sensor: str, model: str = "three-axis"
) -> dict[str, dict[str, Any]]:
    """First-order sensitivity of every parameter to each position's positioning error.

    The change of a parameter's least-squares estimate per arcsec of positioning error
    at one stop (all other stops exact), while the estimator still assumes the nominal
    attitudes (:meth:`CalibrationDesign.positioning_sensitivity` and
    :func:`gimbal_sensitivity`). Evaluated for an error-free sensor: the true errors
    ``K`` change it by a relative amount of order ``|K|`` (~1e-4 for P1).

    Parameters
    ----------
    pset : PositionSet
        The nominal stops.
    site : Site
        Latitude (Earth rate) and gravity.
    sensor : str
        "gyro" or "accel".
    model : str
        Positioning-error model whose axes ``largest`` searches: "three-axis" (east,
        north, up) or "gimbal" (outer and inner gimbal angles).

    Returns
    -------
    dict
        Per parameter name:

        * ``unit``: e.g. ``"ppm/arcsec"`` (:func:`sensitivity_unit`);
        * ``positions``: each position name -> ``about_<axis>_<unit key>`` for the five
          axes of :data:`SENSITIVITY_AXES`, e.g. ``about_north_ppm_per_arcsec``;
        * ``largest``: ``abs_<unit key>``, the largest magnitude over the positions and
          the model's axes, and ``at``, every ``{"position", "axis"}`` (axis as
          ``about_<axis>``) where it occurs (ties within 1e-9; empty if all are zero).

        Values are ``None`` (and ``at`` empty) for unidentifiable parameters; entries
        that vanish structurally are exact zeros.
    """
    if model not in MODEL_AXES:
        raise InputError(
            "positioning_model", f"unknown model {model!r}", f"use one of {', '.join(MODEL_AXES)}"
        )
    design = CalibrationDesign.from_position_set(pset, site, sensor, 0.0)
    j_enu = design.positioning_sensitivity()
    j = np.concatenate([j_enu, gimbal_sensitivity(j_enu, pset)], axis=2)  # (12, N, 5) SI/rad
    scale = np.r_[np.ones(9), np.full(3, np.linalg.norm(design.reference_n))]
    j = np.where(np.abs(j) < _ZERO_RTOL * scale[:, None, None], 0.0, j)
    axes = list(SENSITIVITY_AXES)
    searched = [axes.index(a) for a in MODEL_AXES[model]]
    keys = _position_keys(pset)
    out: dict[str, dict[str, Any]] = {}
    for i, name in enumerate(PARAMETER_NAMES):
        label, ukey, f = sensitivity_unit(name, sensor)
        v = j[i] / f
        ok = bool(np.all(np.isfinite(v)))
        largest: dict[str, Any] = {f"abs_{ukey}": None, "at": []}
        if ok:
            mag = np.abs(v[:, searched])
            top = float(mag.max())
            largest[f"abs_{ukey}"] = top
            if top > 0.0:
                # Symmetric sets give exact ties up to rounding (~1e-15 relative).
                largest["at"] = [
                    {"position": keys[p], "axis": f"about_{axes[searched[a]]}"}
                    for p, a in zip(*np.nonzero(mag >= top * (1.0 - 1e-9)), strict=True)
                ]
        out[name] = {
            "unit": label,
            "largest": largest,
            "positions": {
                key: {
                    f"about_{ax}_{ukey}": (float(v[p, k]) if ok else None)
                    for k, ax in enumerate(axes)
                }
                for p, key in enumerate(keys)
            },
        }
    return out


def sensitivity_axes_text(model: str) -> str:
    """The axes of a positioning-error model in words, for table captions.

    Parameters
    ----------
    model : str
        "three-axis" or "gimbal".

    Returns
    -------
    str
        ``"east, north and up (small rotations of the IMU)"`` or ``"the outer and
        inner gimbal axes (gimbal-angle errors)"``.
    """
    if model == "gimbal":
        return "the outer and inner gimbal axes (gimbal-angle errors)"
    return "east, north and up (small rotations of the IMU)"


def _where(at: list[dict[str, str]]) -> str:
    """``[{p1, about_east}, {p2, about_east}, {p3, about_up}]`` -> ``"p1 p2 east, p3 up"``."""
    if not at:
        return "-"
    groups: dict[str, list[str]] = {}
    for e in at:
        groups.setdefault(e["axis"].removeprefix("about_").replace("_", " "), []).append(
            e["position"]
        )
    return ", ".join(f"{' '.join(ps)} {ax}" for ax, ps in groups.items())


def _largest(p: dict[str, Any]) -> float | str:
    value = next(v for k, v in p["largest"].items() if k.startswith("abs_"))
    if value is None:
        return "n/a"
    return "0" if value == 0.0 else float(value)


SENSITIVITY_HEADER = ["parameter", "unit", "max abs", "at (positions, axis)"]


def sensitivity_rows(block: dict[str, dict[str, Any]]) -> list[list[Any]]:
    """Compact table: per parameter, the largest sensitivity and where it occurs.

    Parameters
    ----------
    block : dict
        A ``positioning_sensitivity`` block (:func:`positioning_sensitivity_summary`).

    Returns
    -------
    list of list
        Rows matching :data:`SENSITIVITY_HEADER`: parameter, unit (parameter unit per
        arcsec), largest magnitude (float; ``"0"`` if every entry vanishes, ``"n/a"`` if
        the parameter is unidentifiable) and where it occurs (``"p2 p3 east"``: at p2
        and p3, about east; ``"-"`` if nowhere).
    """
    return [[name, p["unit"], _largest(p), _where(p["largest"]["at"])] for name, p in block.items()]


def _cell(values: list[float | None]) -> str:
    if any(v is None for v in values):
        return "n/a"
    return " / ".join("0" if v == 0.0 else f"{v:+.3g}" for v in values)


def sensitivity_table(
    block: dict[str, dict[str, Any]], model: str = "three-axis"
) -> tuple[list[str], list[list[Any]]]:
    """Full table of a sensitivity block: one row per parameter, one column per position.

    Parameters
    ----------
    block : dict
        A ``positioning_sensitivity`` block (:func:`positioning_sensitivity_summary`).
    model : str
        "three-axis" (cells give the sensitivities about east / north / up) or "gimbal"
        (about the outer / inner gimbal axis).

    Returns
    -------
    header : list of str
        ``parameter``, ``unit``, one ``"<position> E / N / U"`` (or ``outer / inner``)
        column per position, ``max abs``, ``at``.
    rows : list of list
        Signed cells in the parameter's unit per arcsec, 3 significant digits; ``n/a``
        for unidentifiable parameters.
    """
    axes = MODEL_AXES[model]
    short = " / ".join(_AXIS_SHORT[a] for a in axes)
    first = next(iter(block.values()))
    header = [
        "parameter",
        "unit",
        *[f"{pos} {short}" for pos in first["positions"]],
        "max abs",
        "at",
    ]
    rows = []
    for name, p in block.items():
        cells = [
            _cell([vals[next(k for k in vals if k.startswith(f"about_{a}_"))] for a in axes])
            for vals in p["positions"].values()
        ]
        big = _largest(p)
        big = big if isinstance(big, str) else f"{big:.3g}"
        rows.append([name, p["unit"], *cells, big, _where(p["largest"]["at"])])
    return header, rows


def calibration_summary(
    pset: PositionSet, site: Site, imu: ImuErrors, config: MonteCarloConfig
) -> tuple[dict[str, Any], dict[str, SensorResult]]:
    """Run the Monte Carlo of a position set and summarise it.

    Parameters
    ----------
    pset : PositionSet
        Nominal stops, dwell times (s) and table.
    site : Site
        Latitude and gravity.
    imu : ImuErrors
        True sensor errors and noise (SI).
    config : MonteCarloConfig
        Runs, seed and positioning error (half-width, rad, and model).

    Returns
    -------
    summary : dict
        Keys ``method``, ``positions`` (:func:`positions_summary`), ``n_positions``,
        ``dwell_time_s``, ``indexing_time_s``, ``total_time_s`` (s), ``rank``,
        ``condition_number``, ``unidentifiable``, ``identifiability_messages``,
        ``parameters`` (gyro, :func:`sensor_summary`), ``positioning_sensitivity``
        (gyro, :func:`positioning_sensitivity_summary`, searched over the axes of
        ``config.positioning_model``), ``accel`` (the same keys for the
        accelerometers), ``units`` and ``settings``. Engineering units, see the module.
    results : dict
        The raw :class:`SensorResult` per sensor (SI), for figures.
    """
    results = monte_carlo(pset, site, imu, config)
    summary: dict[str, Any] = {
        "method": pset.name,
        "latitude_deg": math.degrees(site.lat),
        "positions": positions_summary(pset, site),
        "n_positions": len(pset),
        "dwell_time_s": pset.dwell_time,
        "indexing_time_s": pset.indexing_time,
        "total_time_s": pset.total_time,
    }
    model = config.positioning_model
    summary.update(sensor_summary(results["gyro"]))
    summary["positioning_sensitivity"] = positioning_sensitivity_summary(pset, site, "gyro", model)
    summary["accel"] = sensor_summary(results["accel"])
    summary["accel"]["positioning_sensitivity"] = positioning_sensitivity_summary(
        pset, site, "accel", model
    )
    summary["units"] = {
        "sf": "ppm",
        "mis": "arcsec",
        "gyro bias": "deg/h",
        "accel bias": "ug (micro-g)",
        "inputs": "deg/h (gyro), g (accel)",
        "time": "s",
        "positioning_sensitivity": (
            "first-order change of the estimate per arcsec of positioning error at one "
            "position (the others exact), in the parameter's unit per arcsec: ppm/arcsec, "
            "arcsec/arcsec, (deg/h)/arcsec, ug/arcsec. Axes (right-handed; a positive "
            "error means the IMU reached R(angle) times the nominal attitude): "
            + "; ".join(f"about_{k} = {v}" for k, v in SENSITIVITY_AXES.items())
            + f". 'largest' is searched over the axes of the {model} positioning model."
        ),
    }
    summary["settings"] = {
        "runs": config.runs,
        "seed": config.seed,
        "positioning_error_arcsec": config.positioning_error / ARCSEC,
        "positioning_model": config.positioning_model,
        "per_sample": config.per_sample,
        "sample_rate_hz": config.sample_rate,
        "arw_deg_per_sqrt_h": imu.arw / DEG_PER_SQRT_HOUR,
        "vrw_ug_per_sqrt_hz": imu.vrw / MICRO_G_PER_SQRT_HZ,
        "table_rate_deg_s": math.degrees(pset.table.rate),
        "table": pset.table.name,
    }
    return summary, results


def parameter_rows(summary: dict[str, Any]) -> list[list[Any]]:
    """Rows of the per-parameter table, matching :data:`PARAMETER_HEADER`.

    Parameters
    ----------
    summary : dict
        A sensor block with ``parameters`` (:func:`sensor_summary`).

    Returns
    -------
    list of list
        Per parameter: name, unit, true value, mean deviation, std, CRLB, positioning
        sigma and predicted std (floats in the unit; ``"n/a"`` where undefined).
    """
    rows = []
    for name, p in summary["parameters"].items():
        vals = [
            p[k]
            for k in (
                "true",
                "mean_deviation",
                "std",
                "crlb_sigma",
                "positioning_sigma",
                "predicted_std",
            )
        ]
        rows.append([name, p["unit"], *[("n/a" if v is None else float(v)) for v in vals]])
    return rows


PARAMETER_HEADER = [
    "parameter",
    "unit",
    "true",
    "mean dev",
    "std",
    "CRLB",
    "pos. sigma",
    "predicted",
]
