"""Rotation matrices (DCMs), Euler angles in the ENU convention, exp and log maps.

Conventions (stated once, tested in ``tests/test_rotations.py``):

* A DCM ``C_a^b`` maps vector components in frame a to frame b: ``v^b = C_a^b v^a``.
* ``rot_x/rot_y/rot_z(angle)`` are the DCMs ``C_b^a`` of a frame b obtained by
  turning frame a by ``+angle`` (right hand) about the given axis, i.e. the matrix
  that maps b-components to a-components: ``rot_z(a) @ [1,0,0]`` is the new x axis
  in old components. In other words ``rot_z(a) = expm(a [e_z x])``.
* Body frame b is right-front-up (x right, y forward, z up). Heading (yaw) is
  measured clockwise from north, so a heading rate is a rotation about the ENU up
  axis by ``-heading``. Pitch is about body x (nose up positive), roll about body y
  (right wing down positive).
* ``C_b^n = rot_z(-heading) @ rot_x(pitch) @ rot_y(roll)`` (the "312" sequence
  common in Chinese and PSINS literature, with ENU / right-front-up frames).
"""

from __future__ import annotations

import numpy as np


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrix ``[v x]`` such that ``skew(v) @ w == np.cross(v, w)``.

    Parameters
    ----------
    v : array_like, shape (3,) or (..., 3)
        Vector(s), any units, any frame.

    Returns
    -------
    ndarray, shape (3, 3) or (..., 3, 3)
        Skew-symmetric matrix (matrices) in the same units and frame as ``v``.
    """
    v = np.asarray(v, dtype=float)
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1] = -v[..., 2]
    out[..., 0, 2] = v[..., 1]
    out[..., 1, 0] = v[..., 2]
    out[..., 1, 2] = -v[..., 0]
    out[..., 2, 0] = -v[..., 1]
    out[..., 2, 1] = v[..., 0]
    return out


def rot_axis(axis: np.ndarray, angle) -> np.ndarray:
    """DCM ``expm(angle [axis x])`` (Rodrigues) of a right-hand turn about ``axis``.

    Parameters
    ----------
    axis : array_like, shape (3,)
        Rotation axis; must already be a unit vector (it is not normalised).
    angle : float or array_like, shape (...)
        Rotation angle, rad, right hand about ``axis``.

    Returns
    -------
    ndarray, shape (3, 3) for a scalar angle, (..., 3, 3) for an array of angles
        ``C_b^a`` of the turned frame b relative to a (module conventions).
    """
    axis = np.asarray(axis, dtype=float)
    angle = np.asarray(angle, dtype=float)
    k = skew(axis)
    s = np.sin(angle)[..., None, None]
    c = np.cos(angle)[..., None, None]
    return np.eye(3) + s * k + (1.0 - c) * (k @ k)


def _axis_turn(angle, i: int, j: int) -> np.ndarray:
    """``expm(angle [e_k x])`` for the axis k with (i, j, k) cyclic: ``C[i, i] = C[j, j] =
    cos``, ``C[j, i] = sin = -C[i, j]``, ``C[k, k] = 1`` (:func:`rot_axis` for a
    coordinate axis, built from one sine and cosine per angle)."""
    angle = np.asarray(angle, dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros(angle.shape + (3, 3))
    k = 3 - i - j
    out[..., k, k] = 1.0
    out[..., i, i] = c
    out[..., j, j] = c
    out[..., j, i] = s
    out[..., i, j] = -s
    return out


def rot_z_times(angle, m: np.ndarray) -> np.ndarray:
    """``rot_z(angle) @ m`` for (N,) angles and one (3, 3) ``m``, row by row (no matrix
    product per angle): rows ``c m0 - s m1``, ``s m0 + c m1``, ``m2``. Shape (N, 3, 3)."""
    angle = np.asarray(angle, dtype=float)
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
    m = np.asarray(m, dtype=float)
    out = np.empty((len(angle), 3, 3))
    out[:, 0] = c * m[0] - s * m[1]
    out[:, 1] = s * m[0] + c * m[1]
    out[:, 2] = m[2]
    return out


def rot_x(angle) -> np.ndarray:
    """DCM of a right-hand turn by ``angle`` about the x axis; see module conventions.

    Parameters
    ----------
    angle : float or array_like, shape (...)
        Rotation angle, rad.

    Returns
    -------
    ndarray, shape (3, 3) or (..., 3, 3)
        ``expm(angle [e_x x])``: maps turned-frame components to original-frame ones.
    """
    return _axis_turn(angle, 1, 2)


def rot_y(angle) -> np.ndarray:
    """DCM of a right-hand turn by ``angle`` about the y axis; see module conventions.

    Parameters
    ----------
    angle : float or array_like, shape (...)
        Rotation angle, rad.

    Returns
    -------
    ndarray, shape (3, 3) or (..., 3, 3)
        ``expm(angle [e_y x])``: maps turned-frame components to original-frame ones.
    """
    return _axis_turn(angle, 2, 0)


def rot_z(angle) -> np.ndarray:
    """DCM of a right-hand turn by ``angle`` about the z axis; see module conventions.

    Parameters
    ----------
    angle : float or array_like, shape (...)
        Rotation angle, rad.

    Returns
    -------
    ndarray, shape (3, 3) or (..., 3, 3)
        ``expm(angle [e_z x])``: maps turned-frame components to original-frame ones.
    """
    return _axis_turn(angle, 0, 1)


def body_to_nav(heading, pitch, roll) -> np.ndarray:
    """Body-to-navigation DCM ``C_b^n`` from heading, pitch and roll.

    Body frame right-front-up, navigation frame ENU; ``C_b^n = rot_z(-heading) @
    rot_x(pitch) @ rot_y(roll)``. The three angles broadcast against each other.

    Parameters
    ----------
    heading : float or array_like
        Heading, rad, clockwise from north (of the body y axis).
    pitch : float or array_like
        Pitch, rad, about body x, nose up positive.
    roll : float or array_like
        Roll, rad, about body y, right wing down positive.

    Returns
    -------
    ndarray, shape (3, 3) or (..., 3, 3)
        ``C_b^n`` (maps body components to ENU components).
    """
    heading, pitch, roll = np.broadcast_arrays(
        np.asarray(heading, float), np.asarray(pitch, float), np.asarray(roll, float)
    )
    return rot_z(-heading) @ rot_x(pitch) @ rot_y(roll)


def euler_from_dcm(c_bn: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Heading, pitch and roll of a body attitude: the inverse of :func:`body_to_nav`.

    Parameters
    ----------
    c_bn : array_like, shape (3, 3) or (..., 3, 3)
        Body-to-ENU DCM ``C_b^n``.

    Returns
    -------
    heading : ndarray, shape (...)
        Heading, rad, clockwise from north, in [0, 2 pi).
    pitch : ndarray, shape (...)
        Pitch, rad, in [-pi/2, pi/2].
    roll : ndarray, shape (...)
        Roll, rad, in [-pi, pi] (``arctan2`` range).
    """
    c = np.asarray(c_bn, dtype=float)
    pitch = np.arcsin(np.clip(c[..., 2, 1], -1.0, 1.0))
    roll = np.arctan2(-c[..., 2, 0], c[..., 2, 2])
    heading = np.mod(np.arctan2(c[..., 0, 1], c[..., 1, 1]), 2.0 * np.pi)
    return heading, pitch, roll


def heading_of(c_sn: np.ndarray) -> np.ndarray:
    """Heading of a frame's y axis projected onto the local level plane.

    Parameters
    ----------
    c_sn : array_like, shape (3, 3) or (..., 3, 3)
        DCM from the frame (IMU s or body b) to ENU, e.g. ``C_s^n``.

    Returns
    -------
    ndarray, shape (...)
        Heading, rad, clockwise from north, in [0, 2 pi).
    """
    c = np.asarray(c_sn, dtype=float)
    return np.mod(np.arctan2(c[..., 0, 1], c[..., 1, 1]), 2.0 * np.pi)


def log_so3(c: np.ndarray) -> np.ndarray:
    """Rotation vector ``phi`` of a DCM: the inverse of ``rot_axis(phi/|phi|, |phi|)``.

    Accurate for angles up to just below pi, which is all the schedule needs (a
    rotation over one sub-step is a few degrees at most).

    Parameters
    ----------
    c : array_like, shape (3, 3) or (..., 3, 3)
        Rotation matrix (matrices).

    Returns
    -------
    ndarray, shape (3,) or (..., 3)
        Rotation vector, rad, with ``c = expm([phi x])`` (an eigen-axis of ``c``:
        ``c @ phi == phi``; for ``C_{k+1} C_k^T`` of two ``C_s^n`` it is ENU-resolved).
    """
    c = np.asarray(c, dtype=float)
    w = 0.5 * np.stack(
        [c[..., 2, 1] - c[..., 1, 2], c[..., 0, 2] - c[..., 2, 0], c[..., 1, 0] - c[..., 0, 1]],
        axis=-1,
    )
    s = np.linalg.norm(w, axis=-1)
    cos = 0.5 * (np.trace(c, axis1=-2, axis2=-1) - 1.0)
    angle = np.arctan2(s, cos)
    small = s < 1e-12
    factor = np.where(small, 1.0 + angle**2 / 6.0, angle / np.where(small, 1.0, s))
    return w * factor[..., None]
