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

import numpy as np


def rms_norm(vectors: np.ndarray) -> np.ndarray:
    """sqrt(sum_i |v_i|^2) over the source axis.

    Parameters
    ----------
    vectors : (..., N, 2)
        Per-source horizontal error vectors already scaled by their sigma.
    """
    return np.sqrt(np.sum(np.asarray(vectors) ** 2, axis=(-2, -1)))


def worst_case_norm(vectors: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Maximum of ``|sum_i s_i v_i|`` over signs ``s_i = +-1``, and the maximising signs.

    Parameters
    ----------
    vectors : (..., N, 2)
        Per-source 2-vectors (scaled by the source magnitudes).

    Returns
    -------
    norm : (...)
        The maximum norm.
    signs : (..., N)
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
    if n == 0:
        return np.zeros(v.shape[:-2]), np.zeros(v.shape[:-1])
    lead = v.shape[:-2]
    flat = v.reshape(-1, n, 2)
    norm = np.empty(len(flat))
    signs = np.empty((len(flat), n))
    # In blocks of times: the walk holds 2N vertices per time.
    for lo in range(0, len(flat), 4096):
        norm[lo : lo + 4096], signs[lo : lo + 4096] = _walk(flat[lo : lo + 4096])
    return norm.reshape(lead), signs.reshape(lead + (n,))


def _walk(vv: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`worst_case_norm` of (T, N, 2) vectors (N >= 1).

    Directions u and -u give opposite vertices of equal norm, so half a turn of u,
    theta in (0, pi], visits every vertex up to sign: each v_i is crossed once, at
    ``theta_i = (ang_i + pi/2) mod pi`` (where v_i . u changes sign).
    """
    t_n, n = vv.shape[0], vv.shape[1]
    # Signs just after theta = 0, u = (1, 0+): sign of v_x, ties by the sign of v_y.
    s0 = np.where((vv[..., 0] > 0) | ((vv[..., 0] == 0) & (vv[..., 1] >= 0)), 1.0, -1.0)
    theta = (np.arctan2(vv[..., 1], vv[..., 0]) + 0.5 * np.pi) % np.pi
    theta[theta == 0.0] = np.pi  # crossed at 0 already counted in s0: cross it last
    order = np.argsort(theta, axis=-1)
    step = -2.0 * (s0[..., None] * vv)  # crossing v_i flips s_i
    step = np.take_along_axis(step, order[..., None], axis=-2)
    start = np.einsum("tn,tnd->td", s0, vv)
    verts = np.concatenate([start[:, None, :], start[:, None, :] + np.cumsum(step, axis=-2)], 1)
    norms = np.hypot(verts[..., 0], verts[..., 1])  # (T, N + 1)
    best = np.argmax(norms, axis=-1)  # the best vertex has crossed ``best`` sources
    norm = norms[np.arange(t_n), best]
    rank = np.empty_like(order)
    np.put_along_axis(rank, order, np.arange(n)[None, :].repeat(t_n, 0), axis=-1)
    signs = np.where(rank < best[:, None], -s0, s0)
    return norm, signs
