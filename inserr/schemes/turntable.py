"""Turntable geometry and the piecewise table-angle history (the output of every scheme).

Gimbals. The outer (azimuth) axis is the body z axis; the inner axis is the x axis
of the outer gimbal (horizontal when the vehicle is level). With outer angle
``a`` (right hand about body z, i.e. counter-clockwise seen from above) and inner
angle ``b``::

    C_s^b = rot_z(a) @ rot_x(b) @ C_s^t

where ``C_s^t`` is the IMU mounting on the inner gimbal (identity by default; an
off-axis mounting is any other rotation). A single-axis table uses only ``a``.
With a level vehicle at heading H and no mounting offset, the IMU heading is
``H - a``.

A :class:`TableSchedule` is a list of segments, each a *stop*, a constant-rate
*rotation* of one gimbal, or a heading-*isolation* interval in which the outer
gimbal follows a closed-form law that holds the IMU heading fixed.
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from inserr.core.rotations import heading_of, rot_x, rot_z

GIMBALS = ("outer", "inner")


def table_dcm(a, b, mounting: np.ndarray | None = None) -> np.ndarray:
    """IMU-to-body DCM ``C_s^b = rot_z(a) @ rot_x(b) @ C_s^t`` of the table.

    Parameters
    ----------
    a : float or array_like
        Outer (azimuth) gimbal angle, rad, right hand about body z.
    b : float or array_like
        Inner gimbal angle, rad; broadcasts against ``a``.
    mounting : (3, 3) array, optional
        IMU mounting ``C_s^t`` on the inner gimbal (None = identity).

    Returns
    -------
    ndarray, shape (3, 3) or (..., 3, 3)
        ``C_s^b`` (IMU components to body right-front-up components).
    """
    a, b = np.broadcast_arrays(np.asarray(a, float), np.asarray(b, float))
    c = rot_z(a) @ rot_x(b)
    return c if mounting is None else c @ mounting


def gimbal_axis_b(gimbal: str, a: float) -> np.ndarray:
    """Unit rotation axis of a gimbal, resolved in the body frame.

    Parameters
    ----------
    gimbal : {"outer", "inner"}
        Which gimbal.
    a : float
        Outer gimbal angle, rad (only moves the inner axis).

    Returns
    -------
    ndarray, shape (3,)
        Body z for the outer gimbal, ``rot_z(a) @ e_x`` for the inner one.
    """
    if gimbal == "outer":
        return np.array([0.0, 0.0, 1.0])
    return np.array([math.cos(a), math.sin(a), 0.0])  # rot_z(a) @ e_x


def _yaxis_parts(b, mounting: np.ndarray | None):
    """Split ``rot_z(a) u`` with ``u = rot_x(b) C_s^t e_y`` as ``cos a p + sin a q + z``."""
    m = np.eye(3) if mounting is None else mounting
    u = rot_x(np.asarray(b, dtype=float)) @ (m @ np.array([0.0, 1.0, 0.0]))  # (..., 3)
    p = u * np.array([1.0, 1.0, 0.0])
    q = np.stack([-u[..., 1], u[..., 0], np.zeros_like(u[..., 0])], axis=-1)  # e_z x u
    z = u * np.array([0.0, 0.0, 1.0])
    return p, q, z


def imu_heading_offset(
    c_tilt: np.ndarray, a, b=0.0, mounting: np.ndarray | None = None
) -> np.ndarray:
    """Heading (rad) of the IMU y axis for a vehicle at heading 0 with attitude ``c_tilt``.

    For heading-only vehicle motion ``C_b^n(t) = rot_z(-H(t)) C_tilt``, so the IMU
    heading is ``H(t) + imu_heading_offset(C_tilt, a(t), b(t))``: only the gimbal
    angles need the 3-D geometry.

    Parameters
    ----------
    c_tilt : (3, 3) array
        ``C_b^n`` of the vehicle at heading 0 (:attr:`inserr.schemes.vehicle_motion.Motion.tilt`).
    a : float or array_like
        Outer gimbal angle(s), rad.
    b : float or array_like
        Inner gimbal angle(s), rad; broadcasts against ``a``.
    mounting : (3, 3) array, optional
        IMU mounting ``C_s^t`` (None = identity).

    Returns
    -------
    ndarray
        Heading offset, rad, clockwise from north, in [-pi, pi] (not wrapped to
        [0, 2 pi)); shape of ``a`` and ``b`` broadcast.
    """
    return _heading_offset(c_tilt, a, *_yaxis_parts(b, mounting))


def _heading_offset(c_tilt: np.ndarray, a, p, q, z) -> np.ndarray:
    """:func:`imu_heading_offset` from the parts of :func:`_yaxis_parts` (computed once)."""
    a = np.asarray(a, dtype=float)[..., None]
    v = (np.cos(a) * p + np.sin(a) * q + z) @ np.asarray(c_tilt).T
    return np.arctan2(v[..., 0], v[..., 1])


class OuterAxisHeading:
    """IMU heading offset of a single-axis table (inner angle 0) for one vehicle tilt and mounting.

    The IMU heading is ``H(t) + offset(a)`` (:func:`imu_heading_offset`). The
    closed-loop planners evaluate the offset for thousands of angles per run; this
    object does the set-up once and adds what they need besides the offset itself:
    its unit phasor in closed form and bounds of its slope.

    Parameters
    ----------
    c_tilt : (3, 3) array
        ``C_b^n`` of the vehicle at heading 0 (:attr:`Motion.tilt
        <inserr.schemes.vehicle_motion.Motion.tilt>`).
    mounting : (3, 3) array, optional
        IMU mounting ``C_s^t`` (None = identity).
    """

    def __init__(self, c_tilt: np.ndarray, mounting: np.ndarray | None = None):
        self.c_tilt = np.asarray(c_tilt, dtype=float)
        self._parts = _yaxis_parts(0.0, mounting)
        # The IMU y axis in n is C_tilt (cos a p + sin a q + z); as the complex number
        # north + i east it is cos a P + sin a Q + Z with P, Q, Z below, i.e.
        # e^{ia} (P - iQ) / 2 + e^{-ia} (P + iQ) / 2 + Z, and e^{i offset} is that over its modulus.
        p_, q_, z_ = (self.c_tilt @ v for v in self._parts)
        cp, cq, cz = (complex(v[1], v[0]) for v in (p_, q_, z_))
        self.coefficients = ((cp - 1j * cq) / 2, (cp + 1j * cq) / 2, cz)

    def offset(self, a) -> np.ndarray:
        """``imu_heading_offset(c_tilt, a, 0, mounting)``, rad, computed by the same operations."""
        return _heading_offset(self.c_tilt, a, *self._parts)

    def phasor(self, a) -> np.ndarray | complex:
        """``exp(i offset(a))`` in closed form (equal to it to round-off), scalars or arrays.

        Parameters
        ----------
        a : float or array_like
            Outer gimbal angle(s), rad.

        Returns
        -------
        complex or complex ndarray
            Unit phasor ``cos offset + i sin offset``.
        """
        up, um, c = self.coefficients
        if np.ndim(a) == 0:
            e = cmath.exp(1j * float(a))
            w = up * e + um / e + c
            return w / abs(w)
        e = np.exp(1j * np.asarray(a, dtype=float))
        w = up * e + um / e + c
        return w / np.abs(w)

    def _elevation_sine(self) -> tuple[float, float]:
        """``(s, sin theta)``: bound of ``|v_U|`` over all angles, sine of the outer axis' tilt."""
        k_up = float(self.c_tilt[2, 2])
        sin_tilt = math.sqrt(max(0.0, 1.0 - k_up * k_up))
        p, q, z = self._parts
        u_h, u_z = float(np.hypot(p[0], p[1])), abs(float(z[2]))
        return u_z * abs(k_up) + u_h * sin_tilt, sin_tilt

    def min_horizontal(self) -> float:
        """Lower bound of ``|north + i east|`` of the IMU y axis over all angles (0 to 1)."""
        s, _ = self._elevation_sine()
        return math.sqrt(max(0.0, 1.0 - s * s)) - 1e-12

    def curvature_bound(self) -> float:
        """Bound of ``|d^2 offset / d a^2|`` over all angles (inf if the y axis can be vertical).

        With the notation of :meth:`slope_bounds`, ``d offset / d a = -k_U + N / D``,
        ``N = v_U (k_h . v_h)``, ``D = |v_h|^2 = 1 - v_U^2``. Since ``v' = k x v``,
        ``|v_U'| <= sin theta`` and ``|(k_h . v_h)'| <= sin theta``; so ``|N| <= s sin
        theta``, ``|N'| <= sin^2 theta + s sin theta``, ``|D'| <= 2 s sin theta`` and
        ``|(N / D)'| <= |N'| / D + |N| |D'| / D^2`` with ``D >= 1 - s^2``.

        Returns
        -------
        float
            The bound, rad per rad^2.
        """
        s, sin_tilt = self._elevation_sine()
        if s >= 1.0:
            return math.inf
        d_min = 1.0 - s * s
        bound = (sin_tilt**2 + s * sin_tilt) / d_min + 2.0 * (s * sin_tilt) ** 2 / d_min**2
        return bound * (1.0 + 1e-12) + 1e-12  # a few ulp wider, for the computed values

    def slope_bounds(self) -> tuple[float, float]:
        """Bounds ``lo <= -d offset / d a <= hi`` over all angles (``lo > 0``: offset decreasing).

        Turning by ``da`` about the outer axis ``k`` (body z in n) moves the IMU y axis
        ``v`` by ``k x v da``, so ``d offset / d a = -k_U + v_U (k_h . v_h) / |v_h|^2``
        (ENU components, ``_h`` horizontal). With ``|k_h| = sin theta`` (theta the
        tilt of the outer axis) and ``|v_U| <= s = |u_z| cos theta + |u_h| sin theta``
        (``u`` the y axis in table coordinates), the second term is at most
        ``eps = s sin theta / sqrt(1 - s^2)`` in size; the bounds are ``k_U -+ eps``
        (infinite when ``s >= 1``: the y axis can point straight up).

        Returns
        -------
        lo, hi : float
            Bounds of ``-d offset / d a`` (dimensionless).
        """
        k_up = float(self.c_tilt[2, 2])
        s, sin_tilt = self._elevation_sine()
        if s >= 1.0:
            return -math.inf, math.inf
        eps = s * sin_tilt / math.sqrt(1.0 - s * s)
        # Widened by a few ulp so that the bounds hold for the computed values too.
        return k_up - eps - 1e-12, k_up + eps + 1e-12


def isolation_angle(c_bn: np.ndarray, b, mounting: np.ndarray | None, target) -> np.ndarray:
    """Outer angle that puts the IMU heading at ``target`` (rad) for body attitudes ``c_bn``.

    The IMU y axis in n is ``C_b^n rot_z(a) u`` with ``u = rot_x(b) C_s^t e_y``; its east
    and north components are linear in ``(cos a, sin a)``, so the angle that points
    it at heading H solves ``E cos H - N sin H = 0`` in closed form (the root with
    positive projection on the target direction).

    Parameters
    ----------
    c_bn : (..., 3, 3) array
        Vehicle attitude ``C_b^n`` (body right-front-up to ENU).
    b : float or array_like
        Inner gimbal angle(s), rad.
    mounting : (3, 3) array or None
        IMU mounting ``C_s^t`` (None = identity).
    target : float or array_like
        Wanted IMU heading, rad, clockwise from north.

    Returns
    -------
    ndarray, shape (...)
        Outer gimbal angle, rad, in [-2 pi, 2 pi] (not unwrapped; callers pick the
        branch).
    """
    b = np.asarray(b, dtype=float)
    if b.ndim and b.size and np.all(b == b.flat[0]):
        b = b.flat[0]  # one inner angle for every attitude (a single-axis table): its parts once
    p, q, z = _yaxis_parts(b, mounting)
    c_bn = np.asarray(c_bn, dtype=float)
    cp = np.einsum("...ij,...j->...i", c_bn, p)
    cq = np.einsum("...ij,...j->...i", c_bn, q)
    cz = np.einsum("...ij,...j->...i", c_bn, z)
    h = np.asarray(target, dtype=float)
    sh, ch = np.sin(h), np.cos(h)
    # E(a) cos H - N(a) sin H = A cos a + B sin a + C = 0
    a_ = cp[..., 0] * ch - cp[..., 1] * sh
    b_ = cq[..., 0] * ch - cq[..., 1] * sh
    c_ = cz[..., 0] * ch - cz[..., 1] * sh
    r = np.hypot(a_, b_)
    phase = np.arctan2(b_, a_)
    delta = np.arccos(np.clip(-c_ / np.where(r > 0, r, 1.0), -1.0, 1.0))
    cands = (phase + delta, phase - delta)
    proj = []
    for a in cands:
        v = np.cos(a)[..., None] * cp + np.sin(a)[..., None] * cq + cz
        proj.append(v[..., 0] * sh + v[..., 1] * ch)
    # Keep the root whose horizontal projection points along +target, not -target.
    return np.where(proj[0] >= proj[1], cands[0], cands[1])


@dataclass(frozen=True)
class TableSchedule:
    """Piecewise history of the gimbal angles.

    Attributes
    ----------
    t0 : (K,) s
        Segment start times (first is 0).
    duration : (K,) s
    kind : (K,) str
        ``"stop"``, ``"rotate"`` or ``"isolate"``.
    gimbal : (K,) str
        Moving gimbal of a rotation (``"outer"``/``"inner"``); ``""`` otherwise.
    rate : (K,) rad/s
        Signed gimbal rate of a rotation.
    a0, b0 : (K,) rad
        Outer and inner angles at the segment start.
    labels : (K,) str
        Segment labels for plots and reports.
    target_heading : (K,) rad
        IMU heading at the start of an isolation segment (NaN otherwise).
    target_rate : (K,) rad/s
        Rate of the IMU heading during an isolation segment (0 = held fixed;
        +-rate = an indexing turn performed with the yaw compensated).
    mounting : (3, 3) or None
        IMU mounting ``C_s^t`` on the inner gimbal.
    cycle : float or None
        Period of the open-loop cycle (s), None for closed-loop schedules.
    meta : dict
        Extra scheme information (e.g. ``isolation_reversals``); not compared.
    """

    t0: np.ndarray
    duration: np.ndarray
    kind: tuple[str, ...]
    gimbal: tuple[str, ...]
    rate: np.ndarray
    a0: np.ndarray
    b0: np.ndarray
    labels: tuple[str, ...]
    target_heading: np.ndarray
    target_rate: np.ndarray
    mounting: np.ndarray | None = None
    cycle: float | None = None
    meta: dict = field(default_factory=dict, compare=False)

    @property
    def end(self) -> float:
        """End time of the last segment, s."""
        return float(self.t0[-1] + self.duration[-1])

    def __len__(self) -> int:
        return len(self.t0)

    def motor_starts(self) -> int:
        """Number of times the table motor starts (a rotation after a stop, or a reversal).

        Isolation segments count one start per reversal of the compensating rate
        (recorded by the scheme in ``meta["isolation_reversals"]``) plus one when
        entered from a stop.

        Returns
        -------
        int
        """
        n = 0
        prev_kind, prev_sign = "stop", 0.0
        for k, r in zip(self.kind, self.rate, strict=True):
            sign = float(np.sign(r))
            if k == "rotate" and (prev_kind != "rotate" or sign != prev_sign):
                n += 1
            if k == "isolate" and prev_kind == "stop":
                n += 1
            prev_kind, prev_sign = k, sign
        return n + int(self.meta.get("isolation_reversals", 0))

    @cached_property
    def _outer(self) -> np.ndarray:
        """Per segment: whether the outer gimbal moves (kept: angles_at runs often)."""
        return np.array([g == "outer" for g in self.gimbal], dtype=bool)

    @cached_property
    def _isolate(self) -> np.ndarray:
        """Per segment: whether it is an isolation segment."""
        return np.array([kd == "isolate" for kd in self.kind], dtype=bool)

    def angles_at(self, t: np.ndarray, motion=None) -> tuple[np.ndarray, np.ndarray]:
        """Outer and inner gimbal angles at given times.

        Parameters
        ----------
        t : float or array_like
            Times, s, from the start of the schedule (angles hold after the end).
        motion : Motion, optional
            Vehicle motion; required if an isolation segment is sampled.

        Returns
        -------
        a, b : ndarray, shape (len(t),)
            Outer and inner angles, rad (continuous, not wrapped).

        Raises
        ------
        ValueError
            If an isolation segment is sampled without ``motion``.
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        k = np.clip(np.searchsorted(self.t0, t, side="right") - 1, 0, len(self.t0) - 1)
        tau = np.minimum(t - self.t0[k], self.duration[k])
        rate = self.rate[k]
        outer = self._outer[k]
        a = self.a0[k] + np.where(outer, rate * tau, 0.0)
        b = self.b0[k] + np.where(~outer, rate * tau, 0.0)
        iso = self._isolate[k]
        if np.any(iso):
            if motion is None:
                raise ValueError("isolation segments need the vehicle motion")
            ti = t[iso]
            target = self.target_heading[k[iso]] + self.target_rate[k[iso]] * tau[iso]
            a_iso = isolation_angle(motion.attitude(ti), self.b0[k[iso]], self.mounting, target)
            # Branch: for a level vehicle the angle is exactly a0 + d(heading) - d(target);
            # tilt only perturbs it slightly, so the nearest branch to that is the right one.
            ref = (
                self.a0[k[iso]]
                + motion.heading_at(ti)
                - motion.heading_at(self.t0[k[iso]])
                - self.target_rate[k[iso]] * tau[iso]
            )
            a[iso] = ref + np.angle(np.exp(1j * (a_iso - ref)))
        return a, b

    def dcm_at(self, t: np.ndarray, motion=None) -> np.ndarray:
        """IMU-to-body DCM ``C_s^b`` at given times (:func:`table_dcm`).

        Parameters
        ----------
        t : float or array_like
            Times, s.
        motion : Motion, optional
            Vehicle motion; required for isolation segments.

        Returns
        -------
        ndarray, shape (len(t), 3, 3)
        """
        a, b = self.angles_at(t, motion)
        return table_dcm(a, b, self.mounting)

    def imu_heading(self, t: np.ndarray, motion) -> np.ndarray:
        """Heading of the IMU y axis, ``heading_of(C_b^n C_s^b)``, at given times.

        Parameters
        ----------
        t : float or array_like
            Times, s.
        motion : Motion
            Vehicle motion giving ``C_b^n(t)``.

        Returns
        -------
        ndarray, shape (len(t),)
            IMU heading, rad, clockwise from north, in [0, 2 pi).
        """
        return heading_of(motion.attitude(t) @ self.dcm_at(t, motion))


class ScheduleBuilder:
    """Accumulates segments; used by every scheme so none writes its own bookkeeping.

    Parameters
    ----------
    a0, b0 : float
        Outer and inner gimbal angles at t = 0, rad.
    mounting : (3, 3) array, optional
        IMU mounting ``C_s^t`` on the inner gimbal (None = identity).

    Attributes
    ----------
    t : float
        End time of the segments added so far, s.
    a, b : float
        Current outer and inner angles, rad.
    meta : dict
        Copied into :attr:`TableSchedule.meta` by :meth:`build`.
    """

    def __init__(self, a0: float = 0.0, b0: float = 0.0, mounting: np.ndarray | None = None):
        self.t = 0.0
        self.a = a0
        self.b = b0
        self.mounting = mounting
        self._rows: list[tuple] = []
        self.meta: dict = {}

    def stop(self, duration: float, label: str = "stop") -> None:
        """Append a stop: hold both gimbals (skipped if ``duration`` is not positive).

        Parameters
        ----------
        duration : float
            Stop duration, s.
        label : str
            Segment label.
        """
        if duration > 0:
            self._rows.append(
                (self.t, duration, "stop", "", 0.0, self.a, self.b, label, math.nan, 0.0)
            )
            self.t += duration

    def rotate(self, gimbal: str, angle: float, rate: float, label: str | None = None) -> None:
        """Append a constant-rate turn of one gimbal (skipped if ``angle`` is zero).

        Parameters
        ----------
        gimbal : {"outer", "inner"}
            The gimbal that turns.
        angle : float
            Signed turn, rad, right hand about the gimbal axis.
        rate : float
            Gimbal rate, rad/s; only ``|rate|`` is used, the sign follows ``angle``.
        label : str, optional
            Segment label (default ``"rotate <gimbal> <angle> deg"``).
        """
        if angle == 0:
            return
        rate = abs(rate) * math.copysign(1.0, angle)
        dur = angle / rate
        lab = label or f"rotate {gimbal} {math.degrees(angle):+g} deg"
        self._rows.append((self.t, dur, "rotate", gimbal, rate, self.a, self.b, lab, math.nan, 0.0))
        self.t += dur
        if gimbal == "outer":
            self.a += angle
        else:
            self.b += angle

    def isolate(
        self,
        duration: float,
        target: float,
        a_start: float,
        a_end: float,
        target_rate: float = 0.0,
        label: str = "isolate",
    ) -> None:
        """Steer the IMU heading along ``target + target_rate * tau`` for ``duration`` s.

        The outer gimbal follows the vehicle yaw in closed form
        (:func:`isolation_angle`); nothing is added if ``duration`` is not positive.

        Parameters
        ----------
        duration : float
            Segment duration, s.
        target : float
            IMU heading at the segment start, rad, clockwise from north.
        a_start, a_end : float
            Outer gimbal angle at the start and at the end of the segment, rad.
        target_rate : float
            Rate of the IMU heading during the segment, rad/s (0 = held fixed).
        label : str
            Segment label.
        """
        if duration > 0:
            self._rows.append(
                (
                    self.t,
                    duration,
                    "isolate",
                    "outer",
                    0.0,
                    a_start,
                    self.b,
                    label,
                    target,
                    target_rate,
                )
            )
            self.t += duration
            self.a = a_end

    def build(self, cycle: float | None = None) -> TableSchedule:
        """The finished :class:`TableSchedule`.

        Parameters
        ----------
        cycle : float, optional
            Period of the open-loop cycle, s (None for closed-loop schedules).

        Returns
        -------
        TableSchedule

        Raises
        ------
        ValueError
            If no segment was added.
        """
        if not self._rows:
            raise ValueError("empty schedule")
        cols = list(zip(*self._rows, strict=True))
        return TableSchedule(
            t0=np.array(cols[0], float),
            duration=np.array(cols[1], float),
            kind=tuple(cols[2]),
            gimbal=tuple(cols[3]),
            rate=np.array(cols[4], float),
            a0=np.array(cols[5], float),
            b0=np.array(cols[6], float),
            labels=tuple(cols[7]),
            target_heading=np.array(cols[8], float),
            target_rate=np.array(cols[9], float),
            mounting=self.mounting,
            cycle=cycle,
            meta=dict(self.meta),
        )
