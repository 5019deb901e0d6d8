"""Figures of the linear-vs-nonlinear validation (matplotlib, non-interactive backend).

Inputs in SI (linear :class:`~inserr.drift.analysis.DriftResult`, nonlinear
:class:`~inserr.reference.strapdown.ErrorHistory`); drawn in hours, nautical miles, metres
and arc-seconds.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from inserr.core.units import ARCMIN, ARCSEC, HOUR, NMI  # noqa: E402


def _linear_on(t: np.ndarray, lin_t: np.ndarray, values: np.ndarray) -> np.ndarray:
    return np.column_stack([np.interp(t, lin_t, values[:, j]) for j in range(values.shape[1])])


def horizontal_overlay(linear, nonlinear, title: str = "Horizontal position error") -> plt.Figure:
    """Linear (solid) and nonlinear (dashed) horizontal error, and the vector difference below."""
    fig, (ax, axd) = plt.subplots(
        2, 1, figsize=(8, 6), sharex=True, gridspec_kw={"height_ratios": [2, 1]}
    )
    ax.plot(
        linear.t / HOUR,
        linear.horizontal / NMI,
        color="C0",
        lw=1.2,
        label="linear (psi-angle model)",
    )
    ax.plot(
        nonlinear.t / HOUR,
        nonlinear.horizontal / NMI,
        color="C3",
        lw=1.0,
        ls="--",
        label="nonlinear reference (pyins)",
    )
    ax.set_ylabel("horizontal error (nmi)")
    ax.set_title(title)
    ax.legend(fontsize=8)
    d = nonlinear.dr[:, :2] - _linear_on(nonlinear.t, linear.t, linear.nav[:, 6:8])
    axd.plot(nonlinear.t / HOUR, np.linalg.norm(d, axis=1), color="C2", lw=0.8)
    axd.set_ylabel("|dr_nl - dr_lin| (m)")
    axd.set_xlabel("time (h)")
    for a in (ax, axd):
        a.grid(alpha=0.3)
    return fig


def attitude_overlay(linear, nonlinear) -> plt.Figure:
    """Tilts (arcsec) and heading error (arcmin), linear solid, nonlinear dashed."""
    fig, axes = plt.subplots(3, 1, figsize=(8, 6.5), sharex=True)
    labels = (
        "east tilt phi_E (arcsec)",
        "north tilt phi_N (arcsec)",
        "heading error phi_U (arcmin)",
    )
    scale = (ARCSEC, ARCSEC, ARCMIN)
    for k in range(3):
        axes[k].plot(
            linear.t / HOUR, linear.attitude[:, k] / scale[k], color="C0", lw=1.0, label="linear"
        )
        axes[k].plot(
            nonlinear.t / HOUR,
            nonlinear.phi[:, k] / scale[k],
            color="C3",
            lw=0.8,
            ls="--",
            label="nonlinear",
        )
        axes[k].set_ylabel(labels[k], fontsize=8)
        axes[k].grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel("time (h)")
    return fig


def monte_carlo_figure(mc) -> plt.Figure:
    """Monte Carlo horizontal errors about their mean, sample std vs covariance 1 sigma (E, N)."""
    fig, axes = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    t = mc.t / HOUR
    dev = mc.samples - mc.samples.mean(axis=0)
    std = np.std(mc.samples, axis=0, ddof=1)
    sig = np.sqrt(np.maximum(np.diagonal(mc.cov, axis1=1, axis2=2), 0.0))
    for k, name in enumerate(("east", "north")):
        ax = axes[k]
        for r in range(min(len(dev), 30)):
            ax.plot(t, dev[r, :, k], color="0.7", lw=0.5)
        ax.plot(t, std[:, k], color="C3", lw=1.2, ls="--", label="Monte Carlo sample std")
        ax.plot(t, sig[:, k], color="C0", lw=1.2, label="covariance 1 sigma")
        ax.plot(t, -sig[:, k], color="C0", lw=1.2)
        ax.set_ylabel(f"{name} error about mean (m)")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[0].set_title(f"Monte Carlo ({len(mc.runs)} runs) vs covariance")
    axes[-1].set_xlabel("time (h)")
    return fig
