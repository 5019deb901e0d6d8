"""Fast exact propagation of constant IMU errors and white noise at a fixed site.

The step-by-step engine (:mod:`inserr.model.exact_propagation`) carries the IMU
errors as states resolved in n and multiplies a 33 x 33 transition per step; under
a swinging base every step differs, which costs seconds per 72 h. This engine uses
the structure of the problem instead (``docs/theory.md``, "The fast engine"):

1. **Time-invariant navigation dynamics.** At a fixed site with zero velocity the
   navigation-error block ``F`` is constant, so in its eigenbasis
   (:class:`~inserr.model.modal.NavModes`) every mode is a scalar equation
   ``z' = lambda z + u_m(t)`` solved by ``z(t) = e^{lambda (t - a)} z(a) +
   int_a^t e^{lambda (t - s)} u_m(s) ds``.
2. **The attitude only enters the input.** A constant IMU-frame error projects into
   n through ``C_s^n(t)``: a gyro bias ``b`` drives ``psi' = -C b``, a gyro error
   matrix ``K`` drives ``psi' = -C K w_is^s`` with the true IMU rate
   ``w_is^s = C^T (Omega + w_ns^n)``; accelerometer errors drive ``dv' = C b_a`` and
   ``dv' = C K_a f^s`` with ``f^s = C^T f^n``. Every unit source's input is one of the
   63 *features* ``C[a, i]``, ``C[a, i] w_is^s[j]``, ``C[a, i] f^s[j]`` times a constant,
   so the 24 IMU sources cost one weighted time integral of 63 functions.
3. **Quadrature where the attitude is smooth.** The history is split into windows
   inside which ``C_s^n(t)`` is analytic (a stop, a turn, a stretch of a swing: see
   :class:`~inserr.model.attitude_history.Pieces`), short enough that the integrand's
   phase (twice the turn-rate bound, for the products of two attitude matrices, plus
   the fastest mode) stays within :data:`~inserr.model.quadrature.MAX_PHASE`; each
   window is sampled at Chebyshev points and integrated by Fejér's rule, and the
   fine output times inside it by integrating the interpolant
   (:mod:`inserr.model.quadrature`). Where the attitude is constant the integrals are
   closed forms (``int_0^L e^{lambda s} ds = L phi_1(lambda L)``).
4. **Scans, not steps.** The window-to-window recursion
   ``z_{k+1} = e^{lambda L_k} z_k + d_k`` is evaluated for all windows at once as
   ``z_k = e^{lambda s_k} (z_0 + sum_i e^{-lambda s_i} d_i)``, in blocks where a
   growing (free vertical channel) mode would overflow.
5. **White noise in closed form.** ARW and VRW drive the navigation states through
   an attitude-independent (isotropic) input, so the covariance is
   ``P(t) = V [M o Xi(t)] V^H`` with ``M = V^-1 B Q B^T V^-H`` and
   ``Xi_ij(t) = t phi_1((lambda_i + conj(lambda_j)) t)``.

Given a :class:`~inserr.model.attitude_history.TimelineHistory`, the engine solves
exactly the piecewise-constant-rate problem of the step-by-step engine and the two
agree to round-off (``tests/test_fast_propagation.py``); given the composed schedule
(:class:`inserr.schemes.composition.ScheduleHistory`) it integrates the true
continuous motion without sub-steps.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import as_strided
from scipy import sparse
from threadpoolctl import ThreadpoolController

from inserr.core.rotations import skew
from inserr.model.attitude_history import AttitudeHistory, Pieces
from inserr.model.modal import NavModes
from inserr.model.psi_model import DV, PSI, ErrorModel
from inserr.model.quadrature import (
    MAX_PHASE,
    chebyshev_points,
    fejer_weights,
    integral_of_series,
    integration_matrix,
    points_for,
)
from inserr.model.quadrature import _coefficient_matrix as coefficient_matrix

#: Nodes evaluated at once (bounds memory: ~63 features and R modal weights per node).
CHUNK_NODES = 40_000
#: Samples of a constant-rate window: the features are trigonometric polynomials of
#: degree 2 in the turn angle, which 5 equally spaced angles determine exactly.
ROTATION_SAMPLES = 5
#: Fine output times evaluated at once (bounds memory on long runs).
CHUNK_FINE = 200_000
#: Runs with more fine outputs than this split them into at least two blocks, which
#: :func:`engine_threads` threads may compute at once. The blocks depend on the output
#: count only, never on the thread count: the numbers are the same on any machine.
SPLIT_FINE = 50_000
#: Fine outputs of one run of a stop or a turn, at most (plus one window's): longer
#: pieces are cut into several runs (:meth:`_Run._run_lead`).
RUN_OUTPUTS = 4096
#: Largest |Re lambda| * time span of one scan block (keeps exp() within float range).
SCAN_SPAN = 200.0
#: Window boundaries closer than this (s) are merged.
MERGE = 1e-9

#: Feature layout of one node: C[a, i] (9), C[a, i] w[j] (27), C[a, i] f[j] (27).
N_FEATURES = 63


def phi1(z: np.ndarray) -> np.ndarray:
    """``(e^z - 1) / z`` (1 at z = 0), accurate for small and complex ``z``."""
    z = np.asarray(z)
    zero = z == 0
    if not np.any(zero):
        return np.expm1(z) / z
    zz = np.where(zero, 1.0, z)
    out = np.expm1(zz) / zz
    out[zero] = 1.0
    return out


class _OffsetTable:
    """``e^{lambda dt}`` and ``dt phi1(lambda dt)`` for many offsets ``dt`` (s).

    Fine output times on a uniform grid of step ``h`` sit, inside one window, at
    offsets ``dt = delta + k h`` from its start, with one fraction ``delta`` per window
    (``0 <= delta < h``) and integer ``k``. Then, exactly,

    ``e^{lambda dt} = e^{lambda delta} e^{lambda k h}`` and
    ``int_0^dt e^{lambda s} ds = int_0^{k h} e^{lambda s} ds + e^{lambda k h}
    int_0^delta e^{lambda s} ds``,

    so the transcendental functions are evaluated once per window and once per grid
    multiple (a table), and every output costs a lookup and a product. Without a grid
    (``h`` None) or a window index every offset is computed.
    """

    def __init__(
        self, lam: np.ndarray, dt: np.ndarray, h: float | None, window: np.ndarray | None = None
    ):
        self.lam, self.dt = lam, dt
        self.k = None
        if h is None or window is None or not len(dt):
            return
        # Runs of consecutive outputs in one window (outputs and windows are sorted).
        first = np.flatnonzero(np.concatenate([[True], window[1:] != window[:-1]]))
        run = np.repeat(np.arange(len(first)), np.diff(np.append(first, len(dt))))
        delta = dt[first] - np.floor(dt[first] / h + 1e-9) * h
        delta = np.where(delta < 0.0, 0.0, delta)
        k = np.rint((dt - delta[run]) / h).astype(np.int64)
        if np.any(np.abs(dt - delta[run] - k * h) > 1e-9 * np.maximum(1.0, dt)) or k.max() > 2**22:
            return  # not a uniform grid inside the windows: compute every offset
        self.k, self.run, self.first, self.delta = k, run, first, delta
        grid = np.arange(k.max() + 1) * h
        self._exp = np.exp(lam[None, :] * grid[:, None])
        self._phi = grid[:, None] * phi1(lam[None, :] * grid[:, None])
        d = delta[:, None]
        self._exp_d = np.exp(lam[None, :] * d)
        self._phi_d = d * phi1(lam[None, :] * d)

    def exp(self, sel: np.ndarray) -> np.ndarray:
        """``e^{lambda dt}`` at the offsets ``sel`` (index array), (len(sel), R)."""
        if self.k is not None:
            return self._exp[self.k[sel]] * self._exp_d[self.run[sel]]
        return np.exp(self.lam[None, :] * self.dt[sel, None])

    def phi(self, sel: np.ndarray) -> np.ndarray:
        """``dt phi1(lambda dt)`` at the offsets ``sel``, (len(sel), R)."""
        if self.k is not None:
            k = self.k[sel]
            return self._phi[k] + self._exp[k] * self._phi_d[self.run[sel]]
        d = self.dt[sel, None]
        return d * phi1(self.lam[None, :] * d)


# ---------------------------------------------------------------------------------------
# The error sources as the engine sees them
# ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SourceSet:
    """Constant error sources split into IMU errors (inputs) and initial errors (states).

    Attributes
    ----------
    imu_kind : (N,) int
        Per source: 0 gyro bias, 1 accelerometer bias, 2 gyro error-matrix entry,
        3 accelerometer error-matrix entry, -1 initial navigation error.
    imu_i, imu_j : (N,) int
        Axis (bias: i) or matrix entry (i, j) in the IMU frame.
    x0 : (9, N)
        Initial navigation state of each initial-error source (zero columns for IMU
        sources), psi (rad), dv (m/s), dr (m), ENU, per unit value.
    value : (N,)
        Signed magnitudes, SI.
    """

    imu_kind: np.ndarray
    imu_i: np.ndarray
    imu_j: np.ndarray
    x0: np.ndarray
    value: np.ndarray

    @property
    def n(self) -> int:
        """Number of sources."""
        return len(self.value)

    def signed(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Signed totals: gyro bias, accel bias (3,), gyro K, accel K (3, 3), initial x0 (9,)."""
        bg, ba = np.zeros(3), np.zeros(3)
        kg, ka = np.zeros((3, 3)), np.zeros((3, 3))
        for kind, i, j, v in zip(self.imu_kind, self.imu_i, self.imu_j, self.value, strict=True):
            if kind == 0:
                bg[i] += v
            elif kind == 1:
                ba[i] += v
            elif kind == 2:
                kg[i, j] += v
            elif kind == 3:
                ka[i, j] += v
        return bg, ba, kg, ka, self.x0 @ self.value


# ---------------------------------------------------------------------------------------
# Windows
# ---------------------------------------------------------------------------------------
STILL, CACHED, DIRECT, ROTATION, PARTIAL = 0, 1, 2, 3, 4


@dataclass(frozen=True)
class Windows:
    """Intervals of smooth attitude, each inside one piece and one coarse output interval.

    Attributes
    ----------
    a, b : (W,) s
        Window ends.
    piece : (W,) int
        Piece of the history each window lies in.
    n : (W,) int
        Chebyshev points of each window.
    kind : (W,) int
        :data:`STILL` (constant attitude: closed forms), :data:`ROTATION` (constant
        angular velocity: the input is a trigonometric polynomial, closed forms too),
        :data:`CACHED` (table fixed on a periodic vehicle, a whole phase step: the
        vehicle part is integrated once per phase) or :data:`DIRECT` (attitude sampled
        at the window's own points).
    phase : (W,) int
        Phase index of a cached window (its start is ``phase * step`` modulo the
        vehicle period), -1 otherwise.
    coarse : (W,) int
        Index ``j`` of the coarse output time ``t_c[j]`` that ends the window's coarse
        interval ``(t_c[j-1], t_c[j]]``.
    """

    a: np.ndarray
    b: np.ndarray
    piece: np.ndarray
    n: np.ndarray
    kind: np.ndarray
    phase: np.ndarray
    coarse: np.ndarray


def _is_multiple(x: float, y: float) -> bool:
    q = x / y
    return round(q) >= 1 and abs(q - round(q)) < 1e-9


def _cacheable(pieces: Pieces) -> np.ndarray:
    """Pieces whose attitude is a function of the vehicle phase (and not a closed form)."""
    if pieces.phase_class is None:
        return np.zeros(len(pieces.still), dtype=bool)
    constant = pieces.constant if pieces.constant is not None else False
    return (pieces.phase_class >= 0) & ~pieces.still & ~constant


def phase_step(pieces: Pieces, t_coarse: np.ndarray, dt_fine: float | None, fastest: float):
    """Step of the phase grid on which the vehicle part is reused, or None.

    The step divides the vehicle period and keeps a window's phase within
    :data:`~inserr.model.quadrature.MAX_PHASE`. Among such steps, preferably one that
    divides the coarse step (coarse times then never cut a phase window) and is a
    multiple of the fine output step (fine times then sit at the same offsets in
    every window, and their integrals are tabulated once).
    """
    period = pieces.vehicle_period
    if period is None or pieces.phase_class is None:
        return None
    fixed = _cacheable(pieces)
    if not np.any(fixed):
        return None
    rate = 2.0 * float(pieces.bandwidth[fixed].max()) + fastest
    m_min = max(1, int(np.ceil(period * rate / MAX_PHASE)))
    dt_c = float(t_coarse[1] - t_coarse[0]) if len(t_coarse) > 1 else period

    def score(m: int) -> int:
        g = period / m
        fine = dt_fine is not None and _is_multiple(g, dt_fine)
        return 2 * int(_is_multiple(dt_c, g)) + int(fine)

    candidates = range(m_min, m_min + 400)
    best = max(candidates, key=lambda m: (score(m), -m))
    return period / best


def fine_aligned(step: float | None, dt_fine: float | None) -> bool:
    """Whether fine output times fall at the same offsets in every phase window."""
    return step is not None and dt_fine is not None and _is_multiple(step, dt_fine)


def make_windows(
    pieces: Pieces, t_coarse: np.ndarray, fastest_mode: float, step: float | None = None
) -> Windows:
    """Cut the history at its piece boundaries, the coarse times and the phase grid.

    Parameters
    ----------
    pieces : Pieces
        Smooth pieces of the attitude history.
    t_coarse : (Mc,) s
        Coarse output times (0 and the end included).
    fastest_mode : float, 1/s
        Largest ``|lambda|`` of the navigation modes (adds to the integrand's phase).
    step : float, optional
        Phase step of :func:`phase_step` (None: no reuse of the vehicle part).

    Returns
    -------
    Windows
    """
    end = float(pieces.breaks[-1])
    extra = [t_coarse[(t_coarse > 0) & (t_coarse < end)]]
    if step is not None:
        # The phase grid cuts only the pieces whose windows are reused by phase.
        grid = np.arange(1, int(np.floor(end / step)) + 1) * step
        at = np.clip(
            np.searchsorted(pieces.breaks, grid, side="right") - 1, 0, len(pieces.still) - 1
        )
        extra.append(grid[_cacheable(pieces)[at]])
    cuts = np.unique(np.concatenate([pieces.breaks, *extra]))
    cuts = cuts[(cuts >= 0) & (cuts <= end)]
    cuts = cuts[np.concatenate([[True], np.diff(cuts) > MERGE])]
    cuts[-1] = end
    a, b = cuts[:-1], cuts[1:]
    mid = 0.5 * (a + b)
    piece = np.clip(np.searchsorted(pieces.breaks, mid, side="right") - 1, 0, len(pieces.still) - 1)
    constant = pieces.constant[piece] if pieces.constant is not None else np.zeros(len(a), bool)
    kind = np.where(pieces.still[piece], STILL, np.where(constant, ROTATION, DIRECT))
    phase = np.full(len(a), -1)
    if step is not None:
        fixed = _cacheable(pieces)[piece] & (kind == DIRECT)
        k = np.round(a / step).astype(int)
        whole = (
            fixed
            & (np.abs(a - k * step) < 1e3 * MERGE)
            & (np.abs(b - (k + 1) * step) < 1e3 * MERGE)
        )
        m = int(round(pieces.vehicle_period / step))
        # The rest of a stop seen through a fixed table (class 0): part of one phase step,
        # integrated from the same phase template between the window's ends.
        cell = np.floor(a / step + 1e-9).astype(int)
        partial = (
            fixed
            & ~whole
            & (pieces.phase_class[piece] == 0)
            & (b <= (cell + 1) * step + 1e3 * MERGE)
        )
        kind = np.where(whole, CACHED, np.where(partial, PARTIAL, kind))
        phase = np.where(whole, k % m, np.where(partial, cell % m, -1))
    # Products of two attitude matrices oscillate at twice the turn rate.
    rate = 2.0 * pieces.bandwidth[piece] + fastest_mode
    ph = np.where(kind == DIRECT, rate * (b - a), 0.0)
    parts = np.maximum(1, np.ceil(ph / MAX_PHASE)).astype(int)
    if np.any(parts > 1):
        rep = np.repeat(np.arange(len(a)), parts)
        j = np.arange(len(rep)) - np.repeat(np.cumsum(parts) - parts, parts)
        length = (b - a)[rep] / parts[rep]
        a2 = a[rep] + j * length
        b2 = np.where(j == parts[rep] - 1, b[rep], a2 + length)
        a, b, piece, kind, phase, ph = a2, b2, piece[rep], kind[rep], phase[rep], (ph / parts)[rep]
    n = np.where(kind == DIRECT, points_for(ph), np.where(kind == ROTATION, ROTATION_SAMPLES, 1))
    templ = (kind == CACHED) | (kind == PARTIAL)
    if np.any(templ):
        # One template for every phase: sized by the largest bandwidth of a cached piece.
        fixed = _cacheable(pieces)
        cached_phase = (2.0 * float(pieces.bandwidth[fixed].max()) + fastest_mode) * step
        n = np.where(templ, points_for(np.array([cached_phase]))[0], n)
    coarse = np.searchsorted(t_coarse, b - MERGE, side="left")
    return Windows(a, b, piece, n.astype(int), kind, phase, coarse)


# ---------------------------------------------------------------------------------------
# Features
# ---------------------------------------------------------------------------------------
def _features(c: np.ndarray, w_is: np.ndarray, f_s: np.ndarray) -> np.ndarray:
    """(N, 63): ``C[a, i]``, ``C[a, i] w_is[j]``, ``C[a, i] f_s[j]`` (row-major a, i, j)."""
    nn = len(c)
    out = np.empty((nn, N_FEATURES))
    out[:, :9] = c.reshape(nn, 9)
    # Products written in place (views of the rows' 27-entry blocks): no temporaries.
    np.multiply(c[:, :, :, None], w_is[:, None, None, :], out=out[:, 9:36].reshape(nn, 3, 3, 3))
    np.multiply(c[:, :, :, None], f_s[:, None, None, :], out=out[:, 36:].reshape(nn, 3, 3, 3))
    return out


def vehicle_to_imu(y: np.ndarray, m: np.ndarray) -> np.ndarray:
    """Vehicle features (of ``C_b^n``, ``w^b``, ``f^b``) -> IMU features for a fixed table ``m``.

    With the table at ``C_s^b = M``: ``C = C_b^n M``, ``w_is^s = M^T w^b``,
    ``f^s = M^T f^b``, so ``C[a, i] = sum_k C_b^n[a, k] M[k, i]`` and
    ``C[a, i] w^s[j] = sum_kl C_b^n[a, k] w^b[l] M[k, i] M[l, j]``; linear, so it applies
    to integrals of features as well.

    Parameters
    ----------
    y : (B, ..., 63)
        Vehicle features or their integrals; every entry ``y[b]`` is seen through the
        table ``m[b]``.
    m : (B, 3, 3) or (3, 3)
        ``C_s^b`` of the fixed table.

    Returns
    -------
    ndarray, shape of ``y``
    """
    m = np.asarray(m, dtype=float)
    if m.ndim == 2:
        m = m[None]
        y = y[None]
        squeeze = True
    else:
        squeeze = False
    nb = len(m)
    rows = y.shape[1:-1]
    nr = int(np.prod(rows, dtype=int))
    yy = np.ascontiguousarray(y).reshape(nb, nr, N_FEATURES)
    # kron(M, M)[(k, l), (i, j)] = M[k, i] M[l, j]
    mk = (m[:, :, None, :, None] * m[:, None, :, None, :]).reshape(nb, 9, 9)
    out = np.empty((nb, nr, N_FEATURES), dtype=np.result_type(y, m))
    # C[a, i] = sum_k C_b^n[a, k] M[k, i]: rows (r, a) times M.
    out[:, :, :9] = (yy[:, :, :9].reshape(nb, nr * 3, 3) @ m).reshape(nb, nr, 9)
    for lo in (9, 36):
        # C[a, i] x[j] = sum_kl C_b^n[a, k] x^b[l] M[k, i] M[l, j]: rows (r, a) times kron(M, M).
        blk = yy[:, :, lo : lo + 27].reshape(nb, nr * 3, 9)
        out[:, :, lo : lo + 27] = (blk @ mk).reshape(nb, nr, 27)
    out = out.reshape((nb,) + rows + (N_FEATURES,))
    return out[0] if squeeze else out


def signed_coefficients(modes: NavModes, src: SourceSet) -> np.ndarray:
    """(R, 63): modal input of the signed errors as a linear form in the IMU features."""
    bg, ba, kg, ka, _ = src.signed()
    g, acc = modes.gyro_input, modes.accel_input  # (R, 3)
    out = np.zeros((modes.n_modes, N_FEATURES), dtype=complex)
    out[:, :9] = (g[:, :, None] * bg[None, None, :] + acc[:, :, None] * ba[None, None, :]).reshape(
        -1, 9
    )
    out[:, 9:36] = (g[:, :, None, None] * kg[None, None]).reshape(-1, 27)
    out[:, 36:] = (acc[:, :, None, None] * ka[None, None]).reshape(-1, 27)
    return out


def _source_inputs(modes: NavModes, y: np.ndarray, src: SourceSet) -> np.ndarray:
    """Modal inputs (J, R, N) of every source from feature integrals ``y`` (J, R, 63).

    A gyro bias on IMU axis i drives ``psi' = -C e_i``, whose modal input is
    ``sum_a G[r, a] C[a, i]`` (G = :attr:`NavModes.gyro_input`); a gyro error-matrix
    entry (i, j) drives ``-C e_i w_is[j]``; accelerometer errors likewise with
    :attr:`NavModes.accel_input` and ``f^s``.
    """
    g, acc = modes.gyro_input, modes.accel_input  # (R, 3): n-frame error -> modal input
    nj, r = y.shape[0], y.shape[1]
    y1 = y[:, :, :9].reshape(nj, r, 3, 3)  # [j, r, a, i]
    y2 = y[:, :, 9:36].reshape(nj, r, 3, 9)  # [j, r, a, (i, k)]
    y3 = y[:, :, 36:].reshape(nj, r, 3, 9)
    # Contractions over the n axis a, written as broadcast products (small axes: faster
    # than einsum on complex operands).
    g1 = (y1 * g[None, :, :, None]).sum(axis=2)
    a1 = (y1 * acc[None, :, :, None]).sum(axis=2)
    g2 = (y2 * g[None, :, :, None]).sum(axis=2)
    a3 = (y3 * acc[None, :, :, None]).sum(axis=2)
    table = np.concatenate([g1, a1, g2, a3], axis=2)  # (J, R, 3 + 3 + 9 + 9)
    col = np.select(
        [src.imu_kind == 0, src.imu_kind == 1, src.imu_kind == 2, src.imu_kind == 3],
        [src.imu_i, 3 + src.imu_i, 6 + 3 * src.imu_i + src.imu_j, 15 + 3 * src.imu_i + src.imu_j],
        default=-1,
    )
    out = np.zeros((nj, r, src.n), dtype=complex)
    imu = col >= 0
    out[:, :, imu] = table[:, :, col[imu]]
    return out


# ---------------------------------------------------------------------------------------
# Scans
# ---------------------------------------------------------------------------------------
def scan(lam: np.ndarray, t0: float, z0: np.ndarray, t: np.ndarray, incr: np.ndarray) -> np.ndarray:
    """States after each increment of ``z' = lambda z`` with jumps: ``z_k = e^{lambda (t_k -
    t_{k-1})} z_{k-1} + incr_k``.

    Parameters
    ----------
    lam : (R,) complex, 1/s
    t0 : float, s
        Time of ``z0``.
    z0 : (R, ...) complex
        State at ``t0``.
    t : (K,) s
        Increasing times of the increments (each already propagated to its own time).
    incr : (K, R, ...) complex

    Returns
    -------
    ndarray (K, R, ...)
        States at ``t`` (the increment included).
    """
    out = np.empty(incr.shape, dtype=complex)
    extra = (1,) * (incr.ndim - 2)
    lam_b = lam.reshape((1, -1) + extra)
    growth = float(np.max(np.abs(lam.real))) if len(lam) else 0.0
    z, tz = np.asarray(z0, dtype=complex), t0
    k = 0
    while k < len(t):
        # A block in which e^{-lambda (t - tz)} stays within floating-point range.
        if growth > 0:
            stop = int(np.searchsorted(t, tz + SCAN_SPAN / growth, side="right"))
            stop = max(stop, k + 1)
        else:
            stop = len(t)
        dt = (t[k:stop] - tz).reshape((-1, 1) + extra)
        # In place in the output block: e^{lambda dt} cumsum(e^{-lambda dt} incr), with
        # z added to the first term (the cumulative sum carries it to every row), without
        # temporaries: three passes over the block.
        blk = out[k:stop]
        np.multiply(np.exp(-lam_b * dt), incr[k:stop], out=blk)
        blk[0] += z
        np.cumsum(blk, axis=0, out=blk)
        np.multiply(np.exp(lam_b * dt), blk, out=blk)
        z, tz = out[stop - 1], t[stop - 1]
        k = stop
    return out


# ---------------------------------------------------------------------------------------
# The engine
# ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class ConstantErrorResponse:
    """Navigation errors due to constant errors (SI, ENU).

    Attributes
    ----------
    t_fine : (M,) s
    fine : (M, 9)
        Response to all sources with their signed values, on the fine grid.
    t_coarse : (Mc,) s
    coarse : (Mc, 9, N)
        Response to each source (scaled by its value), on the coarse grid.
    windows : dict
        Quadrature windows used, by kind (``still``, ``rotation``, ``cached``,
        ``direct``, ``partial``); ``periods``, the whole periods copied from the first
        (0 without lifting), ``lift_period`` (s, 0 without lifting) and ``phase_step``
        (s, 0 without reuse of the vehicle part by phase).
    nodes : int
        Attitude evaluations used.
    paths : frozenset of str
        The faster ways the outputs were computed (none of them changes the numbers
        beyond round-off, only the work): ``fine-grid`` (fine outputs of a uniform grid
        as one product per window shape) or ``fine-each``; ``states-grid`` or
        ``states-each`` (modal states at fine times, e.g. one lifted period);
        ``cached-blocks`` (whole phase steps as tabulated blocks), ``cached-aligned``
        or ``cached-anywhere`` (in-window integrals of cached windows at tabulated
        offsets, or from their series); ``partial-table`` (partial stops from the
        tabulated blocks); ``rotation-grid`` or ``rotation-each`` (turn integrals per
        grid offset, or per distinct offset).
    """

    t_fine: np.ndarray
    fine: np.ndarray
    t_coarse: np.ndarray
    coarse: np.ndarray
    windows: dict
    nodes: int
    paths: frozenset = frozenset()


def engine_threads() -> int:
    """Threads one analysis may use for its independent blocks of work (1 or 2).

    ``INSERR_THREADS`` if set; else 1 in a process told to use one BLAS thread
    (``OMP_NUM_THREADS`` or ``OPENBLAS_NUM_THREADS`` = 1: a sweep's or a design's worker
    processes, where the parallelism is across points); else 2 if the machine has two
    cores or more. The work is split the same way whatever the count (see
    :data:`SPLIT_FINE`), so the results do not depend on it.
    """
    chosen = os.environ.get("INSERR_THREADS")
    if chosen:
        return max(1, int(chosen))
    if "1" in (os.environ.get("OMP_NUM_THREADS"), os.environ.get("OPENBLAS_NUM_THREADS")):
        return 1
    return 2 if (os.cpu_count() or 1) >= 2 else 1


def run_blocks(tasks: list) -> list:
    """Results of the callables ``tasks`` (independent, writing disjoint outputs), on
    :func:`engine_threads` threads (numpy releases the GIL in its large operations)."""
    threads = engine_threads()
    if threads < 2 or len(tasks) < 2:
        return [task() for task in tasks]
    with ThreadPoolExecutor(max_workers=min(threads, len(tasks))) as pool:
        futures = [pool.submit(task) for task in tasks]
        return [f.result() for f in futures]


_BLAS: list = []  # the process's ThreadpoolController, found once (finding it costs ~1 ms)


def single_thread_blas():
    """Context in which BLAS runs on one thread.

    The engine's matrix products are many and small or medium: a multi-threaded BLAS
    costs more than it saves there (its threads spin while waiting, and fight with
    the processes of a sweep or with other programs).
    """
    if not _BLAS:
        _BLAS.append(ThreadpoolController())
    return _BLAS[0].limit(limits=1, user_api="blas")


def _grid_step(t: np.ndarray) -> float | None:
    """Step of a uniform grid 0, h, 2h, ... (its last point may be shorter), else None."""
    if len(t) < 2 or t[0] != 0.0:
        return None
    h = float(t[1] - t[0])
    inner = t[:-1] if len(t) > 2 else t
    # |diff - h| <= 1e-9 everywhere (False for NaN), without allclose's temporaries.
    return h if float(np.max(np.abs(np.diff(inner) - h))) <= 1e-9 else None


def constant_error_response(
    model: ErrorModel,
    history: AttitudeHistory,
    sources: SourceSet,
    t_fine: np.ndarray,
    t_coarse: np.ndarray,
) -> ConstantErrorResponse:
    """Response of the navigation errors to constant IMU and initial errors.

    Parameters
    ----------
    model : ErrorModel
        Site and vertical mode (its layout is not used: IMU errors are inputs here).
    history : AttitudeHistory
        ``C_s^n(t)`` and ``w_ns^n(t)`` over the run.
    sources : SourceSet
        The constant errors (values signed, SI).
    t_fine : (M,) s
        Output times of the signed response (increasing, within the run).
    t_coarse : (Mc,) s
        Output times of the per-source responses; must start at 0 and end at the
        duration (they cut the quadrature windows).

    Returns
    -------
    ConstantErrorResponse
    """
    with single_thread_blas():
        return _constant_error_response(model, history, sources, t_fine, t_coarse)


def _constant_error_response(model, history, sources, t_fine, t_coarse):
    modes = NavModes(model)
    lam = modes.lam
    t_fine = np.asarray(t_fine, dtype=float)
    t_coarse = np.asarray(t_coarse, dtype=float)
    pieces = history.pieces()
    fastest = float(np.max(np.abs(lam)))
    h, hc = _grid_step(t_fine), _grid_step(t_coarse)
    step = phase_step(pieces, t_coarse, h, fastest)
    lift = _lifting(history, t_fine, t_coarse, (h, hc))
    if lift is None:
        win = make_windows(pieces, t_coarse, fastest, step)
        base_coarse = t_coarse
    else:
        # A periodic history: windows of [0, t0 + P] only; the rest are copies.
        t0, period = lift
        end = t0 + period
        base_coarse = t_coarse[t_coarse <= end + MERGE]
        win = make_windows(_restrict(pieces, end), base_coarse, fastest, step)
    a_sig = signed_coefficients(modes, sources)
    run = _Run(modes, history, pieces, win, base_coarse, a_sig, step, sources)
    run.still_windows()
    run.rotation_windows()
    # The phase-template windows and the sampled ones are independent: side by side on
    # engine_threads(); the sampled windows' per-source inputs are added after the
    # template's, as when they ran one after the other (identical to the last bit).
    sink: list = []
    if np.any((win.kind == CACHED) | (win.kind == PARTIAL) | (win.kind == DIRECT)):
        run_blocks([run.cached_windows, lambda: run.direct_windows(sink)])
    run.add_inputs(sink)
    inputs = run.inputs
    if lift is not None:
        run.full, run.src, inputs = _tile(win, run.inputs, t0, period, t_coarse)
    full = run.full if run.full is not None else win
    z0 = modes.to_modes(sources.signed()[4])
    run.z_end = scan(lam, 0.0, z0, full.b, run.incr[run.src] if run.src is not None else run.incr)
    run.z_start = np.concatenate([z0[None], run.z_end[:-1]])

    # Fine outputs in blocks (a 720 h run at 1 s has 2.6 million of them), and the
    # per-source responses: independent pieces of work, on up to engine_threads().
    fine = np.empty((len(t_fine), 9))

    def per_source() -> np.ndarray:
        # Modal inputs per coarse interval, then the scan over coarse intervals.
        z_src0 = modes.to_modes(sources.x0, axis=0)  # (R, N)
        coarse_z = np.empty((len(t_coarse), modes.n_modes, sources.n), dtype=complex)
        coarse_z[0] = z_src0
        if lift is not None:
            _lifted_coarse(lam, t_coarse, inputs, lift, coarse_z)
        elif len(t_coarse) > 1:
            coarse_z[1:] = scan(lam, float(t_coarse[0]), z_src0, t_coarse[1:], inputs[1:])
        # Scaled by the source values on the way to the (time, source, mode) layout that
        # the navigation map wants: one pass for both (Re(V c z) is linear, values real).
        zz = np.empty((len(t_coarse), sources.n, modes.n_modes), dtype=complex)
        np.multiply(np.moveaxis(coarse_z, 1, 2), sources.value[None, :, None], out=zz)
        return np.moveaxis(modes.to_nav(zz), -1, 1)  # (Mc, 9, N)

    def fine_block(lo: int, hi: int):
        def work() -> None:
            tb = t_fine[lo:hi]
            n0 = int(np.searchsorted(tb, MERGE, side="right"))  # outputs at t = 0 first
            block = fine[lo:hi]
            block[:n0] = modes.to_nav(z0[None])[0]
            if n0 < len(tb):
                run.fine_nav(tb[n0:], h, out=block[n0:])

        return work

    if lift is not None:
        # All outputs after t0 from the periods' states; the first ones below.
        tasks = _lifted_fine(run, modes, lift, t_fine, h, fine)
        stop = tasks.pop()
    else:
        stop, tasks = len(t_fine), []
    run.prepare_fine(h)  # tables shared by the blocks, made once before they start
    tasks += [fine_block(lo, hi) for lo, hi in _blocks(stop)]
    coarse = run_blocks([per_source] + tasks)[0]
    counts = {
        name: int(np.count_nonzero(win.kind == k))
        for name, k in (
            ("still", STILL),
            ("rotation", ROTATION),
            ("cached", CACHED),
            ("direct", DIRECT),
            ("partial", PARTIAL),
        )
    }
    counts["periods"] = 0 if lift is None else int(round((t_coarse[-1] - lift[0]) / lift[1]))
    counts["lift_period"] = 0.0 if lift is None else float(lift[1])
    counts["phase_step"] = 0.0 if step is None else float(step)
    return ConstantErrorResponse(
        t_fine, fine, t_coarse, coarse, counts, run.nodes, frozenset(run.paths)
    )


def _window_of(b: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Index of the window holding each output time: the first window end ``b`` at or
    after ``t - MERGE`` (the last window past the end), for increasing ``t``.

    Equal to ``np.searchsorted(b, t - MERGE, side="left").clip(0, len(b) - 1)``, found
    by placing the few window ends among the many outputs instead.
    """
    s = t - MERGE
    ends = np.searchsorted(s, b, side="right")  # outputs at or before each window end
    counts = np.diff(np.concatenate([[0], ends, [len(s)]]))
    return np.repeat(np.arange(len(b) + 1), counts).clip(0, len(b) - 1)


def _blocks(n: int) -> list[tuple[int, int]]:
    """``(lo, hi)`` blocks of ``n`` fine outputs: at most :data:`CHUNK_FINE` each, and at
    least two above :data:`SPLIT_FINE` (equal sizes; a function of ``n`` only)."""
    if n <= 0:
        return []
    count = max(-(-n // CHUNK_FINE), 2 if n > SPLIT_FINE else 1)
    edges = np.linspace(0, n, count + 1).round().astype(int)
    return [(int(a), int(b)) for a, b in zip(edges[:-1], edges[1:], strict=True)]


def _lifted_fine(run, modes: NavModes, lift, t: np.ndarray, h: float, out: np.ndarray) -> list:
    """Fine outputs of a periodic run: ``z(t0 + k P + s) = e^{lambda s} Z_k + p(s)``.

    ``Z_k`` is the state at the start of period k (from the window scan) and ``p`` the
    response of one period from a zero state (the same for every period, by
    periodicity), so the outputs of all periods are one small real matrix product per
    navigation state. Returns the tasks that fill ``out[j0:]`` (from ``t0`` on; blocks
    of periods, :func:`_blocks`) followed by ``j0``; the outputs before ``t0`` are left
    to the caller.
    """
    t0, period = lift
    j0 = int(round(t0 / h))
    n_s = int(round(period / h))
    lam = modes.lam
    full = run.full
    n_per = int(np.ceil((len(t) - 1 - j0) / n_s))
    # State at the start of each period: the scan's value at the window ending there.
    starts = t0 + np.arange(n_per) * period
    k_end = np.searchsorted(full.b, starts - MERGE, side="left")
    z_k = np.where((starts > MERGE)[:, None], run.z_end[np.minimum(k_end, len(full.b) - 1)],
                   run.z_start[0][None, :])  # fmt: skip
    s = np.arange(1, n_s + 1) * h
    e = np.exp(lam[None, :] * s[:, None])  # (n_s, R)
    # One period from a zero state: the first period's states less its homogeneous part.
    p = run.fine_states(t0 + s, h) - e * z_k[0][None, :]
    vw = modes.out * modes.weight[None, :]  # (9, R): x = Re(V c z)
    # Re(V c (e Z_k + p)) for every period k and offset s: a real product per state.
    a = np.concatenate([z_k.real, -z_k.imag], axis=1)  # (n_per, 2R)
    b = np.concatenate(
        [(e[:, None, :] * vw[None]).real, (e[:, None, :] * vw[None]).imag], axis=2
    )  # (n_s, 9, 2R)
    bt = b.reshape(-1, 2 * len(lam)).T  # (2R, n_s 9)
    part = (p @ vw.T).real  # (n_s, 9)
    n = len(t) - 1 - j0
    # Periods in blocks of about the fine blocks' size (each writes its own rows).
    per_block = max(1, -(-(_blocks(n_per * n_s)[0][1]) // n_s))

    def periods(k0: int, k1: int):
        def work() -> None:
            vals = ((a[k0:k1] @ bt).reshape(k1 - k0, n_s, 9) + part[None]).reshape(-1, 9)
            lo = j0 + 1 + k0 * n_s
            hi = min(j0 + 1 + k1 * n_s, j0 + 1 + n)
            out[lo:hi] = vals[: hi - lo]

        return work

    tasks = [periods(k, min(k + per_block, n_per)) for k in range(0, n_per, per_block)]
    return tasks + [j0 + 1]


def _lifted_coarse(lam: np.ndarray, t: np.ndarray, inputs: np.ndarray, lift, out: np.ndarray):
    """Per-source states on the coarse grid of a periodic run, in place (``out[0]`` given).

    The coarse grid is uniform (step h) and the inputs repeat every period after ``t0``
    (:func:`_tile`), so ``z(t0 + k P + c h) = e^{lambda c h} Z_k + p_c``, with ``p`` the
    response of one period from a zero state and ``Z_k = e^{lambda P} Z_{k-1} + p_P``
    the state at the start of period k: the scan runs over the first period only, and
    every later period is one multiply-add, instead of the scan's several passes.
    """
    t0, period = lift
    h = float(t[1] - t[0])
    j0, n_s = int(round(t0 / h)), int(round(period / h))
    first = j0 + n_s  # index of the end of the first period
    out[1 : first + 1] = scan(lam, float(t[0]), out[0], t[1 : first + 1], inputs[1 : first + 1])
    e = np.exp(lam[None, :] * (np.arange(1, n_s + 1) * h)[:, None])[:, :, None]  # (n_s, R, 1)
    p = out[j0 + 1 : first + 1] - e * out[j0][None]  # (n_s, R, N)
    n_per = -(-(len(t) - 1 - j0) // n_s)  # periods begun after t0
    z = np.empty((n_per,) + out.shape[1:], dtype=complex)
    z[0] = out[j0]
    if n_per > 1:
        # Z_k = e^{lambda P} Z_{k-1} + p_P = e^{lambda k P} Z_0 + g_k p_P with the geometric
        # sum g_k = sum_{i<k} e^{lambda i P} = expm1(lambda k P) / expm1(lambda P) (= k
        # for lambda = 0): two multiply-adds per period, no scan.
        k = np.arange(1, n_per)[:, None]
        lp = lam[None, :] * period
        num, den = np.expm1(lp * k), np.expm1(lp)
        g = np.where(den == 0, k + 0j, num / np.where(den == 0, 1.0, den))
        z[1:] = (num + 1.0)[:, :, None] * z[0][None] + g[:, :, None] * p[-1][None]
    whole = (len(t) - 1 - j0) // n_s  # periods that end within the grid
    if whole > 1:
        rows = out[first + 1 : j0 + 1 + whole * n_s].reshape((whole - 1, n_s) + out.shape[1:])
        np.multiply(e[None], z[1:whole, None], out=rows)
        rows += p[None]
    if whole < n_per:  # the last period, cut by the end of the run
        lo = j0 + 1 + whole * n_s
        out[lo:] = e[: len(t) - lo] * z[whole][None] + p[: len(t) - lo]


def _lifting(
    history, t_fine: np.ndarray, t_coarse: np.ndarray, steps: tuple | None = None
) -> tuple[float, float] | None:
    """``(t0, P)`` if the history repeats with period P after t0, on both output grids.

    Lifting needs at least two whole periods, and every output time and window
    boundary of one period to recur in the next: both grids uniform from 0, and
    ``t0``, ``P`` and the end multiples of their steps. ``P`` is the smallest multiple
    of the history's period that both grid steps divide.
    """
    period = getattr(history, "period", None)
    found = period() if period is not None else None
    if found is None:
        return None
    t0, p = found
    end = float(t_coarse[-1])
    # steps: the grids' (fine, coarse) steps when the caller has them already.
    hf, hc = steps if steps is not None else (_grid_step(t_fine), _grid_step(t_coarse))
    if hc is None or hf is None:
        return None
    for h in (hc, hf):
        if not all(_is_multiple(x, h) or x == 0.0 for x in (t0, end)):
            return None
    # A multiple of a period is a period: lift with the first one both grids divide
    # (a 1290 s four-position cycle on a 60 s grid lifts with 2580 s).
    m = 1
    while end - t0 >= 2 * m * p:
        if _is_multiple(m * p, hc) and _is_multiple(m * p, hf):
            return t0, m * p
        m += 1
    return None


def _restrict(pieces: Pieces, end: float) -> Pieces:
    """The pieces of ``[0, end]`` (the last one cut at ``end``)."""
    n = int(np.searchsorted(pieces.breaks, end - MERGE, side="right"))
    breaks = np.concatenate([pieces.breaks[:n], [end]])

    def cut(a):
        return None if a is None else a[:n]

    return Pieces(
        breaks,
        pieces.bandwidth[:n],
        pieces.still[:n],
        cut(pieces.table),
        pieces.vehicle_period,
        cut(pieces.constant),
        cut(pieces.phase_class),
    )


def _tile(win: Windows, inputs: np.ndarray, t0: float, period: float, t_coarse: np.ndarray):
    """Windows of the whole run from those of ``[0, t0 + P]``, and the per-source inputs.

    Returns the full :class:`Windows`, the index of each full window's base window, and
    the inputs of every coarse interval (copied from the base period's).
    """
    end = float(t_coarse[-1])
    first = np.flatnonzero(win.a >= t0 - MERGE)  # the periodic part of the base windows
    head = np.arange(first[0]) if len(first) else np.arange(len(win.a))
    reps = int(np.floor((end - t0) / period + 1e-9))
    pieces_src = [head, np.tile(first, reps)]
    shifts = [np.zeros(len(head)), np.repeat(np.arange(reps) * period, len(first))]
    rest = end - t0 - reps * period
    if rest > MERGE:
        tail = first[win.b[first] - t0 <= rest + MERGE]
        pieces_src.append(tail)
        shifts.append(np.full(len(tail), reps * period))
    src = np.concatenate(pieces_src)
    shift = np.concatenate(shifts)
    jp = int(round(period / (t_coarse[1] - t_coarse[0])))
    coarse = win.coarse[src] + np.rint(shift / period).astype(int) * jp
    full = Windows(
        win.a[src] + shift, win.b[src] + shift, win.piece[src], win.n[src], win.kind[src],
        win.phase[src], coarse,
    )  # fmt: skip
    # Coarse interval j of period k is interval j - k jp of the base period.
    j = np.arange(len(t_coarse))
    j0 = int(round(t0 / (t_coarse[1] - t_coarse[0])))
    base_j = np.where(j <= j0, j, j0 + (j - j0 - 1) % jp + 1)
    return full, src, inputs[base_j]


class _Run:
    """Working state of one :func:`constant_error_response` call (windows by kind)."""

    def __init__(self, modes, history, pieces, win, t_coarse, a_sig, step, sources):
        self.modes, self.history, self.pieces, self.win = modes, history, pieces, win
        self.t_coarse, self.a_sig, self.step = t_coarse, a_sig, step
        self.lam = modes.lam
        site = modes.model.site
        self.earth, self.f_n = site.earth_rate_n, site.specific_force_n
        nw, r = len(win.a), modes.n_modes
        self.incr = np.zeros((nw, r), dtype=complex)  # signed increment to each window's end
        # Modal input of every source per coarse interval (feature integrals are turned
        # into source inputs as they arrive: N sources take less room than 63 features).
        self.sources = sources
        # Every source's modal input as a linear form in the 63 features, per mode.
        eye = np.broadcast_to(np.eye(N_FEATURES)[:, None, :], (N_FEATURES, r, N_FEATURES))
        self.source_form = np.ascontiguousarray(
            np.moveaxis(_source_inputs(modes, eye, sources), 1, 0)
        )  # (R, 63, N)
        self.inputs = np.zeros((len(t_coarse), r, sources.n), dtype=complex)
        self.u_still = np.zeros((nw, r), dtype=complex)  # constant input of still windows
        self.full: Windows | None = None  # the whole run's windows when lifted
        self.src: np.ndarray | None = None  # their base windows
        self.nodes = 0
        self._lock = threading.Lock()
        self._memo: dict = {}  # tables shared by the fine-output blocks
        self.paths: set[str] = set()  # the faster ways taken (ConstantErrorResponse.paths)

    def _add_features(self, j: np.ndarray, y: np.ndarray, sink: list | None = None) -> None:
        """Add feature integrals ``y`` (K, R, 63) of coarse intervals ``j`` (distinct).

        With ``sink`` the per-source inputs are appended to it as ``(j, inputs)`` instead,
        for :meth:`add_inputs` to add later (a stage running beside another).
        """
        form = self.source_form  # (R, 63, N)
        per = np.empty((len(j), form.shape[0], form.shape[2]), dtype=complex)
        for r in range(form.shape[0]):
            per[:, r, :] = y[:, r, :] @ form[r]
        if sink is not None:
            sink.append((j, per))
        else:
            self.add_inputs([(j, per)])

    def add_inputs(self, sink: list) -> None:
        """Add the per-source inputs a stage left in ``sink`` (:meth:`_add_features`),
        mode by mode as :meth:`_add_features` adds them: the same sums to the last bit."""
        for j, per in sink:
            for r in range(per.shape[1]):
                self.inputs[j, r, :] += per[:, r, :]

    def _count(self, n: int) -> None:
        with self._lock:  # stages may run on two threads
            self.nodes += n

    # --- attitude at nodes ---------------------------------------------------------
    def _imu_features(self, t, piece):
        c, w_ns = self.history.evaluate(t, piece)
        self._count(len(t))
        return self._features_of(c, w_ns)

    def _features_of(self, c: np.ndarray, w_ns: np.ndarray) -> np.ndarray:
        """Features (K, 63) of attitudes ``c`` (K, 3, 3) turning at ``w_ns`` (K, 3) rad/s."""
        w_is = np.einsum("nji,nj->ni", c, self.earth + w_ns)  # C^T (Omega + w): IMU frame
        f_s = np.einsum("nji,j->ni", c, self.f_n)  # C^T f: IMU frame
        return _features(c, w_is, f_s)

    def _to_coarse(self, b: np.ndarray, j: np.ndarray) -> np.ndarray:
        """``e^{lambda (t_c[j] - b)}``: propagation from a window end to its coarse time."""
        return np.exp(self.lam[None, :] * (self.t_coarse[j] - b)[:, None])

    # --- still windows: constant attitude, closed forms ---------------------------------
    def still_windows(self) -> None:
        """Windows of constant attitude: closed forms.

        A still piece holds one attitude: its features and every source's input are
        found once per piece (at the middle of its first window), and once for all the
        stops that hold the same attitude (to 1e-12; a cycle's positions recur), then
        shared by the windows the coarse grid cuts the stops into. The windows' weights
        are summed into their coarse intervals by one sparse product.
        """
        win = self.win
        idx = np.flatnonzero(win.kind == STILL)
        if not len(idx):
            return
        length = win.b[idx] - win.a[idx]
        _, first, of_piece = np.unique(win.piece[idx], return_index=True, return_inverse=True)
        sel = idx[first]
        c, w_ns = self.history.evaluate(0.5 * (win.a[sel] + win.b[sel]), win.piece[sel])
        self._count(len(sel))
        rep, of_key = _distinct(c, w_ns)
        feats = self._features_of(c[rep], w_ns[rep])  # (G, 63): one row per distinct attitude
        held = of_key.reshape(-1)[of_piece.reshape(-1)]  # distinct attitude of each window
        wt = length[:, None] * phi1(self.lam[None, :] * length[:, None])  # int_0^L e^{lambda s}
        u = _apply_form(feats, self.a_sig)[held]
        self.u_still[idx] = u
        self.incr[idx] = wt * u
        w = wt * self._to_coarse(win.b[idx], win.coarse[idx])  # (W, R)
        # Per-source inputs: sum over the windows of a coarse interval of w[w, r] times
        # the input of its attitude.
        form = self.source_form  # (R, 63, N)
        per = np.stack([feats @ f.real + 1j * (feats @ f.imag) for f in form], axis=1)
        _add_rows(self.inputs, *_interval_sums(win.coarse[idx], held, w, per))

    # --- rotation windows: constant angular velocity, closed forms ---------------------
    def rotation_windows(self) -> None:
        """Windows where ``C_s^n`` turns at a constant rate: harmonic closed forms.

        With ``R(tau) = a a^T + cos(rho tau) (I - a a^T) + sin(rho tau) [a x]`` every
        feature is ``sum_k F_k e^{i k rho tau}``, ``|k| <= 2`` (products of two attitude
        matrices; ``C^T w`` is constant about the turn axis). Five equally spaced turn
        angles give the ``F_k`` exactly (a discrete Fourier transform), and
        ``int_0^L e^{lambda (L - tau)} e^{i nu tau} dtau = e^{lambda L} L phi1((i nu - lambda) L)``.

        The ``F_k`` are found once per turn, at its start: a window that begins
        ``theta0 = rho (a_w - a_turn)`` into the turn has ``F_k e^{i k theta0}``. Turns
        with the same start attitude and angular velocity (to 1e-12; a static base
        repeats its cycle's turns) share them, and every source's input per harmonic
        (the sources' linear forms applied to ``F_k``) too, so a window costs its five
        weights per mode, summed into its coarse interval by one sparse product.
        """
        win, lam = self.win, self.lam
        idx = np.flatnonzero(win.kind == ROTATION)
        if not len(idx):
            return
        piece = win.piece[idx]
        head = np.flatnonzero(np.concatenate([[True], piece[1:] != piece[:-1]]))
        of_turn = np.repeat(np.arange(len(head)), np.diff(np.append(head, len(idx))))
        a_turn = win.a[idx][head]
        c_a, w = self.history.evaluate(a_turn, piece[head])
        self._count(len(head))
        rep, of_key = _distinct(c_a, w)
        c_a, w = c_a[rep], w[rep]
        turn = of_key.reshape(-1)[of_turn]  # distinct turn of each window
        rho = np.linalg.norm(w, axis=1)
        axis = w / rho[:, None]
        ks = np.arange(-2, 3)
        theta = 2.0 * np.pi * np.arange(ROTATION_SAMPLES) / ROTATION_SAMPLES
        kx = skew(axis)  # (U, 3, 3)
        rot = (
            np.eye(3)[None, None]
            + np.sin(theta)[None, :, None, None] * kx[:, None]
            + (1.0 - np.cos(theta))[None, :, None, None] * (kx @ kx)[:, None]
        )  # (U, 5, 3, 3): the attitude after turning by theta_j
        c = rot @ c_a[:, None]
        w_is = np.einsum("wjba,wb->wja", c, self.earth + w)
        f_s = np.einsum("wjba,b->wja", c, self.f_n)
        feats = _features(c.reshape(-1, 3, 3), w_is.reshape(-1, 3), f_s.reshape(-1, 3))
        feats = feats.reshape(len(rep), ROTATION_SAMPLES, N_FEATURES)
        # F_k = (1/5) sum_j F(theta_j) e^{-i k theta_j}, k = -2..2
        dft = np.exp(-1j * ks[:, None] * theta[None, :]) / ROTATION_SAMPLES  # (5 k, 5 j)
        fk = np.matmul(dft.real, feats) + 1j * np.matmul(dft.imag, feats)  # (U, 5, 63)
        # Each window's harmonics from its turn's: the phase e^{i k theta0}.
        r_w = rho[turn]
        phase = np.exp(1j * ks[None, :] * (r_w * (win.a[idx] - a_turn[of_turn]))[:, None])
        uk = (fk @ self.a_sig.T)[turn] * phase[:, :, None]  # (W, 5, R): signed input
        nu = ks[None, :] * r_w[:, None]  # (W, 5) rad/s
        length = win.b[idx] - win.a[idx]
        # int_0^L e^{lambda (L - tau)} e^{i nu tau} dtau, per window, harmonic, mode.
        zl = (1j * nu[:, :, None] - lam[None, None, :]) * length[:, None, None]
        wt = (np.exp(lam[None, :] * length[:, None]) * length[:, None])[:, None, :] * phi1(zl)
        self.incr[idx] = (uk * wt).sum(axis=1)
        # Per-source inputs: sum over the windows of a coarse interval of
        # sum_k wt to_c e^{i k theta0} [w, k, r] x (F_k of the turn @ form_r): a sparse
        # (intervals x turns 5) matrix per mode times the turns' harmonic inputs.
        j = win.coarse[idx]
        to_c = self._to_coarse(win.b[idx], j)  # (W, R)
        coef = wt * to_c[:, None, :] * phase[:, :, None]  # (W, 5, R)
        flat_fk = fk.reshape(-1, N_FEATURES)
        per = np.stack([flat_fk @ f for f in self.source_form], axis=1)  # (U 5, R, N)
        cols = (turn[:, None] * ROTATION_SAMPLES + np.arange(ROTATION_SAMPLES)[None, :]).ravel()
        sums = _interval_sums(np.repeat(j, ROTATION_SAMPLES), cols, coef.reshape(-1, len(lam)), per)
        _add_rows(self.inputs, *sums)
        self.rotation_uk = np.zeros((len(win.a), ROTATION_SAMPLES, len(lam)), dtype=complex)
        self.rotation_uk[idx] = uk
        self.rotation_nu = np.zeros((len(win.a), ROTATION_SAMPLES))
        self.rotation_nu[idx] = nu

    def _rotation_integrals_on_grid(self, w, dt, h, run, delta) -> np.ndarray:
        """:meth:`_rotation_integrals` at outputs ``dt = delta + k h`` (one delta per run).

        ``int_0^{delta + k h} e^{mu s} ds = int_0^delta e^{mu s} ds + e^{mu delta}
        int_0^{k h} e^{mu s} ds`` with ``mu = i nu - lambda``: the first factor once per
        run (window), the last once per (turn rate, k) in a table.
        """
        lam = self.lam
        harm = np.arange(-2, 3)
        rates, cls = np.unique(self.rotation_nu[w, -1], return_inverse=True)
        cls = cls.reshape(-1)
        runs, local = np.unique(run, return_inverse=True)
        local = local.reshape(-1)
        k = np.rint((dt - delta[run]) / h).astype(np.int64)
        span = int(k.max()) + 1
        nu = (rates / 2.0)[:, None] * harm[None, :]  # (rates, 5) rad/s: the windows' own
        mu = 1j * nu[:, :, None] - lam[None, None, :]  # (rates, 5, R)
        grid = (np.arange(span) * h)[None, :, None, None]
        tab = grid * phi1(mu[:, None] * grid)  # (rates, span, 5, R)
        run_cls = np.empty(len(runs), dtype=np.int64)
        run_cls[local] = cls
        d = delta[runs][:, None, None]
        mu_run = mu[run_cls]  # (runs, 5, R)
        p_run = d * phi1(mu_run * d)
        e_run = np.exp(mu_run * d)
        vals = p_run[local] + e_run[local] * tab[cls, k]
        return np.einsum("fkr,fkr->fr", self.rotation_uk[w], vals)

    def _rotation_integrals(self, w: np.ndarray, dt: np.ndarray, h: float | None) -> np.ndarray:
        """``int_a^t e^{-lambda (s - a)} u(s) ds`` at fine times of rotation windows."""
        lam = self.lam
        # int_0^d e^{(i nu - lambda) s} ds = d phi1((i nu - lambda) d), evaluated once per
        # distinct (rate, offset) pair: fine times repeat the same offsets turn after turn.
        rates, cls = np.unique(self.rotation_nu[w, -1], return_inverse=True)
        cls = cls.reshape(-1)
        k = np.rint(dt / h).astype(np.int64) if h else None
        if k is not None and np.all(np.abs(dt - k * h) <= 1e-9 * np.maximum(1.0, dt)):
            span = int(k.max()) + 1
            key = cls * span + k
            d_key = (np.arange(len(rates) * span) % span) * h
        else:
            uniq_d, kd = np.unique(np.rint(dt * 1e9).astype(np.int64), return_inverse=True)
            span = len(uniq_d)
            key = cls * span + kd.reshape(-1)
            d_key = np.tile(uniq_d * 1e-9, len(rates))
        nu_key = np.repeat(rates / 2.0, span)[:, None] * np.arange(-2, 3)[None, :]
        used = np.unique(key)
        d = d_key[used][:, None, None]
        table = np.zeros((len(d_key), ROTATION_SAMPLES, len(lam)), dtype=complex)
        table[used] = d * phi1((1j * nu_key[used][:, :, None] - lam[None, None, :]) * d)
        return np.einsum("fkr,fkr->fr", self.rotation_uk[w], table[key])

    # --- cached windows: table fixed, vehicle periodic --------------------------------
    def cached_windows(self) -> None:
        """Whole phase steps of pieces whose attitude depends on the vehicle phase only.

        Class 0: the vehicle seen through a fixed table ``M`` (``C = C_b^n(t) M``): the
        vehicle's own features are integrated once per phase and turned into IMU
        features per table afterwards (:func:`vehicle_to_imu`). Classes >= 1: other
        phase-periodic pieces (e.g. heading-isolation holds of one target heading):
        their IMU features are sampled once per (class, phase) at a representative
        window. Every window of a (class, phase, table) then costs a lookup.
        """
        win, step, lam = self.win, self.step, self.lam
        idx = np.flatnonzero((win.kind == CACHED) | (win.kind == PARTIAL))
        if not len(idx):
            return
        n = int(win.n[idx[0]])
        m = int(round(self.pieces.vehicle_period / step))
        x = chebyshev_points(n)
        s = (x + 1.0) * 0.5 * step  # node offsets in a window
        cls = self.pieces.phase_class[win.piece[idx]]
        ph = win.phase[idx]
        n_cls = int(cls.max()) + 1
        fv = np.zeros((n_cls, m, n, N_FEATURES))
        if np.any(cls == 0):
            t = (np.arange(m)[:, None] * step + s[None, :]).ravel()
            c_bn, w_nb = self.history.evaluate_vehicle(t)
            self._count(len(t))
            w_b = np.einsum("nji,nj->ni", c_bn, self.earth + w_nb)
            f_b = np.einsum("nji,j->ni", c_bn, self.f_n)
            fv[0] = _features(c_bn, w_b, f_b).reshape(m, n, N_FEATURES)
        other = np.flatnonzero(cls > 0)
        if len(other):
            # One representative window per (class, phase) present.
            cp, first = np.unique(cls[other] * m + ph[other], return_index=True)
            rep = idx[other[first]]
            t = (win.a[rep][:, None] + s[None, :]).ravel()
            feats = self._imu_features(t, np.repeat(win.piece[rep], n))
            fv[cp // m, cp % m] = feats.reshape(len(rep), n, N_FEATURES)
        weight = fejer_weights(n) * 0.5 * step
        # Integral over a window of phase p to its end: sum_q w_q e^{lambda (step - s_q)} F_pq.
        wend = weight[:, None] * np.exp(lam[None, :] * (step - s)[:, None])  # (n, R)
        y_phase = np.einsum("qr,cpqf->cprf", wend, fv)  # (C, m, R, 63)
        self.cached_template = (n, s, fv)

        # Tables: class 0 windows see their piece's table; the others the identity. Equal
        # tables are found among the pieces (hundreds), not the windows (thousands).
        pieces, piece_of = np.unique(win.piece[idx], return_inverse=True)
        pcls = self.pieces.phase_class[pieces]
        tables = np.where((pcls == 0)[:, None, None], self.pieces.table[pieces], np.eye(3)[None])
        keys = np.round(tables.reshape(len(pieces), 9), 12)
        uniq, inv_p = np.unique(keys, axis=0, return_inverse=True)
        inv = inv_p.reshape(-1)[piece_of.reshape(-1)]
        mats = uniq.reshape(-1, 3, 3)
        nt = len(mats)
        # Signed input as a linear form in the template features, per table: A_M.
        forms = _vehicle_forms(self.a_sig, mats)  # (T, R, 63)
        self.cached_forms = forms
        self.cached_table = np.full(len(win.a), -1)
        self.cached_table[idx] = inv
        self.cached_class = np.full(len(win.a), -1)
        self.cached_class[idx] = cls
        whole = win.kind[idx] == CACHED
        self._partial_windows(idx[~whole], inv[~whole], mats)
        idx, cls, ph, inv = idx[whole], cls[whole], ph[whole], inv[whole]
        if not len(idx):
            return
        # Signed increment of every (class, phase, table): per mode one product.
        inc = np.empty((n_cls, m, nt, len(lam)), dtype=complex)
        for r in range(len(lam)):
            inc[:, :, :, r] = (
                y_phase[:, :, r, :].reshape(-1, N_FEATURES) @ forms[:, r, :].T
            ).reshape(n_cls, m, nt)
        self.incr[idx] = inc[cls, ph, inv]
        # Per source: the windows of one (coarse interval, class, table) group add up to
        # sum_p c[group, p, r] y_phase[class, p, r, :], with c the summed propagation
        # factors e^{lambda (t_c - b)} of the group's windows of phase p; then one
        # transform per group.
        j = win.coarse[idx]
        w = self._to_coarse(win.b[idx], j)  # (K, R)
        groups, group_of = np.unique((j * n_cls + cls) * nt + inv, return_inverse=True)
        cell = group_of.reshape(-1) * m + ph
        size = len(groups) * m
        coef = np.empty((size, len(lam)), dtype=complex)
        for r in range(len(lam)):
            coef[:, r] = np.bincount(cell, w[:, r].real, size) + 1j * np.bincount(
                cell, w[:, r].imag, size
            )
        coef = coef.reshape(len(groups), m, len(lam))
        g_table = groups % nt
        g_class = (groups // nt) % n_cls
        g_j = groups // (nt * n_cls)
        # In blocks of groups (long runs have tens of thousands of coarse intervals).
        for lo in range(0, len(groups), 4096):
            blk = slice(lo, lo + 4096)
            sums = np.empty((len(groups[blk]), len(lam), N_FEATURES), dtype=complex)
            for c in np.unique(g_class[blk]):
                sel = np.flatnonzero(g_class[blk] == c)
                for r in range(len(lam)):
                    sums[sel, r, :] = coef[blk][sel, :, r] @ y_phase[c, :, r, :]
            acc_imu = vehicle_to_imu(sums, mats[g_table[blk]])
            jj, sums_j = _group_sum(g_j[blk], acc_imu)
            self._add_features(jj, sums_j)

    def _partial_windows(self, idx: np.ndarray, inv: np.ndarray, mats: np.ndarray) -> None:
        """Stops (class 0) that fill part of a phase step, from the phase template.

        On the step ``[c, c + step]`` holding the window ``[a, b]`` the vehicle features
        are the template's (Chebyshev points ``s_q``); the window's integrals are those of
        the interpolant between ``a - c`` and ``b - c`` (differences of two rows of the
        spectral integration matrix), then seen through the window's table as in
        :meth:`cached_windows`: no attitude is sampled.
        """
        if not len(idx):
            return
        win, lam, step = self.win, self.lam, self.step
        n, s_nodes, fv = self.cached_template
        half = 0.5 * step
        start = np.floor(win.a[idx] / step + 1e-9) * step
        alpha, beta = win.a[idx] - start, win.b[idx] - start
        jm = integration_matrix(np.concatenate([alpha, beta]) / half - 1.0, n) * half
        dj = jm[len(idx) :] - jm[: len(idx)]  # (P, n): int_alpha^beta of each node's share
        # y[p] = e^{lambda beta_p} sum_q dj[p, q] e^{-lambda s_q} F[phase_p, q]: the template
        # weighted by e^{-lambda s_q} once per phase, then one real product per phase
        # (complex entries as pairs of reals) instead of one small product per window.
        nr = len(lam)
        tmpl = np.exp(-lam[None, :, None] * s_nodes[:, None, None]) * fv[0][:, :, None, :]
        tmpl = tmpl.view(float).reshape(fv.shape[1], n, nr * 2 * N_FEATURES)  # (m, n, 2 R 63)
        ph = win.phase[idx]
        order = np.argsort(ph, kind="stable")
        cuts = np.flatnonzero(ph[order][1:] != ph[order][:-1]) + 1
        y = np.empty((len(idx), nr, N_FEATURES), dtype=complex)
        for sel in np.split(order, cuts):
            y[sel] = (dj[sel] @ tmpl[ph[sel[0]]]).view(complex).reshape(len(sel), nr, N_FEATURES)
        y *= np.exp(lam[None, :] * beta[:, None])[:, :, None]  # (P, R, 63) to b
        self.incr[idx] = np.einsum("prf,prf->pr", y, self.cached_forms[inv])
        # Per source, per table: the source form seen in the vehicle features
        # (vehicle_to_imu is linear: its matrix is its image of the unit features).
        yc = y * self._to_coarse(win.b[idx], win.coarse[idx])[:, :, None]
        tables = np.unique(inv)
        if 8 * len(tables) > len(idx):
            # Tables hardly repeat (a closed-loop rule stops anywhere): each window's
            # integrals through its own table.
            jj, sums = _group_sum(win.coarse[idx], vehicle_to_imu(yc, mats[inv]))
            self._add_features(jj, sums)
            return
        form = self.source_form  # (R, 63, N)
        for t in tables:
            sel = np.flatnonzero(inv == t)
            lt = vehicle_to_imu(np.eye(N_FEATURES)[None], mats[t][None])[0]  # (63 veh, 63 imu)
            per = np.empty((len(sel), form.shape[0], form.shape[2]), dtype=complex)
            for k in range(form.shape[0]):
                per[:, k, :] = yc[sel, k, :] @ (lt @ form[k])
            jj, sums = _group_sum(win.coarse[idx[sel]], per)
            self.inputs[jj] += sums

    # --- direct windows: attitude sampled at each window's points ----------------------
    def direct_windows(self, sink: list | None = None) -> None:
        """Windows whose attitude is sampled at their own points (turns on a moving
        vehicle, isolation turns); ``sink`` as in :meth:`_add_features`."""
        win, lam = self.win, self.lam
        idx = np.flatnonzero(win.kind == DIRECT)
        if not len(idx):
            return
        # Node times and signed inputs of every direct window, kept for the fine outputs.
        self.direct_first = np.full(len(win.a), -1)
        self.direct_first[idx] = np.concatenate([[0], np.cumsum(win.n[idx])[:-1]])
        total = int(win.n[idx].sum())
        self.direct_t = np.empty(total)
        self.direct_u = np.empty((total, len(lam)), dtype=complex)  # weighted, see below
        csum = np.cumsum(win.n[idx])
        lo = 0
        while lo < len(idx):
            base = csum[lo - 1] if lo else 0
            hi = max(int(np.searchsorted(csum, base + CHUNK_NODES, side="right")), lo + 1)
            sel = idx[lo:hi]
            nd = _nodes(win, sel)
            feats = self._imu_features(nd.t, win.piece[sel][nd.window])
            u = _apply_form(feats, self.a_sig)  # (N, R)
            b_w = win.b[sel][nd.window]
            wt = nd.weight[:, None] * np.exp(lam[None, :] * (b_w - nd.t)[:, None])
            self.incr[sel] = np.add.reduceat(wt * u, nd.first, axis=0)
            # Feature integrals per window (one product per window), then per coarse interval.
            y = _window_sums(nd, win.n[sel], wt, feats)  # (Wc, R, 63) to each window's end
            to_c = self._to_coarse(win.b[sel], win.coarse[sel])  # (Wc, R)
            jj, sums = _group_sum(win.coarse[sel], y * to_c[:, :, None])
            self._add_features(jj, sums, sink)
            self.direct_t[base : base + len(nd.t)] = nd.t
            # e^{-lambda (s - a)} u(s): what the fine outputs integrate (kept, not the input).
            a_w = win.a[sel][nd.window]
            self.direct_u[base : base + len(nd.t)] = u * np.exp(
                -lam[None, :] * (nd.t - a_w)[:, None]
            )
            lo = hi

    # --- fine output times --------------------------------------------------------------
    def prepare_fine(self, dt_fine: float | None) -> None:
        """Make the tables the fine-output blocks share (before they run at once)."""
        if dt_fine is not None:
            self._run_lead(dt_fine)
        if hasattr(self, "cached_template") and fine_aligned(self.step, dt_fine):
            self._cached_nav_table(dt_fine)

    def fine_nav(
        self, t: np.ndarray, dt_fine: float | None, out: np.ndarray | None = None
    ) -> np.ndarray:
        """Signed navigation errors at times ``t`` (s, > 0, increasing), (len(t), 9), in
        ``out`` if given (C-contiguous rows).

        On a uniform output grid the homogeneous part of every window is one real
        matrix product per window shape (:meth:`_nav_on_grid`); otherwise the modal
        states of :meth:`fine_states` are mapped to navigation errors.
        """
        if out is not None and not out.flags.c_contiguous:
            out[:] = self.fine_nav(t, dt_fine)  # the products write whole runs of rows
            return out
        if out is None:
            out = np.empty((len(t), 9))
        if dt_fine is None or not len(t):
            self.paths.add("fine-each")
            out[:] = self.modes.to_nav(self.fine_states(t, dt_fine))
            return out
        full = self.full if self.full is not None else self.win
        wf = _window_of(full.b, t)
        if self.full is None:
            # The windows of one stop or turn (the coarse grid cuts a piece into several)
            # form one run from the first one's start: a piece costs one row of the
            # products of _nav_on_grid, not one per window.
            wf = self._run_lead(dt_fine)[wf]
        w = self.src[wf] if self.src is not None else wf
        dt = t - full.a[wf]
        table = _OffsetTable(self.lam, dt, dt_fine, wf)
        if table.k is None:
            self.paths.add("fine-each")
            out[:] = self.modes.to_nav(self.fine_states(t, dt_fine))
            return out
        self.paths.add("fine-grid")
        return self._nav_on_grid(table, w, wf, dt, dt_fine, out)

    def _run_lead(self, dt_fine: float) -> np.ndarray:
        """Per window: the first window of its run (itself for every window neither
        still nor turning).

        A run is a chain of still windows, or of turn windows, of one piece, cut every
        :data:`RUN_OUTPUTS` outputs of step ``dt_fine``. A stop's input is one constant
        and a turn's one set of harmonics from any of its windows' start on
        (:meth:`rotation_windows`), so outputs anywhere in the run follow from its first
        window's start state and data.
        """
        key = ("lead", dt_fine)
        if key not in self._memo:
            win = self.win
            closed = (win.kind == STILL) | (win.kind == ROTATION)
            joined = np.zeros(len(closed), dtype=bool)
            joined[1:] = (
                closed[1:] & (win.kind[1:] == win.kind[:-1]) & (win.piece[1:] == win.piece[:-1])
            )
            idx = np.arange(len(closed))
            lead = np.maximum.accumulate(np.where(joined, 0, idx))
            # A long stop or turn (a steadily turning vehicle, a timeline's interval) is
            # cut into runs of about RUN_OUTPUTS outputs (plus a window): the products'
            # tables grow with a run's output count.
            part = np.floor((win.a - win.a[lead]) / (RUN_OUTPUTS * dt_fine))
            head = ~joined
            head[1:] |= part[1:] != part[:-1]
            self._memo[key] = np.maximum.accumulate(np.where(head, idx, 0))
        return self._memo[key]

    def _nav_on_grid(self, table, w, wf, dt, dt_fine, out) -> np.ndarray:
        """Navigation errors at outputs ``dt = delta + k h`` into their windows.

        The state is ``e^{lambda k h} X + T_phi(k) U + e^{lambda k h} e^{lambda delta} J``
        with ``X = e^{lambda delta} z_a (+ delta phi1(lambda delta) u)`` and ``U = u`` in a
        still window (``U = 0`` otherwise; :class:`_OffsetTable`). The outputs of a window
        sit at consecutive ``k = k0, k0 + 1, ...``, so the windows with the same first
        offset ``k0`` and output count ``c`` share the real matrix that takes
        ``(Re X, Im X, Re U, Im U)`` to the ``c`` navigation vectors
        ``Re(V (w * (e^{lambda k h} X + T_phi(k) U)))``: one product per window shape.
        The in-window integrals ``J`` of the other kinds are added afterwards.
        """
        modes, lam = self.modes, self.lam
        n_r = len(lam)
        run, k, first = table.run, table.k, table.first
        counts = np.diff(np.append(first, len(k)))
        w_run = w[first]
        kind_run = self.win.kind[w_run]
        ed = table._exp_d  # (runs, R)
        still = kind_run == STILL
        u_run = np.where(still[:, None], self.u_still[w_run], 0.0)
        x_run = ed * self.z_start[wf[first]] + table._phi_d * u_run
        partial = self._partial_on_grid(kind_run, w_run, table, dt_fine)
        if partial is not None:
            # A partial stop [a, b] inside the phase step from c = a - alpha: its in-window
            # part is e^{lambda dt} J(dt) = e^{lambda (alpha + dt)} I(alpha + dt) -
            # e^{lambda dt} e^{lambda alpha} I(alpha), I the template's integral from c.
            # The second term joins the window's start state; the first is the cached
            # windows' tabulated block at the output's offset (alpha + dt) / h from c.
            p_run, shift, _ = partial
            x_run[p_run] -= ed[p_run] * shift
        # Turns at a constant rate (rotation_windows): with mu_h = i nu_h - lambda the
        # in-window integral is J(delta + k h) = sum_h u_h (delta phi1(mu_h delta) +
        # e^{mu_h delta} T_h(k)), T_h(k) = k h phi1(mu_h k h): a part constant over the
        # run, which joins X, and five parts on a table per turn rate, so a turn's
        # outputs are one product per (rate, k0, c) shape, as a stop's are.
        rot_run = kind_run == ROTATION
        rot_cls = np.full(len(first), -1)
        rot_coef = np.zeros((len(first), ROTATION_SAMPLES * n_r), dtype=complex)
        rates = np.zeros(0)
        if np.any(rot_run):
            self.paths.add("rotation-products")
            wr = w_run[rot_run]
            uk, nu = self.rotation_uk[wr], self.rotation_nu[wr]  # (G, 5, R), (G, 5)
            d = table.delta[rot_run][:, None, None]
            mu = 1j * nu[:, :, None] - lam[None, None, :]
            x_run[rot_run] += ed[rot_run] * (uk * (d * phi1(mu * d))).sum(axis=1)
            bh = ed[rot_run][:, None, :] * uk * np.exp(mu * d)
            rot_coef[rot_run] = bh.reshape(len(wr), -1)
            # nu[:, -1] = 2 rho, exactly: each table is built with the rate of its turns
            # (a rounded rate would put a phase error growing with the run's length).
            rates, cls = np.unique(nu[:, -1], return_inverse=True)
            rot_cls[rot_run] = cls.reshape(-1)
        coef = np.concatenate([x_run, u_run, rot_coef], axis=1).view(float)  # re, im pairs
        vw = (modes.out * modes.weight[None, :]).T  # (R, 9): x = Re(sum_r z_r vw[r])
        # Cached windows on the output grid start on it (delta = 0, k0 = 1) and hold one
        # whole phase step: their in-window part is a block of navigation errors per
        # (class, phase, table), added to the product of their shape (one zero block
        # for the other windows of that shape).
        kind = kind_run[run]
        todo = kind != STILL
        cached_block = cached_key = None
        cached_run = kind_run == CACHED
        if np.any(cached_run) and fine_aligned(self.step, dt_fine):
            nav = self._cached_nav_table(dt_fine)  # (C, m, nf, T, 9)
            n_cls, m, nf, n_t = nav.shape[:4]
            blocks = np.moveaxis(nav, 3, 2).reshape(n_cls * m * n_t, nf * 9)
            cached_block = np.concatenate([blocks, np.zeros((1, nf * 9))])
            # Only windows whose outputs are all in this block and on the grid from its
            # start (|lambda| delta <= 1e-12: e^{lambda delta} = 1 to below round-off);
            # one cut by the block's edge keeps its in-window integrals.
            whole = cached_run & (counts == nf) & (k[first] == 1) & (table.delta <= 1e-9)
            if np.any(whole):
                self.paths.add("cached-blocks")
            wc = w_run[whole]
            cached_key = np.full(len(first), len(blocks))
            cached_key[whole] = (
                self.cached_class[wc] * m + self.win.phase[wc]
            ) * n_t + self.cached_table[wc]
            todo &= ~whole[run]
        todo &= ~rot_run[run]
        k0 = k[first]
        span = int(counts.max()) + 1
        kspan = int(k0.max()) + 1
        shape_key = ((rot_cls + 1) * kspan + k0) * span + counts
        shapes, shape_of = np.unique(shape_key, return_inverse=True)
        shape_of = shape_of.reshape(-1)
        order = np.argsort(shape_of, kind="stable")
        bounds = np.searchsorted(shape_of[order], np.arange(len(shapes) + 1))
        harm = np.arange(-2, 3)
        for g, key in enumerate(shapes):
            cls_kk, c = divmod(int(key), span)
            cls, kk = divmod(cls_kk, kspan)
            cls -= 1
            runs = order[bounds[g] : bounds[g + 1]]
            ks = np.arange(kk, kk + c)
            tabs = [table._exp[ks], table._phi[ks]]  # (c, R) each
            if cls >= 0:
                # e^{lambda k h} T_h(k) of this turn rate, harmonics -2..2.
                grid = (ks * dt_fine)[:, None, None]
                mu = 1j * (rates[cls] / 2.0) * harm[None, :, None] - lam[None, None, :]
                th = table._exp[ks][:, None, :] * (grid * phi1(mu * grid))  # (c, 5, R)
                tabs += [th[:, h] for h in range(ROTATION_SAMPLES)]
            parts = len(tabs)
            mats = np.empty((parts * n_r, 2, c, 9))  # rows: (part, mode) x (re, im)
            for part, tab in enumerate(tabs):
                a = tab.T[:, :, None] * vw[:, None, :]  # (R, c, 9): e_r(k) vw[r]
                mats[part * n_r : (part + 1) * n_r, 0] = a.real
                mats[part * n_r : (part + 1) * n_r, 1] = -a.imag
            vals = coef[runs, : 2 * parts * n_r] @ mats.reshape(2 * parts * n_r, c * 9)
            if cached_block is not None and kk == 1 and c == cached_block.shape[1] // 9:
                vals += cached_block[cached_key[runs]]
            # Each run's c outputs are c consecutive rows of out: seen through a view
            # whose row i is rows i .. i + c - 1, a run is one item of c x 9 values (the
            # runs do not overlap, so neither do the writes).
            by_run = as_strided(out, shape=(len(out) - c + 1, c * 9), strides=out.strides)
            by_run[first[runs]] = vals
        if partial is not None:
            p_run, _, rows = partial
            pts = np.flatnonzero(np.isin(run, np.flatnonzero(p_run)))
            out[pts] += rows(pts, run, dt)
            todo &= kind != PARTIAL
        # In-window integrals of the other kinds, added in modal form.
        other = np.flatnonzero(todo)
        if len(other):
            e = table._exp[k[other]] * ed[run[other]]
            ints = self._in_window(
                kind[other], w[other], wf[other], dt[other], dt_fine, (run[other], table.delta)
            )
            out[other] += modes.to_nav(e * ints)
        return out

    def _partial_on_grid(self, kind_run, w_run, table, dt_fine):
        """Partial stops on an output grid aligned with the phase steps, for
        :meth:`_nav_on_grid`: ``(runs, shift, rows)`` or None.

        ``runs`` marks the runs in partial windows, ``shift`` (their count, R) is
        ``e^{lambda alpha} I(alpha)`` of each (taken off the start state), and
        ``rows(pts, run, dt)`` gives the tabulated navigation errors
        ``e^{lambda (alpha + dt)} I(alpha + dt)`` of outputs ``pts``.
        """
        p_run = kind_run == PARTIAL
        if not np.any(p_run) or not fine_aligned(self.step, dt_fine):
            return None
        self.paths.add("partial-table")
        wp = w_run[p_run]
        alpha = self.win.a[wp] - np.floor(self.win.a[wp] / self.step + 1e-9) * self.step
        shift = np.exp(self.lam[None, :] * alpha[:, None]) * self._cached_integrals_anywhere(
            wp, alpha
        )
        nav = self._cached_nav_table(dt_fine)  # (C, m, nf, T, 9)
        n_cls, m, nf, n_t = nav.shape[:4]
        flat = nav.reshape(-1, 9)
        alpha_run = np.zeros(len(w_run))
        alpha_run[p_run] = alpha

        def rows(pts, run, dt):
            wq = w_run[run[pts]]
            pos = np.rint((alpha_run[run[pts]] + dt[pts]) / dt_fine).astype(int)  # 1..nf
            key = ((self.cached_class[wq] * m + self.win.phase[wq]) * nf + pos - 1) * n_t
            return flat[key + self.cached_table[wq]]

        return p_run, shift, rows

    def fine_states(self, t: np.ndarray, dt_fine: float | None) -> np.ndarray:
        """Signed modal states at times ``t`` (s, > 0, increasing), (len(t), R)."""
        full = self.full if self.full is not None else self.win
        wf = np.searchsorted(full.b, t - MERGE, side="left").clip(0, len(full.b) - 1)
        w = self.src[wf] if self.src is not None else wf  # the base window holding the data
        dt = t - full.a[wf]
        table = _OffsetTable(self.lam, dt, dt_fine, wf)
        if table.k is not None:
            self.paths.add("states-grid")
            return self._fine_on_grid(table, w, wf, dt, dt_fine)
        self.paths.add("states-each")
        out = np.empty((len(t), len(self.lam)), dtype=complex)
        kind = self.win.kind[w]
        zs = self.z_start[wf]
        s = np.flatnonzero(kind == STILL)
        if len(s):
            out[s] = table.exp(s) * zs[s] + table.phi(s) * self.u_still[w[s]]
        ns = np.flatnonzero(kind != STILL)
        if len(ns):
            ints = self._in_window(kind[ns], w[ns], wf[ns], dt[ns], dt_fine)
            out[ns] = table.exp(ns) * (zs[ns] + ints)
        return out

    def _fine_on_grid(self, table, w, wf, dt, dt_fine) -> np.ndarray:
        """:meth:`fine_states` for outputs on a uniform grid, window by window.

        With ``dt = delta + k h`` (:class:`_OffsetTable`) the state at an output is
        ``e^{lambda k h} X + T_phi(k) u + e^{lambda k h} e^{lambda delta} J(t)``, where
        ``X = e^{lambda delta} z_a (+ delta phi1(lambda delta) u in a still window)`` is
        one value per window, ``u`` the constant input of a still window (0 otherwise)
        and ``J`` the in-window integral of the other kinds: the per-output work is a
        few lookups and products.
        """
        run, k, first = table.run, table.k, table.first
        w_run = w[first]
        kind_run = self.win.kind[w_run]
        ed = table._exp_d  # (runs, R)
        still = kind_run == STILL
        x_run = ed * self.z_start[wf[first]]
        e = table._exp[k]
        if np.any(still):
            u_run = np.where(still[:, None], self.u_still[w_run], 0.0)
            x_run = x_run + table._phi_d * u_run
            out = e * x_run[run] + table._phi[k] * u_run[run]
        else:
            out = e * x_run[run]
        kind = kind_run[run]
        ns = np.flatnonzero(kind != STILL)
        if len(ns):
            ints = self._in_window(kind[ns], w[ns], wf[ns], dt[ns], dt_fine, (run[ns], table.delta))
            out[ns] += e[ns] * ed[run[ns]] * ints
        return out

    def _in_window(self, kind, w, wf, dt, dt_fine, grid=None) -> np.ndarray:
        """``J = int_a^t e^{-lambda (s - a)} u(s) ds`` at outputs of windows that are not
        still (kinds ``kind``, base windows ``w``, run windows ``wf``, offsets ``dt``),
        (len(dt), R). ``grid``: the outputs' runs and the runs' fractions ``delta`` on a
        uniform output grid (:class:`_OffsetTable`), for the tabulated turn integrals."""
        ints = np.empty((len(dt), len(self.lam)), dtype=complex)
        rr = np.flatnonzero(kind == ROTATION)
        if len(rr):
            if grid is not None:
                self.paths.add("rotation-grid")
                run, delta = grid
                ints[rr] = self._rotation_integrals_on_grid(w[rr], dt[rr], dt_fine, run[rr], delta)
            else:
                self.paths.add("rotation-each")
                ints[rr] = self._rotation_integrals(w[rr], dt[rr], dt_fine)
        c = np.flatnonzero(kind == CACHED)
        if len(c):
            if fine_aligned(self.step, dt_fine):
                self.paths.add("cached-aligned")
                pos = np.clip(np.round(dt[c] / dt_fine).astype(int) - 1, 0, None)
                ints[c] = self._cached_integrals(w[c], pos, dt_fine)
            else:
                self.paths.add("cached-anywhere")
                ints[c] = self._cached_integrals_anywhere(w[c], dt[c])
        d = np.flatnonzero(kind == DIRECT)
        if len(d):
            ints[d] = self._direct_integrals(w[d], dt[d], wf[d])
        p = np.flatnonzero(kind == PARTIAL)
        if len(p):
            # J = e^{lambda alpha} (I(alpha + dt) - I(alpha)), I the template's integral
            # from the start of the phase step.
            wp = w[p]
            alpha = self.win.a[wp] - np.floor(self.win.a[wp] / self.step + 1e-9) * self.step
            both = self._cached_integrals_anywhere(
                np.concatenate([wp, wp]), np.concatenate([alpha + dt[p], alpha])
            )
            ints[p] = np.exp(self.lam[None, :] * alpha[:, None]) * (both[: len(p)] - both[len(p) :])
        return ints

    def _cached_integrals(self, w: np.ndarray, pos: np.ndarray, dt_fine: float) -> np.ndarray:
        """``int_a^t e^{-lambda (s - a)} u(s) ds`` at fine offsets ``pos`` of cached windows."""
        vals = self._cached_offset_table(dt_fine)
        return vals[self.cached_class[w], self.win.phase[w], pos, self.cached_table[w]]

    def _cached_offset_table(self, dt_fine: float) -> np.ndarray:
        """(C, m, nf, T, R): the in-window integral at every fine offset of every
        (class, phase, table), computed once per run."""
        key = ("offsets", dt_fine)
        if key in self._memo:
            return self._memo[key]
        n, s_nodes, fv = self.cached_template
        step, lam = self.step, self.lam
        nf = int(round(step / dt_fine))
        xf = (np.arange(1, nf + 1) * dt_fine) / (0.5 * step) - 1.0
        jmat = integral_of_series(xf, n) @ coefficient_matrix(n) * (0.5 * step)  # (nf, n)
        g = np.exp(-lam[None, :] * s_nodes[:, None])  # (n, R)
        forms = self.cached_forms  # (T, R, 63)
        n_cls, m = fv.shape[0], fv.shape[1]
        vals = np.empty((n_cls, m, nf, len(forms), len(lam)), dtype=complex)
        for r in range(len(lam)):
            # H[c, p, f, feat] = sum_q J[f, q] e^{-lambda_r s_q} F_cpq[feat]; then the forms
            # of every table: one (C m nf, 63) @ (63, T) product per mode.
            h = np.einsum("fq,cpqv->cpfv", jmat * g[None, :, r], fv).reshape(-1, N_FEATURES)
            vals[..., r] = (
                _apply_form(h.real, forms[:, r, :]) + 1j * _apply_form(h.imag, forms[:, r, :])
            ).reshape(n_cls, m, nf, -1)
        self._memo[key] = vals
        return vals

    def _cached_nav_table(self, dt_fine: float) -> np.ndarray:
        """(C, m, nf, T, 9): navigation errors of ``e^{lambda (f + 1) h} J_f`` for every
        (class, phase, fine offset f, table) of the cached windows."""
        key = ("nav", dt_fine)
        if key not in self._memo:
            vals = self._cached_offset_table(dt_fine)
            nf = vals.shape[2]
            e = np.exp(self.lam[None, :] * (np.arange(1, nf + 1) * dt_fine)[:, None])  # (nf, R)
            self._memo[key] = self.modes.to_nav(vals * e[None, None, :, None, :])
        return self._memo[key]

    def _cached_integrals_anywhere(self, w: np.ndarray, dt: np.ndarray) -> np.ndarray:
        """As :meth:`_cached_integrals` for fine times at any offset (grid not aligned).

        The template's signed input of each (class, phase, table) is turned into its
        Chebyshev series once; each fine time then integrates the series to its offset.
        """
        n, s_nodes, fv = self.cached_template
        lam, step = self.lam, self.step
        key = (self.cached_class[w] * fv.shape[1] + self.win.phase[w]) * len(
            self.cached_forms
        ) + self.cached_table[w]
        keys, inv = np.unique(key, return_inverse=True)
        inv = inv.reshape(-1)
        nt, m = len(self.cached_forms), fv.shape[1]
        c_, p_, t_ = keys // (nt * m), (keys // nt) % m, keys % nt
        forms = self.cached_forms[t_]  # (K, R, 63)
        u = np.einsum("kqv,krv->kqr", fv[c_, p_], forms)  # (K, n, R) signed input at nodes
        g = u * np.exp(-lam[None, None, :] * s_nodes[None, :, None])
        coef = np.matmul(coefficient_matrix(n)[None], g)  # (K, n, R)
        ints = integral_of_series(dt / (0.5 * step) - 1.0, n)  # (F, n)
        return 0.5 * step * _apply_series(ints, inv, coef)

    def _direct_integrals(self, w: np.ndarray, dt: np.ndarray, wf: np.ndarray) -> np.ndarray:
        """``int_a^t e^{-lambda (s - a)} u(s) ds`` at fine times of direct windows.

        The Chebyshev series of ``g(s) = e^{-lambda (s - a)} u(s)`` on each window,
        integrated term by term to the output times. Windows of the same shape (points,
        length, fine offsets: every turn of an open-loop table on a still vehicle) share
        one integration matrix, applied to all of them in one product. ``w`` are the
        (base) windows holding the data, ``wf`` the windows of the run (they differ in a
        lifted periodic run, where one base window serves every period).
        """
        win, lam = self.win, self.lam
        out = np.zeros((len(w), len(lam)), dtype=complex)
        wins_f, first_pt, counts = np.unique(wf, return_index=True, return_counts=True)
        wins = w[first_pt]
        length = win.b[wins] - win.a[wins]
        key = np.stack(
            [win.n[wins], np.rint(length * 1e6), np.rint(dt[first_pt] * 1e6), counts], axis=1
        ).astype(np.int64)
        shapes, shape_of, shape_count = np.unique(
            key, axis=0, return_inverse=True, return_counts=True
        )
        shape_of = shape_of.reshape(-1)
        shared = np.flatnonzero(shape_count > 1)
        groups = [np.flatnonzero(shape_of == sh) for sh in shared]
        # The shared integration matrices (cnt, m) of all shapes with the same point
        # count m in one call (a run has tens of shapes, each with a few outputs).
        jmats: list = [None] * len(groups)
        n_of = np.array([int(win.n[wins[g[0]]]) for g in groups], dtype=int)
        for m in np.unique(n_of):
            which = np.flatnonzero(n_of == m)
            xs, halves, sizes = [], [], []
            for i in which:
                g0 = groups[i][0]
                half = 0.5 * length[g0]
                cnt = int(counts[g0])
                xs.append(dt[first_pt[g0] : first_pt[g0] + cnt] / half - 1.0)
                halves.append(np.full(cnt, half))
                sizes.append(cnt)
            mat = integration_matrix(np.concatenate(xs), int(m)) * np.concatenate(halves)[:, None]
            for i, part in zip(which, np.split(mat, np.cumsum(sizes)[:-1]), strict=True):
                jmats[i] = part
        for members, jmat in zip(groups, jmats, strict=True):
            m = jmat.shape[1]
            g = self._direct_g(wins[members], m)  # (Wg, m, R)
            cnt = jmat.shape[0]
            # Points of one window are consecutive (sorted times): first_pt .. + count.
            pts = first_pt[members][:, None] + np.arange(cnt)[None, :]  # (Wg, cnt)
            vals = np.tensordot(jmat, g, axes=([1], [1]))  # (cnt, Wg, R)
            out[pts.T.ravel()] = vals.reshape(cnt * len(members), len(lam))
        # Windows of a shape of their own (irregular stop times): point by point.
        single = np.isin(shape_of, np.flatnonzero(shape_count == 1))
        if np.any(single):
            pts = np.flatnonzero(np.isin(wf, wins_f[single]))
            n_w = win.n[w[pts]]
            for m in np.unique(n_w):
                sub = pts[n_w == m]
                ws, inverse = np.unique(w[sub], return_inverse=True)
                coef = np.tensordot(
                    coefficient_matrix(int(m)), self._direct_g(ws, int(m)), axes=([1], [1])
                )  # (m, Ws, R)
                half = 0.5 * (win.b[w[sub]] - win.a[w[sub]])
                ints = integral_of_series(dt[sub] / half - 1.0, int(m))  # (F, m)
                inv = inverse.reshape(-1)
                acc = _apply_series(ints, inv, np.ascontiguousarray(np.moveaxis(coef, 0, 1)))
                out[sub] = half[:, None] * acc
        return out

    def _direct_g(self, wins: np.ndarray, m: int) -> np.ndarray:
        """``e^{-lambda (s - a)} u(s)`` at the nodes of direct windows ``wins`` (W, m, R)."""
        node = self.direct_first[wins][:, None] + np.arange(m)[None, :]
        return self.direct_u[node]


def _apply_series(ints: np.ndarray, inv: np.ndarray, coef: np.ndarray) -> np.ndarray:
    """``acc[f] = sum_k ints[f, k] coef[inv[f], k]``: (F, R) complex.

    ``ints`` (F, n) real are the integrated Chebyshev polynomials at the outputs, ``coef``
    (K, n, R) the series of each window (or key). Outputs of one key usually come in
    runs (consecutive times of one window): runs of the same length are one batched
    product (c, n) @ (n, R), real and imaginary parts apart.
    """
    first = np.flatnonzero(np.concatenate([[True], inv[1:] != inv[:-1]]))
    cnt = np.diff(np.append(first, len(inv)))
    acc = np.empty((len(inv), coef.shape[2]), dtype=complex)
    for c in np.unique(cnt):
        sel = np.flatnonzero(cnt == c)
        rows = (first[sel][:, None] + np.arange(c)[None, :]).ravel()
        a = ints[rows].reshape(len(sel), c, ints.shape[1])
        g = coef[inv[first[sel]]]  # (G, n, R)
        acc[rows] = (a @ g.real + 1j * (a @ g.imag)).reshape(-1, coef.shape[2])
    return acc


def _vehicle_forms(a_sig: np.ndarray, mats: np.ndarray) -> np.ndarray:
    """(T, R, 63): the signed input as a linear form in the vehicle features, per table.

    ``u = sum_f A[r, f] F_imu[f]`` and ``F_imu = vehicle_to_imu(F_veh, M)``; the form on
    the vehicle features is the transpose map applied to ``A``:
    ``A_M[r, (a, k)] = sum_i A[r, (a, i)] M[k, i]`` and likewise with ``M kron M``.
    """
    t = len(mats)
    r = a_sig.shape[0]
    out = np.empty((t, r, N_FEATURES), dtype=complex)
    a1 = a_sig[:, :9].reshape(r, 3, 3)
    out[:, :, :9] = np.einsum("rai,tki->trak", a1, mats).reshape(t, r, 9)
    for lo in (9, 36):
        a2 = a_sig[:, lo : lo + 27].reshape(r, 3, 3, 3)
        tmp = np.einsum("raij,tlj->trail", a2, mats)
        out[:, :, lo : lo + 27] = np.einsum("trail,tki->trakl", tmp, mats).reshape(t, r, 27)
    return out


def _nodes(win: Windows, sel: np.ndarray) -> _Nodes:
    """Chebyshev nodes and Fejér weights of windows ``sel`` (flat, in window order)."""
    a, b, n = win.a[sel], win.b[sel], win.n[sel]
    half = 0.5 * (b - a)
    first = np.concatenate([[0], np.cumsum(n)[:-1]])
    total = int(n.sum())
    t = np.empty(total)
    w = np.empty(total)
    widx = np.repeat(np.arange(len(a)), n)
    for m in np.unique(n):
        s = np.flatnonzero(n == m)
        x = chebyshev_points(int(m))
        pos = first[s][:, None] + np.arange(m)[None, :]
        t[pos] = a[s][:, None] + (x[None, :] + 1.0) * half[s][:, None]
        w[pos] = fejer_weights(int(m))[None, :] * half[s][:, None]
    return _Nodes(t, w, widx, first)


@dataclass
class _Nodes:
    """The quadrature nodes of a set of windows (flat, in window order)."""

    t: np.ndarray  # (N,) s
    weight: np.ndarray  # (N,) Fejér weight * half length
    window: np.ndarray  # (N,) position of the node's window in the set
    first: np.ndarray  # (W,) index of each window's first node


def _apply_form(feats: np.ndarray, form: np.ndarray) -> np.ndarray:
    """``feats @ form.T`` for real features and a complex form (two real products)."""
    return feats @ form.real.T + 1j * (feats @ form.imag.T)


def _distinct(c: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Attitudes ``c`` (K, 3, 3) with angular velocities ``w`` (K, 3) rad/s that are the
    same to 1e-12 (and 1e-15 rad/s): the index of one of each, and of each one's."""
    key = np.rint(np.concatenate([c.reshape(-1, 9), w * 1e3], axis=1) * 1e12) + 0.0  # no -0
    rows = np.ascontiguousarray(key).view(np.dtype((np.void, key.shape[1] * 8))).reshape(-1)
    _, rep, of = np.unique(rows, return_index=True, return_inverse=True)
    return rep, of.reshape(-1)


def _interval_sums(
    j: np.ndarray, col: np.ndarray, coef: np.ndarray, per: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Sums ``S[j] = sum_m coef[m, r] per[col[m], r, :]`` over the terms m of each coarse
    interval j: ``(intervals, S)``, S (len(intervals), R, N).

    One sparse product for all modes: rows (interval, mode), columns (col, mode), so
    the few distinct inputs ``per`` (stops or turns that recur) are never copied per term.
    """
    jj, row = np.unique(j, return_inverse=True)
    n_r = per.shape[1]
    modes = np.arange(n_r)
    rows = (row.reshape(-1, 1) * n_r + modes).ravel()
    cols = (np.asarray(col).reshape(-1, 1) * n_r + modes).ravel()
    mat = sparse.csr_matrix((coef.ravel(), (rows, cols)), shape=(len(jj) * n_r, per.shape[0] * n_r))
    sums = mat @ per.reshape(per.shape[0] * n_r, -1)
    return jj, sums.reshape(len(jj), n_r, -1)


def _add_rows(target: np.ndarray, rows: np.ndarray, values: np.ndarray) -> None:
    """``target[rows] += values`` for distinct increasing ``rows``; a slice (no gather or
    scatter) when they are consecutive."""
    if len(rows) and rows[-1] - rows[0] == len(rows) - 1:
        target[rows[0] : rows[-1] + 1] += values
    else:
        target[rows] += values


def _group_sum(keys: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sums of ``values`` rows with equal ``keys``: (unique keys, sums)."""
    if len(keys) < 2 or np.all(keys[1:] > keys[:-1]):
        return keys, values  # distinct and sorted already: nothing to add up
    if np.all(keys[1:] >= keys[:-1]):
        k, v = keys, values  # grouped already (the common case): no sort, no copy
    else:
        order = np.argsort(keys, kind="stable")
        k, v = keys[order], values[order]
    first = np.concatenate([[True], k[1:] != k[:-1]])
    start = np.flatnonzero(first)
    if 4 * len(start) < 3 * len(k):
        return k[start], np.add.reduceat(v, start, axis=0)
    # Mostly single rows (a stop cut by the coarse grid, a turn in a few intervals): the
    # first row of each group, plus the second for pairs; longer groups by reduceat on
    # their own (which sums them in its own order: the result is reduceat's to the bit).
    out = v[start]
    size = np.diff(np.append(start, len(k)))
    two = np.flatnonzero(size == 2)
    out[two] += v[start[two] + 1]
    big = np.flatnonzero(size > 2)
    if len(big):
        edges = np.stack([start[big], start[big] + size[big]], axis=1).ravel()
        sums = np.add.reduceat(v, edges[edges < len(k)], axis=0)
        out[big] = sums[::2]
    return k[start], out


def _window_sums(nd: _Nodes, n: np.ndarray, wt: np.ndarray, feats: np.ndarray) -> np.ndarray:
    """Per window: ``sum over its nodes of wt[node, r] * feats[node, f]``, (W, R, 63).

    Windows of equal point count are one batched product each (complex weights as two
    real products).
    """
    out = np.empty((len(n), wt.shape[1], feats.shape[1]), dtype=complex)
    for m in np.unique(n):
        ws = np.flatnonzero(n == m)
        idx = nd.first[ws][:, None] + np.arange(m)[None, :]  # (Wm, m)
        w_t = np.swapaxes(wt[idx], 1, 2)  # (Wm, R, m)
        f = feats[idx]  # (Wm, m, 63)
        out[ws] = np.matmul(w_t.real, f) + 1j * np.matmul(w_t.imag, f)
    return out


# ---------------------------------------------------------------------------------------
# White noise
# ---------------------------------------------------------------------------------------
def white_noise_covariance(
    model: ErrorModel, arw: float, vrw: float, t: Sequence[float] | np.ndarray
) -> np.ndarray:
    """Navigation-error covariance from gyro and accelerometer white noise, in closed form.

    The noise is isotropic (same density on every IMU axis), so its projection into n
    does not depend on the attitude and ``P(t) = V [M o Xi(t)] V^H`` with
    ``M = V^-1 G Q G^T V^-H`` and ``Xi_ij(t) = t phi_1((lambda_i + conj(lambda_j)) t)``.

    Parameters
    ----------
    model : ErrorModel
        Site and vertical mode.
    arw : float, rad/sqrt(s)
        Angle random walk (PSD ``arw^2`` on each gyro axis).
    vrw : float, m/s/sqrt(s)
        Velocity random walk (PSD ``vrw^2`` on each accelerometer axis).
    t : (M,) s
        Times, >= 0.

    Returns
    -------
    ndarray, shape (M, 9, 9)
        Covariance of psi (rad), dv (m/s), dr (m), ENU, symmetrised.
    """
    t = np.asarray(t, dtype=float)
    # The same site, noise and grid give the same covariance: the points of a sweep or
    # a design (one worker runs many) compute it once. A copy goes out (callers own it).
    key = (model, float(arw), float(vrw), t.tobytes())
    if key in _WHITE_CACHE:
        return _WHITE_CACHE[key].copy()
    modes = NavModes(model)
    inv, out = modes.inv_all, modes.out_all
    g = np.zeros((9, 6))
    g[0:3, 0:3] = -np.eye(3)
    g[3:6, 3:6] = np.eye(3)
    if model.vertical == "clamped":
        g[5, :] = 0.0
    q = np.diag([arw**2] * 3 + [vrw**2] * 3)
    m = inv @ g @ q @ g.T @ inv.conj().T
    p = (out @ (m[None] * _xi(modes, t)) @ out.conj().T).real
    p = 0.5 * (p + np.swapaxes(p, 1, 2))
    if len(_WHITE_CACHE) >= 4:
        _WHITE_CACHE.pop(next(iter(_WHITE_CACHE)))
    _WHITE_CACHE[key] = p
    return p.copy()


_WHITE_CACHE: dict = {}
_XI_CACHE: dict = {}


def _xi(modes: NavModes, t: np.ndarray) -> np.ndarray:
    """``Xi_ij(t) = int_0^t e^{(lambda_i + conj(lambda_j)) s} ds`` (M, A, A), kept for reuse.

    It depends on the modes and the times only, not on the noise densities: the ARW
    and VRW runs of one analysis (and the runs of a comparison) share it.
    """
    key = (modes.model, t.tobytes())
    xi = _XI_CACHE.get(key)
    if xi is None:
        lam = modes.lam_all
        s = lam[:, None] + lam.conj()[None, :]
        xi = t[:, None, None] * phi1(s[None] * t[:, None, None])
        if len(_XI_CACHE) >= 4:
            _XI_CACHE.pop(next(iter(_XI_CACHE)))
        _XI_CACHE[key] = xi
    return xi


# ---------------------------------------------------------------------------------------
# Gauss-Markov bias instability
# ---------------------------------------------------------------------------------------
def gauss_markov_covariance(
    model: ErrorModel,
    history: AttitudeHistory,
    sigma: float,
    tau: float,
    sensor: str,
    t: np.ndarray,
) -> np.ndarray:
    """Navigation-error covariance from a first-order Gauss-Markov bias on every IMU axis.

    The bias ``b^s`` (IMU frame, each axis stationary with variance ``sigma^2`` and
    correlation time ``tau``) enters the navigation errors through ``C_s^n(t) b^s``, so,
    unlike white noise, its covariance depends on the attitude history. With
    ``Q(t) = E[x(t) b^s(t)^T]`` (9 x 3) and ``x(0) = 0``::

        Q' = (F - I / tau) Q + sigma^2 B C(t),     P' = F P + P F^T + B C Q^T + Q C^T B^T,

    (``B`` the gyro rows ``-I`` of psi, or the accelerometer rows ``+I`` of dv). In the
    eigenbasis (every mode, conjugates included) ``W = V^-1 Q`` is a constant-error
    response with the modes shifted by ``-1/tau``, and ``P~ = V^-1 P V^-H`` is the integral
    of ``e^{(lambda_i + conj(lambda_j)) (T - s)} [K W^H + W K^H]_ij`` with ``K = V^-1 B C``.
    Both are evaluated window by window on Chebyshev points (``W`` at the points by the
    spectral integration matrix), and scanned from window to window.

    Parameters
    ----------
    model : ErrorModel
        Site and vertical mode.
    history : AttitudeHistory
        ``C_s^n(t)`` over the run.
    sigma : float
        Steady-state 1 sigma of the bias, rad/s (gyro) or m/s^2 (accelerometer).
    tau : float
        Correlation time, s.
    sensor : {"gyro", "accel"}
    t : (M,) s
        Output times: 0, then increasing to the end of the history (they cut the windows).

    Returns
    -------
    ndarray, shape (M, 9, 9)
        Covariance of psi (rad), dv (m/s), dr (m), ENU, symmetrised.
    """
    with single_thread_blas():
        return _gauss_markov(model, history, sigma, tau, sensor, np.asarray(t, dtype=float))


def _gauss_markov(model, history, sigma, tau, sensor, t):
    modes = NavModes(model)
    lam, out, inv = modes.lam_all, modes.out_all, modes.inv_all
    k_in = -inv[:, PSI] if sensor == "gyro" else inv[:, DV]  # (A, 3): n-frame error -> modes
    mu = lam - 1.0 / tau
    fastest = max(float(np.max(np.abs(mu))), 2.0 * float(np.max(np.abs(lam))))
    pieces = history.pieces()
    # Every window sampled (the state W varies inside still windows too).
    plain = Pieces(pieces.breaks, pieces.bandwidth, np.zeros_like(pieces.still))
    win = make_windows(plain, t, fastest)
    win = Windows(win.a, win.b, win.piece, np.maximum(win.n, 8), win.kind, win.phase, win.coarse)
    nw, na = len(win.a), len(lam)
    s2 = sigma * sigma

    def node_inputs(sel):
        nd = _nodes(win, sel)
        c, _ = history.evaluate(nd.t, win.piece[sel][nd.window])
        return nd, np.einsum("ak,nkj->naj", k_in, c)  # K = V^-1 B C at the nodes (N, A, 3)

    # Pass 1: the W increments of every window, then W at every window start.
    d_w = np.empty((nw, na, 3), dtype=complex)
    for sel in _chunks(win, CHUNK_NODES):
        nd, kq = node_inputs(sel)
        wt = nd.weight[:, None] * np.exp(mu[None, :] * (win.b[sel][nd.window] - nd.t)[:, None])
        d_w[sel] = np.add.reduceat(s2 * wt[:, :, None] * kq, nd.first, axis=0)
    w_end = scan(mu, 0.0, np.zeros((na, 3), dtype=complex), win.b, d_w)
    w_start = np.concatenate([np.zeros((1, na, 3), dtype=complex), w_end[:-1]])

    # Pass 2: W at the nodes, the P~ increments of every window.
    d_p = np.empty((nw, na, na), dtype=complex)
    for sel in _chunks(win, CHUNK_NODES):
        nd, kq = node_inputs(sel)
        a_n = win.a[sel][nd.window]
        shift = nd.t - a_n
        g = s2 * np.exp(-mu[None, :] * shift[:, None])[:, :, None] * kq  # (N, A, 3)
        wq = np.empty_like(g)
        for m in np.unique(win.n[sel]):
            ws = np.flatnonzero(win.n[sel] == m)
            idx = nd.first[ws][:, None] + np.arange(m)[None, :]  # (Wm, m)
            x = chebyshev_points(int(m))
            jmat = integration_matrix(x, int(m))  # node values -> integrals to the nodes
            half = 0.5 * (win.b[sel][ws] - win.a[sel][ws])
            ints = np.einsum("qp,wpaj->wqaj", jmat, g[idx]) * half[:, None, None, None]
            wq[idx] = w_start[sel][ws][:, None] + ints
        wq *= np.exp(mu[None, :] * shift[:, None])[:, :, None]
        # P~ increment: sum_q c_q D_q (K W^H + W K^H) D_q^H, D_q = diag(e^{lambda (b - s_q)})
        d = np.exp(lam[None, :] * (win.b[sel][nd.window] - nd.t)[:, None])[:, :, None]
        kd, wd = d * kq * nd.weight[:, None, None], d * wq
        term = kd @ np.conj(np.swapaxes(wd, 1, 2))
        d_p[sel] = np.add.reduceat(term + np.conj(np.swapaxes(term, 1, 2)), nd.first, axis=0)
    nu = lam[:, None] + np.conj(lam)[None, :]
    p_end = scan(nu.ravel(), 0.0, np.zeros(na * na, dtype=complex), win.b, d_p.reshape(nw, -1))
    p_end = p_end.reshape(nw, na, na)
    res = np.zeros((len(t), 9, 9))
    at = np.searchsorted(win.b, t - MERGE, side="left")
    inside = t > MERGE
    p_t = p_end[at[inside]]
    res[inside] = (out[None] @ p_t @ np.conj(out.T)[None]).real
    return 0.5 * (res + np.swapaxes(res, 1, 2))


def _chunks(win: Windows, nodes: int):
    """Index arrays of consecutive windows holding at most ``nodes`` points each."""
    csum = np.cumsum(win.n)
    lo = 0
    while lo < len(win.n):
        base = csum[lo - 1] if lo else 0
        hi = max(int(np.searchsorted(csum, base + nodes, side="right")), lo + 1)
        yield np.arange(lo, hi)
        lo = hi
