"""Rotation-modulation north finder (P3): figures shared by the CLI report and the analysis.

Figures are built on :class:`matplotlib.figure.Figure` directly, so no GUI backend
is ever needed.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from inserr.core.units import DEG, MIL
from inserr.northfinder.study import CONVERGENCE_FRACTION, CONVERGENCE_TOLERANCE, MonteCarloResult


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
    fig = Figure(figsize=(7.5, 4.2))
    ax = fig.add_subplot()
    t = result.times / 60.0
    ax.semilogy(t, result.heading_sigma() / MIL, label="Monte Carlo 1σ")
    ax.semilogy(t, np.abs(result.heading_bias()) / MIL, ":", label="Monte Carlo |bias|")
    ax.semilogy(t, result.bound.heading / MIL, "k--", label="CRLB (white noise)")
    ax.semilogy(t, result.bound_bi.heading / MIL, "k:", lw=0.8, label="CRLB + bias instability")
    ax.axhline(CONVERGENCE_TOLERANCE / MIL, color="r", lw=0.8, label="0.5 mil")
    ax.set_xlabel("time [min]")
    ax.set_ylabel("heading error [mil]")
    ax.set_ylim(1e-2, 1e2)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title or f"Heading error, {result.n_runs} runs")
    return fig


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
    fig = Figure(figsize=(7.5, 3.2))
    ax = fig.add_subplot()
    ax.plot(result.times / 60.0, result.fraction_within())
    ax.axhline(CONVERGENCE_FRACTION, color="r", lw=0.8, label="68 %")
    tc = result.convergence_time()
    if tc is not None:
        ax.axvline(tc / 60.0, color="g", lw=0.8, label=f"converged at {tc:.0f} s")
    ax.set_xlabel("time [min]")
    ax.set_ylabel("fraction within 0.5 mil")
    ax.set_ylim(0, 1.02)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return fig


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
    fig = Figure(figsize=(7.5, 3.6))
    ax = fig.add_subplot()
    t = result.times / 60.0
    ax.semilogy(t, result.lat_sigma() / DEG, label="Monte Carlo 1σ")
    ax.semilogy(t, np.abs(result.lat_bias()) / DEG, ":", label="Monte Carlo |bias|")
    ax.semilogy(t, result.bound.lat / DEG, "k--", label="CRLB")
    ax.set_xlabel("time [min]")
    ax.set_ylabel("latitude error [deg]")
    ax.set_ylim(1e-3, 1e2)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return fig
