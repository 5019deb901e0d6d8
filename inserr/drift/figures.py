"""Figures of the drift reports, in the inserr figure style.

All functions take results in SI and draw in engineering units (hours, nautical
miles, arc-seconds/arc-minutes), returning a :class:`matplotlib.figure.Figure`
built without pyplot (:mod:`inserr.output.figure_style`): nothing is shown, no
backend is chosen, and the caller owns the figure.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from inserr.core.units import ARCMIN, ARCSEC, HOUR, NMI
from inserr.output import figure_style as style


def horizontal_error(results: dict, title: str = "Horizontal position error") -> Figure:
    """Horizontal error per run: signs as given, RMS and worst sign pattern, noise 1-sigma.

    One panel per run (shared axes), so every run shows its own envelope; a single
    run gets a single panel. The run's curve takes its scheme colour
    (:func:`~inserr.output.figure_style.scheme_color`); the RMS over unknown signs is
    black and dashed, the worst sign pattern grey and dotted in every panel, and one
    legend below the panels, outside the data, names them. Curves of more samples
    than the figure has pixel columns are thinned to the min and max per column
    (:func:`~inserr.output.figure_style.minmax_decimate`): the figure looks the same.

    Parameters
    ----------
    results : dict
        Run name -> :class:`inserr.drift.analysis.DriftResult` (times in s, errors in m).
    title : str
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        Time in hours, horizontal error in nautical miles.
    """
    n = len(results)
    cols = 1 if n <= 3 else 2
    rows = -(-n // cols)
    # Fixed margins (no layout engine: a third less drawing time); the bottom margin
    # holds the x label and the legend, the top the title and the panel titles.
    fig, axes = style.fixed_grid(
        rows,
        cols,
        width=style.WIDTH if cols == 1 else style.WIDE,
        panel_height=style.ROW_HEIGHT,
        left=0.75,
        top=0.6,
        bottom=0.95,
        wspace=0.35,
        hspace=0.45,
        sharex=True,
        sharey=True,
        squeeze=False,
    )
    columns = style.plot_columns(fig) // cols
    noise = False
    for i, (name, r) in enumerate(results.items()):
        noise |= _horizontal_panel(axes.flat[i], name, r, style.scheme_color(name, i), columns)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("time (h)")
    for ax in axes[:, 0]:
        ax.set_ylabel("horizontal error (nmi)")
    style.suptitle(fig, title)
    _role_legend(fig, noise)
    return style.finish(fig)


def _role_legend(fig: Figure, noise: bool) -> None:
    """One legend for every panel, below them (outside the data)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    handles = [
        Line2D([], [], color="0.2", lw=1.2, label="signs as given (scheme colour)"),
        Line2D([], [], color=style.ROLE_COLORS["reference"], lw=1.0, ls="--", label=RMS_LABEL),
        Line2D([], [], color=style.ROLE_COLORS["worst"], lw=1.2, ls=":", label=WORST_LABEL),
    ]
    if noise:
        handles.append(Patch(color="0.2", alpha=0.25, label="noise 1-sigma envelope"))
    fig.legend(handles=handles, loc="lower center", ncols=len(handles), frameon=False)


#: Legend texts of the statistical curves (the same in every figure).
RMS_LABEL = "RMS over unknown signs"
WORST_LABEL = "worst sign pattern"


def _horizontal_panel(ax, name: str, r, color: str, columns: int = 2000) -> bool:
    """Draw one run's panel; True when it has a noise envelope."""
    t, h = style.minmax_decimate(r.t / HOUR, r.horizontal / NMI, columns)
    ax.plot(t, h, color=color, lw=1.0, label="signs as given")
    ax.plot(
        r.t_cov / HOUR,
        r.rms_horizontal / NMI,
        color=style.ROLE_COLORS["reference"],
        lw=0.9,
        ls="--",
        label=RMS_LABEL,
    )
    ax.plot(
        r.t_cov / HOUR,
        r.worst_horizontal / NMI,
        color=style.ROLE_COLORS["worst"],
        lw=1.1,
        ls=":",
        label=WORST_LABEL,
    )
    sig = r.noise_horizontal_sigma
    noise = bool(np.any(sig > 0))
    if noise:
        base = np.interp(r.t_cov, r.t, r.horizontal)
        ax.fill_between(
            r.t_cov / HOUR,
            (base - sig) / NMI,
            (base + sig) / NMI,
            color=color,
            alpha=0.25,
            lw=0,
            label="noise 1-sigma envelope",
        )
    ax.set_title(name, color=color)
    style.grid(ax)
    return noise


#: The attitude-error quantities: column title (with unit), component, unit.
ATTITUDE_COLUMNS = (
    ("east tilt error (arcsec)", 0, ARCSEC),
    ("north tilt error (arcsec)", 1, ARCSEC),
    ("heading error (arcmin)", 2, ARCMIN),
)


def attitude_errors(results: dict, title: str = "Attitude errors, signs as given") -> Figure:
    """Tilts (arcsec) and heading error (arcmin): one row of panels per run.

    Runs are never overdrawn: each has its row (east tilt, north tilt, heading
    error), in its scheme colour, axes shared per column so rows compare at a
    glance. An indexed run oscillates at the indexing period, far faster than the
    run: thinned to the min and max per pixel column, its curve reads as the
    envelope of the oscillation.

    Parameters
    ----------
    results : dict
        Run name -> :class:`inserr.drift.analysis.DriftResult`.
    title : str
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    n = len(results)
    # Fixed margins: twelve panels under constrained layout would double the drawing
    # time of the quick-start report; the labels here are short and known.
    fig, axes = style.fixed_grid(
        n, 3, width=style.WIDE, panel_height=1.9, sharex=True, sharey="col", squeeze=False
    )
    columns = style.plot_columns(fig) // 3
    for i, (name, r) in enumerate(results.items()):
        color = style.scheme_color(name, i)
        for k, (label, comp, unit) in enumerate(ATTITUDE_COLUMNS):
            ax = axes[i, k]
            t, y = style.minmax_decimate(r.t / HOUR, r.attitude[:, comp] / unit, columns)
            ax.plot(t, y, color=color, lw=0.8)
            # Four intervals per axis read well on a 1.9 in panel and halve the tick
            # objects matplotlib builds and draws for twelve panels.
            ax.locator_params(nbins=4)
            style.grid(ax)
            if i == 0:
                ax.set_title(label)
        axes[i, 0].set_ylabel(name, color=color, fontweight="bold")
    for ax in axes[-1]:
        ax.set_xlabel("time (h)")
    style.suptitle(fig, title)
    return style.finish(fig)


def error_budget(
    budget: dict[str, float],
    top: int = 12,
    title: str = "Error budget at the end",
    scheme: str | None = None,
) -> Figure:
    """Bar chart of one run's per-source RMS horizontal error at the end (nmi), with its total.

    The rows of :func:`inserr.drift.budget.budget_rows` (the ``top`` largest sources
    by readable name, the others gathered, the root-sum-square total), drawn by
    :func:`budget_figure`.

    Parameters
    ----------
    budget : dict
        Source key -> RMS horizontal error at the end, nmi.
    top : int
        Number of sources shown one by one.
    title : str
        Axes title.
    scheme : str, optional
        Scheme whose budget this is: the bars take its colour.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from inserr.drift.budget import budget_table

    return budget_figure(budget_table({scheme or "": budget}, top), title)


def budget_figure(table, title: str = "Error budget at the end of the run") -> Figure:
    """The budgets of one or more runs on shared rows, as grouped horizontal bars.

    Parameters
    ----------
    table : inserr.drift.budget.BudgetTable
        Rows (readable source names, the gathered rest, the total) and one value per
        run; the same rows as the report's budget table.
    title : str
        Axes title.

    Returns
    -------
    matplotlib.figure.Figure
        One group of bars per row (largest source at the top, the total, hatched, at
        the bottom), one bar per run in its scheme colour, the legend below the axes,
        each bar labelled with its value (nmi).
    """
    rows = table.rows
    n_run = max(len(table.schemes), 1)
    n_row = len(rows)
    bar_h = 0.8 / n_run
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.font_manager import FontProperties

    legend = any(table.schemes) and n_run > 1
    height = 1.4 + n_row * (0.12 + 0.16 * n_run)
    fig = Figure(figsize=(style.WIDTH, height), dpi=style.DPI)
    # Fixed margins, the left one from the widest source name (measured, bold as the
    # total row): no constrained-layout pass, a third less drawing time.
    renderer = FigureCanvasAgg(fig).get_renderer()
    font = FontProperties(size=style.FONT["tick"], weight="bold")
    widest = max(
        (renderer.get_text_width_height_descent(r.label, font, ismath=False)[0] for r in rows),
        default=0.0,
    )
    left = widest / style.DPI + 0.2  # in: the names, the tick marks and a gap
    bottom = 0.95 if legend else 0.55  # in: tick labels, axis label (and the legend)
    fig.subplots_adjust(
        left=left / style.WIDTH,
        right=1 - 0.2 / style.WIDTH,
        bottom=bottom / height,
        top=1 - 0.35 / height,
    )
    ax = fig.add_subplot()
    top = max((v for r in table.values for v in r), default=0.0)
    for j, name in enumerate(table.schemes):
        color = style.scheme_color(name, j) if name else style.series_color(0)
        y = np.arange(n_row)[::-1] + 0.4 - (j + 0.5) * bar_h
        vals = [r[j] for r in table.values]
        bars = ax.barh(y, vals, height=bar_h * 0.92, color=color, label=name or None)
        for bar, row in zip(bars, rows, strict=True):
            if row.kind == "total":
                bar.set_hatch("///")
                bar.set_edgecolor("white")
        # Values under 1 % of the largest bar are unreadable as bars: no label either
        # (the report's table beside the figure has every number).
        texts = [f"{v:.3g}" if v >= 0.01 * top else "" for v in vals]
        ax.bar_label(bars, labels=texts, padding=2, fontsize=style.FONT["annotation"])
    ax.set_yticks(np.arange(n_row)[::-1], [r.label for r in rows])
    for tick, row in zip(ax.get_yticklabels(), rows, strict=True):
        if row.kind == "total":
            tick.set_fontweight("bold")
    ax.set_ylim(-0.6, n_row - 0.4)
    ax.set_xlim(0, 1.15 * top if top > 0 else 1.0)
    ax.set_xlabel("RMS horizontal position error at the end (nmi)")
    ax.set_title(title)
    style.grid(ax, axis="x")
    if legend:
        fig.legend(loc="lower center", ncols=min(n_run, 4), frameon=False)
    return style.finish(fig)


def table_angle(timeline, title: str = "Table angle and horizontal projection") -> Figure:
    """Outer/inner gimbal angles and the horizontal projection of the IMU x axis vs time."""
    t_end = timeline.duration
    t = np.linspace(0.0, t_end, min(20000, int(t_end) * 4 + 2))
    c = timeline.attitude_at(t)
    table = timeline.meta.get("table")
    motion = timeline.meta.get("motion")
    fig, axes = style.subplots(2, 1, height=5.0, sharex=True)
    if table is not None:
        a, b = table.angles_at(t, motion)
        axes[0].plot(t / 60, np.degrees(a), lw=1, label="outer (azimuth)")
        if np.any(b != 0):
            axes[0].plot(t / 60, np.degrees(b), lw=1, label="inner")
        axes[0].legend()
    axes[0].set_ylabel("gimbal angle (deg)")
    for i, lab in enumerate(("E", "N")):
        axes[1].plot(t / 60, c[:, i, 0], lw=1, label=f"C_s^n[{lab}, x]")
        axes[1].plot(t / 60, c[:, i, 1], lw=1, ls="--", label=f"C_s^n[{lab}, y]")
    axes[1].set_ylabel("horizontal projection")
    axes[1].set_xlabel("time (min)")
    axes[1].legend(ncol=2)
    for ax in axes:
        style.grid(ax)
    axes[0].set_title(title)
    return style.finish(fig)
