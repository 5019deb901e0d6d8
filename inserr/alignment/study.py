"""Alignment studies: the filter of :mod:`inserr.alignment.filter` per scheme; tables, figures.

Shared by ``inserr align`` and ``analyses/alignment_observability``: build the IMU
attitude timeline of an indexing scheme running during alignment, run the filter
for several schemes on the same base, and turn the results into tables, sigma(t)
figures and an :class:`~inserr.output.report.Report`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from inserr.alignment.filter import (
    STATES,
    UNITS,
    AlignmentResult,
    Prior,
    Settings,
    describe_eigenvector,
    run_alignment,
)
from inserr.core.earth import Site
from inserr.core.imu import ImuErrors
from inserr.model.timeline import Timeline
from inserr.output.report import Report
from inserr.schemes.vehicle_motion import Motion

#: The states shown in tables and figures (attitude and IMU-frame biases).
SHOWN = (
    "phi_e", "phi_n", "phi_u",
    "gyro_bias_x", "gyro_bias_y", "gyro_bias_z",
    "accel_bias_x", "accel_bias_y", "accel_bias_z",
)  # fmt: skip
_LABEL = {
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


@dataclass(frozen=True)
class Base:
    """Where and how the IMU sits during alignment.

    Parameters
    ----------
    site : Site
    motion : Motion
        Static or swinging base (heading, pitch, roll; yaw swing).
    rate : float, rad/s
        Table rate of the indexing scheme.
    stop : float, s
        Stop (dwell) time of the indexing scheme.
    substep : float, s
        Sub-step of continuous base motion (see :func:`inserr.schemes.composition.build_timeline`).
    """

    site: Site
    motion: Motion
    rate: float
    stop: float
    substep: float = 1.0


def alignment_timeline(base: Base, scheme: str, duration: float) -> Timeline:
    """IMU attitude timeline of ``scheme`` running on ``base`` for ``duration`` seconds."""
    from inserr.schemes.catalogue import build_scheme
    from inserr.schemes.composition import build_timeline

    table = build_scheme(scheme, base.rate, base.stop).plan(base.motion, duration)
    return build_timeline(table, base.motion, duration, base.substep)


def run_schemes(
    base: Base,
    schemes,
    duration: float,
    imu: ImuErrors,
    prior: Prior | None = None,
    settings: Settings | None = None,
) -> dict[str, AlignmentResult]:
    """Run the alignment filter for every scheme on the same base; results by scheme name."""
    from inserr.output.progress import progress

    out = {}
    for name in progress(list(schemes), total=len(schemes), desc="schemes"):
        tl = alignment_timeline(base, name, duration)
        out[name] = run_alignment(base.site, tl, imu, prior, settings, label=name)
    return out


def engineering(name: str, value_si: float) -> float:
    """A reported state's SI value in its engineering unit (:data:`UNITS`)."""
    return float(value_si / UNITS[name][1])


def time_to_reach(t: np.ndarray, sigma: np.ndarray, level: float) -> float:
    """First time after which ``sigma`` stays at or below ``level`` (NaN if it never does)."""
    above = np.flatnonzero(sigma > level)
    if len(above) == 0:
        return float(t[0])
    if above[-1] == len(t) - 1:
        return math.nan
    return float(t[above[-1] + 1])


def summary_rows(results: dict[str, AlignmentResult], states=SHOWN) -> tuple[list[str], list[list]]:
    """Table of final sigma and convergence time: one row per state, two columns per scheme."""
    header = ["state"]
    for name in results:
        header += [f"{name} σ", f"{name} t_conv (s)"]
    rows = []
    for s in states:
        i = STATES.index(s)
        row: list = [UNITS[s][0]]
        for r in results.values():
            conv = r.convergence_time()[i]
            row += [engineering(s, r.final_sigma[i]), "—" if math.isnan(conv) else f"{conv:.0f}"]
        rows.append(row)
    return header, rows


def weakest_directions(
    result: AlignmentResult, count: int = 3, states=SHOWN
) -> list[tuple[float, str]]:
    """The ``count`` least reduced eigen-directions of the normalised final covariance."""
    w, v = result.eigen(states)
    order = np.argsort(-w)[:count]
    return [(float(w[k]), describe_eigenvector(v[:, k], states)) for k in order]


def sigma_figure(results: dict[str, AlignmentResult], states=SHOWN, title: str = ""):
    """sigma(t) of every shown state, one panel per state, one line per scheme (log scale)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cols = 3
    rows = math.ceil(len(states) / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(11, 2.6 * rows), sharex=True)
    axes = np.atleast_1d(axes).reshape(-1)
    for ax, s in zip(axes, states, strict=False):
        i = STATES.index(s)
        for k, (name, r) in enumerate(results.items()):
            ax.plot(r.t / 60.0, r.sigma[:, i] / UNITS[s][1], color=f"C{k}", lw=1.0, label=name)
        sig = np.concatenate([r.sigma[:, i] for r in results.values()])
        # Log scale only where sigma spans a decade or more (else log ticks are unreadable).
        if sig.min() > 0 and sig.max() / sig.min() >= 10.0:
            ax.set_yscale("log")
        ax.set_title(_LABEL.get(s, s), fontsize=9)
        ax.grid(alpha=0.3, which="both")
    for ax in axes[len(states) :]:
        ax.set_visible(False)
    for ax in axes[-cols:]:
        ax.set_xlabel("time (min)")
    axes[0].legend(fontsize=7)
    if title:
        fig.suptitle(title)
    fig.subplots_adjust(hspace=0.35, wspace=0.3)
    return fig


def error_figure(results: dict[str, AlignmentResult], states=("phi_e", "phi_n", "phi_u")):
    """Attitude estimation error of each scheme's simulated run with its ±1 sigma (dashed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(states), figsize=(11, 3.2), sharex=True)
    axes = np.atleast_1d(axes)
    for ax, s in zip(axes, states, strict=True):
        i = STATES.index(s)
        f = UNITS[s][1]
        for k, (name, r) in enumerate(results.items()):
            t = r.t / 60.0
            ax.plot(t, (r.estimate[:, i] - r.truth[:, i]) / f, color=f"C{k}", lw=0.8, label=name)
            ax.plot(t, r.sigma[:, i] / f, color=f"C{k}", lw=0.6, ls="--")
            ax.plot(t, -r.sigma[:, i] / f, color=f"C{k}", lw=0.6, ls="--")
        # Start the axis at the first converged values, not at the prior.
        lim = max(3.0 * max(r.sigma[len(r.t) // 10, i] for r in results.values()) / f, 1e-12)
        ax.set_ylim(-lim, lim)
        ax.set_title(_LABEL.get(s, s), fontsize=9)
        ax.set_xlabel("time (min)")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    fig.suptitle("estimation error of one simulated run (solid) and ±1σ (dashed)", fontsize=10)
    fig.subplots_adjust(wspace=0.3, top=0.82, bottom=0.15)
    return fig


def build_report(
    title: str, results: dict[str, AlignmentResult], context: list[str], payload: dict
) -> Report:
    """Report: settings, summary table, weakest directions, figures, ``results.json``."""
    rep = Report(title)
    rep.results = payload
    rep.heading("Settings")
    for line in context:
        rep.paragraph(line)
    rep.heading("Final 1σ and convergence time")
    rep.paragraph(
        "Convergence time: first time after which σ stays within 10 % of its final value; "
        "'—' = the state was not estimated (σ fell by less than 10 % of its prior)."
    )
    header, rows = summary_rows(results)
    rep.table(header, rows)
    rep.heading("Degree of observability √P0/√Pk at the end")
    deg_rows = []
    for s in SHOWN:
        i = STATES.index(s)
        deg_rows.append(
            [UNITS[s][0]] + [float(r.observability_degree()[i]) for r in results.values()]
        )
    rep.table(["state", *results], deg_rows, fmt="{:.3g}")
    rep.heading("Least reduced directions (normalised eigen-analysis of P)")
    rep.paragraph(
        "Eigen-decomposition of D0⁻¹ P D0⁻¹ with D0 = diag(prior σ): an eigenvalue of 1 is a "
        "combination of states the alignment did not improve at all."
    )
    eig_rows = []
    for name, r in results.items():
        for lam, text in weakest_directions(r):
            eig_rows.append([name, lam, text])
    rep.table(["scheme", "eigenvalue", "direction (prior-σ units)"], eig_rows, fmt="{:.3g}")
    rep.figure(
        sigma_figure(results), "sigma", "1σ of attitude and IMU-frame biases during alignment"
    )
    rep.figure(
        error_figure(results),
        "attitude_error",
        "Attitude estimation error of one simulated run and ±1σ",
    )
    return rep
