"""Alignment studies: the filter of :mod:`inserr.alignment.filter` per scheme, and tables.

Shared by ``inserr align`` and ``analyses/alignment_observability``: build the IMU
attitude timeline of an indexing scheme running during alignment, run the filter
for several schemes on the same base, and turn the results into tables. The σ(t)
figures are in :mod:`inserr.alignment.figures`, the report in
:mod:`inserr.alignment.report`.
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
from inserr.schemes.vehicle_motion import Motion

#: The states shown in tables and figures (attitude and IMU-frame biases).
SHOWN = (
    "phi_e", "phi_n", "phi_u",
    "gyro_bias_x", "gyro_bias_y", "gyro_bias_z",
    "accel_bias_x", "accel_bias_y", "accel_bias_z",
)  # fmt: skip


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
