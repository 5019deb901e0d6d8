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
    run gets a single panel.

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
    fig, axes = style.subplots(
        rows,
        cols,
        width=style.WIDTH if cols == 1 else style.WIDE,
        sharex=True,
        sharey=True,
        squeeze=False,
    )
    for i, (name, r) in enumerate(results.items()):
        _horizontal_panel(axes.flat[i], name, r, style.scheme_color(name, i))
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("time (h)")
    for ax in axes[:, 0]:
        ax.set_ylabel("horizontal error (nmi)")
    style.suptitle(fig, title)
    return style.finish(fig)


def _horizontal_panel(ax, name: str, r, color: str) -> None:
    ax.plot(r.t / HOUR, r.horizontal / NMI, color=color, lw=1.0, label="signs as given")
    ax.plot(
        r.t_cov / HOUR,
        r.rms_horizontal / NMI,
        color=style.ROLE_COLORS["reference"],
        lw=0.9,
        ls="--",
        label="RMS, unknown signs",
    )
    ax.plot(
        r.t_cov / HOUR,
        r.worst_horizontal / NMI,
        color=style.ROLE_COLORS["worst"],
        lw=0.8,
        ls=":",
        label="worst sign pattern",
    )
    sig = r.noise_horizontal_sigma
    if np.any(sig > 0):
        base = np.interp(r.t_cov, r.t, r.horizontal)
        ax.fill_between(
            r.t_cov / HOUR,
            (base - sig) / NMI,
            (base + sig) / NMI,
            color=color,
            alpha=0.25,
            label="noise 1-sigma envelope",
        )
    ax.set_title(name)
    style.grid(ax)
    ax.legend()


def attitude_errors(results: dict) -> Figure:
    """Level tilts (arcsec) and heading error (arcmin) of the deterministic run(s)."""
    fig, axes = style.subplots(3, 1, height=6.5, sharex=True)
    labels = (
        "east tilt phi_E (arcsec)",
        "north tilt phi_N (arcsec)",
        "heading error phi_U (arcmin)",
    )
    scale = (ARCSEC, ARCSEC, ARCMIN)
    for i, (name, r) in enumerate(results.items()):
        for k in range(3):
            axes[k].plot(
                r.t / HOUR,
                r.attitude[:, k] / scale[k],
                color=style.scheme_color(name, i),
                lw=0.8,
                label=name,
            )
    for k in range(3):
        axes[k].set_ylabel(labels[k])
        style.grid(axes[k])
    axes[-1].set_xlabel("time (h)")
    axes[0].legend()
    return style.finish(fig)


def error_budget(
    budget: dict[str, float],
    top: int = 15,
    title: str = "Error budget at the end",
    scheme: str | None = None,
) -> Figure:
    """Horizontal bar chart of per-source RMS horizontal error (nmi).

    Parameters
    ----------
    budget : dict
        Source name -> RMS horizontal error at the end, nmi.
    top : int
        Number of largest sources shown.
    title : str
        Axes title.
    scheme : str, optional
        Scheme whose budget this is: the bars take its colour.

    Returns
    -------
    matplotlib.figure.Figure
    """
    items = sorted(budget.items(), key=lambda kv: -kv[1])[:top][::-1]
    fig = style.new_figure(style.WIDTH, 0.35 * max(len(items), 3) + 1)
    ax = fig.add_subplot()
    color = style.scheme_color(scheme) if scheme else style.series_color(0)
    ax.barh([k for k, _ in items], [v for _, v in items], color=color)
    ax.set_xlabel("RMS horizontal error at the end (nmi)")
    ax.set_title(title)
    style.grid(ax, axis="x")
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
