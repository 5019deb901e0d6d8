"""Sweep: design sweeps over a grid of scenario changes, run on Dask, resumable.

* ``grid`` — the Cartesian grid of scenario changes, validated before any work
  (:func:`~inserr.sweep.grid.build_grid`).
* ``store`` — the sweep's output directory: one atomic record per point, the tidy table.
* ``runner`` — running the points locally or on a dask.distributed cluster
  (:func:`~inserr.sweep.runner.run_sweep`).
* ``figures`` — summary figures chosen by the number of swept parameters.
* ``api`` — the notebook front door: calling the package, ``inserr.sweep(scenario, params)``.
"""

from inserr.core.lazy import callable_package, lazy_exports

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "Grid": "inserr.sweep.grid",
        "build_grid": "inserr.sweep.grid",
        "SweepStore": "inserr.sweep.store",
        "run_sweep": "inserr.sweep.runner",
        "sweep": "inserr.sweep.api",
        "SweepResult": "inserr.sweep.api",
    },
)
callable_package(__name__, "inserr.sweep.api", "sweep")

__all__ = [
    "Grid",
    "build_grid",
    "SweepStore",
    "run_sweep",
    "sweep",
    "SweepResult",
]
