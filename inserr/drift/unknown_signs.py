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
    changes only when u crosses a direction perpendicular to some ``v_i``. Testing
    one direction inside each of the 2N arcs between those critical directions
    visits every vertex.
    """
    v = np.asarray(vectors, dtype=float)
    n = v.shape[-2]
    if n == 0:
        return np.zeros(v.shape[:-2]), np.zeros(v.shape[:-1])
    ang = np.arctan2(v[..., 1], v[..., 0])  # (..., N)
    crit = np.concatenate([ang + 0.5 * np.pi, ang - 0.5 * np.pi], axis=-1) % (2 * np.pi)
    crit = np.sort(crit, axis=-1)
    nxt = np.concatenate([crit[..., 1:], crit[..., :1] + 2 * np.pi], axis=-1)
    mid = 0.5 * (crit + nxt)  # (..., 2N) directions strictly inside each arc
    u = np.stack([np.cos(mid), np.sin(mid)], axis=-1)  # (..., 2N, 2)
    proj = np.einsum("...nd,...kd->...kn", v, u)  # (..., 2N, N)
    s = np.where(proj >= 0, 1.0, -1.0)
    sums = np.einsum("...kn,...nd->...kd", s, v)
    norms = np.linalg.norm(sums, axis=-1)
    best = np.argmax(norms, axis=-1)
    norm = np.take_along_axis(norms, best[..., None], axis=-1)[..., 0]
    signs = np.take_along_axis(s, best[..., None, None], axis=-2)[..., 0, :]
    return norm, signs
