"""P1-style figures of a calibration Monte Carlo, in the inserr figure style.

Inputs are :class:`~inserr.calibration.estimation.SensorResult` (SI); parameters
are drawn in ppm, arcsec, deg/h or micro-g (:func:`inserr.calibration.estimation.parameter_unit`).
Every function returns a :class:`matplotlib.figure.Figure` built without pyplot
(:mod:`inserr.output.figure_style`).
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from inserr.calibration.estimation import PARAMETER_NAMES, SensorResult, parameter_unit
from inserr.output import figure_style as style


def deviation_figure(result: SensorResult, title: str) -> Figure:
    """P1-style figure: estimate minus truth for every run, one panel per parameter.

    The dashed lines mark +-1 predicted sigma (CRLB and positioning error combined).

    Parameters
    ----------
    result : SensorResult
        Monte Carlo result of one triad (SI).
    title : str
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        4 x 3 panels, deviations in ppm, arcsec, deg/h or micro-g against the run number.
    """
    fig, axes = style.subplots(4, 3, width=style.WIDE, height=8.0, sharex=True)
    dev = result.deviations
    runs = np.arange(1, dev.shape[0] + 1)
    ref = style.ROLE_COLORS["reference"]
    for j, name in enumerate(PARAMETER_NAMES):
        ax = axes.flat[j]
        unit, f = parameter_unit(name, result.sensor)
        if result.identifiability.identifiable[j]:
            ax.plot(runs, dev[:, j] / f, ".", ms=3, color=style.series_color(0))
            s = result.predicted_std[j] / f
            ax.axhline(s, ls="--", lw=0.8, color=ref)
            ax.axhline(-s, ls="--", lw=0.8, color=ref)
            ax.axhline(0.0, lw=0.5, color="0.5")
        else:
            ax.text(
                0.5,
                0.5,
                "not identifiable",
                ha="center",
                va="center",
                transform=ax.transAxes,
                fontsize=style.FONT["annotation"],
            )
        ax.set_title(f"{name} [{unit}]")
    for ax in axes[-1]:
        ax.set_xlabel("run")
    style.suptitle(fig, title)
    return style.finish(fig)


def std_figure(results: dict[str, dict[str, SensorResult]], sensor: str, title: str) -> Figure:
    """Bar chart per parameter: Monte Carlo std of each method beside its CRLB and prediction.

    Values are relative to the predicted std of the first method, so the three units
    (ppm, arcsec, deg/h) share one axis.

    Parameters
    ----------
    results : dict
        Label of each method -> ``{"gyro": SensorResult, "accel": SensorResult}``.
    sensor : str
        "gyro" or "accel".
    title : str
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        One group of bars per parameter (dimensionless ratios).
    """
    fig = style.new_figure(style.WIDE, 4.5)
    ax = fig.subplots()
    names = list(PARAMETER_NAMES)
    x = np.arange(len(names))
    first = next(iter(results.values()))[sensor]
    ref = np.where(np.isfinite(first.predicted_std), first.predicted_std, np.nan)
    width = 0.8 / max(1, len(results))
    crlb, predicted = style.ROLE_COLORS["reference"], style.ROLE_COLORS["threshold"]
    for k, (label, res) in enumerate(results.items()):
        r = res[sensor]
        off = (k - (len(results) - 1) / 2) * width
        ax.bar(x + off, r.std / ref, width, color=style.series_color(k), label=f"{label}: MC std")
        ax.plot(x + off, r.crlb_sigma / ref, "_", color=crlb, ms=12)
        ax.plot(x + off, r.predicted_std / ref, "_", color=predicted, ms=12)
    ax.plot([], [], "_", color=crlb, label="CRLB (noise only)")
    ax.plot([], [], "_", color=predicted, label="CRLB + positioning error")
    ax.set_xticks(x, names, rotation=45)
    ax.set_ylabel(f"std / predicted std of {next(iter(results))}")
    ax.set_title(title)
    ax.legend()
    return style.finish(fig)


#: Units of the parameter classes of :func:`class_sweep_figure` (gyro).
_CLASS_UNITS = {"sf": "ppm", "mis": "arcsec", "bias": "deg/h"}


def class_sweep_figure(
    series: dict[str, dict[str, list]],
    xlabel: str,
    title: str,
    logx: bool = True,
    logy: bool = True,
) -> Figure:
    """Three panels (scale factors, misalignments, biases): swept gyro class-RMS sigma.

    Parameters
    ----------
    series : dict
        Label -> ``{"x": [...], "mc": [class RMS dict, ...], "pred": [...]}`` (class
        RMS in ppm, arcsec, deg/h; :func:`inserr.calibration.comparison.class_rms`).
        Markers: Monte Carlo std; lines: prediction.
    xlabel, title : str
    logx, logy : bool
        Logarithmic axes.

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig, axes = style.subplots(1, 3, width=style.WIDE, height=4.0)
    for ax, cls in zip(axes, _CLASS_UNITS, strict=True):
        for k, (label, s) in enumerate(series.items()):
            color = style.series_color(k)
            xs = s["x"]
            ax.plot(xs, [v[cls] for v in s["mc"]], "o", color=color, label=f"{label} MC")
            ax.plot(xs, [v[cls] for v in s["pred"]], "-", color=color, label=f"{label} predicted")
        if logx:
            ax.set_xscale("log")
        if logy:
            ax.set_yscale("log")
        ax.set_xlabel(xlabel)
        ax.set_ylabel(f"RMS std of {cls} [{_CLASS_UNITS[cls]}]")
        style.grid(ax, which="both")
    axes[0].legend()
    style.suptitle(fig, title)
    return style.finish(fig)


#: Line styles of the fitted terms' slope lines in the Allan-deviation figure.
_TERM_STYLES = {
    "white": ("--", "slope -1/2: angle / velocity random walk"),
    "bias_instability": ("-.", "slope 0: bias instability"),
    "rate_random_walk": (":", "slope +1/2: rate random walk"),
    "rate_ramp": ((0, (5, 1, 1, 1, 1, 1)), "slope +1: rate ramp"),
}


def allan_figure(fit, title: str = "") -> Figure:
    """Allan deviation of every axis with the fitted terms and their intervals.

    Two rows (gyro in deg/h, accelerometer in micro-g) by three columns (x, y, z),
    log-log: the measured overlapping Allan deviation with its 1-sigma error bar from
    the number of clusters, the fitted curve with its confidence band (shaded), and
    the slope line of every term the data resolves. One legend below the panels.

    Parameters
    ----------
    fit : inserr.calibration.allan.NoiseFit
        The fitted recording (SI).
    title : str
        Figure title (default: the recording's file name).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    from inserr.calibration.allan import ADEV_UNITS, AXES, SENSORS

    fig, axes = style.fixed_grid(
        2,
        3,
        width=style.WIDE,
        panel_height=2.9,
        left=0.85,
        bottom=1.15,
        wspace=0.75,
        hspace=0.55,
        squeeze=False,
    )
    pct = f"{fit.confidence:.0%}"
    for i, sensor in enumerate(SENSORS):
        unit, si = ADEV_UNITS[sensor]
        for j, axis in enumerate(AXES):
            ax = axes[i, j]
            f = fit.axes[(sensor, axis)]
            c = f.curve
            color = style.series_color(j)
            tau = np.geomspace(c.tau[0], c.tau[-1], 200)
            lo, hi = f.model_band(tau)
            ax.fill_between(tau, lo / si, hi / si, color=color, alpha=0.2, lw=0)
            ax.plot(tau, f.model(tau) / si, color=color, lw=1.3)
            ax.errorbar(
                c.tau,
                c.adev / si,
                yerr=c.rel_error * c.adev / si,
                fmt="o",
                ms=3,
                color="k",
                elinewidth=0.8,
                capsize=1.5,
            )
            for name, term in f.terms.items():
                if term.resolved:
                    ls, _ = _TERM_STYLES[name]
                    ax.plot(tau, f.term_line(name, tau) / si, color="0.35", lw=0.9, ls=ls)
            ax.set_xscale("log")
            ax.set_yscale("log")
            # Limits from the data: an interval reaching 0 runs to the bottom edge.
            ax.set_ylim(0.3 * c.adev.min() / si, 3.0 * c.adev.max() / si)
            ax.set_title(f"{sensor} {axis}")
            style.grid(ax)
            if j == 0:
                ax.set_ylabel(f"Allan deviation ({unit})")
            if i == 1:
                ax.set_xlabel("averaging time tau (s)")
    handles = [
        Line2D([], [], color="k", marker="o", ls="", ms=3, label="data, 1-sigma from clusters"),
        Line2D([], [], color="0.2", lw=1.3, label="fitted sum (axis colour)"),
        Patch(color="0.2", alpha=0.2, label=f"{pct} interval of the fit"),
    ] + [
        Line2D([], [], color="0.35", lw=0.9, ls=ls, label=lab) for ls, lab in _TERM_STYLES.values()
    ]
    fig.legend(handles=handles, loc="lower center", ncols=4, frameon=False, fontsize=7)
    from pathlib import Path

    style.suptitle(fig, title or f"Allan deviation: {Path(fit.recording.source).name}")
    return style.finish(fig)
