"""The IMU attitude history as the fast engine reads it: smooth pieces, evaluated anywhere.

The navigation-error dynamics at a fixed site are time-invariant; the IMU attitude
``C_s^n(t)`` and its angular velocity ``w_ns^n(t)`` (IMU relative to n, resolved in n)
enter only through the input. :mod:`inserr.model.fast_propagation` therefore needs
the history in one form: a list of *pieces* inside which the attitude is an analytic
function of time (a stop, a constant-rate turn, a stretch of a yaw swing), a bound
on how fast it turns there (which sets the quadrature), and the attitude and rate at
any instants of a piece.

Two implementations:

* :class:`TimelineHistory` reads a :class:`~inserr.model.timeline.Timeline`
  (constant angular velocity per interval, exactly the model of the step-by-step
  engine :mod:`inserr.model.exact_propagation`): the two engines then solve the same
  problem, which is how the fast one is tested;
* :class:`inserr.schemes.composition.ScheduleHistory` composes a table schedule and
  a vehicle motion exactly (no sub-steps): the engine integrates the true continuous
  motion.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from inserr.core.rotations import skew
from inserr.model.timeline import Timeline


@dataclass(frozen=True)
class Pieces:
    """Where an attitude history is smooth, and how fast it turns there.

    Attributes
    ----------
    breaks : (P+1,) s
        Increasing piece boundaries, from 0 to the duration.
    bandwidth : (P,) rad/s
        Upper bound on the angular frequencies in ``C_s^n(t)`` inside each piece (for a
        constant-rate piece its rate; for a yaw swing the peak yaw rate plus the swing
        frequency). Products of two attitude matrices have twice this.
    still : (P,) bool
        True where ``C_s^n`` is constant (``w_ns^n = 0``): the input is constant there.
    table : (P, 3, 3) or None
        Where the history is a vehicle motion seen through a *fixed* turntable, the
        table's ``C_s^b`` (so ``C_s^n = C_b^n(t) C_s^b``); NaN where the table moves; None
        when the history has no such structure.
    constant : (P,) bool or None
        True where ``C_s^n`` turns at a *constant* angular velocity (a table turn on a
        still vehicle, a stop on a steadily turning one, every interval of a
        timeline): the input is then a trigonometric polynomial in time and its
        integrals have closed forms. None means nowhere (besides ``still``).
    vehicle_period : float or None
        Period of the vehicle attitude ``C_b^n(t)``, s, if it repeats (a yaw swing, a
        steady turn); with ``phase_class`` it lets the engine integrate the vehicle
        part once per phase.
    phase_class : (P,) int or None
        Pieces whose attitude is a function of the vehicle phase alone: 0 for the
        vehicle seen through the fixed table ``table`` (the engine reuses
        :meth:`AttitudeHistory.evaluate_vehicle`), ``k >= 1`` for pieces that are
        identical functions of the phase within class k (e.g. heading-isolation holds
        of one target heading), -1 otherwise.
    """

    breaks: np.ndarray
    bandwidth: np.ndarray
    still: np.ndarray
    table: np.ndarray | None = None
    vehicle_period: float | None = None
    constant: np.ndarray | None = None
    phase_class: np.ndarray | None = None


class AttitudeHistory(Protocol):
    """What the fast engine needs of an IMU attitude history (see the module docstring)."""

    @property
    def duration(self) -> float:
        """Length of the history, s."""
        ...

    def pieces(self) -> Pieces:
        """The smooth pieces (:class:`Pieces`)."""
        ...

    def evaluate(self, t: np.ndarray, piece: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``C_s^n`` (N, 3, 3) and ``w_ns^n`` (N, 3, rad/s, ENU) at times ``t`` (s).

        ``piece`` (N,) names the piece of each time: a time on a boundary takes the
        rate of the named piece.
        """
        ...

    def evaluate_vehicle(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``C_b^n`` (N, 3, 3) and ``w_nb^n`` (N, 3) of the vehicle alone (with ``table``)."""
        ...


@dataclass(frozen=True)
class TimelineHistory:
    """A :class:`~inserr.model.timeline.Timeline` as an attitude history (one piece per interval).

    Parameters
    ----------
    timeline : Timeline
        Node attitudes and constant angular velocity per interval.
    """

    timeline: Timeline

    @property
    def duration(self) -> float:
        """Length of the timeline, s."""
        return self.timeline.duration

    def pieces(self) -> Pieces:
        """One piece per interval; bandwidth ``|w_k|``; still where ``w_k = 0``; constant rate."""
        rate = np.linalg.norm(self.timeline.omega_n, axis=1)
        return Pieces(self.timeline.times, rate, rate == 0.0, constant=np.ones(len(rate), bool))

    def evaluate(self, t: np.ndarray, piece: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Rodrigues rotation of the interval's start attitude; its constant rate."""
        tl = self.timeline
        t = np.asarray(t, dtype=float)
        k = np.asarray(piece)
        w = tl.omega_n[k]
        rate = np.linalg.norm(w, axis=1)
        axis = w / np.where(rate > 0, rate, 1.0)[:, None]
        ang = (rate * (t - tl.times[k]))[:, None, None]
        kx = skew(axis)
        rot = np.eye(3) + np.sin(ang) * kx + (1.0 - np.cos(ang)) * (kx @ kx)
        return rot @ tl.c_sn[k], w
