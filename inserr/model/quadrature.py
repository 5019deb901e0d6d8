"""Chebyshev quadrature and spectral integration on one interval (Fejér's first rule).

A smooth integrand on ``[a, b]`` is sampled at the ``n`` Chebyshev points of the first
kind ``x_k = cos((2k + 1) pi / (2n))`` (mapped to ``t = a + (x + 1) (b - a) / 2``; no
point sits on an end, so a rate that jumps at a segment boundary is never sampled
there). From the samples:

* :func:`fejer_weights` give the integral over the whole interval (Fejér's first
  rule: the exact integral of the degree ``n - 1`` interpolant);
* :func:`integration_matrix` gives the integrals from ``a`` to any points inside,
  by integrating the interpolant's Chebyshev series term by term.

For an integrand whose highest angular frequency is ``W`` (rad/s) the interpolation
error falls like ``(W (b - a) / 4)^n / n!`` (the interpolant of an entire function
converges super-geometrically); :func:`points_for` picks ``n`` for a relative error
near 1e-15.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np


@lru_cache(maxsize=64)
def chebyshev_points(n: int) -> np.ndarray:
    """The ``n`` Chebyshev points of the first kind on [-1, 1], increasing.

    Parameters
    ----------
    n : int
        Number of points, >= 1.

    Returns
    -------
    ndarray, shape (n,)
    """
    k = np.arange(n)
    return np.cos((2 * k + 1) * np.pi / (2 * n))[::-1].copy()


@lru_cache(maxsize=64)
def _coefficient_matrix(n: int) -> np.ndarray:
    """(n, n): values at :func:`chebyshev_points` -> Chebyshev coefficients (DCT-II)."""
    theta = np.arccos(chebyshev_points(n))
    j = np.arange(n)[:, None]
    c = (2.0 / n) * np.cos(j * theta[None, :])
    c[0] *= 0.5
    return c


@lru_cache(maxsize=64)
def fejer_weights(n: int) -> np.ndarray:
    """Weights of Fejér's first rule on [-1, 1] at :func:`chebyshev_points`.

    Returns
    -------
    ndarray, shape (n,)
        ``sum(w * f(x))`` is the exact integral of the interpolant (sums to 2).
    """
    return integral_of_series(np.array([1.0]), n)[0] @ _coefficient_matrix(n)


def integral_of_series(x: np.ndarray, n: int) -> np.ndarray:
    """``I[m, j] = int_{-1}^{x_m} T_j(s) ds`` for ``j < n``.

    Parameters
    ----------
    x : (M,) array in [-1, 1]
    n : int

    Returns
    -------
    ndarray, shape (M, n)
    """
    x = np.clip(np.asarray(x, dtype=float), -1.0, 1.0)
    # T_0 .. T_n at x by the three-term recurrence T_{k+1} = 2 x T_k - T_{k-1} (stable on
    # [-1, 1], a tenth of the cost of cos(k arccos x)); rows are degrees (contiguous).
    t = np.empty((n + 1, len(x)))
    t[0] = 1.0
    if n >= 1:
        t[1] = x
    for k in range(1, n):
        np.multiply(2.0 * x, t[k], out=t[k + 1])
        t[k + 1] -= t[k - 1]
    out = np.empty((n, len(x)))
    out[0] = x + 1.0
    if n > 1:
        out[1] = 0.5 * (x * x - 1.0)
    for k in range(2, n):
        # int T_k = T_{k+1} / (2 (k+1)) - T_{k-1} / (2 (k-1)), minus its value at -1.
        at_minus_one = (-1.0) ** (k + 1) / (2 * (k + 1)) - (-1.0) ** (k - 1) / (2 * (k - 1))
        out[k] = t[k + 1] / (2 * (k + 1)) - t[k - 1] / (2 * (k - 1)) - at_minus_one
    return out.T


def integration_matrix(x: np.ndarray, n: int) -> np.ndarray:
    """(M, n): node values -> ``int_{-1}^{x_m}`` of their interpolant, on [-1, 1].

    Multiply by half the interval length to integrate in time.
    """
    return integral_of_series(x, n) @ _coefficient_matrix(n)


#: Points per interval by phase budget: ``(largest W (b - a), n)``, checked against
#: the exact segment engine in ``tests/test_fast_propagation.py``.
_POINTS = (
    (0.0, 1),
    (0.25, 8),
    (0.5, 10),
    (1.0, 12),
    (2.0, 15),
    (4.0, 19),
    (6.0, 23),
    (8.0, 26),
    (12.0, 30),
    (16.0, 34),
    (24.0, 41),
    (32.0, 47),
)
# (Up to 8 rad the entries are the original calibration; from 12 rad on, each is the
# smallest n whose worst integration error over the interval, for oscillations up to the
# budget, is below 5e-16 of the interval length, plus the same margin of 4 points the
# 8 rad entry has over that criterion (22 -> 26). Long intervals need fewer points per
# radian: 3.3 at 8 rad, 1.5 at 32 rad.)

#: Largest phase budget ``W (b - a)`` (rad) of one interval; longer ones are split.
MAX_PHASE = 32.0


def points_for(phase: np.ndarray) -> np.ndarray:
    """Number of Chebyshev points for intervals with phase budget ``W (b - a)`` (rad).

    Zero phase (a constant integrand) needs one point; otherwise the smallest table
    entry whose budget covers the interval.
    """
    phase = np.asarray(phase, dtype=float)
    if np.any(phase > _POINTS[-1][0]):
        raise ValueError(f"phase budget {phase.max():g} rad exceeds {_POINTS[-1][0]:g}")
    budgets = np.array([b for b, _ in _POINTS])
    counts = np.array([c for _, c in _POINTS])
    idx = np.searchsorted(budgets, phase, side="left")
    return counts[np.clip(idx, 0, len(counts) - 1)]
