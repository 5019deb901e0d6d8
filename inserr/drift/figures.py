"""Figures for drift reports (matplotlib, non-interactive backend).

All functions take results in SI and draw in engineering units (hours, nautical
miles, arc-seconds/arc-minutes), returning a matplotlib Figure.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from inserr.core.units import ARCMIN, ARCSEC, HOUR, NMI  # noqa: E402


def horizontal_error(results: dict, title: str = "Horizontal position error") -> plt.Figure:
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
    fig, axes = plt.subplots(
        rows,
        cols,
        figsize=(8 if cols == 1 else 11, 1.2 + 2.6 * rows),
        sharex=True,
        sharey=True,
        squeeze=False,
    )
    for i, (name, r) in enumerate(results.items()):
        _horizontal_panel(axes.flat[i], name, r, f"C{i}")
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("time (h)")
    for ax in axes[:, 0]:
        ax.set_ylabel("horizontal error (nmi)")
    fig.suptitle(title)
    fig.tight_layout()
    return fig


def _horizontal_panel(ax, name: str, r, color: str) -> None:
    ax.plot(r.t / HOUR, r.horizontal / NMI, color=color, lw=1.0, label="signs as given")
    ax.plot(
        r.t_cov / HOUR,
        r.rms_horizontal / NMI,
        color="k",
        lw=0.9,
        ls="--",
        label="RMS, unknown signs",
    )
    ax.plot(
        r.t_cov / HOUR,
        r.worst_horizontal / NMI,
        color="C3",
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
    ax.set_title(name, fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)


def attitude_errors(results: dict) -> plt.Figure:
    """Level tilts (arcsec) and heading error (arcmin) of the deterministic run(s)."""
    fig, axes = plt.subplots(3, 1, figsize=(8, 6.5), sharex=True)
    labels = (
        "east tilt phi_E (arcsec)",
        "north tilt phi_N (arcsec)",
        "heading error phi_U (arcmin)",
    )
    scale = (ARCSEC, ARCSEC, ARCMIN)
    for i, (name, r) in enumerate(results.items()):
        for k in range(3):
            axes[k].plot(r.t / HOUR, r.attitude[:, k] / scale[k], color=f"C{i}", lw=0.8, label=name)
    for k in range(3):
        axes[k].set_ylabel(labels[k], fontsize=8)
        axes[k].grid(alpha=0.3)
    axes[-1].set_xlabel("time (h)")
    axes[0].legend(fontsize=8)
    return fig


def error_budget(
    budget: dict[str, float], top: int = 15, title: str = "Error budget at the end"
) -> plt.Figure:
    """Horizontal bar chart of per-source RMS horizontal error (nmi)."""
    items = sorted(budget.items(), key=lambda kv: -kv[1])[:top][::-1]
    fig, ax = plt.subplots(figsize=(7, 0.35 * max(len(items), 3) + 1))
    ax.barh([k for k, _ in items], [v for _, v in items], color="C0")
    ax.set_xlabel("RMS horizontal error at the end (nmi)")
    ax.set_title(title)
    ax.grid(alpha=0.3, axis="x")
    return fig


def table_angle(timeline, title: str = "Table angle and horizontal projection") -> plt.Figure:
    """Outer/inner gimbal angles and the horizontal projection of the IMU x axis vs time."""
    t_end = timeline.duration
    t = np.linspace(0.0, t_end, min(20000, int(t_end) * 4 + 2))
    c = timeline.attitude_at(t)
    table = timeline.meta.get("table")
    motion = timeline.meta.get("motion")
    fig, axes = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    if table is not None:
        a, b = table.angles_at(t, motion)
        axes[0].plot(t / 60, np.degrees(a), lw=1, label="outer (azimuth)")
        if np.any(b != 0):
            axes[0].plot(t / 60, np.degrees(b), lw=1, label="inner")
        axes[0].legend(fontsize=8)
    axes[0].set_ylabel("gimbal angle (deg)")
    for i, lab in enumerate(("E", "N")):
        axes[1].plot(t / 60, c[:, i, 0], lw=1, label=f"C_s^n[{lab}, x]")
        axes[1].plot(t / 60, c[:, i, 1], lw=1, ls="--", label=f"C_s^n[{lab}, y]")
    axes[1].set_ylabel("horizontal projection")
    axes[1].set_xlabel("time (min)")
    axes[1].legend(fontsize=7, ncol=2)
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].set_title(title)
    return fig


def close(fig) -> None:
    """Close a figure (when it is not added to a report)."""
    plt.close(fig)
