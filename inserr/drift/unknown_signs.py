"""Constant errors of unknown sign: RMS and worst case of the horizontal error.

Published comparisons of indexing schemes fix one sign pattern for the biases
(usually all positive). Another pattern can reverse the ranking. With the
horizontal error responses ``a_i(t)`` (2-vectors, metres per unit error) and the
magnitudes ``sigma_i``:

* treating each error as an independent random constant with 1 sigma = its
  magnitude, ``E|dr_h|^2 = sum_i sigma_i^2 |a_i|^2`` (superposition);
* the worst sign combination maximises ``|sum_i s_i sigma_i a_i|`` over
  ``s_i = +-1``: the farthest vertex of a 2-D zonotope, found exactly by sweeping
  the 2N sign patterns that are optimal for some direction (O(N^2) per time,
  vectorised), instead of the 2^N brute force.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def rms_norm(vectors: np.ndarray) -> np.ndarray:
    """sqrt(sum_i |v_i|^2) over the source axis.

    Parameters
    ----------
    vectors : (..., N, 2)
        Per-source horizontal error vectors already scaled by their sigma.
    """
    return np.sqrt(np.sum(np.asarray(vectors) ** 2, axis=(-2, -1)))


def worst_case_norm(
    vectors: np.ndarray, signs: bool = True
) -> tuple[np.ndarray, np.ndarray | None]:
    """Maximum of ``|sum_i s_i v_i|`` over signs ``s_i = +-1``, and the maximising signs.

    Parameters
    ----------
    vectors : (..., N, 2)
        Per-source 2-vectors (scaled by the source magnitudes).
    signs : bool
        Whether to return the maximising signs (False: the norm only, None for them).

    Returns
    -------
    norm : (...)
        The maximum norm.
    signs : (..., N) or None
        A maximising sign pattern (+1/-1).

    Notes
    -----
    The maximum of the convex function |.| over the zonotope is at a vertex; the
    vertex that is extreme in direction u has ``s_i = sign(v_i . u)``, which
    changes only when u crosses a direction perpendicular to some ``v_i``. Walking
    the 2N critical directions in angular order visits every vertex, each one the
    previous plus or minus ``2 v_i`` (a cumulative sum): O(N log N) per time.
    """
    v = np.asarray(vectors, dtype=float)
    n = v.shape[-2]
    want = signs
    if n == 0:
        return np.zeros(v.shape[:-2]), (np.zeros(v.shape[:-1]) if want else None)
    lead = v.shape[:-2]
    flat = v.reshape(-1, n, 2)
    norm = np.empty(len(flat))
    out = np.empty((len(flat), n)) if want else None
    # In blocks of times: the walk holds 2N vertices per time.
    for lo in range(0, len(flat), 4096):
        norm[lo : lo + 4096], s = _walk(flat[lo : lo + 4096], want)
        if want:
            out[lo : lo + 4096] = s
    return norm.reshape(lead), (out.reshape(lead + (n,)) if want else None)


def _walk(vv: np.ndarray, signs: bool = True) -> tuple[np.ndarray, np.ndarray | None]:
    """:func:`worst_case_norm` of (T, N, 2) vectors (N >= 1).

    Directions u and -u give opposite vertices of equal norm, so half a turn of u,
    theta in (0, pi], visits every vertex up to sign. ``v_i`` and ``-v_i`` span the same
    zonotope, so each vector is first turned into the half-plane ``x > 0`` (``x = 0``:
    ``y >= 0``), where its sign is +1 just after theta = 0 (u = (1, 0+)); ``w_i . u``
    then changes sign once, at the angle of ``w_i`` plus pi/2, so the sources are
    crossed in the order of their angles in (-pi/2, pi/2]. That order is the order of
    the pseudo-angle ``y / (x + |y|)`` (monotone there; no arctan). Sources at equal
    angles may be crossed in either order: the vertices between them are inside the
    zonotope and never beat the true ones, so the maximum is the same.
    """
    t_n, n = vv.shape[0], vv.shape[1]
    x, y = vv[..., 0], vv[..., 1]
    s0 = np.where((x > 0) | ((x == 0) & (y >= 0)), 1.0, -1.0)
    wx, wy = s0 * x, s0 * y  # (T, N), wx >= 0
    den = wx + np.abs(wy)
    key = np.divide(wy, den, out=np.zeros_like(wy), where=den > 0)  # zero vectors: anywhere
    order = np.argsort(key, axis=-1)
    flat = (order + (n * np.arange(t_n))[:, None]).ravel()
    sx, sy = wx.sum(axis=1), wy.sum(axis=1)  # the vertex of all signs +1
    # The vertex after crossing the first k sources: start - 2 (w_(1) + ... + w_(k)).
    vx = sx[:, None] - 2.0 * np.cumsum(wx.ravel()[flat].reshape(t_n, n), axis=1)
    vy = sy[:, None] - 2.0 * np.cumsum(wy.ravel()[flat].reshape(t_n, n), axis=1)
    # Squared norms choose the vertex (no overflow below |v| ~ 1e150, far beyond any
    # error here); the norm of the chosen one is taken with hypot.
    sq = vx * vx + vy * vy  # (T, N)
    k = np.argmax(sq, axis=1)
    rows = np.arange(t_n)
    at_start = sx * sx + sy * sy >= sq[rows, k]  # the best vertex has crossed ``best`` sources
    best = np.where(at_start, 0, k + 1)
    norm = np.where(at_start, np.hypot(sx, sy), np.hypot(vx[rows, k], vy[rows, k]))
    if not signs:
        return norm, None
    rank = np.empty_like(order)
    np.put_along_axis(rank, order, np.arange(n)[None, :].repeat(t_n, 0), axis=-1)
    return norm, np.where(rank < best[:, None], -s0, s0)


# --- every sign pattern at once: the range of a figure over the patterns ----------------
# A published figure is usually one sign pattern's maximum over the run,
# ``M(s) = max_t |sum_i s_i v_i(t)|``. Its largest value over the 2^N patterns is the
# worst case above (maximum over time of the per-time maximum). Its smallest value is a
# min-max problem with no such structure; it is bracketed here: a pattern found by
# descent gives an attained value, and an exhaustive search over the largest sources,
# the others bounded by their norms, gives a value no pattern goes below.


def pattern_maximum(vectors: np.ndarray, signs: np.ndarray) -> float:
    """``M(s) = max_t |sum_i s_i v_i(t)|`` for (T, N, 2) vectors and one pattern (N,) of +-1."""
    total = np.einsum("tnd,n->td", np.asarray(vectors, dtype=float), np.asarray(signs, float))
    return float(np.max(np.hypot(total[:, 0], total[:, 1])))


@dataclass(frozen=True)
class SignRange:
    """The range of ``M(s) = max_t |sum_i s_i v_i(t)|`` over the sign patterns ``s``.

    Attributes
    ----------
    highest : float
        The largest ``M(s)`` (exact), with ``highest_signs`` reaching it.
    lowest : float
        The smallest ``M(s)`` found, with ``lowest_signs`` reaching it.
    lowest_bound : float
        No pattern has ``M(s)`` below it (``lowest_bound <= min M <= lowest``).
    """

    highest: float
    highest_signs: np.ndarray
    lowest: float
    lowest_signs: np.ndarray
    lowest_bound: float


def _descend(v: np.ndarray, signs: np.ndarray, cost) -> tuple[np.ndarray, float]:
    """Single sign flips while one lowers ``cost(M(s))`` (the best flip each pass)."""
    s = signs.astype(float).copy()
    total = np.einsum("tnd,n->td", v, s)
    best = cost(float(np.max(np.hypot(total[:, 0], total[:, 1]))))
    while True:
        # M after flipping each sign i: max_t |total - 2 s_i v_i|, all i at once.
        trial = total[:, None, :] - 2.0 * s[None, :, None] * v  # (T, N, 2)
        m = np.max(np.hypot(trial[..., 0], trial[..., 1]), axis=0)
        c = np.array([cost(float(x)) for x in m])
        i = int(np.argmin(c))
        if not c[i] < best - 1e-15 * max(1.0, abs(best)):
            return s, float(pattern_maximum(v, s))
        s[i] = -s[i]
        total = trial[:, i, :]
        best = c[i]


def sign_pattern_range(
    vectors: np.ndarray, exhaustive: int = 16, times: int = 96, starts: int = 16
) -> SignRange:
    """Smallest and largest ``M(s) = max_t |sum_i s_i v_i(t)|`` over the patterns ``s_i = +-1``.

    Parameters
    ----------
    vectors : (T, N, 2) array
        Per-source horizontal error vectors (scaled by the source magnitudes) at the
        T output times.
    exhaustive : int
        Number of largest sources (by ``max_t |v_i|``) whose patterns are all tried for
        the lower bound (2^(exhaustive - 1) patterns: ``M(s) = M(-s)``).
    times : int
        Times (evenly spaced, the last included) at which the exhaustive search is
        evaluated; fewer times keep the bound valid, only looser.
    starts : int
        Best patterns of the exhaustive search from which the descent starts.

    Returns
    -------
    SignRange
        ``highest`` is exact (:func:`worst_case_norm` at its worst time). The bound:
        ``|sum_i s_i v_i| >= |sum_big s_i v_i| - sum_small |v_i|`` at every time, so
        ``min_s M(s) >= min_big max_t' (|sum_big| - sum_small |v_i|)`` over any
        subset of times t'; ``lowest`` is the best descent (single sign flips, all
        times) from the best patterns of that search.
    """
    v = np.asarray(vectors, dtype=float)
    n_t, n = v.shape[:2]
    norm, signs = worst_case_norm(v)
    t_hi = int(np.argmax(norm))
    if n == 0:
        zero = np.zeros(0)
        return SignRange(0.0, zero, 0.0, zero, 0.0)
    size = np.max(np.hypot(v[..., 0], v[..., 1]), axis=0)
    order = np.argsort(-size)
    big, small = order[: min(n, exhaustive)], order[min(n, exhaustive) :]
    k = len(big)
    sel = np.unique(np.linspace(0, n_t - 1, min(n_t, times)).round().astype(int))
    slack = np.sum(np.hypot(v[sel][:, small, 0], v[sel][:, small, 1]), axis=1)  # (T',)
    vb = v[sel][:, big, :].reshape(len(sel), k, 2)
    flat = np.moveaxis(vb, 1, 0).reshape(k, -1)  # (k, 2T')
    codes = np.arange(2 ** (k - 1))
    bound, top = np.inf, []
    for lo in range(0, len(codes), 1 << 14):
        c = codes[lo : lo + (1 << 14)]
        pat = np.ones((len(c), k))
        pat[:, 1:] = 1.0 - 2.0 * ((c[:, None] >> np.arange(k - 1)) & 1)
        sums = (pat @ flat).reshape(len(c), len(sel), 2)
        m = np.max(np.hypot(sums[..., 0], sums[..., 1]) - slack, axis=1)
        bound = min(bound, float(np.max([m.min(), 0.0])))
        best = np.argsort(m)[:starts]
        top += [(float(m[j]), pat[j]) for j in best]
    top = sorted(top, key=lambda x: x[0])[:starts]
    lowest, lowest_signs = math.inf, None
    for _, pat in top:
        s0 = np.ones(n)
        s0[big] = pat
        s, value = _descend(v, s0, lambda x: x)
        if value < lowest:
            lowest, lowest_signs = value, s
    return SignRange(float(norm[t_hi]), signs[t_hi], lowest, lowest_signs, min(bound, lowest))


def _closest_exhaustive(v: np.ndarray, target: float) -> tuple[np.ndarray, float]:
    """The pattern whose ``M(s)`` is closest to ``target``, over all of them (``M(s) = M(-s)``)."""
    n = v.shape[1]
    flat = np.moveaxis(v, 1, 0).reshape(n, -1)
    best, best_gap = np.ones(n), math.inf
    codes = np.arange(2 ** (n - 1))
    for lo in range(0, len(codes), 1 << 12):
        c = codes[lo : lo + (1 << 12)]
        pat = np.ones((len(c), n))
        pat[:, 1:] = 1.0 - 2.0 * ((c[:, None] >> np.arange(n - 1)) & 1)
        sums = (pat @ flat).reshape(len(c), v.shape[0], 2)
        m = np.max(np.hypot(sums[..., 0], sums[..., 1]), axis=1)
        j = int(np.argmin(np.abs(m - target)))
        if abs(m[j] - target) < best_gap:
            best, best_gap = pat[j].copy(), abs(m[j] - target)
    return best, pattern_maximum(v, best)


def closest_pattern(
    vectors: np.ndarray,
    target: float,
    rng: SignRange | None = None,
    walks: int = 64,
    exhaustive: int = 14,
) -> tuple[np.ndarray, float]:
    """A sign pattern whose ``M(s)`` is as close to ``target`` as a search finds.

    With at most ``exhaustive`` sources every pattern is tried (the answer is exact).
    Otherwise the search walks from the lowest to the highest pattern of :func:`sign_pattern_range`
    one flip at a time, in ``walks`` orders (smallest sources first, largest first, and
    seeded random orders: the result is reproducible), keeps the pattern closest to
    ``target``, and improves it by single flips. Each flip changes ``M`` by at most
    ``2 max_t |v_i|``, so a target inside ``[lowest, highest]`` is always reached to
    within ``max_i max_t |v_i|`` (the largest source), usually far closer.

    Returns
    -------
    signs : (N,) ndarray of +-1
    value : float
        ``M(signs)``.
    """
    v = np.asarray(vectors, dtype=float)
    if 0 < v.shape[1] <= exhaustive:
        return _closest_exhaustive(v, target)
    rng = rng or sign_pattern_range(v)
    size = np.max(np.hypot(v[..., 0], v[..., 1]), axis=0)
    differ = np.flatnonzero(rng.lowest_signs != rng.highest_signs)
    orders = [differ[np.argsort(size[differ])], differ[np.argsort(-size[differ])]]
    gen = np.random.default_rng(0)
    orders += [gen.permutation(differ) for _ in range(max(0, walks - 2))]
    best, best_gap = rng.lowest_signs.copy(), abs(rng.lowest - target)
    for order in orders:
        s = rng.lowest_signs.astype(float).copy()
        total = np.einsum("tnd,n->td", v, s)
        for i in order:
            total = total - 2.0 * s[i] * v[:, i, :]
            s[i] = -s[i]
            gap = abs(float(np.max(np.hypot(total[:, 0], total[:, 1]))) - target)
            if gap < best_gap:
                best, best_gap = s.copy(), gap
    return _descend(v, best, lambda x: abs(x - target))


def figure_reach(vectors: np.ndarray, target: float, tol: float = 0.01) -> dict:
    """Can some sign pattern of these errors give the figure ``target`` (``M(s)``, m)?

    Parameters
    ----------
    vectors : (T, N, 2) array
        Per-source horizontal error vectors, m (scaled by the magnitudes).
    target : float
        A published maximum horizontal error, m.
    tol : float
        Relative distance at which a pattern found counts as reaching it.

    Returns
    -------
    dict
        ``lowest_bound``, ``lowest``, ``highest`` (:func:`sign_pattern_range`, m);
        ``closest`` (``M`` of the closest pattern found, m) and ``closest_signs``;
        ``verdict``: ``"reached"`` (within ``tol``), ``"below every pattern"``
        (``target < lowest_bound``: proved), ``"above every pattern"``
        (``target > highest``: proved) or ``"not found"`` (inside the range, missed
        by the search).
    """
    rng = sign_pattern_range(vectors)
    signs, value = closest_pattern(vectors, target, rng)
    if abs(value - target) <= tol * abs(target):
        verdict = "reached"
    elif target < rng.lowest_bound:
        verdict = "below every pattern"
    elif target > rng.highest:
        verdict = "above every pattern"
    else:
        verdict = "not found"
    return {
        "lowest_bound": rng.lowest_bound,
        "lowest": rng.lowest,
        "highest": rng.highest,
        "closest": value,
        "closest_signs": signs,
        "verdict": verdict,
    }
