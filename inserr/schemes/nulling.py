"""The nulling two-position rule: indexing that cannot resonate with the vehicle's heading motion.

Why a new rule (``docs/nulling.md`` has the derivation and the evidence). On a
base that yaws, every constant IMU error leaves, after each turn of the table, a
small *kick* in the accumulated navigation-frame error integral, and the kick
depends on the phase of the heading motion at which the turn happens. Two kinds
matter:

* the *projection* integral ``P(t) = integral of C_s^n dt`` (horizontal rows),
  which multiplies the biases and the Earth-rate part of the scale-factor and
  misalignment errors;
* the *rate-coupled* integrals ``integral of C_s^n K w^s dt`` of the table and
  vehicle rates; on a tilted vehicle the yaw rate has a component along the
  IMU x and y axes, and misalignment x yaw rate drives the heading error.

A fixed stop time makes the turn phases a fixed progression
``phi_k = phi_0 + k alpha`` with ``alpha = 2 pi (Ts + pi / r) / T`` (``T`` the
period of the heading motion). The kicks form sums ``sum_k s_k F(phi_k)`` whose
sign pattern ``s_k`` (+-1, the table position, the turn direction) repeats every
one, two or four turns, so they are geometric series in ``exp(i (nu + m alpha))``
with ``nu`` in {0, pi/2, pi, 3pi/2} and ``m`` a harmonic of the kick function.
They grow linearly when ``nu + m alpha = 0 (mod 2 pi)`` (resonance: the
traditional cycle at 30, 60, 165, 330, 660 s for P0's set-up) and stay bounded
otherwise, by ``|F_m| / |2 sin((nu + m alpha) / 2)|``.

The rule therefore

1. estimates the period of the heading oscillation from the times at which the
   yaw rate changes sign (only the past: what a real controller has), and
2. lengthens every stop by the least amount (less than ``T/2``) that makes the
   swing phase advance per step a golden section of a half period,
   ``frac(2 S / T) = 0.382 or 0.618``: then ``2 m S / T`` is never an integer (the
   sign patterns ``nu = 0, pi``, which carry the strongest kicks, never resonate)
   and ``nu + m alpha`` stays at least ~21 deg from resonance for every ``nu`` and
   ``m = 1, 2, 3``, so every accumulated integral stays within a few single-step
   kicks.

The table follows the mean-zero two-position order ``0 -> +pi -> 0 -> -pi -> 0``
(turns ``+, -, -, +``): pairs of 180 deg turns cancel the rotation-phase
projection on a static base, the net table angle stays within +-pi with mean
zero (so the z-gyro scale factor leaves no mean heading error), and no slip ring
is needed. Turns are exactly 180 deg and stops last at least ``Ts``, so the
motor never starts more often than in the traditional cycle. Without heading
oscillation (static base, steady turn, swing below ``delta``) every stop lasts
``Ts``.

With ``phase="synchronous"`` step 2 is replaced: every stop lasts until the next
turn can be centred on a heading maximum (:func:`synchronous_dwell`), so consecutive
turns are whole swing periods apart and everything linear in the table's sign cancels
over each two-turn cycle instead of staying bounded (``docs/nulling.md`` section 3b).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field

import numpy as np

from inserr.core.errors import InputError
from inserr.core.imu import MISALIGNMENT_INDEX, MISALIGNMENTS
from inserr.core.rotations import log_so3
from inserr.schemes.turntable import ScheduleBuilder, TableSchedule
from inserr.schemes.vehicle_motion import Motion, heading_rate_breaks

#: Turn directions of the mean-zero two-position cycle (0, +pi, 0, -pi, 0).
TURNS = (+1.0, -1.0, -1.0, +1.0)
#: Target swing-phase advance per step, ``frac(step / period)`` modulo :data:`PHASE_MODULUS`:
#: the golden sections of a half period, ``frac(2 step / period)`` = 0.382 or 0.618. Then
#: ``2 m step / period`` is never an integer (no resonance of the sign patterns 0 and pi at
#: any harmonic m) and ``4 m step / period`` stays at least 0.236 from an integer for
#: m = 1, 2, 3 (every sign pattern at least 21 deg from resonance).
PHASE_FRACTIONS = ((3.0 - math.sqrt(5.0)) / 4.0, (math.sqrt(5.0) - 1.0) / 4.0)
PHASE_MODULUS = 0.5
#: Yaw-rate history used for the period estimate, in stop times.
HISTORY_STOPS = 8
#: How the rule places its turns (``phase``): ``"golden"`` lengthens each stop so that
#: the swing phase advances by a golden section (the rule above); ``"synchronous"``
#: centres every turn on a heading maximum (see :func:`synchronous_dwell`).
PHASES = ("golden", "synchronous")
#: Swing tests guessed before they are computed together (see NullingTwoPosition._periods).
SWING_BATCH = 64
#: Yaw-rate samples computed either side of a time where the rate may change sign.
BREAK_SAMPLES = 3


def yaw_rate_reversals(motion: Motion, duration: float, f: float) -> np.ndarray:
    """Times at which the vehicle yaw rate changes sign, from samples at ``f`` Hz.

    Each time is the linear interpolation of the zero between two samples of
    opposite sign, or the middle of a run of exactly-zero samples between them (a
    hold between opposite turns). Where the motion tells where its rate can change
    sign (:func:`~inserr.schemes.vehicle_motion.heading_rate_breaks`) only the
    samples within a few of those times are computed: between them the rate keeps
    its sign, so the other samples cannot change the result. Otherwise every sample
    is, an hour at a time to bound memory.

    Parameters
    ----------
    motion : Motion
        Vehicle motion (heading rate, rad/s, clockwise positive).
    duration : float
        Length of the run, s.
    f : float
        Sampling rate of the yaw rate, Hz.

    Returns
    -------
    (K,) ndarray
        Reversal times, s, sorted and unique.
    """
    breaks = heading_rate_breaks(motion, 0.0, duration)
    if breaks is None:
        return _reversals_sampled(motion, duration, f)
    # Samples 0 .. floor(f duration); BREAK_SAMPLES either side of each break (a margin
    # far beyond the breaks' round-off) hold every sign change and its two samples.
    centre = np.floor(breaks * f).astype(np.int64)
    k = _sorted_unique((centre[:, None] + np.arange(-BREAK_SAMPLES, BREAK_SAMPLES + 2)).ravel())
    k = k[(k >= 0) & (k <= math.floor(duration * f))]
    t = k / f
    return _sorted_unique(_sign_changes(t, motion.heading_rate(t), f))


def _sorted_unique(x: np.ndarray) -> np.ndarray:
    """``np.unique(x)`` by sorting (numpy 2.4's hash-based unique is far slower here)."""
    x = np.sort(x)
    return x[np.concatenate([[True], x[1:] != x[:-1]])] if len(x) else x


def _sign_changes(t: np.ndarray, r: np.ndarray, f: float) -> np.ndarray:
    """Zeros of the rate between consecutive non-zero samples ``(t, r)`` of opposite sign."""
    # A reversal may pass through exact zeros (a hold between opposite turns): look
    # for sign changes between consecutive NON-ZERO samples.
    nz = np.flatnonzero(r != 0.0)
    tn, rn = t[nz], r[nz]
    k = np.flatnonzero(np.sign(rn[1:]) * np.sign(rn[:-1]) < 0)
    adjacent = np.isclose(tn[k + 1] - tn[k], 1.0 / f)
    # Adjacent samples: the interpolated zero. Across a run of zeros: its middle.
    return np.where(
        adjacent,
        tn[k] + rn[k] / (rn[k] - rn[k + 1]) * (tn[k + 1] - tn[k]),
        0.5 * (tn[k] + tn[k + 1]),
    )


def _reversals_sampled(motion: Motion, duration: float, f: float) -> np.ndarray:
    """:func:`yaw_rate_reversals` from every sample, an hour at a time."""
    out = []
    chunk = 3600.0
    t0 = 0.0
    last: tuple[float, float] | None = None  # last non-zero sample (t, rate) seen so far
    while t0 < duration:
        t = np.arange(math.ceil(t0 * f), math.floor(min(t0 + chunk, duration) * f) + 1) / f
        r = motion.heading_rate(t)
        if last is not None:  # carried across chunks
            t, r = np.concatenate([[last[0]], t]), np.concatenate([[last[1]], r])
        out.append(_sign_changes(t, r, f))
        nz = np.flatnonzero(r != 0.0)
        if len(nz):
            last = (float(t[nz[-1]]), float(r[nz[-1]]))
        t0 += chunk
    return _sorted_unique(np.concatenate(out) if out else np.zeros(0))


def heading_period(reversals: np.ndarray, t: float, history: float) -> float | None:
    """Period of the heading oscillation seen in the window ``(t - history, t]``.

    Twice the mean spacing of the yaw-rate reversals in the window; at least three
    reversals are required.

    Parameters
    ----------
    reversals : (K,) array or list
        Sorted yaw-rate reversal times, s (:func:`yaw_rate_reversals`; a list is
        searched faster).
    t : float
        End of the window, s.
    history : float
        Length of the window, s.

    Returns
    -------
    float or None
        Period, s; None with fewer than three reversals in the window.
    """
    lo = bisect.bisect_right(reversals, t - history)
    hi = bisect.bisect_right(reversals, t)
    if hi - lo < 3:
        return None
    return 2.0 * float(reversals[hi - 1] - reversals[lo]) / (hi - lo - 1)


def step_dwell(
    stop: float, turn_time: float, period: float | None, extension: float
) -> float | None:
    """Shortest dwell >= ``stop`` whose step advances the swing phase by the target.

    The target is ``frac(step / period) = x (mod PHASE_MODULUS)`` for ``x`` in
    :data:`PHASE_FRACTIONS`, whichever needs the shorter dwell; the step is the dwell
    plus the turn time.

    Parameters
    ----------
    stop : float
        Minimum stop time ``Ts``, s.
    turn_time : float
        Duration of the table turn that follows the stop, s.
    period : float or None
        Period of the heading oscillation, s (None: no oscillation).
    extension : float
        Longest lengthening allowed, s.

    Returns
    -------
    float or None
        The dwell (s); ``stop`` when ``period`` is None; None if the required
        lengthening exceeds ``extension``.
    """
    if period is None:
        return stop
    phase = ((stop + turn_time) / period) % PHASE_MODULUS
    extra = min((x - phase) % PHASE_MODULUS for x in PHASE_FRACTIONS) * period
    return stop + extra if extra <= extension else None


def heading_maxima(motion: Motion, reversals: np.ndarray) -> np.ndarray:
    """The yaw-rate reversals that are heading maxima (clockwise-most headings).

    Between two consecutive reversals the yaw rate keeps its sign (it may rest at zero),
    so a reversal is a maximum when the heading rose since the previous one (since
    t = 0 for the first). The heading there is known when the reversal is: past data
    only. (The rate just after a reversal is no test: in a hold at a peak, where the
    reversal is placed mid-hold, it reads zero.)
    """
    r = np.asarray(reversals, dtype=float)
    if not len(r):
        return r
    h = motion.heading_at(np.concatenate([[0.0], r]))
    return r[np.diff(h) > 0.0]


def synchronous_dwell(
    stop: float,
    turn_time: float,
    start: float,
    period: float | None,
    last_maximum: float | None,
    extension: float | None,
) -> float | None:
    """Dwell that makes the next turn centred on a heading maximum.

    Every turn of the two-position table flips the sign of the constant errors'
    projection; if every turn happens at the same phase of a periodic heading swing,
    each stop holds a whole number of swing periods, the two halves of every two-turn
    cycle see the same swing with opposite table signs, and everything that is linear
    in the table's sign cancels over the cycle: the bias projection and the kicks of
    the yaw rate on a tilted vehicle (``docs/nulling.md``). Centring the turn on the
    maximum (it starts ``turn_time / 2`` before it, where the yaw rate is least) makes
    the turn itself the same, mirrored, every time. The next maximum is predicted from
    the last one seen and the period estimate (past data only).

    Parameters
    ----------
    stop : float
        Minimum stop time ``Ts``, s.
    turn_time : float
        Duration of the turn that follows, s.
    start : float
        Start of the stop, s.
    period : float or None
        Heading period estimate, s (None: no oscillation seen).
    last_maximum : float or None
        Time of the last heading maximum seen before ``start``, s.
    extension : float or None
        Longest lengthening allowed, s (None: any; the wait never exceeds a period).

    Returns
    -------
    float or None
        The dwell (s); ``stop`` without an oscillation or a maximum; None if the
        lengthening needed exceeds ``extension``.
    """
    if period is None or last_maximum is None:
        return stop
    if not (math.isfinite(period) and period > 0.0):
        raise ValueError(f"heading period must be finite and > 0 s, got {period!r}")
    if not (math.isfinite(last_maximum) and last_maximum <= start):
        raise ValueError(f"last maximum {last_maximum!r} s is not before the stop ({start} s)")
    earliest = start + stop + 0.5 * turn_time  # the first maximum the turn may centre on
    # A maximum within 1e-9 periods of the earliest centre is that centre: the times are
    # sums of many steps (hundreds of thousands of seconds), whose round-off would
    # otherwise push an exact fit to the next period.
    n = max(1, math.ceil((earliest - last_maximum) / period - 1e-9))
    dwell = last_maximum + n * period - 0.5 * turn_time - start
    if dwell - stop <= 1e-9 * period:  # also the round-off just below Ts
        dwell = stop
    return dwell if extension is None or dwell - stop <= extension else None


@dataclass(frozen=True)
class NullingTwoPosition:
    """Two-position indexing whose stop time keeps every error integral bounded.

    See the module docstring for the rule and ``docs/nulling.md`` for why it works.

    Parameters
    ----------
    rate : float
        Table rate, rad/s; every turn is 180 deg about the outer (azimuth) gimbal.
    stop : float
        Minimum stop time ``Ts``, s.
    mounting : (3, 3) array, optional
        IMU mounting ``C_s^t`` on the inner gimbal (see
        :class:`~inserr.schemes.turntable.TableSchedule`).
    f : float
        Sampling rate of the yaw rate used to find its reversals, Hz.
    delta : float
        Smallest peak-to-peak heading oscillation the rule reacts to, rad; below it
        every stop lasts ``Ts``.
    variant : str
        Only ``"threshold"`` (accepted so that the flexible rule's scenario
        options apply unchanged).
    extension : float, optional
        Longest lengthening of a stop, s (default ``Ts`` for the golden phase rule, no
        limit for the synchronous one, whose wait is less than a heading period); when
        more would be needed the stop lasts ``Ts``.
    name : str
        Scheme name used in reports.
    start : str
        ``"stop"`` (default): the run opens with a stop; ``"turn"``: with the first
        turn (+180 deg), each stop then following its turn.
    phase : str
        ``"golden"`` (default): stops lengthened to a golden-section phase advance
        (:func:`step_dwell`); ``"synchronous"``: every turn centred on a heading maximum
        (:func:`synchronous_dwell`). :data:`PHASES`.
    """

    rate: float
    stop: float
    mounting: np.ndarray | None = field(default=None, compare=False)
    f: float = 100.0
    delta: float = 0.01
    variant: str = "threshold"
    extension: float | None = None
    name: str = "nulling-two-position"
    start: str = "stop"
    phase: str = "golden"

    def __post_init__(self) -> None:
        if self.phase not in PHASES:
            raise InputError(
                "scheme.phase",
                f"unknown phase rule {self.phase!r}",
                f"use one of: {', '.join(PHASES)}",
            )
        if self.variant != "threshold":
            raise InputError(
                "scheme.variant",
                f"{self.variant!r} does not apply to {self.name}",
                "remove scheme.variant (the nulling rule has no stop-test variants)",
            )
        if not (math.isfinite(self.f) and self.f > 0):
            raise InputError("scheme.decision_rate", f"must be > 0 Hz, got {self.f!r}")
        if not (math.isfinite(self.delta) and self.delta >= 0):
            raise InputError("scheme.delta", f"must be >= 0 rad, got {self.delta!r}")
        ext = self.extension
        if ext is not None and not (math.isfinite(ext) and ext >= 0):
            raise InputError("scheme.extension", f"must be >= 0 s, got {ext!r}")
        if self.start not in ("stop", "turn"):
            raise InputError(
                "scheme.start", f"unknown opening phase {self.start!r}", "use one of: stop, turn"
            )

    def _swing_seen(self, motion: Motion, times: list[float]) -> np.ndarray:
        """Whether the heading swing (peak to peak) over the history before each time reaches delta.

        The swing is that of 512 evenly spaced headings over ``(t - history, t]``
        (``np.linspace`` of the arrays gives each row as one call per time would). Every
        8th heading is looked at first: when those span ``delta`` so do all 512.
        """
        t = np.asarray(times, dtype=float)
        grid = np.linspace(np.maximum(0.0, t - HISTORY_STOPS * self.stop), t, 512, axis=-1)

        def swing(g: np.ndarray) -> np.ndarray:
            return np.ptp(motion.heading_at(g.ravel()).reshape(g.shape), axis=1)

        seen = swing(grid[:, ::8]) >= self.delta
        rest = np.flatnonzero(~seen)
        if len(rest):
            seen[rest] = swing(grid[rest]) >= self.delta
        return seen

    def _periods(
        self, motion: Motion, duration: float, turn_time: float, ext: float | None
    ) -> tuple[list, list]:
        """Heading period each stop uses (None: no oscillation seen), in order, and the
        heading maxima the synchronous phase rule needs (empty for the golden one).

        A stop's period is the estimate from the yaw-rate reversals before it
        (:func:`heading_period`, a reversal being known one sample after it
        happens), kept only if the heading swing over the same history reaches
        ``delta``. The swing test is the costly part, and every stop's start depends on
        the earlier outcomes; so the stops are run ahead with each outcome guessed
        (the last one known), the guesses are tested together, and the run restarts
        from the first wrong guess. The outcomes are those of testing one by one.
        """
        rev = yaw_rate_reversals(motion, duration, self.f)
        reversals = rev.tolist()
        maxima = heading_maxima(motion, rev).tolist() if self.phase != "golden" else []
        history = HISTORY_STOPS * self.stop
        starts: list[float] = []
        periods: list[float | None] = []
        known: dict[int, bool] = {}  # swing-test outcome of stop i, once tested
        guessed: list[int] = []  # stops whose outcome is guessed, not yet tested
        guess = True
        t = 0.0 if self.start == "stop" else turn_time  # after the opening turn
        while True:
            while t < duration and len(guessed) < SWING_BATCH:
                i = len(starts)
                period = heading_period(reversals, t - 1.0 / self.f, history) if t > 0 else None
                if period is not None:
                    if i not in known:
                        guessed.append(i)
                    if not known.get(i, guess):
                        period = None
                starts.append(t)
                periods.append(period)
                # the builder's clock, in its order
                t += self._dwell(period, turn_time, ext, t, maxima)[0]
                if t >= duration:
                    break
                t += turn_time
            if not guessed:
                return periods, maxima
            seen = self._swing_seen(motion, [starts[i] for i in guessed]).tolist()
            wrong = next((n for n, s in enumerate(seen) if s != guess), None)
            tested = guessed if wrong is None else guessed[: wrong + 1]
            known.update(zip(tested, seen, strict=False))
            if wrong is not None:  # restart at the stop guessed wrong
                i = guessed[wrong]
                t = starts[i]
                del starts[i:], periods[i:]
                guess = seen[wrong]
            guessed = []

    def _dwell(
        self, period: float | None, turn_time: float, ext: float | None, start: float, maxima: list
    ) -> tuple[float, bool]:
        """The dwell (s) of the stop from ``start`` and whether it fell back to ``Ts``
        (:func:`step_dwell`, or :func:`synchronous_dwell` with the last heading maximum
        of ``maxima`` known at ``start``, one sample after it)."""
        if self.phase == "golden":
            dwell = step_dwell(self.stop, turn_time, period, ext)
        else:
            i = bisect.bisect_right(maxima, start - 1.0 / self.f)
            last = maxima[i - 1] if i else None
            dwell = synchronous_dwell(self.stop, turn_time, start, period, last, ext)
        return (self.stop, True) if dwell is None else (dwell, False)

    def plan(self, motion: Motion, duration: float) -> TableSchedule:
        """Plan the table schedule the rule produces for a vehicle motion.

        Parameters
        ----------
        motion : Motion
            Vehicle motion (heading in rad, heading rate in rad/s).
        duration : float
            Length of the run, s.

        Returns
        -------
        TableSchedule
            Stops and 180 deg outer-gimbal turns; ``meta`` records ``fallbacks``
            (stops left at ``Ts`` because the period needed more than
            ``extension``), ``lengthened`` (stops lengthened) and the
            ``period_estimates_s`` used (one per stop, s, NaN where none).
        """
        turn_time = math.pi / self.rate
        if self.extension is not None:
            ext = self.extension
        else:  # golden: Ts; synchronous: any (it never waits more than a period)
            ext = self.stop if self.phase == "golden" else None
        periods, maxima = self._periods(motion, duration, turn_time, ext)
        b = ScheduleBuilder(0.0, 0.0, self.mounting)
        # Turn k follows stop k; opening with a turn shifts the pattern by one.
        first = 0 if self.start == "stop" else 1
        if first:
            b.rotate("outer", TURNS[0] * math.pi, self.rate, "turn +180")
        fallbacks = lengthened = 0
        for k, period in enumerate(periods):
            dwell, fallback = self._dwell(period, turn_time, ext, b.t, maxima)
            fallbacks += fallback
            lengthened += dwell > self.stop
            b.stop(dwell, f"stop {round(math.degrees(b.a)):+d}")
            if b.t >= duration:
                break
            d = TURNS[(k + first) % 4]
            b.rotate("outer", d * math.pi, self.rate, "turn +180" if d > 0 else "turn -180")
        b.meta.update(
            fallbacks=fallbacks,
            lengthened=lengthened,
            period_estimates_s=[math.nan if p is None else p for p in periods],
        )
        return b.build()


# ---------------------------------------------------------------------------------------
# The integrals the rule keeps bounded (for tests, reports and diagnosis)
# ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ErrorIntegrals:
    """Accumulated navigation-frame gyro error integrals per unit IMU error.

    For a unit error of each source the gyro error rate resolved in n is
    ``C_s^n b`` (bias) or ``C_s^n K w_is^s`` (scale factor, misalignment; ``w_is``
    the true IMU rate: Earth + vehicle + table). Its integral is, up to sign
    (``psi' = -eps^n``), the attitude error it would cause without the Earth-rate
    and Schuler coupling, so a scheme is good when these stay bounded.

    Attributes
    ----------
    t : (M,) ndarray
        Output times, s.
    names : tuple of str
        The N sources ``bias_x``... ``sf_z``, ``mis_xy``... ``mis_zy``.
    running : (M, N, 3) ndarray
        Running integral (E, N, U) at each output time: rad per unit error
        (dimensionless scale factor or rad of misalignment), s for a bias of 1 rad/s.
    by_phase : dict {"stop", "turn"} -> (N, 3) ndarray
        Integral over the whole run split by table phase, same units.
    """

    t: np.ndarray
    names: tuple[str, ...]
    running: np.ndarray
    by_phase: dict

    def __getitem__(self, name: str) -> np.ndarray:
        """Running integral of one source, (M, 3)."""
        return self.running[:, self.names.index(name)]


def _unit_matrices() -> tuple[tuple[str, ...], list[tuple[str, int, int]]]:
    rows = [(f"bias_{a}", i, -1) for i, a in enumerate("xyz")]
    rows += [(f"sf_{a}", i, i) for i, a in enumerate("xyz")]
    rows += [(f"mis_{m}", *MISALIGNMENT_INDEX[m]) for m in MISALIGNMENTS]
    return tuple(r[0] for r in rows), rows


def error_integrals(
    table: TableSchedule,
    motion: Motion,
    earth_rate_n: np.ndarray,
    duration: float,
    dt: float = 0.2,
    t_out: np.ndarray | None = None,
) -> ErrorIntegrals:
    """Integrals of the unit gyro error rates over a schedule (midpoint rule, step ``dt``).

    Parameters
    ----------
    table : TableSchedule
        Gimbal-angle history (gives ``C_s^b``).
    motion : Motion
        Vehicle motion (gives ``C_b^n``).
    earth_rate_n : (3,) array
        Earth rate resolved in ENU, rad/s (``Site.earth_rate_n``).
    duration : float
        Length of the run, s.
    dt : float
        Integration step, s (0.2 s resolves swings down to ~10 s periods and the
        6 deg/s turns).
    t_out : (M,) array, optional
        Output times, s (default every 60 s).

    Returns
    -------
    ErrorIntegrals
    """
    names, rows = _unit_matrices()
    if t_out is None:
        t_out = np.arange(0.0, duration + 1e-9, 60.0)
    is_turn = np.array([k != "stop" for k in table.kind])
    running = np.zeros((len(t_out), len(names), 3))
    phase = {"stop": np.zeros((len(names), 3)), "turn": np.zeros((len(names), 3))}
    acc = np.zeros((len(names), 3))
    chunk = 3600.0
    start = 0.0
    h = 1e-3
    while start < duration:
        t = np.arange(start, min(start + chunk, duration) - 1e-12, dt) + 0.5 * dt
        c = motion.attitude(t) @ table.dcm_at(t, motion)
        c_plus = motion.attitude(t + h) @ table.dcm_at(t + h, motion)
        c_minus = motion.attitude(t - h) @ table.dcm_at(t - h, motion)
        w_n = log_so3(c_plus @ np.swapaxes(c_minus, -1, -2)) / (2 * h)
        w_s = np.einsum("kji,kj->ki", c, w_n + earth_rate_n)
        seg = np.clip(np.searchsorted(table.t0, t, side="right") - 1, 0, len(table.t0) - 1)
        turn = is_turn[seg]
        rates = np.empty((len(t), len(names), 3))
        for j, (_, axis, col) in enumerate(rows):
            scale = 1.0 if col < 0 else w_s[:, col : col + 1]
            rates[:, j] = c[:, :, axis] * scale
        phase["stop"] += rates[~turn].sum(axis=0) * dt
        phase["turn"] += rates[turn].sum(axis=0) * dt
        cum = acc + np.cumsum(rates, axis=0) * dt
        ends = t + 0.5 * dt
        sel = (t_out > start - 1e-9) & (t_out <= ends[-1] + 1e-9)
        pos = np.clip(np.searchsorted(ends, t_out[sel] - 1e-9), 0, len(t) - 1)
        running[sel] = cum[pos]
        running[sel & (t_out <= start + 1e-9)] = acc
        acc = cum[-1]
        start += chunk
    return ErrorIntegrals(np.asarray(t_out, float), names, running, phase)
