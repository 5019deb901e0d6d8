"""Rotation-modulation north finder (P3): figures of the report and of the accuracy study.

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


# --- the accuracy study (inserr.northfinder.accuracy) -------------------------------


def rate_figure(r: dict, req_mil: float) -> Figure:
    """Heading 1 sigma vs table rate (log-log), Monte Carlo beside the bounds.

    Parameters
    ----------
    r : dict
        :func:`inserr.northfinder.accuracy.rate_sweep` results.
    req_mil : float
        Requirement, mil.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = style.new_figure(style.WIDTH, 4.2)
    ax = fig.add_subplot()
    ref = style.ROLE_COLORS["reference"]
    rates = [row["rate_deg_s"] for row in r["rows"]]
    for k, (label, marker) in enumerate((("default", "o-"), ("stress", "s-"))):
        ax.loglog(
            rates,
            [row[f"{label}_mc_sigma_mil"] for row in r["rows"]],
            marker,
            color=style.series_color(k),
            label=f"Monte Carlo, {label} gyro bias instability",
        )
        ax.loglog(rates, [row[f"{label}_crlb_bi_mil"] for row in r["rows"]], ":", color=ref, lw=0.8)
    ax.loglog(
        rates,
        [row["default_crlb_mil"] for row in r["rows"]],
        "--",
        color=ref,
        label="CRLB, white noise (dotted: + bias instability)",
    )
    ax.axhline(req_mil, color=style.ROLE_COLORS["threshold"], lw=0.8, label="requirement")
    ax.set_xlabel("table rate [deg/s]")
    ax.set_ylabel("heading 1σ at the requirement time [mil]")
    style.grid(ax, which="both")
    ax.legend()
    return style.finish(fig)


def grade_figure(g: dict, req_mil: float) -> Figure:
    """Heading 1 sigma vs gyro ARW (log-log), with both answers for the required grade.

    Parameters
    ----------
    g : dict
        :func:`inserr.northfinder.accuracy.grade_sweep` results.
    req_mil : float
        Requirement, mil.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = style.new_figure(style.WIDTH, 4.2)
    ax = fig.add_subplot()
    arw = [row["arw_deg_sqrt_h"] for row in g["rows"]]
    ax.loglog(
        arw,
        [row["mc_sigma_mil"] for row in g["rows"]],
        "o-",
        color=style.series_color(0),
        label="Monte Carlo 1σ",
    )
    ax.loglog(
        arw,
        [row["crlb_mil"] for row in g["rows"]],
        "--",
        color=style.ROLE_COLORS["reference"],
        label="CRLB",
    )
    ax.axhline(req_mil, color=style.ROLE_COLORS["threshold"], lw=0.8, label="requirement")
    need = g["required"]
    green = style.series_color(2)
    ax.axvline(
        need["monte_carlo"]["arw_deg_sqrt_h"],
        color=green,
        lw=0.8,
        label="required ARW (Monte Carlo)",
    )
    ax.axvline(
        need["crlb"]["arw_deg_sqrt_h"], color=green, ls=":", lw=0.8, label="required ARW (bound)"
    )
    ax.set_xlabel("gyro ARW [deg/√h] (bias and bias instability scaled alike)")
    ax.set_ylabel("heading 1σ at the requirement time [mil]")
    style.grid(ax, which="both")
    ax.legend()
    return style.finish(fig)


def map_figure(m: dict) -> Figure:
    """Heading and latitude bounds over heading x latitude (log10 colour maps).

    Parameters
    ----------
    m : dict
        :func:`inserr.northfinder.accuracy.heading_latitude_map` results.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = style.new_figure(style.WIDE, 4.4)
    h, lat = np.asarray(m["headings_deg"]), np.asarray(m["latitudes_deg"])
    for k, (key, label) in enumerate(
        (
            ("crlb_heading_mil", "heading CRLB [mil], log10"),
            ("crlb_latitude_deg", "latitude CRLB [deg], log10"),
        )
    ):
        ax = fig.add_subplot(1, 2, k + 1)
        z = np.log10(np.clip(np.asarray(m[key], dtype=float), 1e-6, 1e3))
        pcm = ax.pcolormesh(h, lat, z, shading="nearest", cmap="viridis")
        fig.colorbar(pcm, ax=ax, label=label)
        ax.set_xlabel("heading [deg]")
        ax.set_ylabel("latitude [deg]")
    return style.finish(fig)


def mc_map_figure(m: dict) -> Figure:
    """Monte Carlo sigma / CRLB and bias (mil) over the Monte Carlo cells.

    Parameters
    ----------
    m : dict
        :func:`inserr.northfinder.accuracy.heading_latitude_map` results.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = style.new_figure(style.WIDE, 4.4)
    cells = m["mc_cells"]
    hs = sorted({c["heading_deg"] for c in cells})
    ls = sorted({c["latitude_deg"] for c in cells})
    for k, (key, label) in enumerate(
        (("ratio", "Monte Carlo σ / CRLB"), ("mc_bias_mil", "Monte Carlo bias [mil]"))
    ):
        z = np.full((len(ls), len(hs)), np.nan)
        for c in cells:
            z[ls.index(c["latitude_deg"]), hs.index(c["heading_deg"])] = c[key]
        ax = fig.add_subplot(1, 2, k + 1)
        pcm = ax.pcolormesh(range(len(hs)), range(len(ls)), z, shading="nearest", cmap="coolwarm")
        fig.colorbar(pcm, ax=ax, label=label)
        ax.set_xticks(range(len(hs)), [f"{v:g}" for v in hs])
        ax.set_yticks(range(len(ls)), [f"{v:g}" for v in ls])
        ax.set_xlabel("heading [deg]")
        ax.set_ylabel("latitude [deg]")
    return style.finish(fig)
