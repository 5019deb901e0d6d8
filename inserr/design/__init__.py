"""Designing indexing schedules: search a family of schedules for the one robust to the motion.

``inserr design`` (issue 17) turns the drift analysis around: instead of the error a
given schedule leaves, it looks for the schedule that leaves the least, worst over a
set of vehicle motions, within a motor-start budget. Layer: above
:mod:`inserr.drift` (the objective is the drift engine's per-source response) and
:mod:`inserr.sweep` (its Dask engines run the evaluations), below :mod:`inserr.cli`.

Modules
-------
* ``motions`` — the motion set (grid, seeded random draws, heading histories) and the
  held-out motions.
* ``families`` — what is searched: single-axis tables with free stop times and turn
  angles, the closed-loop rules' parameters, dual-axis orders.
* ``objective`` — one evaluation (a schedule on one motion: RMS horizontal error over
  unknown signs, motor starts, turning time, table range) and the task the engines run.
* ``cache`` — the content-addressed store of every evaluation, which makes a design
  resumable.
* ``search`` — the optimizer (scipy's differential evolution, its generations
  evaluated in batches on Dask).
* ``study`` — the whole design: verification at the full horizon, the comparison with
  the catalogue, the Pareto front, the report and the chosen scheme file.
* ``figures`` — its figures.
"""

from inserr.core.lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "run_design": "inserr.design.study",
        "DesignOutcome": "inserr.design.study",
        "build_family": "inserr.design.families",
        "design_motions": "inserr.design.motions",
        "held_out_motions": "inserr.design.motions",
    },
)

__all__ = ["run_design", "DesignOutcome", "build_family", "design_motions", "held_out_motions"]
