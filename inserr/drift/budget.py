"""The drift error budget as people read it: readable source names, the same rows everywhere.

The drift engine names its sources by key (``gyro_bias_y``,
``gyro_misalignment_xz``, ``initial_attitude_u``, ``arw``); :func:`source_label`
turns a key into words (``gyro bias, y axis``). :func:`budget_rows` gives the rows
that the report's budget table, its budget figure, ``budget.csv`` and
:meth:`inserr.drift.study.SchemeRun.budget` all show: the largest sources, the rest
gathered into one root-sum-square row, and the root-sum-square total.

Why a root-sum-square total: each constant error is a random constant of unknown
sign (1 sigma = its magnitude) and each noise source is independent of the others,
so the mean square of the horizontal error at the end is the sum of the squares of
the per-source contributions (:attr:`inserr.drift.analysis.DriftResult.rms_horizontal`
and :attr:`~inserr.drift.analysis.DriftResult.noise_horizontal_sigma` combined).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

from inserr.output.results import TOTAL_LABEL, rss

#: Column name of the budget value, with its unit.
BUDGET_COLUMN = "RMS horizontal position error at the end (nmi)"

_SENSOR = {"gyro": "gyro", "accel": "accelerometer"}
_ENU = {"e": "east", "n": "north", "u": "up"}
_INITIAL_ATTITUDE = {"e": "initial east tilt error", "n": "initial north tilt error"}
_NOISE = {
    "arw": "gyro angle random walk (ARW)",
    "vrw": "accelerometer velocity random walk (VRW)",
    "gyro_bias_instability": "gyro bias instability (Gauss-Markov)",
    "accel_bias_instability": "accelerometer bias instability (Gauss-Markov)",
}


def is_noise(key: str) -> bool:
    """Whether a budget key is a noise source (else a constant error)."""
    return key in _NOISE


def source_label(key: str) -> str:
    """Readable name of an error-source key of the drift engine.

    Parameters
    ----------
    key : str
        ``gyro_bias_x``, ``accel_scale_factor_z``, ``gyro_misalignment_xy``,
        ``initial_attitude_u``, ``initial_velocity_e``, ``arw``, ... (an unknown key
        is returned unchanged).

    Returns
    -------
    str
        E.g. ``"gyro bias, x axis"``, ``"accelerometer scale factor, z axis"``,
        ``"gyro misalignment, x axis sensing y"``, ``"initial heading error"``,
        ``"initial east velocity error"``, ``"gyro angle random walk (ARW)"``.

    Examples
    --------
    >>> source_label("gyro_misalignment_zx")
    'gyro misalignment, z axis sensing x'
    """
    if key in _NOISE:
        return _NOISE[key]
    head, _, axis = key.rpartition("_")
    sensor, _, what = head.partition("_")
    if sensor in _SENSOR and what in ("bias", "scale_factor") and axis in ("x", "y", "z"):
        return f"{_SENSOR[sensor]} {what.replace('_', ' ')}, {axis} axis"
    if sensor in _SENSOR and what == "misalignment" and len(axis) == 2:
        # M[a, b]: the sensitivity of the a sensor to an input along b (inserr.core.imu).
        return f"{_SENSOR[sensor]} misalignment, {axis[0]} axis sensing {axis[1]}"
    if head == "initial_attitude" and axis in _ENU:
        return _INITIAL_ATTITUDE.get(axis, "initial heading error")
    if head in ("initial_velocity", "initial_position") and axis in _ENU:
        return f"initial {_ENU[axis]} {head.split('_')[1]} error"
    return key


class BudgetRow(NamedTuple):
    """One row of a shown budget.

    Attributes
    ----------
    label : str
        Readable source name (or the "other sources" / total row's label).
    key : str
        The engine's key (``""`` for the gathered and total rows).
    kind : str
        ``"constant"``, ``"noise"``, ``"other"`` or ``"total"``.
    value : float
        RMS horizontal position error at the end, nmi.
    """

    label: str
    key: str
    kind: str
    value: float


def budget_rows(budget: Mapping[str, float], top: int | None = 12) -> list[BudgetRow]:
    """The rows of a shown budget: largest sources, the rest gathered, the total.

    Parameters
    ----------
    budget : mapping
        Source key -> RMS horizontal error at the end, nmi (``metrics()["error_budget"]``).
    top : int or None
        Number of sources shown one by one; the others are gathered into one
        root-sum-square row. None: every source.

    Returns
    -------
    list of BudgetRow
        Largest first; then ``"other N sources (root-sum-square)"`` when sources were
        gathered; then the total (root-sum-square of every source). Empty budget:
        the total row alone, 0.
    """
    items = sorted(budget.items(), key=lambda kv: -kv[1])
    shown = items if top is None else items[:top]
    rest = [] if top is None else items[top:]
    rows = [
        BudgetRow(source_label(k), k, "noise" if is_noise(k) else "constant", float(v))
        for k, v in shown
    ]
    if rest:
        rows.append(
            BudgetRow(
                f"other {len(rest)} sources (root-sum-square)",
                "",
                "other",
                rss(v for _, v in rest),
            )
        )
    rows.append(BudgetRow(TOTAL_LABEL, "", "total", rss(v for _, v in items)))
    return rows


class BudgetTable(NamedTuple):
    """The budgets of several runs on the same rows (a table, a figure, a DataFrame).

    Attributes
    ----------
    schemes : list of str
        Run names, the columns.
    rows : list of BudgetRow
        The rows, with ``value`` the largest over the runs (the sort key).
    values : list of list of float
        ``values[i][j]``: row ``i``, run ``j``, RMS horizontal error at the end, nmi.
    """

    schemes: list[str]
    rows: list[BudgetRow]
    values: list[list[float]]


def budget_table(budgets: Mapping[str, Mapping[str, float]], top: int | None = 12) -> BudgetTable:
    """The budgets of several runs on shared rows: largest sources, the rest, the total.

    Parameters
    ----------
    budgets : mapping
        Run name -> its ``error_budget`` (source key -> nmi).
    top : int or None
        Sources shown one by one, chosen by their largest contribution over the runs;
        the others are gathered per run into one root-sum-square row. None: all.

    Returns
    -------
    BudgetTable
        A source absent from a run contributes 0 to it; the total of each run is the
        root-sum-square of all its sources.
    """
    names = list(budgets)
    keys = {k for b in budgets.values() for k in b}
    peak = {k: max(float(b.get(k, 0.0)) for b in budgets.values()) for k in keys}
    ordered = sorted(keys, key=lambda k: (-peak[k], k))
    shown = ordered if top is None else ordered[:top]
    rest = [] if top is None else ordered[top:]
    rows = [
        BudgetRow(source_label(k), k, "noise" if is_noise(k) else "constant", peak[k])
        for k in shown
    ]
    values = [[float(budgets[n].get(k, 0.0)) for n in names] for k in shown]
    if rest:
        other = [rss(budgets[n].get(k, 0.0) for k in rest) for n in names]
        rows.append(
            BudgetRow(f"other {len(rest)} sources (root-sum-square)", "", "other", max(other))
        )
        values.append(other)
    total = [rss(budgets[n].values()) for n in names]
    rows.append(BudgetRow(TOTAL_LABEL, "", "total", max(total, default=0.0)))
    values.append(total)
    return BudgetTable(names, rows, values)
