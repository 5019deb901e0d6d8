"""Indexing schemes compared on one scenario: figures per error set, schedules, motion grids.

What a scheme comparison on a moving base needs beyond :func:`~inserr.drift.study.run_scheme`:

* :func:`budget_figures` — the all-positive, RMS (unknown signs), worst-sign and
  per-source horizontal errors of one run, for any *error set* (a subset of the
  constant error sources, taken from the same run by superposition: removing the
  unmodulated z-gyro bias, or the initial errors, costs no propagation);
* :func:`table_angle_stats` and :func:`turn_phase_coherence` — what a schedule does
  (net table angle; whether its turns lock onto a periodic swing);
* :func:`compare_cases` and :func:`motion_grid` — several schemes (or variants of one) on
  one scenario, and the same over a grid of yaw-swing periods and amplitudes, run in
  worker processes;
* :func:`ratio_verdict` — one scheme against a reference over such a grid;
* :func:`step_resonance` — whether a fixed stop-and-turn step is a whole or half
  number of swing periods (where a fixed cycle accumulates the turn kicks).

The P0 reproduction (``analyses/p0_swinging_base``) is built on these.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from inserr.core.units import DEG, NMI
from inserr.drift.study import SchemeRun, run_scheme
from inserr.drift.unknown_signs import rms_norm, worst_case_norm
from inserr.scenario.schema import Scenario, load_scenario
from inserr.schemes.turntable import TableSchedule
from inserr.schemes.vehicle_motion import Motion

#: Error sets by name: which constant error sources (by :attr:`Source.name`) they keep.
ERROR_SETS: dict[str, Callable[[str], bool]] = {
    "full": lambda name: True,
    "no z-gyro bias": lambda name: name != "gyro_bias_z",
    "IMU only": lambda name: not name.startswith("initial_"),
    "biases only": lambda name: name.startswith(("gyro_bias_", "accel_bias_")),
}


@dataclass(frozen=True)
class Case:
    """A scheme as compared: a label, the scheme's name and scenario changes (dotted keys)."""

    label: str
    scheme: str
    changes: tuple[tuple[str, object], ...] = ()

    def scenario(self, scen: Scenario) -> Scenario:
        """``scen`` running this case."""
        return scen.with_changes({"scheme.name": self.scheme, **dict(self.changes)})


def source_vectors(run: SchemeRun | object, keep: Callable[[str], bool] | str = "full"):
    """Per-source horizontal error vectors of a run restricted to an error set.

    Parameters
    ----------
    run : SchemeRun or DriftResult
        A run (its :attr:`~SchemeRun.result`) or a drift result.
    keep : callable or str
        Predicate on the source name, or a key of :data:`ERROR_SETS`.

    Returns
    -------
    vectors : (Mc, N, 2) ndarray, m
        Horizontal position error (E, N) per kept source, scaled by its magnitude.
    names : list of str
        The kept sources, in column order.
    """
    res = getattr(run, "result", run)
    test = ERROR_SETS[keep] if isinstance(keep, str) else keep
    cols = [j for j, s in enumerate(res.sources) if test(s.name)]
    return res.source_horizontal[:, cols], [res.sources[j].name for j in cols]


def budget_figures(run, keep: Callable[[str], bool] | str = "full") -> dict:
    """All-positive, RMS and worst-sign horizontal error of one error set (nmi, max over the run).

    Parameters
    ----------
    run : SchemeRun or DriftResult
    keep : callable or str
        The error set (see :func:`source_vectors`).

    Returns
    -------
    dict
        ``all_positive_nmi`` (every kept error with its sign as given: P0's kind of
        figure), ``rms_nmi`` (each a random constant of that 1 sigma), ``worst_nmi``
        (the worst sign pattern), all maxima over the coarse grid;
        ``final_all_positive_nmi``; ``budget_nmi``: each source's error at the end,
        largest first.
    """
    v, names = source_vectors(run, keep)
    det = np.linalg.norm(v.sum(axis=1), axis=-1)
    budget = {n: float(np.linalg.norm(v[-1, i]) / NMI) for i, n in enumerate(names)}
    return {
        "all_positive_nmi": float(det.max() / NMI),
        "rms_nmi": float(rms_norm(v).max() / NMI),
        "worst_nmi": float(worst_case_norm(v, signs=False)[0].max() / NMI),
        "final_all_positive_nmi": float(det[-1] / NMI),
        "budget_nmi": dict(sorted(budget.items(), key=lambda kv: -kv[1])),
    }


def table_angle_stats(table: TableSchedule, motion: Motion, duration: float) -> dict:
    """Mean, largest ``|angle|`` and final outer-gimbal angle of a schedule (deg, 20001 samples)."""
    a, _ = table.angles_at(np.linspace(0.0, duration, 20001), motion)
    return {
        "mean_deg": float(np.mean(a) / DEG),
        "max_abs_deg": float(np.max(np.abs(a)) / DEG),
        "final_deg": float(a[-1] / DEG),
    }


def turn_phase_coherence(table: TableSchedule, period: float, duration: float) -> dict | None:
    """How strongly a schedule's turns lock onto a periodic swing (``docs/nulling.md``, section 2).

    With ``phi_k`` the swing phase at the start of turn ``k``, the largest
    ``|mean_k exp(i (nu k + m phi_k))|`` over the sign-pattern frequencies ``nu`` in
    {0, pi/2, pi, 3 pi/2} and the harmonics ``m`` = 1, 2, 3: 1 means the kicks of
    some sign pattern all add up (resonance), values near 0 that they cancel.

    Parameters
    ----------
    table : TableSchedule
    period : float
        Swing period, s (``inf`` for no swing: every phase is 0).
    duration : float
        Turns starting after it are left out, s.

    Returns
    -------
    dict or None
        ``value``, ``m`` and ``nu_quarter_turns`` (nu in units of pi/2) of the
        largest; None with fewer than four turns.
    """
    starts = [
        k
        for k in range(len(table))
        if table.kind[k] == "rotate" and (k == 0 or table.kind[k - 1] != "rotate")
    ]
    t = table.t0[starts]
    t = t[t < duration]
    if len(t) < 4:
        return None
    phi = 2 * math.pi * t / period
    k = np.arange(len(t))
    best = {"value": -1.0}
    for m in (1, 2, 3):
        for j, nu in enumerate((0.0, 0.5 * math.pi, math.pi, 1.5 * math.pi)):
            c = float(abs(np.mean(np.exp(1j * (nu * k + m * phi)))))
            if c > best["value"]:
                best = {"value": c, "m": m, "nu_quarter_turns": j}
    return best


def step_resonance(step: float, period: float, tol: float = 0.05) -> tuple[float, bool]:
    """A fixed step (stop + turn, s) in swing periods, and whether it is within ``tol`` of a
    whole or half number of periods (the turn kicks of some sign pattern then add up)."""
    k = step / period
    half = round(2 * k) / 2
    return k, half > 0 and abs(k - half) <= tol * half


@dataclass
class CaseRun:
    """One case of a comparison: its summary (JSON-able), run and scenario."""

    summary: dict
    run: SchemeRun
    scenario: Scenario


def run_case(scen: Scenario, case: Case, error_sets: Iterable[str] = ("full",)) -> CaseRun:
    """Run one case and summarise it: figures per error set, motor starts, table angle, noise.

    Parameters
    ----------
    scen : Scenario
        The base scenario (the case's changes are applied to it).
    case : Case
    error_sets : iterable of str
        Keys of :data:`ERROR_SETS` to summarise (:func:`budget_figures`).

    Returns
    -------
    CaseRun
        ``summary`` holds ``label``, ``scheme``, one :func:`budget_figures` dict per error
        set, ``motor_starts_per_hour``, ``fallbacks`` (closed-loop rules), the
        final noise 1 sigma (nmi), :func:`table_angle_stats`,
        :func:`turn_phase_coherence` and the wall time (s).
    """
    s = case.scenario(scen)
    t0 = time.perf_counter()
    run = run_scheme(s)
    elapsed = time.perf_counter() - t0
    table = run.table
    summary = {
        "label": case.label,
        "scheme": case.scheme,
        **{name: budget_figures(run, name) for name in error_sets},
        "motor_starts_per_hour": run.motor_starts_per_hour,
        "fallbacks": table.meta.get("fallbacks"),
        "noise_1sigma_final_nmi": float(run.result.noise_horizontal_sigma[-1] / NMI),
        "table_angle": table_angle_stats(table, s.motion, s.duration),
        "turn_phase_coherence": turn_phase_coherence(
            table, getattr(s.motion, "period", math.inf), s.duration
        ),
        "time_s": elapsed,
    }
    return CaseRun(summary, run, s)


def compare_cases(
    scen: Scenario, cases: Sequence[Case], error_sets: Iterable[str] = ("full",)
) -> dict[str, CaseRun]:
    """:func:`run_case` for every case, by label, in order."""
    return {c.label: run_case(scen, c, tuple(error_sets)) for c in cases}


def _grid_point(args: tuple) -> dict:
    """One point of :func:`motion_grid` (top level, so worker processes can run it)."""
    path, changes, period, amp, case = args
    scen = load_scenario(path).with_changes(
        {**changes, "motion.period": f"{period} s", "motion.amplitude": f"{amp} deg/s"}
    )
    r = run_case(scen, case, ("full", "no z-gyro bias")).summary
    horiz = r["no z-gyro bias"]
    return {
        "period_s": period,
        "amplitude_deg_s": amp,
        "heading_half_range_deg": amp * period / (2 * math.pi),
        "label": case.label,
        "rms_full_nmi": r["full"]["rms_nmi"],
        "rms_horizontal_nmi": horiz["rms_nmi"],
        "all_positive_horizontal_nmi": horiz["all_positive_nmi"],
        "worst_horizontal_nmi": horiz["worst_nmi"],
        "motor_starts_per_hour": r["motor_starts_per_hour"],
        "top_sources": dict(list(horiz["budget_nmi"].items())[:3]),
        "time_s": r["time_s"],
    }


def motion_grid(
    path: str | Path,
    cases: Sequence[Case],
    periods: Sequence[float],
    amplitudes: Sequence[float],
    *,
    changes: dict | None = None,
    jobs: int = 1,
) -> list[dict]:
    """Every case over a grid of yaw-swing periods (s) and amplitudes (deg/s).

    The scenario file at ``path`` (a yaw-swing motion) is loaded in each worker with
    ``changes`` and the point's period and amplitude applied; noise is whatever the
    scenario has (the figures are of the constant errors only).

    Returns
    -------
    list of dict
        One per (amplitude, period, case), in that order: ``period_s``,
        ``amplitude_deg_s``, ``heading_half_range_deg``, ``label``, ``rms_full_nmi``,
        and, without the z-gyro bias (the error no rotation about the up axis
        modulates), ``rms_horizontal_nmi``, ``all_positive_horizontal_nmi``,
        ``worst_horizontal_nmi``, ``top_sources``; ``motor_starts_per_hour``, ``time_s``.
    """
    todo = [
        (str(path), dict(changes or {}), p, a, c)
        for a in amplitudes
        for p in periods
        for c in cases
    ]
    if jobs > 1:
        with ProcessPoolExecutor(max_workers=jobs) as pool:
            return list(pool.map(_grid_point, todo))
    return [_grid_point(item) for item in todo]


def ratio_verdict(points: list[dict], reference: str, key: str = "rms_horizontal_nmi") -> dict:
    """Each case against ``reference`` over a grid of :func:`motion_grid` points.

    Returns
    -------
    dict
        Per label (the reference left out): ``cases``, ``better_or_equal`` (ratio <= 1),
        ``worse_cases`` (period, amplitude, ratio), ``largest_ratio``,
        ``smallest_ratio``, ``median_ratio``, and with a 2 % band ``better_2pct``,
        ``level_2pct``, ``worse_2pct``.
    """

    def at(p: dict) -> tuple:
        return p["period_s"], p["amplitude_deg_s"]

    ref = {at(p): p[key] for p in points if p["label"] == reference}
    out = {}
    for label in dict.fromkeys(p["label"] for p in points):
        if label == reference:
            continue
        ratios = {at(p): p[key] / ref[at(p)] for p in points if p["label"] == label}
        vals = np.array(list(ratios.values()))
        worse = sorted(k for k, r in ratios.items() if r > 1.0)

        def point(k: tuple, ratios: dict = ratios) -> dict:
            return {"period_s": k[0], "amplitude_deg_s": k[1], "ratio": ratios[k]}

        out[label] = {
            "cases": len(ratios),
            "better_or_equal": len(ratios) - len(worse),
            "worse_cases": [point(k) for k in worse],
            "largest_ratio": point(max(ratios, key=ratios.get)),
            "smallest_ratio": point(min(ratios, key=ratios.get)),
            "median_ratio": float(np.median(vals)),
            "better_2pct": int(np.sum(vals < 0.98)),
            "level_2pct": int(np.sum((vals >= 0.98) & (vals <= 1.02))),
            "worse_2pct": int(np.sum(vals > 1.02)),
        }
    return out


#: Unit-error integrals that show why a scheme drifts on a swinging base: name ->
#: (channel, what it is). Names as in :func:`inserr.schemes.nulling.error_integrals`.
INTEGRALS = {
    "bias_x": ("horizontal", "x-gyro bias: horizontal projection of IMU x (s per rad/s)"),
    "bias_y": ("horizontal", "y-gyro bias: horizontal projection of IMU y"),
    "mis_xz": ("up", "x gyro sensing z rate: tilt x yaw-rate term in the heading channel"),
    "mis_zx": ("up", "z gyro sensing x rate: the same tilt x yaw-rate term"),
    "mis_yz": ("up", "y gyro sensing z rate"),
    "mis_zy": ("up", "z gyro sensing y rate"),
    "sf_z": ("up", "z-gyro scale factor: net table (and vehicle) angle"),
}


def integral_summary(run: SchemeRun, names: Iterable[str] = tuple(INTEGRALS)) -> dict:
    """Accumulated unit-error integrals of a run, split by table phase (stops / turns).

    Driven by the table and vehicle rates only (the Earth-rate part of ``K w`` acts like
    a bias), sampled at 0.25 s (:func:`inserr.schemes.nulling.error_integrals`).

    Returns
    -------
    dict
        Per name of :data:`INTEGRALS`: ``channel``; ``stops``, ``turns`` and ``end``
        (the whole-run integral, horizontal magnitude or up component), its
        ``time_mean``, ``max_abs`` and ``half_way_abs``. Biases in s, the others in
        rad per unit error.
    """
    from inserr.schemes.nulling import error_integrals

    duration = run.history.duration
    ei = error_integrals(
        run.table,
        run.history.motion,
        np.zeros(3),
        duration,
        dt=0.25,
        t_out=np.linspace(0.0, duration, 145),
    )
    out = {}
    for name in names:
        channel = INTEGRALS[name][0]
        j = ei.names.index(name)

        horizontal = channel == "horizontal"

        def part(v: np.ndarray, horizontal: bool = horizontal) -> float:
            return float(np.linalg.norm(v[:2])) if horizontal else float(v[2])

        run_j = ei.running[:, j]
        mag = np.linalg.norm(run_j[:, :2], axis=1) if horizontal else np.abs(run_j[:, 2])
        out[name] = {
            "channel": channel,
            "stops": part(ei.by_phase["stop"][j]),
            "turns": part(ei.by_phase["turn"][j]),
            "end": part(run_j[-1]),
            "time_mean": part(run_j.mean(axis=0)),
            "max_abs": float(mag.max()),
            "half_way_abs": float(mag[len(mag) // 2]),
        }
    return out


def rms_figure(runs: dict[str, SchemeRun], keep: str = "full", title: str = ""):
    """RMS (unknown signs) horizontal error of each run against time, one error set.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from inserr.output import figure_style as style

    fig = style.new_figure(style.WIDTH, 4.5)
    ax = fig.subplots()
    for i, (label, run) in enumerate(runs.items()):
        v, _ = source_vectors(run, keep)
        t = run.result.t_cov / 3600.0
        ax.plot(t, rms_norm(v) / NMI, color=style.scheme_color(label, i), lw=1.0, label=label)
    ax.set(xlabel="time (h)", ylabel="RMS horizontal error, unknown signs (nmi)", title=title)
    style.grid(ax)
    ax.legend()
    return style.finish(fig)


def grid_figure(points: list[dict], key: str = "rms_horizontal_nmi", ylabel: str = ""):
    """A :func:`motion_grid` figure against swing period, one panel per amplitude (log-log).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from inserr.output import figure_style as style

    amps = sorted({p["amplitude_deg_s"] for p in points})
    fig = style.new_figure(style.WIDTH, 3.2 * len(amps))
    axes = np.atleast_1d(fig.subplots(len(amps), 1, sharex=True))
    for ax, amp in zip(axes, amps, strict=True):
        for i, label in enumerate(dict.fromkeys(p["label"] for p in points)):
            pts = [p for p in points if p["label"] == label and p["amplitude_deg_s"] == amp]
            pts.sort(key=lambda p: p["period_s"])
            x, y = [p["period_s"] for p in pts], [p[key] for p in pts]
            ax.plot(x, y, "o-", color=style.scheme_color(label, i), ms=3, lw=1, label=label)
        ax.set(xscale="log", yscale="log", ylabel=ylabel or key, title=f"amplitude {amp:g} deg/s")
        style.grid(ax, which="both")
    axes[0].legend()
    axes[-1].set_xlabel("swing period (s)")
    return style.finish(fig)


def comparison_table(
    rows: dict[str, dict], error_sets: Sequence[str] = ("full",)
) -> tuple[list[str], list[list]]:
    """Header and rows of a comparison of :func:`run_case` summaries (by label).

    Columns: the all-positive, RMS and worst figure of each error set (nmi), motor
    starts per hour, closed-loop fallbacks, mean and largest ``|table angle|``.
    """
    figures = {"all-positive": "all_positive_nmi", "RMS": "rms_nmi", "worst": "worst_nmi"}
    header = [
        "scheme",
        *(f"{m}, {es} (nmi)" for es in error_sets for m in figures),
        "motor starts/h",
        "fallbacks",
        "mean / max abs table angle (deg)",
    ]
    body = [
        [
            label,
            *(r[es][key] for es in error_sets for key in figures.values()),
            r["motor_starts_per_hour"],
            "-" if r["fallbacks"] is None else r["fallbacks"],
            f"{r['table_angle']['mean_deg']:.0f} / {r['table_angle']['max_abs_deg']:.0f}",
        ]
        for label, r in rows.items()
    ]
    return header, body


def drift_summary(run: SchemeRun, top: int = 6) -> dict:
    """Headline horizontal and heading figures of one run (nmi, arcmin).

    Returns
    -------
    dict
        ``scheme``; ``max_horizontal_nmi``, ``final_horizontal_nmi`` (every error as
        given), ``rms_unknown_signs_nmi``, ``worst_signs_nmi`` (maxima over the run);
        ``max_abs_heading_error_arcmin``, ``final_heading_error_arcmin``;
        ``motor_starts_per_hour``; the ``top`` largest sources at the end:
        ``horizontal_budget_nmi`` and ``heading_budget_arcmin`` (``|heading error|``).
    """
    from inserr.core.units import ARCMIN

    m = run.metrics()
    res = run.result
    heading = {
        s.name: abs(float(res.source_heading[-1, j])) / ARCMIN for j, s in enumerate(res.sources)
    }
    return {
        "scheme": run.name,
        "max_horizontal_nmi": m["max_horizontal_error_nmi"],
        "final_horizontal_nmi": m["final_horizontal_error_nmi"],
        "rms_unknown_signs_nmi": m["rms_horizontal_error_nmi"],
        "worst_signs_nmi": m["worst_case_horizontal_error_nmi"],
        "max_abs_heading_error_arcmin": float(np.abs(res.attitude[:, 2]).max() / ARCMIN),
        "final_heading_error_arcmin": float(res.attitude[-1, 2] / ARCMIN),
        "motor_starts_per_hour": m["motor_starts_per_hour"],
        "horizontal_budget_nmi": dict(list(m["error_budget"].items())[:top]),
        "heading_budget_arcmin": dict(sorted(heading.items(), key=lambda kv: -kv[1])[:top]),
    }


def cycle_summary(scen: Scenario, names: Iterable[str]) -> dict:
    """Closed-form cycle integrals of periodic schemes on the scenario's (static) motion.

    Returns
    -------
    dict
        Per scheme name: ``cycle_time_s``; ``horizontal_cycle_integral_s`` (2x2, the
        horizontal projection of IMU x, y integrated over one cycle, s), its ``stops``
        and ``turns`` parts; ``residual_drift_fraction`` (of a horizontal bias) and the
        ``equivalent_horizontal_drift_deg_h`` of the scenario's largest horizontal gyro
        bias; ``up_axis_cycle_integral_s`` (the up gyro's: the whole cycle, unmodulated);
        ``motor_starts_per_hour``.
    """
    from inserr.core.units import DEG_PER_HOUR
    from inserr.schemes.cycle_integrals import cycle_integrals

    out = {}
    bias = float(np.max(np.abs(scen.imu.gyro_bias[:2])))
    for name in names:
        ci = cycle_integrals(scen.scheme(name), scen.motion)
        out[name] = {
            "cycle_time_s": ci.cycle_time,
            "horizontal_cycle_integral_s": ci.horizontal,
            "stops_horizontal_s": ci.stops[:2, :2],
            "turns_horizontal_s": ci.turns[:2, :2],
            "residual_drift_fraction": ci.residual_drift_fraction,
            "equivalent_horizontal_drift_deg_h": ci.residual_drift_fraction * bias / DEG_PER_HOUR,
            "up_axis_cycle_integral_s": ci.full[2, 2],
            "motor_starts_per_hour": ci.motor_starts_per_hour,
        }
    return out


def heading_figure(panels: dict[str, dict[str, SchemeRun]]):
    """Heading error against time, one panel per title: ``{title: {label: run}}`` (arcmin).

    Returns
    -------
    matplotlib.figure.Figure
    """
    from inserr.core.units import ARCMIN
    from inserr.output import figure_style as style

    fig, axes = style.subplots(len(panels), 1, height=3.0 * len(panels), sharex=True)
    for ax, (title, runs) in zip(np.atleast_1d(axes), panels.items(), strict=True):
        for i, (label, run) in enumerate(runs.items()):
            r = run.result
            color = style.scheme_color(label, i)
            ax.plot(r.t / 3600.0, r.attitude[:, 2] / ARCMIN, color=color, lw=1.0, label=label)
        ax.set(ylabel="heading error (arcmin)", title=title)
        style.grid(ax)
        ax.legend()
    np.atleast_1d(axes)[-1].set_xlabel("time (h)")
    return style.finish(fig)
