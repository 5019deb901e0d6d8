"""Closed-loop indexing rules: the next step depends on the run (the IMU heading).

``flexible-two-position`` (P0's rule, threshold or zero-crossing stop test) and
``heading-isolation`` live here; ``nulling-two-position`` (inserr's heading-motion-aware
rule) has its own module, :mod:`inserr.schemes.nulling`. Each is a small frozen object
whose one method ``plan(motion, duration)`` returns a
:class:`~inserr.schemes.turntable.TableSchedule`.

The rules are defined on samples (the flexible rule's heading at ``f`` = 100 Hz, the
isolation's table rate at 4 Hz), and a plan gives the schedule those samples give.
It does not compute every sample, though (a 72 h run has 26 million): where the
vehicle motion is one of :mod:`inserr.schemes.vehicle_motion`'s own, closed forms
(sums of the heading phasor over a stop) and bounds (how fast the IMU heading can
move between two samples; where the table rate can reverse) show which samples can
matter, and only those are computed, with the same operations as the sampled rule.
Any other motion is sampled in full.
"""

from __future__ import annotations

import bisect
import cmath
import math
from dataclasses import dataclass, field

import numpy as np

from inserr.core.errors import InputError
from inserr.schemes.turntable import (
    OuterAxisHeading,
    ScheduleBuilder,
    TableSchedule,
    imu_heading_offset,
    isolation_angle,
)
from inserr.schemes.vehicle_motion import (
    HeadingHistory,
    Motion,
    Turn,
    YawSwing,
    heading_accel_bound,
    heading_rate_bound,
    heading_rate_breaks,
)


def _check_start(start: str) -> None:
    """Refuse an opening phase other than ``"stop"`` or ``"turn"`` (``scheme.start``)."""
    if start not in ("stop", "turn"):
        raise InputError(
            "scheme.start", f"unknown opening phase {start!r}", "use one of: stop, turn"
        )


def _imu_heading(motion: Motion, t: np.ndarray, a: np.ndarray, mounting) -> np.ndarray:
    """IMU heading (rad) of a single-axis table at outer angle ``a`` on ``motion``, times ``t``."""
    return motion.heading_at(t) + imu_heading_offset(motion.tilt, a, 0.0, mounting)


def _best_sample(score: np.ndarray, ok: np.ndarray, rtol: float = 1e-9) -> int:
    """Index of the smallest ``score`` among ``ok`` samples (all if none), earliest of ties.

    Values within ``rtol`` (relative to the score's range, at least 1e-12) of the
    minimum count as ties, so round-off cannot pick a later sample of a flat score.
    """
    pool = np.flatnonzero(ok) if np.any(ok) else np.arange(len(score))
    vals = score[pool]
    tol = max(1e-12, rtol * float(np.ptp(score)))
    return int(pool[np.flatnonzero(vals <= vals.min() + tol)[0]])


def _merge(starts: np.ndarray, stops: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Union of the ranges ``[start, stop)`` as disjoint sorted ranges (starts and stops sorted)."""
    if not len(starts):
        return starts, stops
    new = np.concatenate([[True], starts[1:] > stops[:-1]])
    return starts[new], np.append(stops[np.flatnonzero(new)[1:] - 1], stops[-1])


def _ranges(starts: np.ndarray, stops: np.ndarray) -> np.ndarray:
    """Concatenation of ``np.arange(start, stop)`` over the pairs (integers; empty ones allowed)."""
    lengths = np.maximum(np.asarray(stops) - np.asarray(starts), 0)
    total = int(lengths.sum())
    if total == 0:
        return np.zeros(0, dtype=np.int64)
    first = np.concatenate([[0], np.cumsum(lengths)[:-1]])
    return np.repeat(np.asarray(starts) - first, lengths) + np.arange(total)


# ---------------------------------------------------------------------------------------
# Flexible rule, stop sums: sum of exp(i psi) over the decision samples of one stop
# ---------------------------------------------------------------------------------------
# During a stop the table angle a is fixed, so psi = H(t) + offset(a) and
# sum exp(i psi) = exp(i offset(a)) * sum exp(i H(k / f)): only the vehicle heading is
# summed, and for the motions below that sum has a closed form. Each class is called
# as ``sums(k0, k1, a)`` and returns ``(sum cos psi, sum sin psi)`` over samples k0..k1-1.


def _dirichlet(theta, n):
    """``sum_{j=0}^{n-1} exp(i j theta)`` for arrays ``theta`` (rad) and ``n`` (>= 0)."""
    # The sum is 2 pi periodic in theta; reducing to [-pi, pi] keeps sin(theta / 2)
    # accurate near multiples of 2 pi and leaves a small theta untouched.
    theta = np.asarray(theta, float)
    half = 0.5 * (theta - 2.0 * math.pi * np.round(theta / (2.0 * math.pi)))
    s = np.sin(half)
    ratio = np.where(s == 0.0, n, np.sin(n * half) / np.where(s == 0.0, 1.0, s))
    return np.exp(1j * (n - 1) * half) * ratio


# 2 pi as an integer over 2^200, from pi to 80 decimals (1e-80, beyond the 2^-200 kept).
_PI_E80 = int("314159265358979323846264338327950288419716939937510582097494459230781640628620899")
_TWO_PI_BITS = 200
_TWO_PI_INT = (2 * _PI_E80 << _TWO_PI_BITS) // 10**80


class _ExactPhase:
    """``(h + r (k / f - t)) mod 2 pi`` in ``[0, 2 pi)`` for integers ``k``, computed exactly.

    Why exactly. The sampled rule rounds the heading of each sample on its own, and
    those errors average out over a stop. A phase computed once for a whole stop
    would carry its rounding (a few 1e-12 rad after 72 h at 6 deg/s) into all of the
    stop's 30 000 samples alike, and the running sums would drift from the sampled
    ones by 1e-9 of their size. Integers make it exact: every float is a ratio of
    integers, and 2 pi is known to 2^-200.
    """

    def __init__(self, h: float, r: float, t: float, f: float):
        (hn, hd), (rn, rd), (tn, td), (fn, fd) = (x.as_integer_ratio() for x in (h, r, t, f))
        # h + r (k fd / fn - tn / td) = (num0 + num1 k) / den
        self._num0 = hn * rd * fn * td - rn * tn * fn * hd
        self._num1 = rn * fd * td * hd
        den = hd * rd * fn * td
        self._period = den * _TWO_PI_INT  # 2 pi in units of 1 / (den 2^200)
        self._unit = den << _TWO_PI_BITS

    def __call__(self, k: int) -> float:
        return (((self._num0 + self._num1 * k) << _TWO_PI_BITS) % self._period) / self._unit


@dataclass(frozen=True)
class _SampledStopSums:
    """Any motion: the heading at every sample of the stop (the rule's definition)."""

    motion: Motion
    f: float
    geo: OuterAxisHeading

    def __call__(self, k0: int, k1: int, a: float) -> tuple[float, float]:
        h = self.motion.heading_at(np.arange(k0, k1) / self.f) + self.geo.offset(a)
        return float(np.cos(h).sum()), float(np.sin(h).sum())


class _StaticStopSums:
    """A heading that never changes: the sampled sums, computed once per (samples, angle).

    These are the sampled rule's own sums (same operations), not a closed form: on a
    static base the crossing test can fall exactly on a sample (half a turn from the
    stop), where round-off alone decides, so the sums must round as the rule's do. A
    static run visits a handful of table angles, so few are computed, each as numpy's
    sum of the one repeated cosine (sine).
    """

    def __init__(self, motion: Motion, f: float, geo: OuterAxisHeading):
        self._sampled = _SampledStopSums(motion, f, geo)
        self._known: dict[tuple[int, float], tuple[float, float]] = {}

    def __call__(self, k0: int, k1: int, a: float) -> tuple[float, float]:
        key = (k1 - k0, a)
        if key not in self._known:
            # Every sample of the stop has the same heading, so the rule's array of
            # cosines (sines) is one value repeated: the value from a few samples
            # (elementwise, the same operations), summed as numpy sums the array.
            few = self._sampled.motion.heading_at(np.arange(8) / self._sampled.f)
            h = few + self._sampled.geo.offset(a)
            n = k1 - k0
            self._known[key] = (
                float(np.full(n, np.cos(h)[0]).sum()),
                float(np.full(n, np.sin(h)[0]).sum()),
            )
        return self._known[key]


#: Pieces with at least this many samples in a stop get an exact phase (:class:`_ExactPhase`);
#: on shorter ones a rounded phase errs less than the sampled sum's own round-off.
_EXACT_PHASE_SAMPLES = 1000


class _LinearStopSums:
    """Heading linear between knots (static base, steady turn, heading history).

    Piece ``i`` holds the samples from ``ceil(f t_i)`` up to the next piece's first,
    with heading ``h_i + r_i (t - t_i)``; the last piece runs on for ever. Its sum is
    a geometric series (:func:`_dirichlet`).
    """

    def __init__(self, knots, headings, rates, f: float, geo: OuterAxisHeading):
        self.t = np.asarray(knots, float)
        self.h = np.asarray(headings, float)
        self.r = np.asarray(rates, float)
        self.f = f
        self.geo = geo
        first = np.ceil(self.t * f).astype(np.int64)
        self.first = first
        self.next_first = np.append(first[1:], np.iinfo(np.int64).max)
        self._exact: dict[int, _ExactPhase] = {}

    def _exact_phase(self, i: int) -> _ExactPhase:
        if i not in self._exact:
            self._exact[i] = _ExactPhase(self.h[i], self.r[i], self.t[i], self.f)
        return self._exact[i]

    @classmethod
    def of(cls, motion: Motion, f: float, geo: OuterAxisHeading) -> _LinearStopSums:
        """The pieces of a static motion, a steady turn or a heading history."""
        if type(motion) is HeadingHistory:
            # heading_at interpolates between the samples and holds the last one.
            rates = np.append(np.diff(motion.headings) / np.diff(motion.times), 0.0)
            return cls(motion.times, motion.headings, rates, f, geo)
        rate = motion.rate if type(motion) is Turn else 0.0
        return cls([0.0], [motion.heading], [rate], f, geo)

    def __call__(self, k0: int, k1: int, a: float) -> tuple[float, float]:
        # Pieces holding samples k0..k1-1, one more each side for round-off in ceil(f t_i).
        i0 = max(int(np.searchsorted(self.t, k0 / self.f, side="right")) - 2, 0)
        i1 = int(np.searchsorted(self.t, (k1 - 1) / self.f, side="right")) + 1
        sl = slice(i0, i1)
        lo = np.maximum(k0, self.first[sl])
        n = np.maximum(np.minimum(k1, self.next_first[sl]) - lo, 0)
        phase = self.h[sl] + self.r[sl] * (lo / self.f - self.t[sl])
        for i in np.flatnonzero(n >= _EXACT_PHASE_SAMPLES):  # see _ExactPhase
            phase[i] = self._exact_phase(i0 + i)(int(lo[i]))
        z = np.sum(np.exp(1j * phase) * _dirichlet(self.r[sl] / self.f, n))
        z *= self.geo.phasor(a)
        return z.real, z.imag


class _SwingStopSums:
    """Yaw swing ``H = h0 + z sin(W t)``, ``z = A / W``: the Jacobi-Anger expansion.

    ``exp(i z sin x) = sum_m J_m(z) exp(i m x)``, so the sum over samples ``k0 + j``
    is ``exp(i h0) sum_m J_m(z) exp(i m x0) D_m(n)`` with ``x0 = W k0 / f`` and ``D_m``
    the geometric sum of ``exp(i m W j / f)``. Orders with ``|J_m(z)| < 1e-18`` are left
    out (they begin before ``|z| + 10 |z|^(1/3) + 25``).
    """

    def __init__(self, motion: YawSwing, f: float, geo: OuterAxisHeading):
        from scipy.special import jv

        self.w = 2.0 * math.pi / motion.period
        z = motion.amplitude / self.w
        order = math.ceil(abs(z) + 10.0 * abs(z) ** (1.0 / 3.0) + 25.0)
        jm = jv(np.arange(order + 1), abs(z))
        order = int(np.flatnonzero(np.abs(jm) > 1e-18)[-1])  # the rest adds < 1e-13 to a sum
        self.m = np.arange(-order, order + 1)
        self.im = 1j * self.m
        self.jm = jv(self.m, z)
        self.f = f
        self.h0 = cmath.exp(1j * motion.heading)
        self.x0 = _ExactPhase(0.0, self.w, 0.0, f)  # swing phase at sample k
        self.geo = geo
        self._weights: dict[int, np.ndarray] = {}  # n -> J_m D_m(n): stops share a few n

    def __call__(self, k0: int, k1: int, a: float) -> tuple[float, float]:
        n = k1 - k0
        if n not in self._weights:
            self._weights[n] = self.jm * _dirichlet(self.m * (self.w / self.f), n)
        z = self.h0 * complex(np.exp(self.x0(k0) * self.im) @ self._weights[n])
        z *= self.geo.phasor(a)
        return z.real, z.imag


def _stop_sums(motion: Motion, f: float, geo: OuterAxisHeading):
    """The stop-sum function for ``motion``: closed form where one is known, else sampled."""
    kind = type(motion)
    if kind in (Motion, Turn, YawSwing, HeadingHistory) and motion.is_static:
        return _StaticStopSums(motion, f, geo)
    if kind is YawSwing:
        return _SwingStopSums(motion, f, geo)
    if kind in (Motion, Turn, HeadingHistory):
        return _LinearStopSums.of(motion, f, geo)
    return _SampledStopSums(motion, f, geo)


# ---------------------------------------------------------------------------------------
# Flexible rule, variable turns: the first sample that passes the stop test
# ---------------------------------------------------------------------------------------
def _passes(expr, other, s_other, variant: str, delta: float) -> np.ndarray:
    """The stop test at samples of a turn, as the rule defines it.

    ``crossing`` compares each sample with the one given before it (the caller makes
    sure that is its neighbour); the first has none (the first of a turn is compared
    with itself: never a sign change).
    """
    if variant == "threshold":
        hit = np.abs(expr) < delta
    else:
        sign = np.sign(expr)
        hit = np.concatenate([[False], sign[1:] != sign[:-1]])
    if s_other != 0:
        hit &= np.sign(other) == -s_other
    return hit


#: :meth:`_TurnSearch._recurring_turn` could not answer: search the turn.
_SEARCH = object()

#: Samples of a turn computed together at most (see _TurnSearch._first_in).
_CHUNK = 128


class _TurnSearch:
    """Stop test over one variable turn, without computing all of its samples.

    The IMU heading at sample ``j`` of a turn starting at ``(t0, a0)`` is
    ``psi_j = H(t0 + j / f) + offset(a0 +- w j / f)``. The turn is first looked at every
    ``stride`` samples (about a second apart); a stretch between two of those can
    hold a passing sample only if ``expr`` (and ``other``, for the sign condition) can
    reach the test's band in it, and only such stretches are computed sample by
    sample, with the sampled rule's own operations (:meth:`values`), so the first
    passing sample is the sampled rule's. How far they can reach:

    * ``|psi'| <= L = max|H'| + w max|offset'|`` (:func:`heading_rate_bound`,
      :meth:`OuterAxisHeading.slope_bounds`), so ``cos psi`` and ``sin psi`` move by at
      most ``L`` per second;
    * where ``H`` has a continuous rate (:func:`heading_accel_bound`), their second
      derivative is at most ``|psi''| + L^2`` with ``|psi''| <= max|H''| + w^2
      max|offset''|`` (:meth:`OuterAxisHeading.curvature_bound`), and they stay within
      ``that x spacing^2 / 8`` of the straight line through the two coarse values: a
      far tighter bound where the heading moves slowly.

    The test's band is ``delta`` (threshold) or ``L / f`` (crossing: a sign change
    between neighbours needs ``|expr| <= L / f``). The coarse look uses the closed
    form of ``exp(i psi)`` (:meth:`OuterAxisHeading.phasor`, unnormalised); its
    difference from the sampled values and all round-off are added to the reach.
    When ``L`` is not known (a motion not defined in
    :mod:`inserr.schemes.vehicle_motion`) every sample is computed.
    """

    def __init__(self, rule: FlexibleTwoPosition, motion: Motion, duration: float):
        self.rule = rule
        self.motion = motion
        self.geo = OuterAxisHeading(motion.tilt, rule.mounting)
        # A vehicle that never turns: its heading, so that no sample asks the motion for
        # it (the same value heading_at gives at every time; the same sums follow).
        self.heading = float(motion.heading_at(np.zeros(1))[0]) if motion.is_static else None
        self.static_phasor: dict = {}  # per direction, on a static base (see first_pass)
        self._recurring: dict = {}  # turns from one start angle (see _recurring_turn)
        w, f = rule.rate, rule.f
        self.per_turn = int(math.ceil(2 * math.pi / w * f))
        self.j = j = np.arange(1, self.per_turn + 1)
        # Time and table angle from the turn's start at samples 1..per_turn, computed
        # as the sampled rule computes them (j / f, d w j / f).
        self.dt = j / f
        self.da = {d: d * w * j / f for d in (1.0, -1.0)}
        hdot = heading_rate_bound(motion)
        lo, hi = self.geo.slope_bounds()
        self.lipschitz = None
        self.roundoff = None  # bound of |closed form - sampled| of cos psi, sin psi
        self.short_ends = None  # the fallback's stretches (see best_sample)
        self.short_bend = self.short_reach = None
        # The fallback's turn: the samples short of a whole revolution.
        self.n_short = ns = int(np.count_nonzero(rule.rate * j / f < 2 * math.pi - 1e-9))
        # The closed form's terms along those samples: e^{i a} = e^{i a0} e^{i da}, so
        # up e^{i a} + um e^{-i a} = e^{i a0} (up e^{i da}) + e^{-i a0} (um e^{-i da}).
        up, um, _ = self.geo.coefficients
        turn = {d: np.exp(1j * self.da[d][:ns]) for d in (1.0, -1.0)}
        self.short_terms = {d: (up * e, um * np.conj(e)) for d, e in turn.items()}
        if hdot is None or not math.isfinite(hi) or self.per_turn < 2:
            return
        self.lipschitz = lip = hdot + w * max(abs(lo), abs(hi))  # rad/s
        # Round-off in psi (heading, offset, the sample times and angles they are
        # computed at, the closed form) is a few ulp of the largest heading, rate x
        # time or table angle reached; 1e-12 of them is a thousandfold margin. The
        # unnormalised closed form is off by at most 1 - min_horizontal.
        t_max = duration + rule.stop + 2 * math.pi / w
        slack = 1e-12 * (10.0 + abs(motion.heading) + 2.0 * hdot * t_max)
        # The closed form divides by |w| >= min_horizontal: round-off grows by its inverse.
        min_h = self.geo.min_horizontal()
        self.roundoff = slack / min_h if min_h > 0 else None
        # The coarse look keeps only the larger of the exp(+-i a) terms of the closed
        # form, unnormalised: off by at most the others plus 1 - min_horizontal.
        up, um, cz = self.geo.coefficients
        self.sense = -1.0 if abs(um) >= abs(up) else 1.0
        self.coef = um if self.sense < 0 else up
        slack += abs(up) + abs(um) - abs(self.coef) + abs(cz) + 1.0 - self.geo.min_horizontal()
        stride = max(1, round(rule.f))  # a second
        self.coarse = np.append(j[:-1:stride], self.per_turn)
        self.coarse_dt = self.coarse / f
        gap = np.diff(self.coarse) / f
        self.band = (rule.delta if rule.variant == "threshold" else lip / f) + slack
        hddot = heading_accel_bound(motion)
        curve = self.geo.curvature_bound()
        if hddot is not None and math.isfinite(curve):
            self.bend = (hddot + w * w * curve + lip * lip) * gap**2 / 8.0 + slack
            self.reach = None
        else:
            self.bend = None
            self.reach = lip * gap + 2.0 * slack
        # The kept term's phase from the turn at the coarse samples, both directions.
        self.turned = {d: self.sense * d * w * self.coarse_dt for d in (1.0, -1.0)}
        if self.heading is not None:
            # exp(i (H + turned)) does not depend on the turn's start time: once.
            full = np.full(len(self.coarse_dt), self.heading)
            self.static_phasor = {d: np.exp(1j * (full + v)) for d, v in self.turned.items()}
        # The fallback's look at the turn short of a revolution: samples a second apart
        # (ending at the last short one) and, per stretch between them, how far cos psi
        # and sin psi can leave the chord (with the curvature bound) or move along it
        # (with the slope bound only); see best_sample.
        ends = np.unique(np.append(j[:ns:stride], ns))
        g = np.diff(ends) / f
        self.short_ends = ends
        if hddot is not None and math.isfinite(curve):
            self.short_bend, self.short_reach = (hddot + w * w * curve + lip * lip) * g**2 / 8, None
        else:
            self.short_bend, self.short_reach = None, lip * g
        self.short_rot = {d: np.exp(1j * d * w * ends / f) for d in (1.0, -1.0)}

    def values(self, t0: float, a0: float, direction: float, which: int, j: np.ndarray):
        """``(main, other)`` at samples ``j`` of a turn from ``(t0, a0)`` (sampled rule)."""
        # Consecutive samples (the usual case) as a slice: a view, not a copy.
        k = slice(j[0] - 1, j[-1]) if j[-1] - j[0] == len(j) - 1 else j - 1
        a = a0 + self.da[direction][k]
        if self.heading is not None:
            h = self.heading + self.geo.offset(a)
        else:
            h = self.motion.heading_at(t0 + self.dt[k]) + self.geo.offset(a)
        return (np.cos(h), np.sin(h)) if which == 0 else (np.sin(h), np.cos(h))

    def _near(self, expr: np.ndarray, toward: np.ndarray | None, more: float) -> np.ndarray:
        """Which coarse stretches can hold a passing sample (class docstring).

        ``expr`` and ``toward`` (``other`` times the sign it must have, None without a
        sign condition) at the coarse samples; ``more`` is extra round-off.
        """
        if self.bend is not None:
            # Within bend of the line through the ends: does that line come within the
            # band (its values span [min, max] of the ends)?
            tol = self.bend + more
            near = (np.minimum(expr[:-1], expr[1:]) <= self.band + tol) & (
                np.maximum(expr[:-1], expr[1:]) >= -self.band - tol
            )
            if toward is not None:
                near &= np.maximum(toward[:-1], toward[1:]) > -tol
            return near
        # Within reach of both ends (reach: how far L carries across the stretch).
        size = np.abs(expr)
        reach = self.reach + 2.0 * more
        near = size[:-1] + size[1:] <= reach + 2.0 * (self.band + more)
        if toward is not None:
            near &= toward[:-1] + toward[1:] > -reach
        return near

    def first_pass(self, t0, a0, direction, which, c, s_other) -> int | None:
        """Sample number (1..per_turn) of the first sample passing the test, None if none does.

        ``c`` is the stop-sum term ``S / (f Ts)`` added to ``main``; ``s_other`` the sign
        ``other`` must not have (0: no sign condition).
        """
        if self.heading is not None and self.rule.variant == "threshold":
            found = self._recurring_turn(a0, direction, which, c, s_other)
            if found is not _SEARCH:
                return found
        if self.lipschitz is None:
            return self._first_in(t0, a0, direction, which, c, s_other, self.j)
        jc = self.coarse
        # exp(i psi) at the coarse samples, roughly: exp(i H) times the kept term.
        if direction in self.static_phasor:
            turned = self.static_phasor[direction]
        else:
            turned = np.exp(
                1j * (self.motion.heading_at(t0 + self.coarse_dt) + self.turned[direction])
            )
        psi = turned * (self.coef * cmath.exp(1j * self.sense * a0))
        main, other = (psi.real, psi.imag) if which == 0 else (psi.imag, psi.real)
        # The table angle's round-off grows with it: 1e-12 of it on top.
        more = 1e-12 * abs(a0)
        near = self._near(main + c, None if s_other == 0 else other * -s_other, more)
        # The candidate stretches' samples (each with the sample before it, the crossing
        # test's neighbour), all computed at once.
        cand = np.flatnonzero(near).tolist()
        if not cand:
            return None
        expr = main + c
        parts = []
        done = 1  # samples before this are taken
        for i in cand:
            if self.bend is not None:
                lo, hi = self._narrow(i, float(expr[i]), float(expr[i + 1]), more)
            else:
                lo, hi = int(jc[i]), int(jc[i + 1])
            lo = max(lo - 1, done)
            if hi >= lo:
                parts.append(np.arange(lo, hi + 1))
                done = hi + 1
        j = parts[0] if len(parts) == 1 else np.concatenate(parts)
        return self._first_in(t0, a0, direction, which, c, s_other, j)

    def _recurring_turn(self, a0, direction, which, c, s_other):
        """:meth:`first_pass` of a turn that starts where one started before, on a
        static base; :data:`_SEARCH` for the first turn from that angle.

        On a static base a turn's samples depend only on its start angle, direction and
        test (not on its start time), and a static run starts its turns from a handful
        of table angles again and again, with only the stop sums' term ``c`` changing.
        From the second turn on, the turn's samples (all of them, with the rule's own
        operations) are kept with their ``main`` values sorted (those meeting the sign
        condition), so the samples that can pass, ``|main + c| < delta``, are a range
        found by two binary searches (widened by 1e-12, far beyond the sum's
        round-off) and tested exactly; the first that passes is the answer. The last
        answer is tried first: it stands if it still passes and none of the samples
        before it comes within reach.
        """
        key = (a0, direction, which)
        seen = self._recurring.get(key)
        if seen is None:
            self._recurring[key] = {}
            return _SEARCH
        if s_other not in seen:
            if "main" not in seen:
                seen["main"], seen["other"] = self.values(0.0, a0, direction, which, self.j)
            main, other = seen["main"], seen["other"]
            idx = (
                np.arange(len(main)) if s_other == 0 else np.flatnonzero(np.sign(other) == -s_other)
            )
            idx = idx[np.argsort(main[idx], kind="stable")]
            seen[s_other] = (idx, main[idx], [])
        idx, ordered, last = seen[s_other]
        delta = self.rule.delta
        reach = delta + 1e-12
        if last:
            # The answer of the last turn from here, n: it stands if sample n still
            # passes and no earlier one comes within reach (the same float operations
            # on Python floats; the earlier samples' values sorted in a list).
            n, main_n, before = last
            if abs(main_n + c) < delta and bisect.bisect_left(
                before, -c - reach
            ) == bisect.bisect_right(before, -c + reach):
                return n
        lo = int(np.searchsorted(ordered, -c - reach, side="left"))
        hi = int(np.searchsorted(ordered, -c + reach, side="right"))
        if lo >= hi:
            return None
        cand = idx[lo:hi]
        hit = cand[np.abs(seen["main"][cand] + c) < delta]
        if not len(hit):
            return None
        first = int(hit.min())
        earlier = idx < first
        last[:] = [first + 1, float(seen["main"][first]), np.sort(ordered[earlier]).tolist()]
        return first + 1

    def _narrow(self, i: int, e0: float, e1: float, more: float) -> tuple[int, int]:
        """The samples of coarse stretch ``i`` where the line through its ends is in reach.

        A passing sample has ``|expr| < band``, so the line through the ends' values
        ``(e0, e1)`` is within ``band + bend`` of zero there: solve for that part of the
        line, widened by a sample. Returns the first and last sample.
        """
        j0, j1 = int(self.coarse[i]), int(self.coarse[i + 1])
        reach = self.band + self.bend[i] + more
        slope = e1 - e0
        if slope == 0.0:
            return j0, j1
        u = sorted(((-reach - e0) / slope, (reach - e0) / slope))
        n = j1 - j0
        lo = j0 + max(0, math.floor(u[0] * n) - 1)
        return lo, max(lo, j0 + min(n, math.ceil(u[1] * n) + 1))

    def _first_in(self, t0, a0, direction, which, c, s_other, j: np.ndarray) -> int | None:
        """First passing sample among samples ``j`` (sorted; sampled rule), None if none passes."""
        # A few hundred samples at a time: the first passing sample is usually early.
        for k in range(0, len(j), _CHUNK):
            part = j[max(k - 1, 0) : k + _CHUNK]  # with the last one before, for crossing
            main, other = self.values(t0, a0, direction, which, part)
            hit = _passes(main + c, other, s_other, self.rule.variant, self.rule.delta)
            if self.rule.variant != "threshold":
                hit[1:] &= np.diff(part) == 1  # a neighbour must be the sample just before
            hit[0] &= k == 0  # else the previous part's last, already tested
            if hit.any():
                return int(part[np.argmax(hit)])
        return None

    def best_sample(self, t0, a0, direction, which, c, s_other) -> int:
        """The fallback's sample number: the best sample of one turn (class docstring).

        The choice is the sampled rule's (:func:`_best_sample` on :meth:`values` of the
        whole turn). Where a round-off bound is known the turn is looked at in closed
        form (:meth:`OuterAxisHeading.phasor`, within ``tol`` of the sampled values):
        first a second apart, where bounds on how far ``cos psi`` and ``sin psi`` move
        between those samples leave only the stretches that can hold the best sample,
        the turn's largest or smallest score (they set the tie tolerance) or a sample
        whose sign condition is unknown (:meth:`_stretches`); then at every sample of
        those stretches; :meth:`values` is computed only at the samples that can decide
        the choice: those whose sign condition is in doubt, those that can be the
        turn's largest or smallest score, and those that can be the best or tie with it.
        """
        ns = self.n_short
        if self.roundoff is None:
            main, other = self.values(t0, a0, direction, which, self.j)
            expr = main[:ns] + c
            sign_ok = (np.sign(other[:ns]) == -s_other) | (s_other == 0)
            return _best_sample(np.abs(expr), sign_ok) + 1
        tol = self.roundoff + 1e-12 * abs(a0)  # |closed form - sampled|, main and other
        e0 = cmath.exp(1j * a0)
        found = self._stretches(t0, e0, direction, which, c, s_other, tol)
        if found is not None:
            got = self._decide(t0, a0, e0, direction, which, c, s_other, tol, *found)
            if got is not None:
                return got
        # Every sample short of a revolution (the bounds could not settle the choice).
        return self._decide(t0, a0, e0, direction, which, c, s_other, tol, np.arange(ns))

    def _decide(self, t0, a0, e0, direction, which, c, s_other, tol, idx, any_ok=None, tie=None):
        """:meth:`best_sample` on the samples ``idx`` (0-based, sorted), which must hold
        every sample that can decide it. ``any_ok``: whether any sample of the turn
        meets the sign condition (None: decided on ``idx``, which is then the whole
        turn). ``tie``: bounds ``(lo, hi)`` of :func:`_best_sample`'s tie tolerance
        (None: computed from the turn's exact largest and smallest scores, which
        ``idx`` then holds); None is returned if the choice depends on where in
        ``(lo, hi)`` it is."""
        t = t0 + self.dt[idx]
        plus, minus = self.short_terms[direction]
        w = plus[idx] * e0 + minus[idx] * e0.conjugate() + self.geo.coefficients[2]
        psi = np.exp(1j * self.motion.heading_at(t)) * w
        psi /= np.abs(w)
        main, other = (psi.real, psi.imag) if which == 0 else (psi.imag, psi.real)
        score = np.abs(main + c)
        n = len(idx)
        # Samples whose sign condition the closed form cannot decide.
        if s_other == 0:
            sure, doubt = np.ones(n, dtype=bool), np.zeros(n, dtype=bool)
        else:
            side = -s_other * other
            sure, doubt = side > tol, np.abs(side) <= tol
        if tie is None:
            top = score >= score.max() - 2 * tol
            bottom = score <= score.min() + 2 * tol
        else:
            top = bottom = np.zeros(n, dtype=bool)
        need = np.flatnonzero(doubt | top | bottom)
        exact = np.full(n, np.nan)
        ok = sure.copy()
        if len(need):
            ex_main, ex_other = self.values(t0, a0, direction, which, idx[need] + 1)
            exact[need] = np.abs(ex_main + c)
            ok[need] = (np.sign(ex_other) == -s_other) | (s_other == 0)
        ok &= sure | doubt  # the others fail the condition for certain
        if any_ok is None:
            any_ok = bool(ok.any())
        pool = ok if any_ok else np.ones(n, dtype=bool)
        if tie is None:
            # _best_sample's tie tolerance from the exact range of the scores.
            lo = hi = max(1e-12, 1e-9 * float(np.nanmax(exact[top]) - np.nanmin(exact[bottom])))
        else:
            lo, hi = tie
        cand = pool & (score <= score[pool].min() + 2 * tol + hi)
        rest = np.flatnonzero(cand & np.isnan(exact))
        if len(rest):
            ex_main, _ = self.values(t0, a0, direction, which, idx[rest] + 1)
            exact[rest] = np.abs(ex_main + c)
        sel = np.flatnonzero(cand)
        vals = exact[sel]
        tied = vals <= vals.min() + lo  # as _best_sample compares
        if np.any((vals <= vals.min() + hi) & ~tied):
            return None  # a tie or not, depending on the tolerance's exact value
        return int(idx[sel[np.flatnonzero(tied)[0]]]) + 1

    def _stretches(self, t0, e0, direction, which, c, s_other, tol):
        """``(samples, any_ok)``: the samples (0-based, sorted) of the stretches that
        :meth:`best_sample` must look at, and whether any sample of the turn meets the
        sign condition; None when the bounds cannot tell (every sample is looked at).

        Per stretch between two looked-at samples ``f_0, f_1`` (``expr`` or the sign
        side ``-s_other * other``, closed form, within ``tol``), every sample in it is
        within ``[min(f_0, f_1) - b, max(f_0, f_1) + b]`` (``b`` the bend bound, off the
        chord) or ``[(f_0 + f_1 - r) / 2, (f_0 + f_1 + r) / 2]`` (``r`` = slope bound x
        length); likewise ``|expr|``.
        """
        ends = self.short_ends
        if ends is None:
            return None
        i0 = ends - 1
        t = t0 + self.dt[i0]
        w = (
            (self.geo.coefficients[0] * e0) * self.short_rot[direction]
            + (self.geo.coefficients[1] * e0.conjugate()) * np.conj(self.short_rot[direction])
            + self.geo.coefficients[2]
        )
        psi = np.exp(1j * self.motion.heading_at(t)) * w / np.abs(w)
        main, other = (psi.real, psi.imag) if which == 0 else (psi.imag, psi.real)
        expr = main + c
        # The closed form here (e^{i a} from e^{i a0} e^{i da}) adds a few ulp to tol.
        tol = tol + 1e-12

        def bounds(f, absolute):
            f0, f1 = f[:-1], f[1:]
            if absolute:
                a0_, a1_ = np.abs(f0), np.abs(f1)
                if self.short_bend is not None:
                    lo = np.where(f0 * f1 <= 0, 0.0, np.minimum(a0_, a1_)) - self.short_bend
                    hi = np.maximum(a0_, a1_) + self.short_bend
                else:
                    lo = 0.5 * (a0_ + a1_ - self.short_reach)
                    hi = 0.5 * (a0_ + a1_ + self.short_reach)
            elif self.short_bend is not None:
                lo = np.minimum(f0, f1) - self.short_bend
                hi = np.maximum(f0, f1) + self.short_bend
            else:
                lo = 0.5 * (f0 + f1 - self.short_reach)
                hi = 0.5 * (f0 + f1 + self.short_reach)
            return lo - 2 * tol, hi + 2 * tol

        lo_e, hi_e = bounds(expr, True)
        score = np.abs(expr)
        if s_other == 0:
            sure = np.ones(len(lo_e), dtype=bool)
            never = ~sure
        else:
            lo_s, hi_s = bounds(-s_other * other, False)
            sure, never = lo_s > 0, hi_s < 0
        if sure.any():
            any_ok = True
        elif never.all():
            any_ok = False
        else:
            return None  # whether any sample meets the condition is decided sample by sample
        may_pool = ~never if any_ok else np.ones(len(lo_e), dtype=bool)
        # An upper bound of the best score: a looked-at sample surely in the pool.
        if any_ok:
            side = -s_other * other if s_other != 0 else np.ones(len(expr))
            known = side > 2 * tol
            if not known.any():
                return None
            best = float(score[known].min()) + 2 * tol
        else:
            best = float(score.min()) + 2 * tol
        # Bounds of the rule's tie tolerance 1e-9 x (range of the exact scores): the
        # range is at least that of the looked-at samples, at most that of the bounds.
        tie_lo = max(1e-12, 1e-9 * float(score.max() - score.min() - 2 * tol))
        tie_hi = max(1e-12, 1e-9 * float(hi_e.max() - max(lo_e.min(), 0.0)))
        keep = may_pool & (lo_e <= best + 4 * tol + tie_hi)
        first = ends[:-1][keep]
        last = ends[1:][keep]
        idx = np.unique(np.concatenate([i0, _ranges(first - 1, last)]))
        return idx, any_ok, (tie_lo, tie_hi)


@dataclass(frozen=True)
class FlexibleTwoPosition:
    """P0's flexible dual-position rule (as reconstructed in the paper digest).

    Running sums over the *stop* phases only, sampled at ``f``:
    ``Sc = sum cos(psi_imu)``, ``Ss = sum sin(psi_imu)``. One cycle:

    1. stop ``Ts``; turn forward and stop when ``|cos psi + Sc/(f Ts)| < delta`` and
       ``sin psi`` has the sign opposite to ``Ss``;
    2. stop ``Ts``; turn +180 deg;
    3. stop ``Ts``; turn backward and stop when ``|sin psi + Ss/(f Ts)| < delta`` and
       ``cos psi`` has the sign opposite to ``Sc``;
    4. stop ``Ts``; turn -180 deg.

    ``variant="crossing"`` replaces the ``< delta`` test by a sign change of the
    expression between samples (with the same sign condition). A sum that vanishes
    to round-off (``|S| <= 1e-9 f Ts``, e.g. when every stop spans whole revolutions
    of the IMU heading, as on a vehicle turning at 6 deg/s with 300 s stops) sets no
    sign condition: its sign would be noise.

    Fallback. The rule can fail: ``|Sc/(f Ts)| > 1`` has no root, and a yawing
    vehicle can carry psi past the window or hold it still (a vehicle turning at
    the table rate in the table's direction freezes psi for the whole turn). If no
    sample of one full turn (360 deg of table angle) passes the test, the table
    stops at the *best* sample of that turn instead of turning again: the one with
    the smallest ``|expression|`` among the samples that meet the sign condition (all
    samples if none does), the earliest (shortest turn) among equal values. A
    fallback turn is therefore always shorter than 360 deg, and it stops where the
    next stop cancels as much of the residue as one turn can reach. Choosing the
    best sample needs the IMU heading over the coming turn: the planner reads it
    from the vehicle motion, i.e. it assumes the heading over one turn (60 s at
    6 deg/s) is predictable; the regular stop test uses only the present sample.
    (The earlier fallback kept turning into a second revolution: 16 fallback turns of
    360.06 to 720 deg in 6 h of a steady 6 deg/s vehicle turn; comparison in
    ``docs/schemes.md``.) Fallback
    turns are labelled ``"variable turn (fallback)"`` and counted in
    ``meta["fallbacks"]``.

    Psi_imu is the true IMU heading (the INS's own heading differs by its heading
    error, arc-minutes, which does not move a 0.01 threshold).

    ``start="turn"`` leaves out the opening stop: the run begins with step 1's
    variable turn, its stop test on empty sums (``Sc = Ss = 0``, so no sign condition).
    """

    rate: float
    stop: float
    delta: float = 0.01
    f: float = 100.0
    variant: str = "threshold"
    mounting: np.ndarray | None = field(default=None, compare=False)
    name: str = "flexible-two-position"
    start: str = "stop"

    def __post_init__(self) -> None:
        if self.variant not in ("threshold", "crossing"):
            raise InputError(
                "scheme.variant", f"unknown variant {self.variant!r}", "use threshold or crossing"
            )
        _check_start(self.start)

    def _variable_turn(
        self, b: ScheduleBuilder, sums: list, which: int, direction: float, search
    ) -> bool:
        """Turn until the stop test passes; returns True if the fallback was used."""
        scale = self.f * self.stop
        c = sums[which] / scale
        # A sum that is zero to round-off sets no sign condition (see the class docstring).
        s_other = (
            math.copysign(1.0, sums[1 - which]) if abs(sums[1 - which]) > 1e-9 * scale else 0.0
        )
        n = search.first_pass(b.t, b.a, direction, which, c, s_other)
        fallback = n is None
        if fallback:
            n = search.best_sample(b.t, b.a, direction, which, c, s_other)
        b.rotate(
            "outer",
            direction * self.rate * n / self.f,
            self.rate,
            "variable turn" + (" (fallback)" if fallback else ""),
        )
        return fallback

    def plan(self, motion: Motion, duration: float) -> TableSchedule:
        """Run the rule over ``duration`` seconds of ``motion``."""
        search = _TurnSearch(self, motion, duration)
        stop_sums = _stop_sums(motion, self.f, search.geo)
        b = ScheduleBuilder(0.0, 0.0, self.mounting)
        sums = [0.0, 0.0]  # Sc, Ss
        fallbacks = 0
        phase = 0
        opening_stop = self.start == "stop"
        while b.t < duration:
            if opening_stop or phase != 0 or b.t > 0:
                # The stop's samples: those at or after its start and before its end.
                k0 = math.ceil(b.t * self.f - 1e-9)
                k1 = math.ceil((b.t + self.stop) * self.f - 1e-9)
                sc, ss = stop_sums(k0, k1, b.a)
                sums = [sums[0] + sc, sums[1] + ss]
                b.stop(self.stop)
                if b.t >= duration:
                    break
            if phase == 0:
                fallbacks += self._variable_turn(b, sums, 0, +1.0, search)
            elif phase == 1:
                b.rotate("outer", math.pi, self.rate)
            elif phase == 2:
                fallbacks += self._variable_turn(b, sums, 1, -1.0, search)
            else:
                b.rotate("outer", -math.pi, self.rate)
            phase = (phase + 1) % 4
        b.meta["fallbacks"] = fallbacks
        b.meta["stop_sums"] = sums
        return b.build()


@dataclass(frozen=True)
class HeadingIsolation:
    """Two-position indexing with the vehicle's yaw removed by the table.

    The table steers the IMU heading along the static-base two-position pattern
    (hold ``Ts``, turn 180 deg at ``rate``, hold, turn 180 deg, hold, turn back, hold,
    turn back), compensating the vehicle yaw at every instant with the closed-form
    outer-gimbal angle of :func:`inserr.schemes.turntable.isolation_angle`. The motor therefore
    runs continuously; every reversal of the table rate counts as a motor start
    (``meta["isolation_reversals"]``).

    Why the run opens with an isolation *hold* (``kind == "isolate"``, label
    ``"hold 0"``, target rate 0) and not a literal stop: a stop is the phase in which
    the IMU keeps one orientation, so that a bias projects onto a fixed
    navigation-frame direction. Every other scheme gets that by freezing the gimbals
    because its navigation-frame attitude changes only with the vehicle; this scheme
    exists to remove the vehicle's yaw, so its stop freezes the IMU *heading* and the
    table absorbs the yaw. The hold starts at t = 0 at the first position (table
    angle 0, IMU heading ``h0`` = the vehicle's heading at t = 0 plus the mounting
    offset) and lasts ``stop``; on a vehicle that does not yaw it is a literal stop
    (the table angle stays constant, ``tests/test_schedule.py``). Freezing the
    gimbals instead would let the first position swing with the yaw, which is
    exactly what the scheme is built to prevent.

    ``meta["isolation_reversals"]`` counts the sign changes of the outer angle's
    change between neighbouring samples at ``count_rate``, hour by hour (the pair
    that straddles two hours is not compared), changes of at most 1e-9 rad left out
    (:func:`_count_reversals`).
    """

    rate: float
    stop: float
    mounting: np.ndarray | None = field(default=None, compare=False)
    name: str = "heading-isolation"
    count_rate: float = 4.0  # Hz at which table-rate reversals are counted
    start: str = "stop"

    def __post_init__(self) -> None:
        _check_start(self.start)

    def _segments(self, h0: float, duration: float) -> list[tuple[float, float, float, str]]:
        """``(duration, start heading, heading-rate sign, label)`` of every segment, in order.

        With ``start="turn"`` the opening hold is left out: the run begins with the
        first turn.
        """
        turn = math.pi / self.rate
        pattern = [(-1.0, "180"), (-1.0, "360"), (+1.0, "180"), (+1.0, "0")]
        hold = max(self.stop, 0.0)  # the builder skips (and does not time) empty segments
        first_hold = hold if self.start == "stop" else 0.0
        segs = [(first_hold, h0, 0.0, "hold 0")]
        t, h = first_hold, h0  # the builder's clock: t += each duration
        i = 0
        while t < duration:
            sign, lab = pattern[i % 4]
            segs.append((turn, h, sign, f"turn -> {lab}"))
            t += turn
            h += sign * math.pi
            if t >= duration:
                break
            segs.append((self.stop, h, 0.0, f"hold {lab}"))
            t += hold
            i += 1
        return segs

    def plan(self, motion: Motion, duration: float) -> TableSchedule:
        """Schedule of isolation segments covering ``duration``."""
        h0 = float(_imu_heading(motion, np.array([0.0]), np.array([0.0]), self.mounting)[0])
        segs = [s for s in self._segments(h0, duration) if s[0] > 0]
        dur = np.array([s[0] for s in segs])
        start = np.array([s[1] for s in segs])
        sign = np.array([s[2] for s in segs])
        t_start = np.zeros(len(segs))
        for k in range(1, len(segs)):  # the builder's clock, summed in its order
            t_start[k] = t_start[k - 1] + dur[k - 1]
        t_end = t_start + dur
        target = start + sign * math.pi
        # Outer angle at each segment end (closed form, all at once), then its branch:
        # next to the level-vehicle prediction from the angle at the segment start.
        raw = isolation_angle(motion.attitude(t_end), 0.0, self.mounting, target)
        h_start, h_end = motion.heading_at(t_start), motion.heading_at(t_end)
        b = ScheduleBuilder(0.0, 0.0, self.mounting)
        for k, (d, h, s, label) in enumerate(segs):
            guess = b.a + float(h_end[k] - h_start[k]) - (float(target[k]) - h)
            a_end = guess + math.remainder(float(raw[k]) - guess, 2 * math.pi)
            b.isolate(d, h, b.a, a_end, s * self.rate, label)
        sched = b.build()
        sched.meta["isolation_reversals"] = _count_reversals(
            sched, motion, duration, self.count_rate
        )
        return sched


# ---------------------------------------------------------------------------------------
# Heading isolation: reversals of the table rate
# ---------------------------------------------------------------------------------------
_COUNT_CHUNK = 3600.0  # s; the count compares neighbouring samples within each hour


def _count_reversals(sched: TableSchedule, motion: Motion, duration: float, rate_hz: float) -> int:
    """Sign changes of the outer-gimbal rate, sampled at ``rate_hz``.

    The rate's sign between two neighbouring samples (within the same hour) is the
    sign of the change of the outer angle; changes of at most 1e-9 rad are left out.
    Computed from the motion's closed form where possible
    (:func:`_count_reversals_from_breaks`), else from every sample.
    """
    n = _count_reversals_from_breaks(sched, motion, duration, rate_hz)
    return n if n is not None else _count_reversals_sampled(sched, motion, duration, rate_hz)


def _count_reversals_sampled(
    sched: TableSchedule, motion: Motion, duration: float, rate_hz: float
) -> int:
    """:func:`_count_reversals` from the outer angle at every sample (chunked by hour)."""
    n = 0
    last = 0.0
    t0 = 0.0
    while t0 < duration:
        t = np.arange(t0, min(t0 + _COUNT_CHUNK, duration), 1.0 / rate_hz)
        a, _ = sched.angles_at(t, motion)
        d = np.diff(np.unwrap(a))
        s = np.sign(d[np.abs(d) > 1e-9])
        if len(s):
            seq = np.concatenate([[last], s]) if last else s
            n += int(np.count_nonzero(np.diff(seq)))
            last = s[-1]
        t0 += _COUNT_CHUNK
    return n


def _count_reversals_from_breaks(
    sched: TableSchedule, motion: Motion, duration: float, rate_hz: float
) -> int | None:
    """:func:`_count_reversals` without the outer angle at every sample (None: cannot).

    Why it works. In an isolation segment the outer angle is ``a = G(phi)`` with
    ``phi = H(t) - target(t)``: the vehicle attitude enters the closed form only
    through ``H - target`` (turning the vehicle and the target heading together turns
    the solution with them). ``G`` inverts ``-offset``, so it increases, with slope
    between ``1/hi`` and ``1/lo`` (:meth:`OuterAxisHeading.slope_bounds`; needs
    ``lo > 0``). The outer angle therefore changes with the sign of the change of
    ``phi``, and ``phi' = H' - target_rate`` can change sign only at the times
    :func:`heading_rate_breaks` gives for that segment's target rate and at segment
    boundaries. Between those times every sample pair changes the angle the same
    way, so one pair whose change is clearly above 1e-9 stands for the whole run of
    pairs. The pairs holding a break are taken one by one from ``phi``; where a
    change is within round-off of 0 or 1e-9 the outer angle itself is computed
    (:meth:`TableSchedule.angles_at`), as in the sampled count.

    The samples are ``g / rate_hz`` (hour by hour, as ``np.arange`` gives them); this
    needs them exact in binary (``1 / rate_hz`` a short binary fraction, 0.25 s at
    the default 4 Hz).
    """
    step = 1.0 / rate_hz
    per_hour = _COUNT_CHUNK / step
    if not (per_hour.is_integer() and (step * 2.0**32).is_integer()):
        return None
    if any(k != "isolate" for k in sched.kind) or np.any(sched.b0):
        return None
    lo, hi = OuterAxisHeading(motion.tilt, sched.mounting).slope_bounds()
    if not lo > 0:
        return None
    last_seg = len(sched.t0) - 1
    events = [sched.t0[1:]]
    for level in sorted(set(sched.target_rate.tolist())):
        br = heading_rate_breaks(motion, float(level), duration)
        if br is None:
            return None
        k = np.clip(np.searchsorted(sched.t0, br, side="right") - 1, 0, last_seg)
        events.append(br[sched.target_rate[k] == level])
    # Piecewise-linear headings: phi' is constant between breaks, not only of one sign.
    constant = type(motion) in (Motion, Turn, HeadingHistory) or motion.is_static
    hour = math.floor(duration / _COUNT_CHUNK) * _COUNT_CHUNK
    n = int(hour / step) + len(np.arange(hour, duration, step))  # samples, as the hours give
    if n < 2:
        return 0

    def phi(g: np.ndarray) -> np.ndarray:
        # H - target at samples g, segment and time taken as angles_at takes them.
        t = g * step
        k = np.clip(np.searchsorted(sched.t0, t, side="right") - 1, 0, last_seg)
        tau = np.minimum(t - sched.t0[k], sched.duration[k])
        return motion.heading_at(t) - sched.target_heading[k] - sched.target_rate[k] * tau

    # Round-off of a and of phi: a few ulp of the largest heading or angle involved
    # (16 ulp: a fourfold margin over the roundings in either).
    scale = 8 * math.pi + float(np.max(np.abs(motion.heading_at(np.array([0.0, duration])))))
    scale += float(np.max(np.abs(sched.target_heading))) + float(np.max(np.abs(sched.a0)))
    tiny = 16 * np.finfo(float).eps * scale

    def classify(pairs: np.ndarray, margin: float = tiny) -> np.ndarray:
        """Sign of each pair's angle change: +-1 counted, 0 left out, NaN too close to call."""
        d = phi(pairs + 1) - phi(pairs)
        size = np.abs(d)
        counted = (size - margin) / hi - margin > 1e-9
        left_out = (size + margin) / lo + margin <= 1e-9
        return np.where(counted, np.sign(d), np.where(left_out, 0.0, np.nan))

    def settle(pairs: np.ndarray, sign: np.ndarray) -> np.ndarray:
        """The NaN signs replaced by those of the outer angle itself."""
        unsure = np.isnan(sign)
        if unsure.any():
            p = pairs[unsure]
            a, _ = sched.angles_at(np.concatenate([p, p + 1]) * step, motion)
            d = a[len(p) :] - a[: len(p)]
            sign[unsure] = np.where(np.abs(d) > 1e-9, np.sign(d), 0.0)
        return sign

    # Pair g compares samples g and g + 1, unless g + 1 starts an hour. The pairs
    # whose span (widened by 1 us for the breaks' round-off) holds a break:
    e = np.sort(np.concatenate(events))
    first = np.floor((e - 1e-6) / step).astype(np.int64)
    stop = np.floor((e + 1e-6) / step).astype(np.int64) + 1
    pairs = _ranges(*_merge(np.clip(first, 0, n - 1), np.clip(stop, 0, n - 1)))
    pairs = pairs[(pairs + 1) % int(per_hour) != 0]
    where, signs = [pairs], [settle(pairs, classify(pairs))]
    # The runs of compared pairs between them: the middle pair stands for its run if
    # its change is clearly counted, or, with phi' constant, clearly left out (with a
    # wider margin: the other pairs differ from it by round-off).
    hours = np.arange(int(per_hour) - 1, n - 1, int(per_hour))
    taken = np.sort(np.concatenate([[-1], pairs, hours, [n - 1]]))
    gap = np.flatnonzero(np.diff(taken) > 1)
    starts, stops = taken[gap] + 1, taken[gap + 1]
    mid = (starts + stops) // 2
    s_mid = classify(mid, 4 * tiny if constant else tiny)
    settled = (np.abs(s_mid) == 1) | ((s_mid == 0) & constant)
    where.append(mid)
    signs.append(np.where(settled, s_mid, 0.0))
    whole = np.flatnonzero(~settled)
    if len(whole):
        p = _ranges(starts[whole], stops[whole])
        where.append(p)
        signs.append(settle(p, classify(p)))
    seq = np.concatenate(signs)[np.argsort(np.concatenate(where), kind="stable")]
    seq = seq[seq != 0]
    return int(np.count_nonzero(np.diff(seq)))
