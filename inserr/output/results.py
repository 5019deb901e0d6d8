"""What every study result offers a notebook: metrics, DataFrames, a budget, a figure, HTML.

:class:`StudyResult` is the one interface of the results the front door returns
(``inserr.drift``, ``inserr.compare``, ``inserr.align``, ``inserr.calibrate``,
``inserr.northfind``, ``inserr.sweep``, ``inserr.imu_budget``):

* ``metrics()`` — the headline numbers as a plain ``dict`` (engineering units in
  the key names, the same numbers as ``results.json`` and ``--json``);
* ``to_dataframe()`` — a :class:`pandas.DataFrame`: the time series with the unit
  in every column name, or the per-run table;
* ``budget()`` — a :class:`pandas.DataFrame` of error sources (readable labels) and
  their contributions, with a root-sum-square total as its last row;
* ``plot()`` — a :class:`matplotlib.figure.Figure` (never shown, no backend chosen);
* ``_repr_html_()`` — the summary Jupyter displays: metrics and budget tables.

pandas and matplotlib are imported by the methods that need them, never by this
module, so that ``import inserr`` and the command line stay light.
"""

from __future__ import annotations

import html
import math
from abc import ABC, abstractmethod
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # pragma: no cover - typing only
    import pandas as pd
    from matplotlib.figure import Figure

#: Label of the last row of every budget.
TOTAL_LABEL = "total (root-sum-square)"


def rss(values: Iterable[float]) -> float:
    """Root-sum-square of ``values`` (the total of independent contributions)."""
    return math.sqrt(math.fsum(float(v) ** 2 for v in values))


def budget_frame(
    rows: Iterable[tuple[str, str, float]],
    value_column: str,
    *,
    kind_column: str = "type",
    total_label: str = TOTAL_LABEL,
    sort: bool = True,
) -> pd.DataFrame:
    """A budget as a DataFrame: one row per source, the root-sum-square total last.

    Parameters
    ----------
    rows : iterable of (label, kind, value)
        Readable source label, its kind (e.g. ``"constant"``, ``"noise"``) and its
        contribution (one unit for all rows, named in ``value_column``).
    value_column : str
        Name of the value column, with its unit (``"... (nmi)"``).
    kind_column : str
        Name of the kind column.
    total_label : str
        Label of the total row.
    sort : bool
        Largest contribution first (else in the given order).

    Returns
    -------
    pandas.DataFrame
        Index ``source`` (the labels, then ``total_label``); columns ``kind_column``
        and ``value_column``. The total is the root-sum-square of the rows, the
        total of independent contributions.
    """
    import pandas as pd

    rows = list(rows)
    if sort:
        rows.sort(key=lambda r: -r[2])
    total = rss(r[2] for r in rows)
    frame = pd.DataFrame(
        {
            kind_column: [r[1] for r in rows] + ["total"],
            value_column: [float(r[2]) for r in rows] + [total],
        },
        index=pd.Index([r[0] for r in rows] + [total_label], name="source"),
    )
    return frame


def scalar_items(metrics: Mapping[str, Any]) -> list[tuple[str, Any]]:
    """The scalar entries of a metrics dict (numbers, strings, booleans), in order."""
    return [
        (k, v)
        for k, v in metrics.items()
        if isinstance(v, (int, float, str, bool)) or v is None or hasattr(v, "item")
    ]


def _cell(value: Any) -> str:
    if isinstance(value, bool) or value is None:
        return html.escape(str(value))
    if isinstance(value, (int, float)) or hasattr(value, "item"):
        v = float(value)
        return "—" if not math.isfinite(v) else f"{v:.4g}"
    return html.escape(str(value))


def html_table(header: list[str], rows: Iterable[Iterable[Any]]) -> str:
    """An HTML table (cells escaped; numbers with 4 significant digits)."""
    out = ["<table><thead><tr>"]
    out += [f"<th>{html.escape(str(h))}</th>" for h in header]
    out.append("</tr></thead><tbody>")
    for r in rows:
        out.append("<tr>" + "".join(f"<td>{_cell(c)}</td>" for c in r) + "</tr>")
    out.append("</tbody></table>")
    return "".join(out)


def frame_html(frame: pd.DataFrame, max_rows: int = 15) -> str:
    """A DataFrame as a compact HTML table (index as the first column, long frames cut).

    The last row is kept when rows are cut (a budget's total stays visible).
    """
    n = len(frame)
    if n > max_rows:
        keep = list(range(max_rows - 1)) + [n - 1]
        shown = frame.iloc[keep]
    else:
        shown = frame
    header = [frame.index.name or "", *map(str, frame.columns)]
    rows = [
        [idx, *row] for idx, row in zip(shown.index, shown.itertuples(index=False), strict=True)
    ]
    note = f"<p><em>{n - len(shown)} rows not shown</em></p>" if n > len(shown) else ""
    return html_table(header, rows) + note


class StudyResult(ABC):
    """The interface of every study result of the front door (see the module).

    Subclasses implement :meth:`metrics`, :meth:`to_dataframe`, :meth:`budget` and
    :meth:`plot`, and set :attr:`title`; :meth:`_repr_html_` is shared.
    """

    #: Heading of the Jupyter summary.
    title: str = "inserr result"

    @abstractmethod
    def metrics(self) -> dict:
        """Headline numbers as a plain dict (engineering units named in the keys)."""

    @abstractmethod
    def to_dataframe(self) -> pd.DataFrame:
        """The time series (units in the column names) or the per-run table."""

    @abstractmethod
    def budget(self) -> pd.DataFrame:
        """Sources with readable labels and their contributions; the RSS total last."""

    @abstractmethod
    def plot(self) -> Figure:
        """The study's main figure (a new :class:`matplotlib.figure.Figure`)."""

    def _summary_metrics(self) -> list[tuple[str, Any]]:
        """Rows of the metrics table of :meth:`_repr_html_` (scalars of :meth:`metrics`)."""
        return scalar_items(self.metrics())

    def _repr_html_(self) -> str:
        """Jupyter's view: title, headline metrics and the budget."""
        parts = [f"<h4>{html.escape(self.title)}</h4>"]
        parts.append(html_table(["metric", "value"], self._summary_metrics()))
        budget = self.budget()
        if len(budget):
            parts.append("<p><strong>Budget</strong></p>")
            parts.append(frame_html(budget))
        return "<div class='inserr-result'>" + "".join(parts) + "</div>"
