"""Figures of the linear-vs-nonlinear validation, in the inserr figure style.

Inputs in SI (linear :class:`~inserr.drift.analysis.DriftResult`, nonlinear
:class:`~inserr.reference.strapdown.ErrorHistory`); drawn in hours, nautical miles, metres
and arc-seconds. Every function returns a :class:`matplotlib.figure.Figure` built
without pyplot (:mod:`inserr.output.figure_style`).
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from inserr.core.units import ARCMIN, ARCSEC, HOUR, NMI
from inserr.output import figure_style as style


def _linear_on(t: np.ndarray, lin_t: np.ndarray, values: np.ndarray) -> np.ndarray:
    return np.column_stack([np.interp(t, lin_t, values[:, j]) for j in range(values.shape[1])])


def horizontal_overlay(linear, nonlinear, title: str = "Horizontal position error") -> Figure:
    """Linear (solid) and nonlinear (dashed) horizontal error, and the vector difference below."""
    fig, (ax, axd) = style.subplots(
        2, 1, height=6.0, sharex=True, gridspec_kw={"height_ratios": [2, 1]}
    )
    ax.plot(
        linear.t / HOUR,
        linear.horizontal / NMI,
        color=style.ROLE_COLORS["linear"],
        lw=1.2,
        label="linear (psi-angle model)",
    )
    ax.plot(
        nonlinear.t / HOUR,
        nonlinear.horizontal / NMI,
        color=style.ROLE_COLORS["nonlinear"],
        lw=1.0,
        ls="--",
        label="nonlinear reference (pyins)",
    )
    ax.set_ylabel("horizontal error (nmi)")
    ax.set_title(title)
    ax.legend()
    d = nonlinear.dr[:, :2] - _linear_on(nonlinear.t, linear.t, linear.nav[:, 6:8])
    axd.plot(
        nonlinear.t / HOUR, np.linalg.norm(d, axis=1), color=style.ROLE_COLORS["difference"], lw=0.8
    )
    axd.set_ylabel("|dr_nl - dr_lin| (m)")
    axd.set_xlabel("time (h)")
    for a in (ax, axd):
        style.grid(a)
    return style.finish(fig)


def attitude_overlay(linear, nonlinear) -> Figure:
    """Tilts (arcsec) and heading error (arcmin), linear solid, nonlinear dashed."""
    fig, axes = style.subplots(3, 1, height=6.5, sharex=True)
    labels = (
        "east tilt phi_E (arcsec)",
        "north tilt phi_N (arcsec)",
        "heading error phi_U (arcmin)",
    )
    scale = (ARCSEC, ARCSEC, ARCMIN)
    for k in range(3):
        axes[k].plot(
            linear.t / HOUR,
            linear.attitude[:, k] / scale[k],
            color=style.ROLE_COLORS["linear"],
            lw=1.0,
            label="linear",
        )
        axes[k].plot(
            nonlinear.t / HOUR,
            nonlinear.phi[:, k] / scale[k],
            color=style.ROLE_COLORS["nonlinear"],
            lw=0.8,
            ls="--",
            label="nonlinear",
        )
        axes[k].set_ylabel(labels[k])
        style.grid(axes[k])
    axes[0].legend()
    axes[-1].set_xlabel("time (h)")
    return style.finish(fig)


def monte_carlo_figure(mc) -> Figure:
    """Monte Carlo horizontal errors about their mean, sample std vs covariance 1 sigma (E, N)."""
    fig, axes = style.subplots(2, 1, height=6.0, sharex=True)
    t = mc.t / HOUR
    dev = mc.samples - mc.samples.mean(axis=0)
    std = np.std(mc.samples, axis=0, ddof=1)
    sig = np.sqrt(np.maximum(np.diagonal(mc.cov, axis1=1, axis2=2), 0.0))
    for k, name in enumerate(("east", "north")):
        ax = axes[k]
        for r in range(min(len(dev), 30)):
            ax.plot(t, dev[r, :, k], color=style.ROLE_COLORS["sample"], lw=0.5)
        ax.plot(
            t,
            std[:, k],
            color=style.ROLE_COLORS["nonlinear"],
            lw=1.2,
            ls="--",
            label="Monte Carlo sample std",
        )
        ax.plot(
            t, sig[:, k], color=style.ROLE_COLORS["reference"], lw=1.2, label="covariance 1 sigma"
        )
        ax.plot(t, -sig[:, k], color=style.ROLE_COLORS["reference"], lw=1.2)
        ax.set_ylabel(f"{name} error about mean (m)")
        style.grid(ax)
    axes[0].legend()
    axes[0].set_title(f"Monte Carlo ({len(mc.runs)} runs) vs covariance")
    axes[-1].set_xlabel("time (h)")
    return style.finish(fig)
