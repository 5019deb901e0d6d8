"""Exact propagation of error states and covariances over a timeline, step by step.

The timeline is a :class:`~inserr.model.timeline.Timeline`.

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

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from inserr.model.discretization import DT_QUANTUM, OMEGA_QUANTUM, Discretizer
from inserr.model.timeline import Timeline

#: Longest block of matrix powers kept in memory at once.
POWER_BLOCK = 512


@dataclass(frozen=True)
class Steps:
    """The merged step list of a timeline and one or more output grids.

    Attributes
    ----------
    dt : (S,) s
        Step durations.
    omega_n : (S, 3) rad/s
        Angular velocity of the IMU frame relative to n, resolved in ENU, in each
        step (quantized; zero when the timeline was ignored).
    key : (S,) int
        Index into the unique ``(w, dt)`` pairs.
    unique_omega : (U, 3) rad/s
        The unique quantized angular velocities (ENU).
    unique_dt : (U,) s
        The matching unique quantized durations.
    records : list of (S,) int
        Per output grid: the output index recorded at the end of each step, -1 if none.
    """

    dt: np.ndarray
    omega_n: np.ndarray
    key: np.ndarray
    unique_omega: np.ndarray
    unique_dt: np.ndarray
    records: list[np.ndarray]

    @property
    def record(self) -> np.ndarray:
        """Record indices (S,) of the first output grid (-1 where none)."""
        return self.records[0]


def make_steps(
    timeline: Timeline,
    t_out: np.ndarray,
    use_omega: bool = True,
    extra_grids: Sequence[np.ndarray] = (),
) -> Steps:
    """Merge interval boundaries and output times into one step list.

    Parameters
    ----------
    timeline : Timeline
        IMU attitude history; its node times are the interval boundaries.
    t_out : (M,) s
        Output times in [0, duration], increasing. A time 0 is recorded before the
        first step by the caller.
    use_omega : bool
        If False (model without rotating states), interval boundaries are ignored:
        the steps are just the output intervals.
    extra_grids : sequence of arrays
        Further output grids, s (each gets its own record array).

    Returns
    -------
    Steps
        Steps between consecutive merged nodes (nodes closer than ``10 DT_QUANTUM``
        merged), each inside one constant-rate interval.
    """
    grids = [np.asarray(t_out, dtype=float), *(np.asarray(g, dtype=float) for g in extra_grids)]
    end = timeline.duration
    for g in grids:
        # Each output time must end its own step: duplicates (to within the merge
        # tolerance) would leave a record unwritten, and times past the end would be
        # extrapolated with the last interval's rate.
        if g.size and not (
            np.all(np.isfinite(g))
            and g[0] >= 0.0
            and g[-1] <= end + 10 * DT_QUANTUM
            and np.all(np.diff(g) > 10 * DT_QUANTUM)
        ):
            raise ValueError(
                f"output times must be finite, strictly increasing (by > {10 * DT_QUANTUM:g} s) "
                f"and within [0, {end:g}] s"
            )
    base = timeline.times if use_omega else np.array([0.0, end])
    nodes = np.unique(np.concatenate([base, *grids]))
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
    records = []
    ends = nodes[1:]
    for g in grids:
        # For each output time > 0, the step that ends at it (to within the quantum).
        record = np.full(len(dt), -1, dtype=np.int64)
        pos = np.searchsorted(ends, g - 10 * DT_QUANTUM)
        valid = (g > 10 * DT_QUANTUM) & (pos < len(ends))
        record[pos[valid]] = np.nonzero(valid)[0]
        records.append(record)
    return Steps(
        dt=dt,
        omega_n=uniq[inverse, :3] * OMEGA_QUANTUM,
        key=inverse.reshape(-1),
        unique_omega=uniq[:, :3] * OMEGA_QUANTUM,
        unique_dt=uniq[:, 3] * DT_QUANTUM,
        records=records,
    )


def _runs(key: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Starts and stops of maximal runs of equal consecutive keys."""
    change = np.nonzero(np.diff(key))[0] + 1
    return np.concatenate([[0], change]), np.concatenate([change, [len(key)]])


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
    """Yield ``(start, stop, key, Phi)`` per run, discretizing a group of runs at a time.

    Grouping keeps memory bounded when continuous motion yields many distinct steps.
    """
    if len(steps.key) == 0:
        return
    starts, stops = _runs(steps.key)
    for g in range(0, len(starts), group):
        a_s, b_s = starts[g : g + group], stops[g : g + group]
        kk = steps.key[a_s]
        ks = np.unique(kk)
        mats = disc.transitions(steps.unique_omega[ks], steps.unique_dt[ks])
        phi_of = dict(zip(ks.tolist(), mats, strict=True))
        for a, b, k in zip(a_s.tolist(), b_s.tolist(), kk.tolist(), strict=True):
            yield a, b, k, phi_of[k]


@dataclass(frozen=True)
class Output:
    """What to record: states ``rows`` of columns ``cols`` at times ``t``.

    Attributes
    ----------
    t : (M,) s
        Output times, increasing, within [0, duration].
    rows : slice or index array
        State indices to record (default: the nine navigation states).
    cols : slice or index array
        Columns of the propagated state matrix to record (default: all).
    """

    t: np.ndarray
    rows: slice | np.ndarray = field(default_factory=lambda: slice(0, 9))
    cols: slice | np.ndarray = field(default_factory=lambda: slice(None))


def propagate_outputs(
    disc: Discretizer, timeline: Timeline, x0: np.ndarray, outputs: Sequence[Output]
) -> list[np.ndarray]:
    """Deterministic propagation of state columns, recorded on several output grids at once.

    One pass over the timeline serves every grid, so an expensive continuous-motion
    timeline is discretized once.

    Parameters
    ----------
    disc : Discretizer
        Discretization cache of the error model.
    timeline : Timeline
        IMU attitude history (``C_s^n``, ``w`` resolved in ENU).
    x0 : (n,) or (n, N)
        Initial augmented state column(s), SI, state order of :attr:`Layout.names`.
    outputs : sequence of Output
        What to record and when; at least one.

    Returns
    -------
    list of ndarray
        One array of shape (M_o, len(rows_o), len(cols_o)) per output, in the
        state units.
    """
    n = disc.model.layout.n
    x = np.array(x0, dtype=float).reshape(n, -1)
    # Index with slices where possible: basic indexing is a cheap view in the hot loop.
    idx_rows = [o.rows if isinstance(o.rows, slice) else np.asarray(o.rows) for o in outputs]
    idx_cols = [o.cols if isinstance(o.cols, slice) else np.asarray(o.cols) for o in outputs]
    sizes = [
        (len(np.arange(n)[r]), len(np.arange(x.shape[1])[c]))
        for r, c in zip(idx_rows, idx_cols, strict=True)
    ]
    outs = [np.empty((len(o.t), *sz)) for o, sz in zip(outputs, sizes, strict=True)]

    def pick(v: np.ndarray, r, c) -> np.ndarray:
        return v[r][:, c]  # views when r and c are slices (the hot path)

    for o, out, r, c in zip(outputs, outs, idx_rows, idx_cols, strict=True):
        if len(o.t) and o.t[0] <= 10 * DT_QUANTUM:
            out[0] = pick(x, r, c)
    steps = make_steps(
        timeline, outputs[0].t, disc.model.layout.rotating, [o.t for o in outputs[1:]]
    )
    powers = _Powers()
    recs = steps.records
    for start, stop, k, phi in _iter_runs(disc, steps):
        length = stop - start
        if length == 1:
            x = phi @ x
            for rec, out, r, c in zip(recs, outs, idx_rows, idx_cols, strict=True):
                j = rec[start]
                if j >= 0:
                    out[j] = pick(x, r, c)
            continue
        done = 0
        while done < length:
            block = min(POWER_BLOCK, length - done)
            pw = powers.get(k, phi, block)
            for rec, out, r, c in zip(recs, outs, idx_rows, idx_cols, strict=True):
                rr = rec[start + done : start + done + block]
                sel = rr >= 0
                if np.any(sel):
                    out[rr[sel]] = np.einsum("jab,bc->jac", pw[sel][:, r, :], x[:, c])
            x = pw[block - 1] @ x
            done += block
    return outs


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
        Initial augmented state(s) (see :func:`inserr.model.error_sources.initial_state`).
    t_out : (M,) s
        Output times, increasing, within [0, duration].
    rows : slice or index array, optional
        States to record (default: the nine navigation states).

    Returns
    -------
    ndarray, shape (M, len(rows), N), or (M, len(rows)) for a 1-D ``x0``
        The recorded states, SI (psi rad, dv m/s, dr m, ENU for the default rows).
    """
    squeeze = np.ndim(x0) == 1
    out = propagate_outputs(
        disc,
        timeline,
        x0,
        [Output(np.asarray(t_out, float), slice(0, 9) if rows is None else rows)],
    )[0]
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
        IMU attitude history (``C_s^n``, ``w`` resolved in ENU).
    p0 : (n, n)
        Initial covariance, state units squared.
    t_out : (M,) s
        Output times, increasing, within [0, duration].

    Returns
    -------
    ndarray, shape (M, n, n)
        Symmetrised covariance at each output time, state units squared.
    """
    t_out = np.asarray(t_out, dtype=float)
    p = np.array(p0, dtype=float)
    out = np.empty((len(t_out), *p.shape))
    if len(t_out) and t_out[0] <= 10 * DT_QUANTUM:
        out[0] = p
    steps = make_steps(timeline, t_out, use_omega=disc.model.layout.rotating)
    rec = steps.record
    for start, stop, _, phi in _iter_runs(disc, steps):
        qd = disc.noise(steps.omega_n[start], steps.dt[start])
        for i in range(start, stop):
            p = phi @ p @ phi.T + qd
            r = rec[i]
            if r >= 0:
                out[r] = 0.5 * (p + p.T)
    return out
