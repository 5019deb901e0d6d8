"""The notebook front door of design sweeps: ``inserr.sweep(...)``.

Calling the package (``inserr.sweep(scenario, ["scheme.stop=60,120,300 s"])``) runs
:func:`sweep`: the grid of scenario changes on Dask, resumable in its output
directory (as ``inserr sweep``), returning a :class:`SweepResult` with the common
interface (:class:`~inserr.output.results.StudyResult`).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from inserr.output.results import TOTAL_LABEL, StudyResult
from inserr.scenario.schema import Scenario, as_scenario
from inserr.sweep.grid import Grid, build_grid, default_out_dir
from inserr.sweep.runner import SweepOutcome, run_sweep
from inserr.sweep.store import check_sweep_dir

if TYPE_CHECKING:  # pragma: no cover - typing only
    import pandas as pd
    from matplotlib.figure import Figure


def _param_texts(params: Iterable[str] | Mapping[str, Any] | None) -> list[str] | None:
    if params is None:
        return None
    if isinstance(params, str):
        return [params]
    if isinstance(params, Mapping):
        out = []
        for key, values in params.items():
            vals = [values] if isinstance(values, str) else list(values)
            out.append(f"{key}=" + ",".join(str(v) for v in vals))
        return out
    return list(params)


def sweep(
    scenario: Scenario | str | Path | dict,
    params: Iterable[str] | Mapping[str, Any] | None = None,
    *,
    out: str | Path | None = None,
    workers: int | None = None,
    scheduler: Any = None,
    plots: bool = False,
) -> SweepResult:
    """A design sweep: one drift analysis per point of a grid (``inserr.sweep(...)``).

    Parameters
    ----------
    scenario : Scenario, str, Path or dict
        The base scenario.
    params : list of str or dict, optional
        The swept values: ``["scheme.stop=60,120 s", "gyro-bias=0.01,0.02"]`` (as
        ``--param``) or ``{"scheme.stop": ["60 s", "120 s"]}``. Default: the
        scenario's ``sweep.parameters``.
    out : str or Path, optional
        Output directory (resumable; default ``sweep-<scenario name>``).
    workers : int, optional
        Local worker processes (default: the CPUs available).
    scheduler : str or distributed.Client, optional
        As ``--scheduler``.
    plots : bool
        Draw the summary figures into ``out`` too.

    Returns
    -------
    SweepResult
    """
    base = as_scenario(scenario)
    grid = build_grid(base, _param_texts(params))
    source = scenario if isinstance(scenario, (str, Path)) else None
    out_dir = check_sweep_dir(out if out is not None else default_out_dir(base, source))
    outcome = run_sweep(grid, out_dir, scheduler=scheduler, workers=workers, plots=plots)
    return SweepResult(base, grid, outcome)


@dataclass
class SweepResult(StudyResult):
    """A finished (or resumed) sweep: its grid and its table.

    Attributes
    ----------
    scenario : Scenario
        The base scenario.
    grid : Grid
    outcome : SweepOutcome
        What :func:`inserr.sweep.runner.run_sweep` did (``results.csv``, counts).
    """

    scenario: Scenario
    grid: Grid
    outcome: SweepOutcome

    @property
    def title(self) -> str:  # type: ignore[override]
        return f"inserr sweep: {self.scenario.name} ({len(self.grid.points)} points)"

    def metrics(self) -> dict[str, Any]:
        """Points per status, computed and resumed counts, the output directory."""
        o = self.outcome
        return {
            "points": len(self.grid.points),
            "counts": dict(o.counts),
            "computed": o.computed,
            "resumed": o.resumed,
            "out_dir": str(o.out_dir),
            "results_csv": str(o.results_csv),
        }

    def to_dataframe(self) -> pd.DataFrame:
        """The per-point table of ``results.csv`` (parameters, status, metrics with units)."""
        import pandas as pd

        return pd.DataFrame(self.outcome.rows, columns=self.outcome.header)

    def budget(self) -> pd.DataFrame:
        """Which error source dominates where: per source, its points and largest share.

        A sweep keeps each point's largest error source (``top_error_source``) and its
        RMS horizontal contribution at the end, nmi. Rows: those sources (readable
        names), how many points each dominates and its largest contribution; the
        last row counts every point analysed.
        """
        import pandas as pd

        from inserr.drift.budget import source_label

        frame = self.to_dataframe()
        ok = frame[frame["status"] == "ok"] if "status" in frame else frame.iloc[0:0]
        col = "top_error_source"
        rows = []
        if col in ok and len(ok):
            for key, group in ok.groupby(col, sort=False):
                rows.append((source_label(str(key)), len(group), float(group[f"{col}_nmi"].max())))
        rows.sort(key=lambda r: -r[1])
        total = (f"{TOTAL_LABEL.split(' ')[0]}: points analysed", len(ok), float("nan"))
        rows.append(total)
        return pd.DataFrame(
            [r[1:] for r in rows],
            index=pd.Index([r[0] for r in rows], name="source"),
            columns=["points where it is the largest source", "largest contribution (nmi)"],
        )

    def plot(self) -> Figure:
        """The sweep's first summary figure (:func:`inserr.sweep.figures.figures`)."""
        from inserr.sweep.figures import figures

        figs = figures(self.grid, self.outcome.header, self.outcome.rows)
        return next(iter(figs.values()))

    def _summary_metrics(self) -> list[tuple[str, Any]]:
        m = self.metrics()
        return [("points", m["points"]), *m["counts"].items(), ("output", m["out_dir"])]
