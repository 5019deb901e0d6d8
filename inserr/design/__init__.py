"""Designing indexing schedules: search a family of schedules for the one robust to the motion.

``inserr design`` (issue 17) turns the drift analysis around: instead of the error a
given schedule leaves, it looks for the schedule that leaves the least, worst over a
set of vehicle motions, within a motor-start budget. Layer: above
:mod:`inserr.drift` (the objective is the drift engine's per-source response) and
:mod:`inserr.sweep` (its Dask engines run the evaluations), below :mod:`inserr.cli`.

Modules
-------
* :mod:`~inserr.design.motions`: the motion set (grid, seeded random draws, heading
  histories) and the held-out motions;
* :mod:`~inserr.design.families`: what is searched (single-axis tables with free stop
  times and turn angles, the closed-loop rules' parameters, dual-axis orders);
* :mod:`~inserr.design.objective`: one evaluation (a schedule on one motion: RMS
  horizontal error over unknown signs, motor starts, turning time, table range) and
  the task the engines run;
* :mod:`~inserr.design.cache`: the content-addressed store of every evaluation, which
  makes a design resumable;
* :mod:`~inserr.design.search`: the optimizer (scipy's differential evolution, its
  generations evaluated in batches on Dask) and the verification at the full horizon;
* :mod:`~inserr.design.study`: the whole design, the comparison with the catalogue,
  the Pareto front and the report; :mod:`~inserr.design.figures` its figures.
"""
