"""Exact propagation of error states and covariances over a :class:`~inserr.timeline.Timeline`.

Both propagators march over a *step list*: the union of the timeline's interval
boundaries and the requested output times. Every step lies inside one
constant-angular-velocity interval, so its transition matrix ``expm(A(w) dt)`` is
exact (no Euler steps). Steps are grouped into *runs* of identical ``(w, dt)``: a
run of L steps is evaluated with the stacked powers ``Phi, Phi^2, ... Phi^L`` in one
vectorised product, which is why a 72 h run at 1 s output costs a fraction of a
second. Many state vectors (columns) are propagated at once: by superposition the
response to N error sources costs little more than the response to one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from inserr.discretize import DT_QUANTUM, OMEGA_QUANTUM, Discretizer
from inserr.timeline import Timeline

#: Longest block of matrix powers kept in memory at once.
POWER_BLOCK = 512


@dataclass(frozen=True)
class Steps:
    """The merged step list of a timeline and an output grid.

    Attributes
    ----------
    dt : (S,) s
    omega_n : (S, 3) rad/s (quantized)
    key : (S,) int
        Index into the unique ``(w, dt)`` pairs.
    unique_omega, unique_dt : the unique pairs.
    record : (S,) int
        Output index recorded at the end of each step, -1 if none.
    """

    dt: np.ndarray
    omega_n: np.ndarray
    key: np.ndarray
    unique_omega: np.ndarray
    unique_dt: np.ndarray
    record: np.ndarray


def make_steps(timeline: Timeline, t_out: np.ndarray, use_omega: bool = True) -> Steps:
    """Merge interval boundaries and output times into one step list.

    Parameters
    ----------
    timeline : Timeline
    t_out : (M,) s
        Output times in [0, duration], increasing. A time 0 is recorded before the
        first step by the caller.
    use_omega : bool
        If False (model without rotating states), interval boundaries are ignored:
        the steps are just the output intervals.
    """
    t_out = np.asarray(t_out, dtype=float)
    end = timeline.duration
    if use_omega:
        nodes = np.union1d(timeline.times, t_out)
    else:
        nodes = np.union1d([0.0, end], t_out)
    # Merge times closer than the dt quantum (e.g. an output time equal to a node
    # up to rounding): they would give zero-length steps.
    keep = np.concatenate([[True], np.diff(nodes) > 10 * DT_QUANTUM])
    nodes = nodes[keep]
    dt = np.diff(nodes)
    mid = 0.5 * (nodes[:-1] + nodes[1:])
    if use_omega:
        omega = timeline.omega_n[timeline.interval_index(mid)]
    else:
        omega = np.zeros((len(dt), 3))
    k_w = np.round(omega / OMEGA_QUANTUM).astype(np.int64)
    k_dt = np.round(dt / DT_QUANTUM).astype(np.int64)
    keys = np.column_stack([k_w, k_dt])
    # Unique over run representatives only: long stops give long runs of equal keys.
    starts = np.concatenate([[True], np.any(keys[1:] != keys[:-1], axis=1)])
    uniq, inv_runs = np.unique(keys[starts], axis=0, return_inverse=True)
    inverse = inv_runs.reshape(-1)[np.cumsum(starts) - 1]
    # Record index: for each output time > 0, the step that ends closest to it.
    record = np.full(len(dt), -1, dtype=np.int64)
    ends = nodes[1:]
    pos = np.searchsorted(ends, t_out - 10 * DT_QUANTUM)
    valid = (t_out > 10 * DT_QUANTUM) & (pos < len(ends))
    record[pos[valid]] = np.nonzero(valid)[0]
    return Steps(
        dt=dt,
        omega_n=uniq[inverse, :3] * OMEGA_QUANTUM,
        key=inverse.reshape(-1),
        unique_omega=uniq[:, :3] * OMEGA_QUANTUM,
        unique_dt=uniq[:, 3] * DT_QUANTUM,
        record=record,
    )


def _runs(key: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of maximal runs of equal consecutive keys."""
    if len(key) == 0:
        return []
    change = np.nonzero(np.diff(key))[0] + 1
    starts = np.concatenate([[0], change])
    stops = np.concatenate([change, [len(key)]])
    return list(zip(starts.tolist(), stops.tolist(), strict=True))


class _Powers:
    """Stacked powers Phi^1..Phi^L of each unique transition, grown on demand."""

    def __init__(self):
        self._stack: dict[int, np.ndarray] = {}

    def get(self, k: int, phi: np.ndarray, length: int) -> np.ndarray:
        stack = self._stack.get(k)
        if stack is None or len(stack) < length:
            have = 0 if stack is None else len(stack)
            new = np.empty((length, *phi.shape))
            if have:
                new[:have] = stack
            else:
                new[0] = phi
                have = 1
            for i in range(have, length):
                new[i] = phi @ new[i - 1]
            self._stack[k] = stack = new
        return stack[:length]


def _iter_runs(disc: Discretizer, steps: Steps, group: int = 4096):
    """Yield ``(start, stop, key, Phi, powers)`` per run, discretizing a group of runs at a time.

    Grouping keeps memory bounded when continuous motion yields many distinct steps.
    """
    runs = _runs(steps.key)
    powers = _Powers()
    for g in range(0, len(runs), group):
        chunk = runs[g : g + group]
        ks = sorted({int(steps.key[a]) for a, _ in chunk})
        mats = disc.transitions(steps.unique_omega[ks], steps.unique_dt[ks])
        phi_of = dict(zip(ks, mats, strict=True))
        for a, b in chunk:
            k = int(steps.key[a])
            yield a, b, k, phi_of[k], powers


def propagate_states(
    disc: Discretizer,
    timeline: Timeline,
    x0: np.ndarray,
    t_out: np.ndarray,
    rows: slice | np.ndarray | None = None,
) -> np.ndarray:
    """Deterministic (noise-free) propagation of one or many state vectors.

    Parameters
    ----------
    disc : Discretizer
        Discretization cache of the error model.
    timeline : Timeline
        IMU attitude history.
    x0 : (n,) or (n, N)
        Initial augmented state(s) (see :func:`inserr.sources.initial_state`).
    t_out : (M,) s
        Output times, increasing, within [0, duration].
    rows : slice or index array, optional
        States to record (default: the nine navigation states).

    Returns
    -------
    ndarray, shape (M, len(rows), N) — or (M, len(rows)) for a 1-D ``x0``.
    """
    squeeze = np.ndim(x0) == 1
    x = np.array(x0, dtype=float).reshape(disc.model.layout.n, -1)
    rows = slice(0, 9) if rows is None else rows
    n_rec = len(np.arange(disc.model.layout.n)[rows])
    t_out = np.asarray(t_out, dtype=float)
    out = np.empty((len(t_out), n_rec, x.shape[1]))
    if len(t_out) and t_out[0] <= 10 * DT_QUANTUM:
        out[0] = x[rows]
    steps = make_steps(timeline, t_out, use_omega=disc.model.layout.rotating)
    for start, stop, k, phi, powers in _iter_runs(disc, steps):
        rec = steps.record[start:stop]
        length = stop - start
        if length == 1:
            x = phi @ x
            if rec[0] >= 0:
                out[rec[0]] = x[rows]
            continue
        done = 0
        while done < length:
            block = min(POWER_BLOCK, length - done)
            pw = powers.get(k, phi, block)
            r = rec[done : done + block]
            sel = r >= 0
            if np.any(sel):
                out[r[sel]] = np.einsum("jab,bc->jac", pw[sel][:, rows, :], x)
            x = pw[block - 1] @ x
            done += block
    return out[..., 0] if squeeze else out


def propagate_covariance(
    disc: Discretizer,
    timeline: Timeline,
    p0: np.ndarray,
    t_out: np.ndarray,
) -> np.ndarray:
    """Covariance propagation ``P <- Phi P Phi^T + Qd`` over the timeline.

    Exact for each constant-angular-velocity step. When the model has no rotating
    states (only white noise driving the navigation states), the noise covariance
    does not depend on the IMU attitude at all and the steps are simply the output
    intervals.

    Parameters
    ----------
    disc : Discretizer
        Must have been built with a noise intensity ``q``.
    timeline : Timeline
    p0 : (n, n)
        Initial covariance.
    t_out : (M,) s
        Output times, increasing.

    Returns
    -------
    ndarray, shape (M, n, n)
    """
    t_out = np.asarray(t_out, dtype=float)
    p = np.array(p0, dtype=float)
    out = np.empty((len(t_out), *p.shape))
    if len(t_out) and t_out[0] <= 10 * DT_QUANTUM:
        out[0] = p
    steps = make_steps(timeline, t_out, use_omega=disc.model.layout.rotating)
    for start, stop, _, phi, _ in _iter_runs(disc, steps):
        w, h = steps.omega_n[start], steps.dt[start]
        qd = disc.noise(w, h)
        for i in range(start, stop):
            p = phi @ p @ phi.T + qd
            r = steps.record[i]
            if r >= 0:
                out[r] = 0.5 * (p + p.T)
    return out
