"""Rotation-modulation north finder (P3): figures shared by the report and the analysis.

Figures are built on :class:`matplotlib.figure.Figure` directly, in the inserr
figure style (:mod:`inserr.output.figure_style`), so no GUI backend is ever needed.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from inserr.core.units import DEG, MIL
from inserr.northfinder.study import CONVERGENCE_FRACTION, CONVERGENCE_TOLERANCE, MonteCarloResult
from inserr.output import figure_style as style


def heading_history_figure(result: MonteCarloResult, title: str = "") -> Figure:
    """Plot heading error vs time: Monte Carlo 1 sigma and |bias| beside the Cramér-Rao bound.

    Left axis in mil (log scale), time in minutes; the 0.5 mil line is the
    convergence tolerance.

    Parameters
    ----------
    result : MonteCarloResult
        Error histories (rad, s) and the bounds with and without bias instability.
    title : str
        Axes title (default: "Heading error, <n> runs").

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = style.new_figure(style.WIDTH, 4.2)
    ax = fig.add_subplot()
    t = result.times / 60.0
    ref = style.ROLE_COLORS["reference"]
    ax.semilogy(
        t, result.heading_sigma() / MIL, color=style.series_color(0), label="Monte Carlo 1σ"
    )
    ax.semilogy(
        t,
        np.abs(result.heading_bias()) / MIL,
        ":",
        color=style.series_color(1),
        label="Monte Carlo |bias|",
    )
    ax.semilogy(t, result.bound.heading / MIL, "--", color=ref, label="CRLB (white noise)")
    ax.semilogy(
        t, result.bound_bi.heading / MIL, ":", color=ref, lw=0.8, label="CRLB + bias instability"
    )
    ax.axhline(
        CONVERGENCE_TOLERANCE / MIL, color=style.ROLE_COLORS["threshold"], lw=0.8, label="0.5 mil"
    )
    ax.set_xlabel("time [min]")
    ax.set_ylabel("heading error [mil]")
    ax.set_ylim(1e-2, 1e2)
    style.grid(ax, which="both")
    ax.legend()
    ax.set_title(title or f"Heading error, {result.n_runs} runs")
    return style.finish(fig)


def convergence_figure(result: MonteCarloResult) -> Figure:
    """Plot the fraction of runs with ``|heading error| <= 0.5 mil`` vs time.

    The 68 % line and, if reached, the convergence time are marked; time in minutes.

    Parameters
    ----------
    result : MonteCarloResult
        Heading error histories (rad) at the filter-period times (s).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = style.new_figure(style.WIDTH, 3.2)
    ax = fig.add_subplot()
    ax.plot(result.times / 60.0, result.fraction_within(), color=style.series_color(0))
    ax.axhline(CONVERGENCE_FRACTION, color=style.ROLE_COLORS["threshold"], lw=0.8, label="68 %")
    tc = result.convergence_time()
    if tc is not None:
        ax.axvline(tc / 60.0, color=style.series_color(2), lw=0.8, label=f"converged at {tc:.0f} s")
    ax.set_xlabel("time [min]")
    ax.set_ylabel("fraction within 0.5 mil")
    ax.set_ylim(0, 1.02)
    style.grid(ax)
    ax.legend()
    return style.finish(fig)


def latitude_history_figure(result: MonteCarloResult) -> Figure:
    """Plot latitude error vs time: Monte Carlo 1 sigma and |bias| beside the bound.

    Error in deg (log scale), time in minutes. With latitude known the curves are
    empty (NaN).

    Parameters
    ----------
    result : MonteCarloResult
        Latitude error histories (rad) and the white-noise bound.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = style.new_figure(style.WIDTH, 3.6)
    ax = fig.add_subplot()
    t = result.times / 60.0
    ax.semilogy(t, result.lat_sigma() / DEG, color=style.series_color(0), label="Monte Carlo 1σ")
    ax.semilogy(
        t,
        np.abs(result.lat_bias()) / DEG,
        ":",
        color=style.series_color(1),
        label="Monte Carlo |bias|",
    )
    ax.semilogy(t, result.bound.lat / DEG, "--", color=style.ROLE_COLORS["reference"], label="CRLB")
    ax.set_xlabel("time [min]")
    ax.set_ylabel("latitude error [deg]")
    ax.set_ylim(1e-3, 1e2)
    style.grid(ax, which="both")
    ax.legend()
    return style.finish(fig)
