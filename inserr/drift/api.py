"""The notebook front door of the drift study: ``inserr.drift`` and ``inserr.compare``.

Both take a scenario as a notebook has it — an :class:`~inserr.scenario.schema.Scenario`,
the path of a TOML file, or a nested dict — and return results with the common
interface (:class:`~inserr.output.results.StudyResult`): ``metrics()``,
``to_dataframe()``, ``budget()``, ``plot()`` and a Jupyter summary::

    import inserr

    scen = inserr.load_scenario("analyses/quickstart/scenario.toml")
    run = inserr.drift(scen, "two-position")          # one scheme: a SchemeRun
    both = inserr.compare(scen, ["none", "two-position"])
    both.to_dataframe()                                # one row per scheme
    both.budget()                                      # sources x schemes, RSS total
    fig = both.plot()                                  # a matplotlib Figure
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from inserr.drift.budget import BUDGET_COLUMN, budget_rows
from inserr.drift.study import (
    METRIC_COLUMNS,
    SchemeRun,
    metric_values,
    run_scheme,
    timeseries_columns,
)
from inserr.output.results import TOTAL_LABEL, StudyResult, frame_html, rss
from inserr.scenario.schema import Scenario, as_scenario

if TYPE_CHECKING:  # pragma: no cover - typing only
    import pandas as pd
    from matplotlib.figure import Figure


def drift(scenario: Scenario | str | Path | dict, scheme: str | None = None) -> SchemeRun:
    """Drift of a scenario under one indexing scheme (``inserr.drift(...)``).

    Parameters
    ----------
    scenario : Scenario, str, Path or dict
        The scenario, a TOML file or a dict of sections
        (:func:`~inserr.scenario.schema.as_scenario`).
    scheme : str, optional
        Scheme name (default: the scenario's ``scheme.name``).

    Returns
    -------
    SchemeRun
        ``metrics()``, ``to_dataframe()``, ``budget()``, ``plot()``.
    """
    return run_scheme(as_scenario(scenario), scheme)


def compare(
    scenario: Scenario | str | Path | dict, schemes: Iterable[str] | None = None
) -> Comparison:
    """Several schemes on one scenario (``inserr.compare(...)``).

    Parameters
    ----------
    scenario : Scenario, str, Path or dict
        The scenario (see :func:`drift`).
    schemes : iterable of str, optional
        Scheme names, in the order shown. Default: the scenario's scheme followed by
        its ``compare.schemes`` (what ``inserr run`` compares).

    Returns
    -------
    Comparison
    """
    scen = as_scenario(scenario)
    if schemes is None:
        names = (scen.scheme_name,) + tuple(n for n in scen.compare if n != scen.scheme_name)
    else:
        names = tuple(dict.fromkeys([schemes] if isinstance(schemes, str) else schemes))
    return Comparison(scen, {name: run_scheme(scen, name) for name in names})


@dataclass
class Comparison(StudyResult):
    """Scheme runs on one scenario, side by side.

    Attributes
    ----------
    scenario : Scenario
    runs : dict
        Scheme name -> :class:`~inserr.drift.study.SchemeRun` (``comparison[name]``).
    """

    scenario: Scenario
    runs: dict[str, SchemeRun]

    @property
    def title(self) -> str:  # type: ignore[override]
        return f"inserr comparison: {self.scenario.name}"

    def __getitem__(self, name: str) -> SchemeRun:
        return self.runs[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self.runs)

    def __len__(self) -> int:
        return len(self.runs)

    def metrics(self) -> dict[str, Any]:
        """``{"scenario": name, "runs": {scheme: run.metrics()}}`` (plain dict)."""
        return {
            "scenario": self.scenario.name,
            "runs": {name: r.metrics() for name, r in self.runs.items()},
        }

    def to_dataframe(self) -> pd.DataFrame:
        """The comparison table: one row per scheme (index), headline errors with units."""
        import pandas as pd

        return pd.DataFrame(
            [metric_values(r) for r in self.runs.values()],
            index=pd.Index(list(self.runs), name="scheme"),
            columns=list(METRIC_COLUMNS),
        )

    def timeseries(self, step: float | None = None) -> pd.DataFrame:
        """Every run's time series, stacked (long format, a ``scheme`` column).

        Parameters
        ----------
        step : float, s, optional
            Row step (default the scenario's ``output.export_step``).
        """
        import pandas as pd

        return pd.concat(
            [pd.DataFrame(timeseries_columns(r, step)) for r in self.runs.values()],
            ignore_index=True,
        )

    def budget(self) -> pd.DataFrame:
        """Sources (readable labels) x schemes, nmi at the end; RSS total per scheme last.

        A source absent from a scheme's budget contributes 0 to it. Rows are sorted
        by their largest contribution over the schemes.
        """
        import pandas as pd

        per_scheme = {}
        for name, r in self.runs.items():
            rows = budget_rows(r.result.metrics["error_budget"], top=None)[:-1]
            per_scheme[name] = {b.label: b.value for b in rows}
        labels = sorted(
            {label for d in per_scheme.values() for label in d},
            key=lambda lab: -max(d.get(lab, 0.0) for d in per_scheme.values()),
        )
        data = {
            name: [d.get(lab, 0.0) for lab in labels] + [rss(d.values())]
            for name, d in per_scheme.items()
        }
        frame = pd.DataFrame(data, index=pd.Index(labels + [TOTAL_LABEL], name="source"))
        frame.columns.name = BUDGET_COLUMN
        return frame

    def plot(self) -> Figure:
        """Horizontal position error, one panel per scheme (its colour)."""
        from inserr.drift.figures import horizontal_error

        return horizontal_error({n: r.result for n, r in self.runs.items()}, title=self.title)

    def plot_attitude(self) -> Figure:
        """Attitude errors, one row of panels per scheme."""
        from inserr.drift.figures import attitude_errors

        return attitude_errors({n: r.result for n, r in self.runs.items()})

    def report(self, out_dir: str | Path, source: str | Path | None = None) -> Path:
        """Write the drift report of this comparison (as ``inserr run``) and return its path."""
        from inserr.drift.report import build_report

        return build_report(self.scenario, list(self.runs.values()), source=source).write(out_dir)

    def _repr_html_(self) -> str:
        import html

        return (
            f"<div class='inserr-result'><h4>{html.escape(self.title)}</h4>"
            + frame_html(self.to_dataframe())
            + "<p><strong>Budget</strong></p>"
            + frame_html(self.budget())
            + "</div>"
        )
