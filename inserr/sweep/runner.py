"""Running a sweep on Dask: locally without a server, or on an existing dask.distributed cluster.

Engines
-------
* ``processes`` (default with more than one worker): Dask's local multiprocessing
  scheduler, one task per point (``chunksize=1`` so a slow point does not hold
  back a batch). The per-point work is Python-heavy with small numpy matrices
  (a profile of a 72 h point spends most of its time in the Python loop of
  :mod:`inserr.model.exact_propagation`), so threads could overlap only the numpy calls;
  processes run points truly in parallel (``benchmarks/sweep.py``). Workers start
  with one BLAS thread each: the parallelism is across points.
* ``sync``: in this process, one point after the other (the default with one
  worker: no process to spawn, same numbers).
* ``threads``: Dask's threaded scheduler. Points share the process's
  discretization cache (thread-safe, and its content does not depend on the order
  of the points), but the Python-bound loop gains little from threads.
* an address (``tcp://HOST:PORT``) or a ``distributed.Client``: the points are
  submitted to an existing cluster. Its workers need inserr installed and, for
  ``motion.file`` scenarios, the scenario's directory at the same path. As the
  work is Python-bound, start one single-threaded worker process per core
  (``dask worker ADDRESS --nworkers N --nthreads 1``).

Whatever the engine, each result comes back to this process, which writes the
point's record atomically as soon as it arrives (:mod:`inserr.sweep.store`), so
an interrupted sweep keeps every finished point. A point that raises is recorded
as ``failed`` by the worker itself; a worker that dies (process killed, cluster
worker lost) fails only the points it was running, and the rest go on.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any

from dask.callbacks import Callback

from inserr.core.errors import InputError
from inserr.output.progress import Bar
from inserr.output.report import dumps
from inserr.sweep.grid import Grid
from inserr.sweep.store import (
    FAILED,
    OK,
    SweepStore,
    invalid_record,
    point_record,
    remove_stale_figures,
    write_results,
)

LOCAL_SCHEDULERS = ("processes", "threads", "sync")

#: Called with (point id, worker result) as each point finishes.
OnResult = Callable[[str, dict[str, Any]], None]


def default_workers() -> int:
    """CPUs this process may use.

    Returns
    -------
    int
        The size of the CPU affinity mask (on Linux), else the CPU count; at least 1.
    """
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


#: Entries of ``SchemeRun.metrics()`` that echo the inputs (the point's parameters say them).
INPUT_ECHOES = ("scheme", "hours")


def headline_metrics(metrics: dict[str, Any]) -> dict[str, Any]:
    """The scalar headline numbers of a run, plus its largest error source.

    Parameters
    ----------
    metrics : dict
        ``SchemeRun.metrics()`` of one drift analysis.

    Returns
    -------
    dict
        Its scalar entries (units in their names: ``max_horizontal_error_nmi`` in
        nmi, ``motor_starts_per_hour`` per hour, ...) without the ones that echo the
        inputs, its warnings joined into one string, and ``top_error_source`` with
        its contribution ``top_error_source_nmi`` (nmi).
    """
    out = {
        k: v
        for k, v in metrics.items()
        if k not in INPUT_ECHOES and isinstance(v, (int, float, str)) and not isinstance(v, bool)
    }
    notes = metrics.get("warnings")
    if isinstance(notes, list):
        out["warnings"] = "; ".join(str(n) for n in notes)  # e.g. a cycle near Schuler resonance
    budget = metrics.get("error_budget") or {}
    if budget:
        name, value = next(iter(budget.items()))  # the budget is sorted, largest first
        out["top_error_source"] = name
        out["top_error_source_nmi"] = value
    return out


def run_point(payload: str) -> dict[str, Any]:
    """Worker side: the drift analysis of one point (payload from :meth:`Grid.payload`).

    Never raises: an error becomes a ``failed`` result carrying its message, so
    one bad point cannot sink the sweep.

    Parameters
    ----------
    payload : str
        JSON text from :meth:`inserr.sweep.grid.Grid.payload`.

    Returns
    -------
    dict
        ``status`` (``ok`` or ``failed``), ``error`` (message, ``""`` if none),
        ``metrics`` (:func:`headline_metrics`, when ok) and ``elapsed_s``, the
        wall time of the point (s).
    """
    from inserr.drift import study as summary
    from inserr.scenario.schema import scenario_from_dict

    t0 = time.perf_counter()
    try:
        p = json.loads(payload)
        base = scenario_from_dict(p["base"], Path(p["base_dir"]) if p["base_dir"] else None)
        run = summary.run_scheme(base.with_changes(p["changes"]))
        result = {"status": OK, "error": "", "metrics": headline_metrics(run.metrics())}
    except Exception as exc:  # noqa: BLE001 - any failure is this point's, not the sweep's
        result = {"status": FAILED, "error": f"{type(exc).__name__}: {exc}"}
    result["elapsed_s"] = time.perf_counter() - t0
    return result


def _task_key(pid: str) -> str:
    return f"inserr-sweep-{pid}"


class LocalEngine:
    """Dask's local schedulers: no server, ``workers`` processes or threads.

    Parameters
    ----------
    scheduler : str
        One of :data:`LOCAL_SCHEDULERS`: ``"processes"``, ``"threads"`` or ``"sync"``.
    workers : int
        Worker processes or threads (1 for ``sync``).
    """

    def __init__(self, scheduler: str, workers: int):
        self.scheduler = scheduler
        self.workers = workers

    def describe(self) -> str:
        """One line naming the engine, for the summary of a run.

        Returns
        -------
        str
            E.g. ``"dask processes scheduler, 2 worker(s)"``.
        """
        return f"dask {self.scheduler} scheduler, {self.workers} worker(s)"

    def run(self, tasks: dict[str, str], on_result: OnResult) -> None:
        """Run ``tasks``, reporting each result as it arrives.

        A worker process that dies fails the points it was running (reported as
        ``failed``); the other points are run again on a new pool.

        Parameters
        ----------
        tasks : dict of str to str
            Point id -> payload (:meth:`inserr.sweep.grid.Grid.payload`).
        on_result : callable
            Called in this thread as ``on_result(point_id, result)`` once per
            point, with the dict of :func:`run_point`.
        """
        from concurrent.futures.process import BrokenProcessPool

        remaining = dict(tasks)
        while remaining:
            sink = _ResultSink(on_result)
            try:
                self._compute(remaining, sink)
            except BrokenProcessPool as exc:
                # A worker process died; the points it ran are the suspects. The
                # others were never started or already reported: go on without them.
                for pid in sorted(sink.running):
                    on_result(
                        pid,
                        {"status": FAILED, "error": f"worker process lost ({exc}); rerun to retry"},
                    )
                    sink.reported.add(pid)
                if not sink.reported:
                    for pid in remaining:
                        on_result(
                            pid,
                            {"status": FAILED, "error": f"worker processes cannot start ({exc})"},
                        )
                    return
            remaining = {pid: p for pid, p in remaining.items() if pid not in sink.reported}

    def _compute(self, tasks: dict[str, str], sink: _ResultSink) -> None:
        import dask

        delayed = [
            dask.delayed(run_point, pure=False)(p, dask_key_name=_task_key(pid))
            for pid, p in tasks.items()
        ]
        kwargs: dict[str, Any] = {"scheduler": self.scheduler}
        if self.scheduler != "sync":
            kwargs["num_workers"] = self.workers
        if self.scheduler == "processes":
            kwargs["chunksize"] = 1
            kwargs["initializer"] = partial(exit_with_parent, os.getpid())
        with sink, _one_blas_thread_per_process(self.scheduler == "processes"):
            dask.compute(*delayed, **kwargs)

    def close(self) -> None:
        """Release the engine (nothing to do: Dask's local pools end with each run)."""


#: How often a worker process checks that the process that started it still runs, s.
PARENT_POLL = 0.5


def exit_with_parent(parent: int) -> None:
    """Worker-process initializer: end this process as soon as its parent is gone.

    A sweep's worker processes are children of the ``inserr sweep`` process. If that
    process is killed outright (SIGKILL, the OOM killer), nothing tells the workers,
    which would be re-parented and go on computing for nobody (and keep the
    multiprocessing resource tracker alive). A daemon thread in each worker
    watches its parent's pid every :data:`PARENT_POLL` seconds and ends the worker
    when the parent changes; the resource tracker then ends too, as its last
    client is gone. (A watchdog thread rather than Linux's ``PR_SET_PDEATHSIG``,
    which fires when the *thread* that started the worker ends, not the process,
    and exists on Linux only.)

    Parameters
    ----------
    parent : int
        The pid of the process that starts the workers, taken there: a worker may
        start up only after its parent was killed, and would then see pid 1.
    """
    import threading

    if os.getppid() != parent:
        os._exit(1)

    def watch() -> None:
        while True:
            time.sleep(PARENT_POLL)
            if os.getppid() != parent:
                os._exit(1)  # nobody is waiting for this worker's results any more

    threading.Thread(target=watch, name="inserr-parent-watch", daemon=True).start()


#: Environment variables that size the BLAS/OpenMP thread pools of a new process.
BLAS_THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")


@contextmanager
def _one_blas_thread_per_process(active: bool):
    """Let worker processes start with one BLAS thread each (unless the user chose otherwise).

    The parallelism is across points; a BLAS pool per worker would only fight for
    the same cores (dask.distributed's nannies do the same for their workers).
    Spawned workers inherit the environment while the pool starts, hence a context.
    """
    if not active:
        yield
        return
    added = [v for v in BLAS_THREAD_VARS if v not in os.environ]
    for v in added:
        os.environ[v] = "1"
    try:
        yield
    finally:
        for v in added:
            os.environ.pop(v, None)


class _ResultSink(Callback):
    """Dask callback that hands each finished point to ``on_result`` (in the calling thread)."""

    def __init__(self, on_result: OnResult):
        super().__init__()
        self.on_result = on_result
        self.running: set[str] = set()
        self.reported: set[str] = set()

    @staticmethod
    def _pid(key) -> str | None:
        prefix = _task_key("")
        return key[len(prefix) :] if isinstance(key, str) and key.startswith(prefix) else None

    def _pretask(self, key, dsk, state) -> None:
        pid = self._pid(key)
        if pid is not None:
            self.running.add(pid)

    def _posttask(self, key, result, dsk, state, worker_id) -> None:
        pid = self._pid(key)
        if pid is not None:
            self.running.discard(pid)
            self.reported.add(pid)
            self.on_result(pid, result)


class ClusterEngine:
    """An existing dask.distributed cluster (by address, or a connected Client).

    Parameters
    ----------
    scheduler : str or distributed.Client
        The scheduler's address (``tcp://HOST:PORT``), connected to now (10 s
        timeout) and closed by :meth:`close`, or a connected Client, left open.

    Raises
    ------
    InputError
        The cluster cannot be reached.
    """

    def __init__(self, scheduler: Any):
        from distributed import Client

        self._own = not isinstance(scheduler, Client)
        if self._own:
            try:
                self.client = Client(scheduler, timeout="10s", set_as_default=False)
            except (OSError, TimeoutError, ValueError) as exc:
                raise InputError(
                    "scheduler",
                    f"cannot connect to {scheduler!r} ({exc})",
                    "start the cluster (e.g. dask scheduler / dask worker) or check the address",
                ) from None
        else:
            self.client = scheduler

    def describe(self) -> str:
        """One line naming the engine, for the summary of a run.

        Returns
        -------
        str
            E.g. ``"dask.distributed cluster at tcp://127.0.0.1:8786"``.
        """
        return f"dask.distributed cluster at {self.client.scheduler.address}"

    def run(self, tasks: dict[str, str], on_result: OnResult) -> None:
        """Submit ``tasks`` to the cluster, reporting each result as it arrives.

        A point whose task fails on the cluster (e.g. ``KilledWorker`` after its
        workers died) is reported as ``failed``; the others go on. On an
        interrupt, the points not finished are cancelled on the cluster.

        Parameters
        ----------
        tasks : dict of str to str
            Point id -> payload (:meth:`inserr.sweep.grid.Grid.payload`).
        on_result : callable
            Called in this thread as ``on_result(point_id, result)`` once per
            point, with the dict of :func:`run_point`.
        """
        from distributed import as_completed

        futures = {
            self.client.submit(run_point, p, key=_task_key(pid), pure=False): pid
            for pid, p in tasks.items()
        }
        try:
            for fut in as_completed(list(futures), loop=self.client.loop):
                pid = futures[fut]
                try:
                    result = fut.result()
                except Exception as exc:  # noqa: BLE001 - e.g. KilledWorker: this point fails, not the sweep
                    result = {"status": FAILED, "error": f"{type(exc).__name__}: {exc}"}
                on_result(pid, result)
        finally:
            # On an interrupt, do not leave our work queued on a shared cluster.
            self.client.cancel([f for f in futures if not f.done()])

    def close(self) -> None:
        """Close the connection if this engine opened it (a Client passed in stays open)."""
        if self._own:
            self.client.close()


def open_engine(scheduler: Any = None, workers: int | None = None) -> LocalEngine | ClusterEngine:
    """The engine for ``--scheduler`` / ``--workers`` (connects to a cluster now, before any work).

    Parameters
    ----------
    scheduler : str or distributed.Client or engine, optional
        ``None`` (local processes, or ``sync`` with one worker), ``"processes"``,
        ``"threads"``, ``"sync"``, a cluster address (``tcp://HOST:PORT``), a Client,
        or an engine already opened (returned as is).
    workers : int, optional
        Local workers (default: the CPUs available). Not allowed with a cluster.

    Returns
    -------
    LocalEngine or ClusterEngine

    Raises
    ------
    InputError
        Unknown scheduler, bad worker count, ``workers`` with a cluster, unreachable cluster.
    """
    if isinstance(scheduler, (LocalEngine, ClusterEngine)):
        return scheduler
    if workers is not None and (
        isinstance(workers, bool) or not isinstance(workers, int) or workers < 1
    ):
        raise InputError("workers", f"must be an integer >= 1, got {workers!r}")
    if scheduler is None or scheduler in LOCAL_SCHEDULERS:
        n = workers or default_workers()
        name = scheduler or ("processes" if n > 1 else "sync")
        return LocalEngine(name, 1 if name == "sync" else n)
    if isinstance(scheduler, str) and "://" not in scheduler and ":" not in scheduler:
        raise InputError(
            "scheduler",
            f"unknown scheduler {scheduler!r}",
            f"give a cluster address tcp://HOST:PORT or one of: {', '.join(LOCAL_SCHEDULERS)}",
        )
    if workers is not None:
        raise InputError(
            "workers",
            "does not apply to a cluster (its workers do the work)",
            "give no worker count",
        )
    return ClusterEngine(scheduler)


@dataclass
class SweepOutcome:
    """What :func:`run_sweep` did.

    Attributes
    ----------
    out_dir : Path
        The output directory.
    results_csv : Path
        ``OUT/results.csv``.
    header : list of str
    rows : list of list
        The tidy table written to ``results.csv`` (:func:`inserr.sweep.store.table`).
    computed : int
        Points analysed by this run.
    resumed : int
        Points skipped because an earlier run had finished them.
    counts : dict
        Number of points per status (ok, failed, invalid, pending).
    plots : list of Path
        The figures written (empty with ``plots=False``).
    engine : str
        What ran the points (:meth:`LocalEngine.describe`).
    """

    out_dir: Path
    results_csv: Path
    header: list[str]
    rows: list[list[Any]]
    computed: int
    resumed: int
    counts: dict[str, int]
    plots: list[Path]
    engine: str


def run_sweep(
    grid: Grid,
    out_dir: str | Path,
    *,
    scheduler: Any = None,
    workers: int | None = None,
    plots: bool = True,
) -> SweepOutcome:
    """Run every unfinished point of ``grid`` and write ``out_dir`` (resumable).

    Nothing is created before the engine is ready (an unreachable cluster is an
    :class:`InputError` with no directory left behind). ``results.csv`` is written
    even when the run is interrupted, with status ``pending`` for the points not
    done yet. Figures in ``out_dir`` always describe ``results.csv``: those of
    earlier results are replaced or removed (also with ``plots=False`` and after
    an interrupted run); files inserr did not write are left alone.

    Parameters
    ----------
    grid : Grid
        The validated grid (:func:`inserr.sweep.grid.build_grid`).
    out_dir : str or Path
        Output directory; a directory of an earlier run is resumed.
    scheduler : str or distributed.Client or engine, optional
        See :func:`open_engine`.
    workers : int, optional
        Local workers (see :func:`open_engine`).
    plots : bool
        Draw the summary figures (:mod:`inserr.sweep.figures`).

    Returns
    -------
    SweepOutcome

    Raises
    ------
    InputError
        Bad scheduler or worker count, unreachable cluster (before ``out_dir`` exists).
    """
    engine = open_engine(scheduler, workers)
    engine_text = engine.describe()
    store = SweepStore(out_dir)
    try:
        store.prepare(grid)
        done = store.finished(grid)
        by_id = {pt.id: pt for pt in grid.points}
        for pt in grid.points:
            if pt.error:
                rec = invalid_record(grid, pt)
                if store.load(pt.id) != json.loads(dumps(rec)):
                    store.save(rec)
        todo = {pt.id: grid.payload(pt) for pt in grid.points if not pt.error and pt.id not in done}
        computed = 0
        with Bar(total=len(todo), desc="sweep", unit="point") as bar:

            def on_result(pid: str, result: dict[str, Any]) -> None:
                nonlocal computed
                store.save(point_record(grid, by_id[pid], result))
                computed += 1
                bar.update()

            completed = False
            try:
                engine.run(todo, on_result)
                completed = True
            finally:
                path, header, rows = write_results(store, grid)
                if not completed:
                    remove_stale_figures(store.root)  # they show earlier results
    finally:
        engine.close()
    figures: list[Path] = []
    if plots:
        from inserr.sweep.figures import write_figures

        figures = write_figures(grid, header, rows, store.root)
    else:
        remove_stale_figures(store.root)
    counts: dict[str, int] = {}
    for r in rows:
        status = r[header.index("status")]
        counts[status] = counts.get(status, 0) + 1
    return SweepOutcome(
        store.root, path, header, rows, computed, len(done), counts, figures, engine_text
    )
