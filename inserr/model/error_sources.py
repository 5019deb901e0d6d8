"""Error sources and the initial augmented state they define.

Every constant error (bias, scale factor, misalignment, per axis; initial attitude,
velocity and position error, per component) is one *source*. Its unit response is
a column of the initial augmented state; the deterministic run is the sum of the
columns weighted by the signed magnitudes, and any other sign pattern or a
random-constant treatment is a different weighting of the same propagated columns
(superposition).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from inserr.core.imu import AXES, MISALIGNMENT_INDEX, MISALIGNMENTS, ImuErrors, InitialErrors
from inserr.model.psi_model import DR, DV, PSI, ErrorModel, Layout, position_angle

_ENU = ("e", "n", "u")


@dataclass(frozen=True)
class Source:
    """One constant error source.

    Attributes
    ----------
    name : str
        e.g. ``gyro_bias_x``, ``accel_misalignment_zy``, ``initial_attitude_u``.
    group : str
        ``gyro_bias``, ``accel_bias``, ``gyro_scale_factor``, ``gyro_misalignment``,
        ``accel_scale_factor``, ``accel_misalignment``, ``initial_attitude``,
        ``initial_velocity``, ``initial_position``.
    value : float
        Signed magnitude, SI (rad/s, m/s^2, dimensionless, rad, m/s, m).
    """

    name: str
    group: str
    value: float


def layout_for(imu: ImuErrors) -> Layout:
    """The smallest augmented layout that carries every error of ``imu``.

    Parameters
    ----------
    imu : ImuErrors
        The IMU error budget.

    Returns
    -------
    Layout
        Biases always; scale factor/misalignment and Gauss-Markov states only if
        ``imu`` has them.
    """
    return Layout(
        bias=True,
        scale_misalignment=imu.has_scale_misalignment,
        bias_instability=imu.has_bias_instability,
    )


def constant_sources(
    imu: ImuErrors, init: InitialErrors, vertical: str = "clamped"
) -> list[Source]:
    """All non-zero constant error sources, in a fixed order.

    Order: gyro bias, accelerometer bias, gyro scale factor, gyro misalignment,
    accelerometer scale factor, accelerometer misalignment (IMU axes x, y, z), then
    initial attitude, velocity and position (E, N, U).

    Parameters
    ----------
    imu : ImuErrors
        Constant IMU errors, SI, IMU frame.
    init : InitialErrors
        Initial attitude (rad), velocity (m/s) and position (m) errors, ENU.
    vertical : {"clamped", "free"}
        With ``"clamped"`` the vertical velocity and position errors are dropped.

    Returns
    -------
    list of Source
        One per non-zero component, value in SI.
    """
    out: list[Source] = []

    def add(group: str, labels, values) -> None:
        for lab, v in zip(labels, np.asarray(values, dtype=float), strict=True):
            if v != 0.0:
                out.append(Source(f"{group}_{lab}", group, float(v)))

    add("gyro_bias", AXES, imu.gyro_bias)
    add("accel_bias", AXES, imu.accel_bias)
    add("gyro_scale_factor", AXES, imu.gyro_scale_factor)
    add("gyro_misalignment", MISALIGNMENTS, imu.gyro_misalignment)
    add("accel_scale_factor", AXES, imu.accel_scale_factor)
    add("accel_misalignment", MISALIGNMENTS, imu.accel_misalignment)
    add("initial_attitude", _ENU, init.attitude)
    mask = np.array([1.0, 1.0, 0.0 if vertical == "clamped" else 1.0])
    add("initial_velocity", _ENU, init.velocity * mask)
    add("initial_position", _ENU, init.position * mask)
    return out


def unit_column(model: ErrorModel, source: Source, c_sn0: np.ndarray) -> np.ndarray:
    """Initial augmented state for a unit value (+1 SI) of ``source``.

    Parameters
    ----------
    model : ErrorModel
        Supplies the layout and the site (for the position-error angle).
    source : Source
        The error source; only its group and axis label are used, not its value.
    c_sn0 : (3, 3)
        IMU-to-navigation DCM ``C_s^n`` at t = 0: IMU-frame errors are resolved in n
        with it (``C_s^n e`` for biases, ``C_s^n K C_n^s`` for K matrices).

    Returns
    -------
    ndarray, shape (n,)
        Initial augmented state. An initial position error also sets
        ``psi = -dtheta`` so that the true attitude error ``phi`` stays zero.
    """
    lay = model.layout
    x = np.zeros(lay.n)
    group, lab = source.group, source.name.rsplit("_", 1)[1]
    if group in ("gyro_bias", "accel_bias"):
        e = np.zeros(3)
        e[AXES.index(lab)] = 1.0
        x[lay["eps" if group == "gyro_bias" else "nabla"]] = c_sn0 @ e
    elif group in (
        "gyro_scale_factor",
        "accel_scale_factor",
        "gyro_misalignment",
        "accel_misalignment",
    ):
        k = np.zeros((3, 3))
        if group.endswith("scale_factor"):
            i = AXES.index(lab)
            k[i, i] = 1.0
        else:
            k[MISALIGNMENT_INDEX[lab]] = 1.0
        x[lay["kg" if group.startswith("gyro") else "ka"]] = (c_sn0 @ k @ c_sn0.T).reshape(-1)
    elif group == "initial_attitude":
        # psi = phi - dtheta; with zero position error psi = phi.
        x[PSI][_ENU.index(lab)] = 1.0
    elif group == "initial_velocity":
        x[DV][_ENU.index(lab)] = 1.0
    elif group == "initial_position":
        dr = np.zeros(3)
        dr[_ENU.index(lab)] = 1.0
        x[DR] = dr
        x[PSI] = -position_angle(model.site, dr)  # phi unchanged: psi = phi - dtheta
    else:  # pragma: no cover - guarded by constant_sources
        raise ValueError(group)
    return x


def source_matrix(model: ErrorModel, sources: list[Source], c_sn0: np.ndarray) -> np.ndarray:
    """Unit columns of all sources side by side.

    Parameters
    ----------
    model : ErrorModel
    sources : list of Source
        N sources (e.g. from :func:`constant_sources`).
    c_sn0 : (3, 3)
        IMU-to-navigation DCM ``C_s^n`` at t = 0.

    Returns
    -------
    ndarray, shape (n, N)
        Column j is :func:`unit_column` of ``sources[j]`` (shape (n, 0) for none).
    """
    if not sources:
        return np.zeros((model.layout.n, 0))
    return np.column_stack([unit_column(model, s, c_sn0) for s in sources])


def source_set(model: ErrorModel, sources: list[Source]):
    """The sources as a :class:`~inserr.model.fast_propagation.SourceSet`.

    Parameters
    ----------
    model : ErrorModel
        Supplies the site (the position-error angle of an initial position error).
    sources : list of Source
        Constant error sources with their signed values (SI).

    Returns
    -------
    SourceSet
        IMU errors as (kind, i, j) in the IMU frame; initial errors as navigation states.
    """
    from inserr.model.fast_propagation import SourceSet

    n = len(sources)
    kind = np.full(n, -1)
    ii = np.zeros(n, dtype=int)
    jj = np.zeros(n, dtype=int)
    x0 = np.zeros((9, n))
    groups = {
        "gyro_bias": 0,
        "accel_bias": 1,
        "gyro_scale_factor": 2,
        "gyro_misalignment": 2,
        "accel_scale_factor": 3,
        "accel_misalignment": 3,
    }
    nav_model = ErrorModel(model.site, Layout(bias=False), vertical=model.vertical)
    for s, src in enumerate(sources):
        lab = src.name.rsplit("_", 1)[1]
        if src.group in groups:
            kind[s] = groups[src.group]
            if src.group.endswith("bias"):
                ii[s] = AXES.index(lab)
            elif src.group.endswith("scale_factor"):
                ii[s] = jj[s] = AXES.index(lab)
            else:
                ii[s], jj[s] = MISALIGNMENT_INDEX[lab]
        else:
            x0[:, s] = unit_column(nav_model, src, np.eye(3))[:9]
    return SourceSet(kind, ii, jj, x0, np.array([s.value for s in sources], dtype=float))
