"""The IMU attitude history seen by the error model: constant-angular-velocity intervals.

A :class:`Timeline` is what schemes and vehicle motions (``inserr.schemes.composition``) hand
to the propagation engine: node times ``t_0 = 0 < t_1 < ... < t_K``, the exact IMU
attitude ``C_s^n`` at every node, and in each interval the constant angular velocity
``w_k`` (of s relative to n, resolved in n, rad/s) that carries ``C_s^n(t_k)`` into
``C_s^n(t_{k+1}) = expm(dt_k [w_k x]) C_s^n(t_k)``.

Stops and constant-rate rotations about one axis are represented exactly by one
interval each. Continuous motion (a swinging vehicle) is cut into sub-steps whose
angular velocity is the geodesic one between exact nodes, so node attitudes are
exact and the path between nodes is the shortest rotation.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from inserr.core.errors import InputError
from inserr.core.rotations import skew


@dataclass(frozen=True)
class Timeline:
    """Piecewise-constant-angular-velocity attitude history of the IMU.

    Parameters
    ----------
    times : (K+1,) s
        Node times, strictly increasing, starting at 0.
    c_sn : (K+1, 3, 3)
        IMU-to-navigation DCM at every node.
    omega_n : (K, 3) rad/s
        Angular velocity of s relative to n, resolved in n, in each interval.
    labels : (K,) str, optional
        What each interval is ("stop A", "rotate +180", "swing", ...).
    motor_starts : int
        Table motor starts over the run (from the scheme).
    meta : dict
        The table schedule and vehicle motion it was built from, for plots.
    """

    times: np.ndarray
    c_sn: np.ndarray
    omega_n: np.ndarray
    labels: tuple[str, ...] = ()
    motor_starts: int = 0
    meta: dict = field(default_factory=dict, compare=False)

    def __post_init__(self) -> None:
        t = np.asarray(self.times, dtype=float)
        c = np.asarray(self.c_sn, dtype=float)
        w = np.asarray(self.omega_n, dtype=float).reshape(-1, 3)
        if t.ndim != 1 or len(t) < 2 or t[0] != 0.0 or np.any(np.diff(t) <= 0):
            raise InputError("timeline.times", "node times must start at 0 and increase")
        if c.shape != (len(t), 3, 3) or w.shape != (len(t) - 1, 3):
            raise InputError("timeline", "c_sn must be (K+1, 3, 3) and omega_n (K, 3)")
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "c_sn", c)
        object.__setattr__(self, "omega_n", w)
        if not self.labels:
            object.__setattr__(self, "labels", ("",) * (len(t) - 1))

    @property
    def duration(self) -> float:
        """Total duration, s."""
        return float(self.times[-1])

    @classmethod
    def static(cls, c_sn: np.ndarray, duration: float, label: str = "static") -> Timeline:
        """A single stop of ``duration`` seconds with constant ``C_s^n``."""
        c = np.asarray(c_sn, dtype=float)
        return cls(np.array([0.0, duration]), np.stack([c, c]), np.zeros((1, 3)), (label,))

    def attitude_at(self, t: np.ndarray) -> np.ndarray:
        """``C_s^n`` at arbitrary times (s), exact along each interval; (len(t), 3, 3)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        k = np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, len(self.omega_n) - 1)
        w = self.omega_n[k]
        rate = np.linalg.norm(w, axis=1)
        axis = np.where(rate[:, None] > 0, w / np.where(rate > 0, rate, 1.0)[:, None], [0, 0, 1.0])
        ang = (rate * (t - self.times[k]))[:, None, None]
        kx = skew(axis)
        rot = np.eye(3) + np.sin(ang) * kx + (1.0 - np.cos(ang)) * (kx @ kx)
        return rot @ self.c_sn[k]

    def interval_index(self, t: np.ndarray) -> np.ndarray:
        """Index of the interval containing each time (right-continuous)."""
        return np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, len(self.omega_n) - 1)
