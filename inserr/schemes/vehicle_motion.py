"""Vehicle motions at a fixed site: static, yaw swing, constant-rate turn, heading history.

A motion gives the body attitude ``C_b^n(t)`` (body right-front-up, n = ENU) and the
body angular velocity relative to n, ``w_nb^n(t)`` (rad/s, resolved in n). Only the
heading moves; pitch and roll are constant and the IMU sits at the centre of
rotation (no lever arm), so the specific force stays ``[0, 0, g]`` and the
position stays fixed: a moored ship yawing, a vehicle turning on the spot, a
swinging-base test stand. Heading is clockwise from north, so a heading rate
``r`` is the angular velocity ``[0, 0, -r]`` in ENU.

That is inserr's *internal* sense. A scenario may declare its headings and heading
rates counter-clockwise from north instead (``motion.heading_convention``,
:data:`HEADING_CONVENTIONS`); the scenario layer turns them into this sense
(:func:`heading_sign`) before a motion is built, and :meth:`Motion.describe` writes
them back in the declared sense. Nothing else in inserr sees the convention.

Each motion also says where it is *piecewise constant-rate* (so the schedule can
use exact single intervals) via :meth:`Motion.pieces`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from inserr.core.errors import InputError, require_finite
from inserr.core.rotations import body_to_nav, rot_z_times

#: The senses in which a scenario may give headings, heading rates, yaw swings, heading
#: histories and the IMU mounting heading (``motion.heading_convention``); the first is
#: inserr's internal sense and the default.
HEADING_CONVENTIONS = ("clockwise-from-north", "counter-clockwise-from-north")


def heading_sign(convention: str) -> float:
    """Factor from a heading (or heading rate) in ``convention`` to inserr's internal sense.

    Parameters
    ----------
    convention : str
        One of :data:`HEADING_CONVENTIONS`.

    Returns
    -------
    float
        +1 for ``"clockwise-from-north"``, -1 for ``"counter-clockwise-from-north"``
        (its own inverse: the same factor converts back).

    Raises
    ------
    InputError
        For any other name.
    """
    if convention == HEADING_CONVENTIONS[0]:
        return 1.0
    if convention == HEADING_CONVENTIONS[1]:
        return -1.0
    raise InputError(
        "motion.heading_convention",
        f"unknown convention {convention!r}",
        f"use one of: {', '.join(HEADING_CONVENTIONS)}",
    )


@dataclass(frozen=True)
class Motion:
    """Base class and static motion: constant pitch and roll, heading ``heading_at(t)``.

    Parameters
    ----------
    heading : float, rad
        Initial heading of the body y (forward) axis, clockwise from north.
    pitch : float, rad
        Pitch about body x, nose up positive; within (-pi/2, pi/2).
    roll : float, rad
        Roll about body y, right wing down positive.

    Attributes
    ----------
    name : str
        Short label of the motion kind (class attribute: ``"static"`` here).
    """

    heading: float = 0.0
    pitch: float = 0.0
    roll: float = 0.0

    def __post_init__(self) -> None:
        for name in ("heading", "pitch", "roll"):
            require_finite(getattr(self, name), name)
        if abs(self.pitch) >= math.pi / 2:
            raise InputError("pitch", "must be within (-90, 90) deg")

    name = "static"

    def heading_at(self, t: np.ndarray) -> np.ndarray:
        """Heading of the body at given times.

        Parameters
        ----------
        t : float or array_like
            Times, s, from the start of the run.

        Returns
        -------
        ndarray, shape of ``t``
            Heading, rad, clockwise from north (unwrapped).
        """
        return np.full(np.shape(t), self.heading, dtype=float)

    def heading_rate(self, t: np.ndarray) -> np.ndarray:
        """Heading rate of the body at given times.

        Parameters
        ----------
        t : float or array_like
            Times, s, from the start of the run.

        Returns
        -------
        ndarray, shape of ``t``
            Heading rate, rad/s, clockwise positive.
        """
        return np.zeros(np.shape(t))

    @property
    def tilt(self) -> np.ndarray:
        """``C_b^n`` (3, 3) at heading 0: every motion here is ``rot_z(-H(t)) @ tilt``."""
        return body_to_nav(0.0, self.pitch, self.roll)

    def attitude(self, t: np.ndarray) -> np.ndarray:
        """Body attitude ``C_b^n`` (body right-front-up to ENU) at given times.

        Parameters
        ----------
        t : float or array_like
            Times, s, from the start of the run.

        Returns
        -------
        ndarray, shape (len(t), 3, 3)
            ``C_b^n``; a scalar ``t`` counts as one time.
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        return rot_z_times(-self.heading_at(t).ravel(), self.tilt).reshape(t.shape + (3, 3))

    def rate_n(self, t: np.ndarray) -> np.ndarray:
        """Body angular velocity relative to n, ``w_nb^n = [0, 0, -heading_rate]``.

        Parameters
        ----------
        t : float or array_like
            Times, s, from the start of the run.

        Returns
        -------
        ndarray, shape (len(t), 3)
            Angular velocity of b relative to n, resolved in ENU, rad/s.
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        out = np.zeros((len(t), 3))
        out[:, 2] = -self.heading_rate(t)
        return out

    def pieces(self, duration: float) -> tuple[np.ndarray, bool]:
        """Breakpoints of the motion and whether its rate is constant between them.

        Parameters
        ----------
        duration : float
            Length of the run, s.

        Returns
        -------
        breaks : ndarray, shape (P,)
            Increasing times in [0, duration], s, starting at 0 and ending at ``duration``.
        constant : bool
            True if the heading rate is constant between consecutive breakpoints (so
            each piece is one exact constant-rate interval).
        """
        return np.array([0.0, duration]), True

    @property
    def is_static(self) -> bool:
        """True if the heading never changes."""
        return True

    def rate_bound(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Bound on the angular frequencies of the body attitude over each ``[a_i, b_i]``.

        The fast engine (:mod:`inserr.model.fast_propagation`) sizes its quadrature with
        it: the heading rate for a constant-rate motion, the peak rate plus the swing
        frequency for a yaw swing.

        Parameters
        ----------
        a, b : (P,) arrays, s
            Interval ends.

        Returns
        -------
        ndarray, shape (P,)
            rad/s (zero for a static base).
        """
        return np.zeros(np.shape(a))

    def constant_rate(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Whether the heading rate is constant over each ``[a_i, b_i]`` (bool array).

        True for a static base, a steady turn, and a heading history between samples.
        """
        return np.ones(np.shape(a), dtype=bool)

    def repeat_period(self) -> float | None:
        """Period after which the body attitude repeats exactly, s (None if it never does).

        The fast engine reuses its quadrature of the vehicle part from one period to
        the next. A static base returns None (its attitude is constant: nothing to reuse).
        """
        return None

    def describe(self, convention: str = HEADING_CONVENTIONS[0]) -> str:
        """One-line human description, angles in degrees.

        Parameters
        ----------
        convention : str
            Sense in which headings and heading rates are written
            (:data:`HEADING_CONVENTIONS`; the scenario's ``motion.heading_convention``).
        """
        k = heading_sign(convention)
        return (
            f"static, heading {math.degrees(k * self.heading):g} deg, "
            f"pitch {math.degrees(self.pitch):g} deg, "
            f"roll {math.degrees(self.roll):g} deg"
        )


Static = Motion


@dataclass(frozen=True)
class YawSwing(Motion):
    """Heading rate ``A cos(2 pi t / T)``: heading ``psi0 + A T / (2 pi) sin(2 pi t / T)``.

    ``psi0`` is the inherited ``heading``; ``pitch`` and ``roll`` as in :class:`Motion`.

    Parameters
    ----------
    amplitude : float, rad/s
        Peak heading rate A (clockwise positive).
    period : float, s
        Swing period T, > 0.
    """

    amplitude: float = 0.0
    period: float = 60.0
    name = "yaw-swing"

    def __post_init__(self) -> None:
        super().__post_init__()
        require_finite(self.amplitude, "yaw_swing.amplitude")
        if not (math.isfinite(self.period) and self.period > 0):
            raise InputError("yaw_swing.period", f"must be > 0 s, got {self.period!r}")

    def heading_at(self, t):
        """Heading ``psi0 + A T / (2 pi) sin(2 pi t / T)``.

        Arguments, returns and units as :meth:`Motion.heading_at`.
        """
        w = 2.0 * math.pi / self.period
        return self.heading + self.amplitude / w * np.sin(w * np.asarray(t, dtype=float))

    def heading_rate(self, t):
        """Heading rate ``A cos(2 pi t / T)``.

        Arguments, returns and units as :meth:`Motion.heading_rate`.
        """
        w = 2.0 * math.pi / self.period
        return self.amplitude * np.cos(w * np.asarray(t, dtype=float))

    def pieces(self, duration):
        """One piece ``[0, duration]``, constant-rate only when the amplitude is zero.

        Arguments, returns and units as :meth:`Motion.pieces`.
        """
        return np.array([0.0, duration]), self.amplitude == 0.0

    @property
    def is_static(self) -> bool:
        """True if the amplitude is zero."""
        return self.amplitude == 0.0

    def rate_bound(self, a, b):
        """Peak yaw rate plus the swing frequency (the heading is ``A T / 2 pi sin(2 pi t / T)``).

        Arguments, returns and units as :meth:`Motion.rate_bound`.
        """
        if self.amplitude == 0.0:
            return np.zeros(np.shape(a))
        return np.full(np.shape(a), abs(self.amplitude) + 2.0 * math.pi / self.period)

    def constant_rate(self, a, b):
        """Constant only without swing.

        Arguments, returns and units as :meth:`Motion.constant_rate`.
        """
        return np.full(np.shape(a), self.amplitude == 0.0)

    def repeat_period(self):
        """The swing period (None without swing).

        Arguments, returns and units as :meth:`Motion.repeat_period`.
        """
        return float(self.period) if self.amplitude != 0.0 else None

    def describe(self, convention=HEADING_CONVENTIONS[0]):
        """One-line human description, angles in degrees (see :meth:`Motion.describe`)."""
        amp = heading_sign(convention) * self.amplitude
        return (
            f"yaw swing {math.degrees(amp):g} deg/s peak, period {self.period:g} s "
            "(heading amplitude "
            f"{math.degrees(amp * self.period / (2 * math.pi)):.3g} deg), "
            f"pitch {math.degrees(self.pitch):g} deg, roll {math.degrees(self.roll):g} deg"
        )


@dataclass(frozen=True)
class Turn(Motion):
    """Constant heading rate (turning on the spot).

    Parameters
    ----------
    rate : float, rad/s
        Heading rate, clockwise positive; ``heading``, ``pitch`` and ``roll`` as in
        :class:`Motion` (``heading`` is the heading at t = 0).
    """

    rate: float = 0.0
    name = "turn"

    def heading_at(self, t):
        """Heading ``heading + rate * t``.

        Arguments, returns and units as :meth:`Motion.heading_at`.
        """
        return self.heading + self.rate * np.asarray(t, dtype=float)

    def heading_rate(self, t):
        """The constant heading rate.

        Arguments, returns and units as :meth:`Motion.heading_rate`.
        """
        return np.full(np.shape(t), self.rate, dtype=float)

    @property
    def is_static(self) -> bool:
        """True if the rate is zero."""
        return self.rate == 0.0

    def rate_bound(self, a, b):
        """The constant heading rate.

        Arguments, returns and units as :meth:`Motion.rate_bound`.
        """
        return np.full(np.shape(a), abs(self.rate))

    def repeat_period(self):
        """One full turn, ``2 pi / |rate|`` (None without turning).

        Arguments, returns and units as :meth:`Motion.repeat_period`.
        """
        return 2.0 * math.pi / abs(self.rate) if self.rate != 0.0 else None

    def describe(self, convention=HEADING_CONVENTIONS[0]):
        """One-line human description, angles in degrees (see :meth:`Motion.describe`)."""
        k = heading_sign(convention)
        return (
            f"turn at {math.degrees(k * self.rate):g} deg/s "
            f"from heading {math.degrees(k * self.heading):g} deg"
        )


@dataclass(frozen=True)
class HeadingHistory(Motion):
    """A user-supplied heading history, linearly interpolated (constant rate between samples).

    Parameters
    ----------
    times : (K,) s
        Sample times, K >= 2, strictly increasing, starting at 0.
    headings : (K,) rad
        Heading at each sample, clockwise from north, unwrapped (no 360 deg jumps).
        ``heading`` is set to ``headings[0]``; ``pitch`` and ``roll`` as in :class:`Motion`.
    """

    times: np.ndarray = field(default_factory=lambda: np.array([0.0, 1.0]))
    headings: np.ndarray = field(default_factory=lambda: np.zeros(2))
    name = "heading-history"

    def __post_init__(self) -> None:
        super().__post_init__()
        t = np.asarray(self.times, dtype=float)
        h = np.asarray(self.headings, dtype=float)
        if t.ndim != 1 or t.shape != h.shape or len(t) < 2:
            raise InputError(
                "motion.heading_history", "needs matching time and heading columns (>= 2 rows)"
            )
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(h))):
            raise InputError("motion.heading_history", "contains a non-finite value")
        if t[0] != 0.0 or np.any(np.diff(t) <= 0):
            raise InputError("motion.heading_history", "times must start at 0 and increase")
        object.__setattr__(self, "times", t)
        object.__setattr__(self, "headings", h)
        object.__setattr__(self, "heading", float(h[0]))

    def heading_at(self, t):
        """Heading linearly interpolated between samples (held at the ends).

        Arguments, returns and units as :meth:`Motion.heading_at`.
        """
        return np.interp(t, self.times, self.headings)

    def heading_rate(self, t):
        """Heading rate of the sample interval containing each time.

        Arguments, returns and units as :meth:`Motion.heading_rate`.
        """
        t = np.asarray(t, dtype=float)
        k = np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, len(self.times) - 2)
        return np.diff(self.headings)[k] / np.diff(self.times)[k]

    @property
    def is_static(self) -> bool:
        """True if every sampled heading equals the first."""
        return bool(np.all(self.headings == self.headings[0]))

    def constant_rate(self, a, b):
        """Constant within one sample interval of the history.

        Arguments, returns and units as :meth:`Motion.constant_rate`.
        """
        i0 = np.searchsorted(self.times, a, side="right") - 1
        i1 = np.searchsorted(self.times, b, side="left") - 1
        return np.asarray(i1 <= i0)

    def rate_bound(self, a, b):
        """Largest heading rate of the sample intervals that overlap each ``[a_i, b_i]``.

        Arguments, returns and units as :meth:`Motion.rate_bound`.
        """
        rates = np.abs(np.diff(self.headings) / np.diff(self.times))
        # Running maximum over the sample intervals from the one holding a to the one holding b.
        i0 = np.clip(np.searchsorted(self.times, a, side="right") - 1, 0, len(rates) - 1)
        i1 = np.clip(np.searchsorted(self.times, b, side="left") - 1, 0, len(rates) - 1)
        out = rates[i0].astype(float)
        # Intervals spanning several samples (rare: pieces are cut at the samples).
        for k in np.flatnonzero(np.atleast_1d(i1 > i0)):
            out.flat[k] = rates[i0.flat[k] : i1.flat[k] + 1].max()
        return out

    def pieces(self, duration):
        """The sample times inside the run: the rate is constant between them.

        Arguments, returns and units as :meth:`Motion.pieces`.
        """
        if duration > self.times[-1] + 1e-9:
            raise InputError(
                "motion.heading_history",
                f"covers {self.times[-1]:g} s but the run lasts {duration:g} s",
                "extend the history or shorten the run",
            )
        inner = self.times[(self.times > 0) & (self.times < duration)]
        return np.concatenate([[0.0], inner, [duration]]), True

    def describe(self, convention=HEADING_CONVENTIONS[0]):
        """One-line human description (the convention does not change it)."""
        return f"heading history of {len(self.times)} samples over {self.times[-1]:g} s"


# ---------------------------------------------------------------------------------------
# What the closed-loop planners may assume about a motion without sampling it at 100 Hz
# ---------------------------------------------------------------------------------------
# Only the motions defined above are known here; a planner given any other Motion
# subclass (None below) samples it at the decision rate, as it always did.


def heading_rate_bound(motion: Motion) -> float | None:
    """Bound on the absolute heading rate at every time, so ``|H(t) - H(s)| <= bound |t - s|``.

    Unlike :meth:`Motion.rate_bound` (a frequency bound that sizes the fast engine's
    quadrature, swing frequency included) this is a bound on ``|H'|`` alone, and it
    is None for motion types this module does not define, so that callers relying on
    it fall back to sampling.

    Parameters
    ----------
    motion : Motion
        Vehicle motion.

    Returns
    -------
    float or None
        The bound, rad/s (the least one for these motions); None for a motion type
        not defined in this module.
    """
    kind = type(motion)
    if kind is Motion:
        return 0.0
    if kind is YawSwing:
        return abs(motion.amplitude)
    if kind is Turn:
        return abs(motion.rate)
    if kind is HeadingHistory:
        # Linear between samples and held outside them (heading_at interpolates).
        return float(np.max(np.abs(np.diff(motion.headings) / np.diff(motion.times))))
    return None


def heading_accel_bound(motion: Motion) -> float | None:
    """Bound on ``|H''|`` at every time, for motions whose heading rate is continuous.

    Parameters
    ----------
    motion : Motion
        Vehicle motion.

    Returns
    -------
    float or None
        The bound, rad/s^2; None for a heading history (its rate jumps at the
        samples) or a motion type not defined in this module.
    """
    kind = type(motion)
    if kind in (Motion, Turn):
        return 0.0
    if kind is YawSwing:
        return abs(motion.amplitude) * 2.0 * math.pi / motion.period
    return None


def heading_rate_breaks(motion: Motion, level: float, t_end: float) -> np.ndarray | None:
    """Times that split ``[0, t_end]`` into pieces on which ``heading_rate - level`` keeps one sign.

    On each open interval between consecutive returned times (and before the first,
    after the last) ``motion.heading_rate(t) - level`` is continuous and either
    never zero or identically zero. The times are exact to round-off (a few ulp);
    callers that sample the rate must allow a margin of a sample or so.

    Parameters
    ----------
    motion : Motion
        Vehicle motion.
    level : float
        Heading-rate level, rad/s.
    t_end : float
        End of the span of interest, s.

    Returns
    -------
    ndarray or None
        Sorted times in ``[0, t_end]``, s (possibly empty); None for a motion type not
        defined in this module.
    """
    kind = type(motion)
    if kind in (Motion, Turn):
        return np.zeros(0)  # constant rate
    if kind is HeadingHistory:
        # heading_rate is constant between the samples, with a jump at each.
        t = motion.times
        return t[(t > 0.0) & (t <= t_end)]
    if kind is YawSwing:
        amp = motion.amplitude
        if amp == 0.0 or abs(level) > abs(amp):
            return np.zeros(0)
        # A cos(w t) = level at w t = +-alpha + 2 pi n (a double root when |level| = |A|).
        w = 2.0 * math.pi / motion.period
        alpha = math.acos(max(-1.0, min(1.0, level / amp)))
        n = np.arange(-1, math.floor(w * t_end / (2.0 * math.pi)) + 2)
        t = np.sort(np.concatenate([2.0 * math.pi * n + alpha, 2.0 * math.pi * n - alpha]) / w)
        t = t[(t >= 0.0) & (t <= t_end)]
        return t[np.concatenate([[True], np.diff(t) > 0])] if len(t) else t  # double roots once
    return None
