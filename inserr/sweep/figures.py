"""Summary plots of a sweep, chosen by the number of swept parameters.

* one parameter: lines of the horizontal error against it (maximum over the
  run with the signs as given, RMS with unknown signs, worst sign pattern);
* two parameters: heatmaps (first parameter down, second across), one annotated
  cell per point, for the maximum error with signs as given and for the worst
  sign pattern;
* three or more: small multiples, one heatmap of the first two parameters per
  combination of the others, all on one colour scale (one figure per metric, at
  most :data:`MAX_FACETS` panels). Small multiples keep every number readable in
  the units of the table, which a parallel-coordinates plot would not.

Points that failed or were invalid are blank (grey) cells or gaps in a line. The
colour or y scale is logarithmic when the values span more than a factor
:data:`LOG_SPAN`, as errors of different schemes often do. Axis labels carry the
unit of the values (``stop (s)``: the flag's unit for bare numbers, else the unit
the values were written in), see :meth:`inserr.sweep.grid.Param.label`.

Every figure carries the PNG text chunk :data:`inserr.sweep.store.FIGURE_MARK`;
:func:`write_figures` removes the marked figures of earlier results that it did
not write again, and only those.
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np
from matplotlib.colors import LogNorm, Normalize
from matplotlib.figure import Figure

from inserr.output import figure_style as style
from inserr.output.report import write_bytes_atomic
from inserr.sweep.grid import Grid, Param
from inserr.sweep.store import FIGURE_MARK, remove_stale_figures

LINE_METRICS = (
    ("max_horizontal_error_nmi", "max, signs as given"),
    ("rms_horizontal_error_nmi", "max of RMS, unknown signs"),
    ("worst_case_horizontal_error_nmi", "max, worst sign pattern"),
)
MAP_METRICS = (
    ("max_horizontal_error_nmi", "max horizontal error, signs as given (nmi)"),
    ("worst_case_horizontal_error_nmi", "max horizontal error, worst sign pattern (nmi)"),
)
MAX_FACETS = 16
LOG_SPAN = 20.0


def metric_array(grid: Grid, header: list[str], rows: list[list[Any]], metric: str) -> np.ndarray:
    """Values of ``metric`` on the grid, shape ``grid.shape`` (NaN where there is none).

    Parameters
    ----------
    grid : Grid
    header, rows
        The table of :func:`inserr.sweep.store.table`.
    metric : str
        A column name, e.g. ``"max_horizontal_error_nmi"``.

    Returns
    -------
    numpy.ndarray
        The metric in the unit of its column (nmi for the error metrics), NaN for
        points without a number (failed, invalid, pending) or a missing column.
    """
    out = np.full(len(rows), np.nan)
    if metric in header:
        col = header.index(metric)
        for i, r in enumerate(rows):
            v = r[col]
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                out[i] = float(v)
    return out.reshape(grid.shape)


def _norm(values: np.ndarray) -> Normalize:
    good = values[np.isfinite(values)]
    if good.size == 0:
        return Normalize(0.0, 1.0)
    lo, hi = float(good.min()), float(good.max())
    if lo > 0 and hi / lo > LOG_SPAN:
        return LogNorm(lo, hi)
    return Normalize(lo, hi if hi > lo else lo + 1.0)


def _positions(p: Param) -> tuple[np.ndarray, list[str] | None, str]:
    nums, _ = p.axis()
    if nums is not None:
        return np.array(nums), None, p.label()
    return np.arange(len(p.values), dtype=float), p.ticks(), p.label()


def _lines(grid: Grid, header: list[str], rows: list[list[Any]]) -> Figure:
    p = grid.params[0]
    x, ticks, label = _positions(p)
    order = np.argsort(x, kind="stable")
    fig = style.new_figure(style.WIDTH, 4.2)
    ax = fig.add_subplot()
    every = []
    for i, (metric, text) in enumerate(LINE_METRICS):
        y = metric_array(grid, header, rows, metric)
        every.append(y)
        ax.plot(x[order], y[order], marker="o", lw=1.2, color=style.series_color(i), label=text)
    allv = np.concatenate(every)
    if isinstance(_norm(allv), LogNorm):
        ax.set_yscale("log")
    if ticks is not None:
        ax.set_xticks(x, ticks, rotation=30 if max(map(len, ticks)) > 6 else 0)
    ax.set_xlabel(label)
    ax.set_ylabel("horizontal position error (nmi)")
    ax.set_title(f"Sweep of {p.name}: horizontal error over {_hours(grid)}")
    style.grid(ax)
    ax.legend()
    return style.finish(fig)


def _heatmap(ax, z: np.ndarray, down: Param, across: Param, norm: Normalize) -> Any:
    cmap = matplotlib.colormaps["viridis"].with_extremes(bad="0.85")
    im = ax.imshow(np.ma.masked_invalid(z), norm=norm, cmap=cmap, origin="lower", aspect="auto")
    across_ticks = across.ticks()
    ax.set_yticks(range(len(down.values)), down.ticks())
    ax.set_xticks(
        range(len(across.values)),
        across_ticks,
        rotation=30 if max(map(len, across_ticks)) > 6 else 0,
    )
    ax.set_ylabel(down.label())
    ax.set_xlabel(across.label())
    if z.size <= 64:
        for (i, j), v in np.ndenumerate(z):
            text = f"{v:.3g}" if math.isfinite(v) else "x"
            rgba = cmap(norm(v)) if math.isfinite(v) else (1, 1, 1, 1)
            dark = 0.299 * rgba[0] + 0.587 * rgba[1] + 0.114 * rgba[2] < 0.5
            ax.text(
                j,
                i,
                text,
                ha="center",
                va="center",
                fontsize=style.FONT["annotation"],
                color="white" if dark else "black",
            )
    return im


def _heatmaps(grid: Grid, header: list[str], rows: list[list[Any]]) -> Figure:
    down, across = grid.params
    fig, axes = style.subplots(
        1, len(MAP_METRICS), width=5.2 * len(MAP_METRICS), height=4.2, squeeze=False
    )
    for ax, (metric, text) in zip(axes[0], MAP_METRICS, strict=True):
        z = metric_array(grid, header, rows, metric)
        im = _heatmap(ax, z, down, across, _norm(z))
        ax.set_title(text)
        fig.colorbar(im, ax=ax, shrink=0.85)
    style.suptitle(fig, f"Sweep over {_hours(grid)} (grey: failed or invalid point)")
    return style.finish(fig)


def _facets(grid: Grid, header: list[str], rows: list[list[Any]], metric: str, text: str) -> Figure:
    down, across, *rest = grid.params
    z = metric_array(grid, header, rows, metric)
    combos = list(itertools.product(*(range(len(p.values)) for p in rest)))
    shown = combos[:MAX_FACETS]
    ncols = min(4, len(shown))
    nrows = math.ceil(len(shown) / ncols)
    fig, axes = style.subplots(nrows, ncols, width=3.6 * ncols, height=3.1 * nrows, squeeze=False)
    norm = _norm(z)
    im = None
    for ax, combo in zip(axes.flat, shown, strict=False):
        im = _heatmap(ax, z[(slice(None), slice(None), *combo)], down, across, norm)
        ax.set_title(
            ", ".join(f"{p.name}={p.value_texts()[i]}" for p, i in zip(rest, combo, strict=True))
        )
    for ax in axes[:, 1:].flat:
        # one set of row labels per row of panels: repeated, they overlap the panel to the left
        ax.set_ylabel("")
        ax.tick_params(labelleft=False)
    for ax in list(axes.flat)[len(shown) :]:
        ax.set_visible(False)
    more = (
        f" (first {len(shown)} of {len(combos)} combinations)" if len(shown) < len(combos) else ""
    )
    style.suptitle(fig, f"{text} over {_hours(grid)}{more}")
    if im is not None:
        fig.colorbar(im, ax=axes.ravel().tolist(), shrink=0.8)
    return style.finish(fig)


def _hours(grid: Grid) -> str:
    return (
        f"{grid.base.duration / 3600.0:g} h"
        if "scenario.duration" not in _swept_keys(grid)
        else "the run"
    )


def _swept_keys(grid: Grid) -> set[str]:
    return {k for p in grid.params for ch in p.changes for k in ch}


def figures(grid: Grid, header: list[str], rows: list[list[Any]]) -> dict[str, Figure]:
    """Summary figures by file stem (see the module docstring for the choice).

    Parameters
    ----------
    grid : Grid
    header, rows
        The table of :func:`inserr.sweep.store.table` (errors in nmi).

    Returns
    -------
    dict of str to matplotlib.figure.Figure
        ``{"sweep": ...}`` for one or two parameters, one ``sweep_<metric>`` per
        metric of :data:`MAP_METRICS` for three or more (not managed by pyplot:
        nothing to close).
    """
    n = len(grid.params)
    if n == 1:
        return {"sweep": _lines(grid, header, rows)}
    if n == 2:
        return {"sweep": _heatmaps(grid, header, rows)}
    return {
        f"sweep_{metric}": _facets(grid, header, rows, metric, text) for metric, text in MAP_METRICS
    }


def write_figures(
    grid: Grid, header: list[str], rows: list[list[Any]], out_dir: Path
) -> list[Path]:
    """Write the summary figures as PNG files in ``out_dir`` (each atomically).

    Figures inserr wrote there for earlier results (another grid) and not
    written again now are removed; if drawing fails, every figure inserr wrote
    there is removed, so that no figure contradicts ``results.csv``.

    Parameters
    ----------
    grid : Grid
    header, rows
        The table of :func:`inserr.sweep.store.table`, as in ``results.csv``.
    out_dir : Path
        The sweep's output directory.

    Returns
    -------
    list of Path
        The figures written, ``OUT/<stem>.png`` (see :func:`figures`).
    """
    paths: list[Path] = []
    try:
        for stem, fig in figures(grid, header, rows).items():
            path = Path(out_dir) / f"{stem}.png"
            write_bytes_atomic(path, style.png_bytes(fig, metadata=dict([FIGURE_MARK])))
            paths.append(path)
    except BaseException:
        remove_stale_figures(out_dir)
        raise
    remove_stale_figures(out_dir, keep=paths)
    return paths
