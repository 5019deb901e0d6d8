"""Design of calibration position sets: enumerate table stops, rank by precision per unit time.

Criterion (D-optimality with the time charged). With white noise of density ``q``
and dwell ``T`` at every stop, the Fisher information of the 12 parameters of one
triad is block diagonal with three identical 4x4 blocks::

    F_axis = sum_p (T / q^2) a_p a_p^T,    a_p = [u_p / |r|, 1]

(the regressors of every sensor axis, inputs scaled by the reference magnitude so the
blocks are dimensionless apart from ``1/q^2``). ``det(F)^(1/12) = det(F_axis)^(1/4)``
is the inverse squared geometric mean of the axes of the confidence ellipsoid; it grows
in proportion to the dwell time. Charging the time::

    criterion = det(F_axis)^(1/4) / T_total,     T_total = n T + indexing time

is information per second. The ratio of two sets' criteria is the ratio of the times
they need to reach the same D-precision, and does not depend on ``q`` or on the
parameter units (scaling a column multiplies every determinant by the same factor).
With ``sensors="gyro+accel"`` the criterion is the geometric mean of the gyro and
accelerometer ``det^(1/4)`` divided by the time.

The candidate stops are the gimbal-angle grid ``{0, step, 2 step, ...}^2`` of each
mechanism of :func:`candidate_tables`; the visiting order of each subset is the one
with the shortest indexing time (brute force over orders, open path, the clock starting
at the first stop as for the built-in sets).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from inserr.calibration.estimation import CalibrationDesign, reference_vector, sensor_inputs
from inserr.calibration.two_axis_table import (
    DEFAULT_DWELL,
    DEFAULT_RATE,
    P1_INNER_AXIS_ANGLE,
    Position,
    PositionSet,
    TwoAxisTable,
    azimuth_table,
    trunnion_table,
    up_axis_label,
)
from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.core.units import ARCSEC, DEG, PPM

#: Which sensors the criterion serves.
DESIGN_SENSORS = ("gyro", "gyro+accel")


def candidate_tables(rate: float = DEFAULT_RATE, settle: float = 0.0) -> dict[str, TwoAxisTable]:
    """The two-axis table mechanisms searched by the designer.

    ``azimuth``: vertical outer axis, inner axis = IMU x (conventional mounting);
    ``azimuth-offaxis``: vertical outer axis, inner axis at -45 deg to IMU x (P1);
    ``trunnion``: horizontal outer axis along east, inner axis = IMU z.

    Parameters
    ----------
    rate : float
        Table indexing rate, rad/s.
    settle : float
        Settling time added to every move, s.

    Returns
    -------
    dict of str to TwoAxisTable
        The three mechanisms by name (IMU frame s = ENU at zero gimbal angles).
    """
    return {
        "azimuth": azimuth_table(0.0, rate, settle),
        "azimuth-offaxis": azimuth_table(P1_INNER_AXIS_ANGLE, rate, settle),
        "trunnion": trunnion_table(rate, settle),
    }


def _regressors(attitudes: np.ndarray, site: Site, sensor: str) -> np.ndarray:
    r = reference_vector(site, sensor)
    u = sensor_inputs(attitudes, r) / np.linalg.norm(r)
    return np.column_stack([u, np.ones(len(u))])


def _det_rank(gram: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Determinant and rank of symmetric PSD 4x4 matrices (..., 4, 4)."""
    ev = np.linalg.eigvalsh(gram)
    # Relative threshold 1e-10 on the Gram eigenvalues (sigma^2), i.e. 1e-5 on singular
    # values: coarser than calibration's RANK_RTOL on singular values because eigvalsh
    # resolves an exactly singular direction only to ~1e-16 of the largest eigenvalue,
    # which RANK_RTOL**2 = 1e-20 would count as rank. Designs here are either well
    # conditioned or exactly singular, so the two tests agree on every candidate.
    tol = 1e-10 * ev[..., -1:]
    rank = np.sum(ev > tol, axis=-1)
    det = np.where(rank == 4, np.prod(np.clip(ev, 0.0, None), axis=-1), 0.0)
    return det, rank


def set_criterion(
    pset: PositionSet, site: Site, sensors: str = "gyro", arw: float = 1.0, vrw: float = 1.0
) -> float:
    """D-optimal information per second (module docstring) of an existing position set.

    Parameters
    ----------
    pset : PositionSet
        The stops (attitudes ``C_s^n``, dwells in s) and the table (indexing time).
    site : Site
        Latitude and gravity (the inputs depend on them).
    sensors : str
        "gyro" or "gyro+accel".
    arw : float
        Gyro ARW, rad/sqrt(s); only scales the criterion (the default 1 matches the
        unscaled criterion of :func:`design_sets`).
    vrw : float
        Accelerometer VRW, m/s/sqrt(s); same role.

    Returns
    -------
    float
        ``det(F_axis)^(1/4) / T_total``, in units of ``1/q^2`` (geometric mean over the
        sensors); 0 if a design is not full rank. Ratios between sets do not depend
        on ``arw``/``vrw``.
    """
    _check_sensors(sensors)
    att, w = pset.attitudes, pset.dwells
    vals = []
    for sensor, q in (("gyro", arw), ("accel", vrw))[: 1 if sensors == "gyro" else 2]:
        a = _regressors(att, site, sensor)
        det, rank = _det_rank((a.T * w) @ a / q**2)
        vals.append(float(det) ** 0.25 if rank == 4 else 0.0)
    return float(np.prod(vals) ** (1.0 / len(vals))) / pset.total_time


@dataclass(frozen=True)
class Candidate:
    """One ranked position set.

    Attributes
    ----------
    mechanism : str
        Key of :func:`candidate_tables`.
    table : TwoAxisTable
        The mechanism itself.
    stops : tuple of (float, float)
        (outer, inner) gimbal angles, rad, in visiting order.
    dwell : float
        Dwell per stop, s.
    total_time, indexing_time : float
        Dwell plus indexing time, and indexing time alone, s.
    gyro_rank, accel_rank : int
        Ranks of the 12-parameter designs.
    criterion : float
        Information per second (module docstring), with unit noise density.
    equivalents : int
        Number of other sets on the same mechanism with the same size, criterion and time.
    """

    mechanism: str
    table: TwoAxisTable
    stops: tuple[tuple[float, float], ...]
    dwell: float
    total_time: float
    indexing_time: float
    gyro_rank: int
    accel_rank: int
    criterion: float
    equivalents: int = 0

    def position_set(self) -> PositionSet:
        """The candidate as a :class:`PositionSet` (stops named p1, p2, ...).

        Returns
        -------
        PositionSet
        """
        return PositionSet(
            f"{self.mechanism}-{len(self.stops)}",
            self.table,
            tuple(Position(o, i, self.dwell, f"p{k + 1}") for k, (o, i) in enumerate(self.stops)),
        )

    def stops_deg(self) -> list[tuple[int, int]]:
        """Gimbal angles of the stops rounded to whole degrees in [0, 360).

        Returns
        -------
        list of (int, int)
            (outer, inner) per stop, deg, in visiting order.
        """
        return [(round(math.degrees(o)) % 360, round(math.degrees(i)) % 360) for o, i in self.stops]


def _check_sensors(sensors: str) -> None:
    if sensors not in DESIGN_SENSORS:
        raise InputError(
            "calibration.design_sensors",
            f"unknown choice {sensors!r}",
            f"use one of {DESIGN_SENSORS}",
        )


def _best_orders(cost: np.ndarray, combos: np.ndarray, chunk: int = 1000):
    """Shortest open path through every subset: (time (M,), order (M, k))."""
    k = combos.shape[1]
    perms = np.array(list(itertools.permutations(range(k))))
    times = np.empty(len(combos))
    orders = np.empty(combos.shape, dtype=int)
    for s in range(0, len(combos), chunk):
        c = combos[s : s + chunk]
        path = c[:, perms]  # (m, P, k) state indices
        t = cost[path[..., :-1], path[..., 1:]].sum(axis=-1)
        best = np.argmin(t, axis=1)
        times[s : s + chunk] = t[np.arange(len(c)), best]
        orders[s : s + chunk] = path[np.arange(len(c)), best]
    return times, orders


def _up_axes_match(combos: np.ndarray, labels: list[str], up_axes: Sequence[str]) -> np.ndarray:
    """Mask of the stop subsets whose up axes are exactly ``up_axes`` (as a multiset)."""
    if combos.shape[1] != len(up_axes):
        return np.zeros(len(combos), dtype=bool)
    names = sorted(set(labels) | set(up_axes))
    codes = np.array([names.index(x) for x in labels])
    target = np.sort([names.index(x) for x in up_axes])
    return np.all(np.sort(codes[combos], axis=1) == target, axis=1)


def design_sets(
    site: Site,
    dwell: float = DEFAULT_DWELL,
    sizes: tuple[int, ...] = (4, 5, 6),
    sensors: str = "gyro",
    step: float = 90.0 * DEG,
    rate: float = DEFAULT_RATE,
    settle: float = 0.0,
    top: int = 10,
    tables: dict[str, TwoAxisTable] | None = None,
    up_axes: Sequence[str] | None = None,
) -> list[Candidate]:
    """Enumerate position sets reachable with gimbal steps of ``step`` and rank them.

    Parameters
    ----------
    site : Site
        Latitude and gravity (the inputs depend on them).
    dwell : float
        Dwell per stop, s (the same at every stop).
    sizes : tuple of int
        Numbers of stops to try, each 4..6 (4 is the minimum for rank 12).
    sensors : str
        "gyro" (rank only the gyro design; P1's aim) or "gyro+accel".
    step : float
        Gimbal step, rad: 90 deg (the 90/180 deg grid) or 180 deg (180 deg moves only).
    rate, settle : float
        Table indexing rate (rad/s) and settling time per move (s).
    top : int
        Number of candidates returned (best first), ties merged (``equivalents``).
    tables : dict, optional
        Mechanisms to search (default :func:`candidate_tables`).
    up_axes : sequence of str, optional
        Keep only sets whose stops point exactly these signed IMU axes up, in any
        order (labels of :func:`~inserr.calibration.two_axis_table.up_axis_label`;
        e.g. ``("+x", "-x", "+y", "-y", "+z", "-z")``: every axis up and down).
        Sizes other than ``len(up_axes)`` are then skipped.

    Returns
    -------
    list of Candidate
        Full-rank sets only, best criterion first (shorter time breaks ties).
    """
    _check_sensors(sensors)
    # Exhaustive enumeration with brute-force visiting orders stays fast (~1 s) only on the
    # 4 x 4 grid of 90 deg steps and for at most 6 stops (6! orders per subset).
    if not math.isfinite(step) or min(abs(step - 0.5 * math.pi), abs(step - math.pi)) > 1e-9:
        raise InputError(
            "calibration.design_step",
            f"{math.degrees(step):g} deg is not supported",
            "use 90 or 180 deg",
        )
    n_grid = round(2.0 * math.pi / step)
    for k in sizes:
        if not 4 <= k <= 6:
            raise InputError(
                "calibration.design_sizes",
                f"size {k} outside 4..6",
                "give sizes such as 4,5,6 (12 parameters need at least 4 stops)",
            )
    tables = candidate_tables(rate, settle) if tables is None else tables
    angles = [m * step for m in range(n_grid)]
    grid = [(o, i) for o in angles for i in angles]
    found: dict[tuple, Candidate] = {}
    for mech, table in tables.items():
        att = np.stack([table.attitude(o, i) for o, i in grid])
        labels = [up_axis_label(c) for c in att]
        cost = np.array([[table.move_time(a, b) for b in grid] for a in grid])
        outer = {}
        for sensor in ("gyro", "accel"):
            a = _regressors(att, site, sensor)
            outer[sensor] = np.einsum("si,sj->sij", a, a) * dwell  # / q^2 dropped: ratio-invariant
        for k in sizes:
            if k > len(grid):
                continue
            combos = np.array(list(itertools.combinations(range(len(grid)), k)))
            if up_axes is not None:
                combos = combos[_up_axes_match(combos, labels, up_axes)]
                if not len(combos):
                    continue
            det_g, rank_g = _det_rank(outer["gyro"][combos].sum(axis=1))
            det_a, rank_a = _det_rank(outer["accel"][combos].sum(axis=1))
            ok = rank_g == 4 if sensors == "gyro" else (rank_g == 4) & (rank_a == 4)
            if not np.any(ok):
                continue
            combos, det_g, det_a = combos[ok], det_g[ok], det_a[ok]
            rank_g, rank_a = rank_g[ok], rank_a[ok]
            t_index, orders = _best_orders(cost, combos)
            total = k * dwell + t_index
            info = det_g**0.25 if sensors == "gyro" else (det_g * det_a) ** 0.125
            crit = info / total
            for m in range(len(combos)):
                # Sets equal in everything that is ranked are merged into one row.
                key = (mech, k, float(f"{crit[m]:.9g}"), float(f"{total[m]:.6g}"), int(rank_a[m]))
                if key in found:
                    c = found[key]
                    found[key] = replace(c, equivalents=c.equivalents + 1)
                    continue
                found[key] = Candidate(
                    mech,
                    table,
                    tuple(grid[s] for s in orders[m]),
                    dwell,
                    float(total[m]),
                    float(t_index[m]),
                    3 * int(rank_g[m]),
                    3 * int(rank_a[m]),
                    float(crit[m]),
                )
    ranked = sorted(found.values(), key=lambda c: (-c.criterion, c.total_time, len(c.stops)))
    return ranked[:top]


def describe_candidate(
    c: Candidate, site: Site, arw: float, best: float, references: dict[str, float]
) -> dict:
    """JSON-ready report row of a candidate: stops, times, ranks, efficiencies, gyro CRLB.

    Parameters
    ----------
    c : Candidate
        The ranked set.
    site : Site
        Latitude and gravity.
    arw : float
        Gyro ARW, rad/sqrt(s), for the gyro Cramer-Rao bounds.
    best : float
        Criterion of the best candidate (relative efficiency 1).
    references : dict of str to float
        Criteria of reference sets (:func:`set_criterion`, unit noise), by name.

    Returns
    -------
    dict
        Stops in deg, times in s, ranks, gyro condition number, ``relative_efficiency``,
        largest gyro CRLB of the scale factors (ppm) and misalignments (arcsec),
        ``equivalent_sets`` and ``efficiency_vs_<name>`` per reference.
    """
    pset = c.position_set()
    gyro = CalibrationDesign.from_position_set(pset, site, "gyro", arw)
    sigma = gyro.crlb_sigma()
    row = {
        "mechanism": c.mechanism,
        "n_positions": len(c.stops),
        "stops_outer_inner_deg": c.stops_deg(),
        "total_time_s": c.total_time,
        "indexing_time_s": c.indexing_time,
        "gyro_rank": c.gyro_rank,
        "accel_rank": c.accel_rank,
        "gyro_condition_number": gyro.condition_number(),
        "relative_efficiency": c.criterion / best,
        "gyro_crlb_max_sf_ppm": float(np.max(sigma[0:3])) / PPM,
        "gyro_crlb_max_mis_arcsec": float(np.max(sigma[3:9])) / ARCSEC,
        "equivalent_sets": c.equivalents,
    }
    for name, value in references.items():
        row[f"efficiency_vs_{name}"] = c.criterion / value if value > 0 else math.inf
    return row
