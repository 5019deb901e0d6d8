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

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from inserr.model.attitude_history import AttitudeHistory, Pieces
from inserr.model.modal import NavModes
from inserr.model.psi_model import ErrorModel
from inserr.model.quadrature import (
    MAX_PHASE,
    chebyshev_points,
    fejer_weights,
    integral_of_series,
    points_for,
)
from inserr.model.quadrature import _coefficient_matrix as coefficient_matrix

#: Nodes evaluated at once (bounds memory: ~63 features and R modal weights per node).
CHUNK_NODES = 40_000
#: Largest |Re lambda| * time span of one scan block (keeps exp() within float range).
SCAN_SPAN = 200.0
#: Window boundaries closer than this (s) are merged.
MERGE = 1e-9

#: Feature layout of one node: C[a, i] (9), C[a, i] w[j] (27), C[a, i] f[j] (27).
N_FEATURES = 63


def phi1(z: np.ndarray) -> np.ndarray:
    """``(e^z - 1) / z`` (1 at z = 0), accurate for small and complex ``z``."""
    z = np.asarray(z)
    small = z == 0
    out = np.expm1(np.where(small, 1.0, z)) / np.where(small, 1.0, z)
    return np.where(small, 1.0, out)


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
        Chebyshev points of each window (1 where the attitude is constant).
    still : (W,) bool
        Constant attitude (closed-form integrals).
    coarse : (W,) int
        Index ``j`` of the coarse output time ``t_c[j]`` that ends the window's coarse
        interval ``(t_c[j-1], t_c[j]]``.
    """

    a: np.ndarray
    b: np.ndarray
    piece: np.ndarray
    n: np.ndarray
    still: np.ndarray
    coarse: np.ndarray


def make_windows(pieces: Pieces, t_coarse: np.ndarray, fastest_mode: float) -> Windows:
    """Cut the history at its piece boundaries and the coarse times, then by phase budget.

    Parameters
    ----------
    pieces : Pieces
        Smooth pieces of the attitude history.
    t_coarse : (Mc,) s
        Coarse output times (0 and the end included).
    fastest_mode : float, 1/s
        Largest ``|lambda|`` of the navigation modes (adds to the integrand's phase).

    Returns
    -------
    Windows
    """
    end = float(pieces.breaks[-1])
    cuts = np.unique(np.concatenate([pieces.breaks, t_coarse[(t_coarse > 0) & (t_coarse < end)]]))
    cuts = cuts[np.concatenate([[True], np.diff(cuts) > MERGE])]
    cuts[-1] = end
    a, b = cuts[:-1], cuts[1:]
    mid = 0.5 * (a + b)
    piece = np.clip(np.searchsorted(pieces.breaks, mid, side="right") - 1, 0, len(pieces.still) - 1)
    still = pieces.still[piece]
    # Products of two attitude matrices oscillate at twice the turn rate.
    rate = 2.0 * pieces.bandwidth[piece] + fastest_mode
    phase = np.where(still, 0.0, rate * (b - a))
    parts = np.maximum(1, np.ceil(phase / MAX_PHASE)).astype(int)
    if np.any(parts > 1):
        rep = np.repeat(np.arange(len(a)), parts)
        k = np.arange(len(rep)) - np.repeat(np.cumsum(parts) - parts, parts)
        length = (b - a)[rep] / parts[rep]
        a2 = a[rep] + k * length
        b2 = np.where(k == parts[rep] - 1, b[rep], a2 + length)
        a, b, piece, still, phase = a2, b2, piece[rep], still[rep], (phase / parts)[rep]
    n = np.where(still, 1, points_for(phase))
    coarse = np.searchsorted(t_coarse, b - MERGE, side="left")
    return Windows(a, b, piece, n.astype(int), still, coarse)


# ---------------------------------------------------------------------------------------
# Nodes and features
# ---------------------------------------------------------------------------------------
@dataclass
class _Nodes:
    """The quadrature nodes of a run of windows (flat, in time order)."""

    t: np.ndarray  # (N,) s
    weight: np.ndarray  # (N,) Fejér weight * half length (0 for still windows' midpoint)
    window: np.ndarray  # (N,) index into the chunk's windows
    first: np.ndarray  # (Wc,) index of each window's first node


def _nodes(win: Windows, sl: slice) -> _Nodes:
    a, b, n = win.a[sl], win.b[sl], win.n[sl]
    half = 0.5 * (b - a)
    first = np.concatenate([[0], np.cumsum(n)[:-1]])
    total = int(n.sum())
    t = np.empty(total)
    w = np.empty(total)
    widx = np.repeat(np.arange(len(a)), n)
    for m in np.unique(n):
        sel = np.flatnonzero(n == m)
        x = chebyshev_points(int(m))
        pos = first[sel][:, None] + np.arange(m)[None, :]
        t[pos] = a[sel][:, None] + (x[None, :] + 1.0) * half[sel][:, None]
        w[pos] = fejer_weights(int(m))[None, :] * half[sel][:, None]
    return _Nodes(t, w, widx, first)


def _features(c: np.ndarray, w_is: np.ndarray, f_s: np.ndarray) -> np.ndarray:
    """(N, 63): ``C[a, i]``, ``C[a, i] w_is[j]``, ``C[a, i] f_s[j]`` (row-major a, i, j)."""
    nn = len(c)
    out = np.empty((nn, N_FEATURES))
    out[:, :9] = c.reshape(nn, 9)
    out[:, 9:36] = (c[:, :, :, None] * w_is[:, None, None, :]).reshape(nn, 27)
    out[:, 36:] = (c[:, :, :, None] * f_s[:, None, None, :]).reshape(nn, 27)
    return out


def _source_inputs(modes: NavModes, y: np.ndarray, src: SourceSet) -> np.ndarray:
    """Modal inputs (J, R, N) of every source from feature integrals ``y`` (J, R, 63)."""
    g, acc = modes.gyro_input, modes.accel_input  # (R, 3): n-frame error -> modal input
    y1 = y[:, :, :9].reshape(len(y), -1, 3, 3)  # [j, r, a, i]
    y2 = y[:, :, 9:36].reshape(len(y), -1, 3, 3, 3)  # [j, r, a, i, k]
    y3 = y[:, :, 36:].reshape(len(y), -1, 3, 3, 3)
    out = np.zeros((len(y), modes.n_modes, src.n), dtype=complex)
    for s, (kind, i, j) in enumerate(zip(src.imu_kind, src.imu_i, src.imu_j, strict=True)):
        if kind == 0:
            out[:, :, s] = np.einsum("ra,jra->jr", g, y1[:, :, :, i])
        elif kind == 1:
            out[:, :, s] = np.einsum("ra,jra->jr", acc, y1[:, :, :, i])
        elif kind == 2:
            out[:, :, s] = np.einsum("ra,jra->jr", g, y2[:, :, :, i, j])
        elif kind == 3:
            out[:, :, s] = np.einsum("ra,jra->jr", acc, y3[:, :, :, i, j])
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
        acc = np.cumsum(np.exp(-lam_b * dt) * incr[k:stop], axis=0)
        out[k:stop] = np.exp(lam_b * dt) * (z[None] + acc)
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
    windows : int
        Quadrature windows used.
    nodes : int
        Attitude evaluations used.
    """

    t_fine: np.ndarray
    fine: np.ndarray
    t_coarse: np.ndarray
    coarse: np.ndarray
    windows: int
    nodes: int


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
    modes = NavModes(model)
    lam = modes.lam
    r = modes.n_modes
    site = model.site
    earth, f_n = site.earth_rate_n, site.specific_force_n
    t_fine = np.asarray(t_fine, dtype=float)
    t_coarse = np.asarray(t_coarse, dtype=float)
    win = make_windows(history.pieces(), t_coarse, float(np.max(np.abs(lam))))
    bg, ba, kg, ka, x0 = sources.signed()
    g_in, a_in = modes.gyro_input, modes.accel_input

    nw = len(win.a)
    z_end = np.empty((nw, r), dtype=complex)  # signed state at window ends
    y_coarse = np.zeros((len(t_coarse), r, N_FEATURES), dtype=complex)
    fine_idx = np.searchsorted(win.b, t_fine - MERGE, side="left").clip(0, nw - 1)
    fine_z = np.zeros((len(t_fine), r), dtype=complex)
    z_prev, t_prev = modes.to_modes(x0), 0.0
    nodes_used = 0

    # Chunks of whole windows, at most CHUNK_NODES nodes each.
    bounds = [0]
    csum = np.cumsum(win.n)
    while bounds[-1] < nw:
        base = csum[bounds[-1] - 1] if bounds[-1] else 0
        nxt = int(np.searchsorted(csum, base + CHUNK_NODES, side="right"))
        bounds.append(max(nxt, bounds[-1] + 1))
    for lo, hi in zip(bounds[:-1], bounds[1:], strict=True):
        sl = slice(lo, hi)
        nd = _nodes(win, sl)
        nodes_used += len(nd.t)
        a_w, b_w = win.a[sl], win.b[sl]
        c, w_ns = history.evaluate(nd.t, win.piece[sl][nd.window])
        w_is = np.einsum("nji,nj->ni", c, earth + w_ns)  # C^T (Omega + w), IMU frame
        f_s = np.einsum("nji,j->ni", c, f_n)  # C^T f, IMU frame
        eps = np.einsum("nij,nj->ni", c, bg + w_is @ kg.T)  # C (b_g + K_g w_is)
        nab = np.einsum("nij,nj->ni", c, ba + f_s @ ka.T)
        u = eps @ g_in.T + nab @ a_in.T  # (N, R) modal input of the signed errors
        still = win.still[sl][nd.window]
        length = (b_w - a_w)[nd.window]
        # Integration weights to the window end: Fejér weight * e^{lambda (b - t)}; a still
        # window's one node carries the closed form int_0^L e^{lambda s} ds = L phi1(lambda L).
        wt = nd.weight[:, None] * np.exp(lam[None, :] * (b_w[nd.window] - nd.t)[:, None])
        if np.any(still):
            ls = length[still][:, None]
            wt[still] = ls * phi1(lam[None, :] * ls)
        incr = np.add.reduceat(wt * u, nd.first, axis=0)  # (Wc, R)
        z_chunk = scan(lam, t_prev, z_prev, b_w, incr)
        z_end[sl] = z_chunk
        z_start = np.concatenate([z_prev[None], z_chunk[:-1]])
        z_prev, t_prev = z_chunk[-1], float(b_w[-1])

        # Per-source feature integrals, propagated to the end of their coarse interval.
        feats = _features(c, w_is, f_s)
        cj = win.coarse[sl][nd.window]
        to_coarse = np.exp(lam[None, :] * (t_coarse[cj] - b_w[nd.window])[:, None])
        _accumulate(y_coarse, cj, wt * to_coarse, feats)

        # Fine output times inside this chunk's windows.
        fsel = np.flatnonzero((fine_idx >= lo) & (fine_idx < hi) & (t_fine > MERGE))
        if len(fsel):
            fine_z[fsel] = _fine_states(
                lam, win, lo, nd, u, z_start, t_fine[fsel], fine_idx[fsel]
            )
    nc = len(t_coarse)
    z0 = modes.to_modes(x0)
    fine_z[t_fine <= MERGE] = z0
    # Per source: inputs per coarse interval, then the scan over coarse intervals.
    z_src0 = modes.to_modes(sources.x0, axis=0)  # (R, N)
    inputs = _source_inputs(modes, y_coarse[1:], sources)  # (Mc-1, R, N)
    coarse_z = np.empty((nc, r, sources.n), dtype=complex)
    coarse_z[0] = z_src0
    if nc > 1:
        coarse_z[1:] = scan(lam, float(t_coarse[0]), z_src0, t_coarse[1:], inputs)
    fine = modes.to_nav(fine_z)
    coarse = modes.to_nav(coarse_z * sources.value[None, None, :], axis=1)
    return ConstantErrorResponse(t_fine, fine, t_coarse, coarse, nw, nodes_used)


def _accumulate(y: np.ndarray, cj: np.ndarray, wt: np.ndarray, feats: np.ndarray) -> None:
    """``y[j] += sum over nodes of interval j of wt[node, r] * feats[node, f]``."""
    # Nodes are in time order, so each coarse interval is one contiguous run.
    start = np.flatnonzero(np.concatenate([[True], cj[1:] != cj[:-1]]))
    count = np.diff(np.concatenate([start, [len(cj)]]))
    width = int(count.max())
    pos = np.arange(len(cj)) - np.repeat(start, count)
    run = np.repeat(np.arange(len(start)), count)
    wpad = np.zeros((len(start), width, wt.shape[1]), dtype=complex)
    fpad = np.zeros((len(start), width, feats.shape[1]))
    wpad[run, pos] = wt
    fpad[run, pos] = feats
    wt_t = np.swapaxes(wpad, 1, 2)
    y[cj[start]] += np.matmul(wt_t.real, fpad) + 1j * np.matmul(wt_t.imag, fpad)


def _fine_states(
    lam: np.ndarray,
    win: Windows,
    lo: int,
    nd: _Nodes,
    u: np.ndarray,
    z_start: np.ndarray,
    t: np.ndarray,
    widx: np.ndarray,
) -> np.ndarray:
    """Signed modal states at times ``t`` inside windows ``widx`` (global indices)."""
    k = widx - lo
    a = win.a[widx]
    dt = t - a
    out = np.exp(lam[None, :] * dt[:, None]) * z_start[k]
    still = win.still[widx]
    if np.any(still):
        s = np.flatnonzero(still)
        node = nd.first[k[s]]
        out[s] += dt[s, None] * phi1(lam[None, :] * dt[s, None]) * u[node]
    moving = np.flatnonzero(~still)
    if len(moving):
        # int_a^t e^{lambda (t - s)} u(s) ds = e^{lambda (t-a)} int_a^t e^{-lambda (s-a)} u(s) ds:
        # the Chebyshev series of g(s) = e^{-lambda (s - a)} u(s) on each window, integrated
        # term by term to the output times.
        n_w = win.n[widx[moving]]
        half = 0.5 * (win.b[widx[moving]] - a[moving])
        x = dt[moving] / half - 1.0
        acc = np.zeros((len(moving), len(lam)), dtype=complex)
        for m in np.unique(n_w):
            sel = np.flatnonzero(n_w == m)
            wins, inverse = np.unique(k[moving[sel]], return_inverse=True)
            idx = nd.first[wins][:, None] + np.arange(m)[None, :]  # (Wm, m) node indices
            a_w = win.a[lo + wins]
            g = u[idx] * np.exp(-lam[None, None, :] * (nd.t[idx] - a_w[:, None])[..., None])
            coef = np.einsum("kq,wqr->wkr", coefficient_matrix(int(m)), g)  # per window
            ints = integral_of_series(x[sel], int(m))  # (F, m)
            acc[sel] = half[sel][:, None] * np.einsum("fk,fkr->fr", ints, coef[inverse])
        out[moving] += np.exp(lam[None, :] * dt[moving, None]) * acc
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
    modes = NavModes(model)
    t = np.asarray(t, dtype=float)
    inv, out, lam = modes.inv_all, modes.out_all, modes.lam_all
    g = np.zeros((9, 6))
    g[0:3, 0:3] = -np.eye(3)
    g[3:6, 3:6] = np.eye(3)
    if model.vertical == "clamped":
        g[5, :] = 0.0
    q = np.diag([arw**2] * 3 + [vrw**2] * 3)
    m = inv @ g @ q @ g.T @ inv.conj().T
    s = lam[:, None] + lam.conj()[None, :]
    xi = t[:, None, None] * phi1(s[None] * t[:, None, None])
    p = np.einsum("ia,tab,jb->tij", out, m[None] * xi, out.conj()).real
    return 0.5 * (p + np.swapaxes(p, 1, 2))
