"""Figures of the alignment studies, in the inserr figure style.

σ(t) of the attitude and IMU-frame bias states per scheme, and the estimation error
of one simulated run against its ±1σ; inputs are
:class:`~inserr.alignment.filter.AlignmentResult` (SI), drawn in minutes and the
engineering unit of each state (:data:`inserr.alignment.filter.UNITS`). Every
function returns a :class:`matplotlib.figure.Figure` built without pyplot
(:mod:`inserr.output.figure_style`).
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure

from inserr.alignment.filter import STATES, UNITS, AlignmentResult
from inserr.alignment.study import SHOWN
from inserr.output import figure_style as style

#: Panel titles of the shown states.
LABELS = {
    "phi_e": "φE (arcsec)",
    "phi_n": "φN (arcsec)",
    "phi_u": "φU heading (arcmin)",
    "gyro_bias_x": "gyro bias x (deg/h)",
    "gyro_bias_y": "gyro bias y (deg/h)",
    "gyro_bias_z": "gyro bias z (deg/h)",
    "accel_bias_x": "accel bias x (µg)",
    "accel_bias_y": "accel bias y (µg)",
    "accel_bias_z": "accel bias z (µg)",
}


def sigma_figure(results: dict[str, AlignmentResult], states=SHOWN, title: str = "") -> Figure:
    """σ(t) of every shown state, one panel per state, one line per scheme (log scale).

    Parameters
    ----------
    results : dict
        Scheme name -> alignment result.
    states : sequence of str
        States shown, one panel each (names of :data:`inserr.alignment.filter.STATES`).
    title : str
        Figure title (none by default).

    Returns
    -------
    matplotlib.figure.Figure
        Time in minutes, σ in each state's engineering unit.
    """
    cols = 3
    rows = math.ceil(len(states) / cols)
    fig, axes = style.subplots(rows, cols, width=style.WIDE, height=2.6 * rows, sharex=True)
    axes = np.atleast_1d(axes).reshape(-1)
    for ax, s in zip(axes, states, strict=False):
        i = STATES.index(s)
        for k, (name, r) in enumerate(results.items()):
            ax.plot(
                r.t / 60.0,
                r.sigma[:, i] / UNITS[s][1],
                color=style.scheme_color(name, k),
                lw=1.0,
                label=name,
            )
        sig = np.concatenate([r.sigma[:, i] for r in results.values()])
        # Log scale only where sigma spans a decade or more (else log ticks are unreadable).
        if sig.min() > 0 and sig.max() / sig.min() >= 10.0:
            ax.set_yscale("log")
        ax.set_title(LABELS.get(s, s))
        style.grid(ax, which="both")
    for ax in axes[len(states) :]:
        ax.set_visible(False)
    for ax in axes[-cols:]:
        ax.set_xlabel("time (min)")
    axes[0].legend()
    if title:
        style.suptitle(fig, title)
    return style.finish(fig)


def error_figure(results: dict[str, AlignmentResult], states=("phi_e", "phi_n", "phi_u")) -> Figure:
    """Attitude estimation error of each scheme's simulated run with its ±1σ (dashed).

    Parameters
    ----------
    results : dict
        Scheme name -> alignment result (with its simulated run).
    states : sequence of str
        States shown, one panel each.

    Returns
    -------
    matplotlib.figure.Figure
        Time in minutes, errors in each state's engineering unit.
    """
    fig, axes = style.subplots(1, len(states), width=style.WIDE, height=3.2, sharex=True)
    axes = np.atleast_1d(axes)
    for ax, s in zip(axes, states, strict=True):
        i = STATES.index(s)
        f = UNITS[s][1]
        for k, (name, r) in enumerate(results.items()):
            t = r.t / 60.0
            color = style.scheme_color(name, k)
            ax.plot(t, (r.estimate[:, i] - r.truth[:, i]) / f, color=color, lw=0.8, label=name)
            ax.plot(t, r.sigma[:, i] / f, color=color, lw=0.6, ls="--")
            ax.plot(t, -r.sigma[:, i] / f, color=color, lw=0.6, ls="--")
        # Start the axis at the first converged values, not at the prior.
        lim = max(3.0 * max(r.sigma[len(r.t) // 10, i] for r in results.values()) / f, 1e-12)
        ax.set_ylim(-lim, lim)
        ax.set_title(LABELS.get(s, s))
        ax.set_xlabel("time (min)")
        style.grid(ax)
    axes[0].legend()
    style.suptitle(fig, "estimation error of one simulated run (solid) and ±1σ (dashed)")
    return style.finish(fig)


def stop_sweep_figure(runs: dict[str, AlignmentResult]) -> Figure:
    """Heading and accelerometer-bias σ(t) of the stop-time sweep, one line per stop.

    Parameters
    ----------
    runs : dict
        Stop label -> filter result.
    """
    fig, axes = style.subplots(1, 2, width=style.WIDE, height=3.6)
    for k, (label, r) in enumerate(runs.items()):
        for ax, state in zip(axes, ("phi_u", "accel_bias_x"), strict=True):
            i = STATES.index(state)
            ax.semilogy(
                r.t / 60,
                r.sigma[:, i] / UNITS[state][1],
                color=style.series_color(k),
                lw=1,
                label=f"stop {label}",
            )
    axes[0].set_ylabel("heading σ (arcmin)")
    axes[1].set_ylabel("accel bias x σ (µg)")
    for ax in axes:
        ax.set_xlabel("time (min)")
        style.grid(ax, which="both")
    axes[0].legend()
    return style.finish(fig)


def comparison_figures(runs: dict) -> dict[str, Figure]:
    """The figures of the scheme comparison, by file stem.

    Parameters
    ----------
    runs : dict
        The runs of :func:`inserr.alignment.comparison.compare_schemes`: ``static`` and
        ``swing`` (scheme -> result) and ``stop_sweep`` (stop label -> result).

    Returns
    -------
    dict
        ``sigma_static``, ``sigma_swing``, ``attitude_error_static``, ``stop_sweep``.
    """
    return {
        "sigma_static": sigma_figure(runs["static"], title="static base"),
        "sigma_swing": sigma_figure(runs["swing"], title="P0 swinging base"),
        "attitude_error_static": error_figure(runs["static"]),
        "stop_sweep": stop_sweep_figure(runs["stop_sweep"]),
    }
