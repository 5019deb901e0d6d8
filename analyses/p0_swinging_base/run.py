"""P0 reproduction: indexing schemes on a swinging base, P0's two experiments and a sweep.

Reads ``scenario.toml`` (experiment 1, yaw period 120 s) and ``scenario_exp2.toml``
(experiment 2, 60 s) beside this file and writes ``results/`` (figures,
``results.json`` and ``REPORT.md``, every number in the report taken from the
results). The nonlinear reference of ``nonlinear.py`` (another analysis) writes
``results/nonlinear.json``; the report compares with it when it exists.

    python analyses/p0_swinging_base/run.py [--quick] [--jobs N]

``--quick`` runs 6 h cases and a three-point sweep into ``results/quick/``.

Budgets. "full" is P0's IMU budget. "horizontal" removes the z-gyro bias only: it
is the one error no rotation about the up axis can modulate, and at 0.003 deg/h it
alone is ~6 nmi after 72 h, which hides every difference between schemes. The
z-gyro scale factor and the z-gyro misalignments are kept on purpose: the table
angle and the tilt of the vehicle make them scheme-dependent (see the report).
Both budgets come from the same run (per-source superposition), so they cost one
propagation per case.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from inserr.core.units import DEG, HOUR, NMI
from inserr.drift import figures as plots
from inserr.drift.analysis import DriftResult, analyze_drift
from inserr.drift.study import describe
from inserr.drift.unknown_signs import rms_norm, worst_case_norm
from inserr.output import figure_style as style
from inserr.output.report import Report, dumps, write_text_atomic
from inserr.scenario.schema import Scenario, load_scenario
from inserr.schemes.composition import build_timeline
from inserr.schemes.nulling import error_integrals

HERE = Path(__file__).resolve().parent
EXPERIMENTS = {"exp1": "scenario.toml", "exp2": "scenario_exp2.toml"}
#: The one source no single-axis scheme can modulate; removed for the "horizontal" budget.
UNMODULATED = ("gyro_bias_z",)
SWEEP_PERIODS_S = (20, 30, 45, 60, 90, 120, 165, 240, 330, 480, 660, 1200)
SWEEP_AMPLITUDES_DEG_S = (1, 3, 6)
QUICK_HOURS = 6.0


@dataclass(frozen=True)
class Case:
    """A scheme as compared here: a label, the scheme name and scenario changes."""

    label: str
    scheme: str
    changes: tuple[tuple[str, object], ...] = ()

    def scenario(self, scen: Scenario) -> Scenario:
        return scen.with_changes({"scheme.name": self.scheme, **dict(self.changes)})


CASES = (
    Case("none", "none"),
    Case("two-position", "two-position"),
    Case("flexible (threshold)", "flexible-two-position"),
    Case("flexible (crossing)", "flexible-two-position", (("scheme.variant", "crossing"),)),
    Case("heading-isolation", "heading-isolation"),
    Case("nulling-two-position", "nulling-two-position"),
)
SWEEP_CASES = tuple(c for c in CASES if c.scheme not in ("none", "heading-isolation"))
TRADITIONAL = "two-position"
NULLING = "nulling-two-position"


# --- one case ---------------------------------------------------------------------------
def budget_summary(res: DriftResult, exclude: tuple[str, ...] = ()) -> dict:
    """All-positive, RMS and worst-case horizontal error (nmi, max over the run) of a budget.

    Computed from the per-source responses on the coarse grid, so a budget without
    some sources needs no new propagation.
    """
    keep = [j for j, s in enumerate(res.sources) if s.name not in exclude]
    v = res.source_horizontal[:, keep]
    det = np.linalg.norm(v.sum(axis=1), axis=-1)
    names = [res.sources[j].name for j in keep]
    budget = {n: float(np.linalg.norm(v[-1, i]) / NMI) for i, n in enumerate(names)}
    return {
        "all_positive_nmi": float(det.max() / NMI),
        "rms_nmi": float(rms_norm(v).max() / NMI),
        "worst_nmi": float(worst_case_norm(v)[0].max() / NMI),
        "final_all_positive_nmi": float(det[-1] / NMI),
        "budget_nmi": dict(sorted(budget.items(), key=lambda kv: -kv[1])),
    }


def table_angle_stats(timeline, duration: float) -> dict:
    """Mean, largest |.| and final outer-gimbal angle (deg) of a run's schedule."""
    table, motion = timeline.meta["table"], timeline.meta["motion"]
    t = np.linspace(0.0, duration, 20001)
    a, _ = table.angles_at(t, motion)
    return {
        "mean_deg": float(np.mean(a) / DEG),
        "max_abs_deg": float(np.max(np.abs(a)) / DEG),
        "final_deg": float(a[-1] / DEG),
    }


def phase_coherence(table, period: float, duration: float) -> dict | None:
    """How strongly the turns lock onto the swing (docs/nulling.md, section 2).

    For the swing phase ``phi_k`` at the start of turn ``k``, the largest
    ``|mean_k exp(i (nu k + m phi_k))|`` over the sign-pattern frequencies ``nu`` in
    {0, pi/2, pi, 3pi/2} and the harmonics ``m`` = 1, 2, 3: 1 means every kick adds up
    (resonance), values near 0 mean the kicks cancel. None without table turns.
    """
    rot = [
        k
        for k in range(len(table))
        if table.kind[k] == "rotate" and (k == 0 or table.kind[k - 1] != "rotate")
    ]
    t = table.t0[rot]
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


def run_case(scen: Scenario, case: Case, *, noise: bool, dt_out: float, dt_cov: float) -> dict:
    """Plan, compose and analyse one case; returns a JSON-able summary (+ the result)."""
    s = case.scenario(scen)
    t0 = time.perf_counter()
    table = s.scheme().plan(s.motion, s.duration)
    t1 = time.perf_counter()
    tl = build_timeline(table, s.motion, s.duration, s.substep)
    t2 = time.perf_counter()
    imu = s.imu if noise else s.imu.without_noise()
    res = analyze_drift(s.site, imu, s.init, tl, dt_out=dt_out, dt_cov=dt_cov, vertical=s.vertical)
    t3 = time.perf_counter()
    out = {
        "label": case.label,
        "scheme": case.scheme,
        "full": budget_summary(res),
        "horizontal": budget_summary(res, UNMODULATED),
        "motor_starts_per_hour": tl.motor_starts * HOUR / tl.duration,
        "fallbacks": table.meta.get("fallbacks"),
        "noise_1sigma_final_nmi": float(res.noise_horizontal_sigma[-1] / NMI),
        "table_angle": table_angle_stats(tl, s.duration),
        "turn_phase_coherence": phase_coherence(
            table, getattr(s.motion, "period", math.inf), s.duration
        ),
        "time_s": {"plan": t1 - t0, "timeline": t2 - t1, "analysis": t3 - t2},
    }
    return {"summary": out, "result": res, "table": table, "scenario": s}


def _sweep_point(args: tuple) -> dict:
    """One sweep case (top-level so that worker processes can run it)."""
    path, hours, period, amp, case = args
    scen = load_scenario(path)
    changes = {"motion.period": f"{period} s", "motion.amplitude": f"{amp} deg/s"}
    if hours is not None:
        changes["scenario.duration"] = f"{hours} h"
    scen = scen.with_changes(changes)
    r = run_case(scen, case, noise=False, dt_out=600.0, dt_cov=600.0)["summary"]
    return {
        "period_s": period,
        "amplitude_deg_s": amp,
        "heading_half_range_deg": amp * period / (2 * math.pi),
        "label": case.label,
        "rms_full_nmi": r["full"]["rms_nmi"],
        "rms_horizontal_nmi": r["horizontal"]["rms_nmi"],
        "all_positive_horizontal_nmi": r["horizontal"]["all_positive_nmi"],
        "worst_horizontal_nmi": r["horizontal"]["worst_nmi"],
        "motor_starts_per_hour": r["motor_starts_per_hour"],
        "top_sources": dict(list(r["horizontal"]["budget_nmi"].items())[:3]),
        "time_s": sum(r["time_s"].values()),
    }


def sweep(path: Path, hours: float | None, periods, amplitudes, jobs: int) -> list[dict]:
    """RMS horizontal error over the (period, amplitude) grid for the sweep cases."""
    todo = [(path, hours, p, a, c) for a in amplitudes for p in periods for c in SWEEP_CASES]
    if jobs > 1:
        with ProcessPoolExecutor(max_workers=jobs) as pool:
            return list(pool.map(_sweep_point, todo))
    out = []
    for i, item in enumerate(todo, 1):
        out.append(_sweep_point(item))
        r = out[-1]
        print(
            f"sweep {i}/{len(todo)} T={r['period_s']} A={r['amplitude_deg_s']} {r['label']}: "
            f"{r['rms_horizontal_nmi']:.3f} nmi",
            file=sys.stderr,
            flush=True,
        )
    return out


# --- diagnosis --------------------------------------------------------------------------
DIAGNOSED = {
    "bias_x": ("horizontal", "x-gyro bias: horizontal projection of IMU x (s per rad/s)"),
    "bias_y": ("horizontal", "y-gyro bias: horizontal projection of IMU y"),
    "mis_xz": ("up", "x gyro sensing z rate: tilt x yaw-rate term in the heading channel"),
    "mis_zx": ("up", "z gyro sensing x rate: the same tilt x yaw-rate term"),
    "mis_yz": ("up", "y gyro sensing z rate"),
    "mis_zy": ("up", "z gyro sensing y rate"),
    "sf_z": ("up", "z-gyro scale factor: net table (and vehicle) angle"),
}


def diagnose(case_run: dict) -> dict:
    """Accumulated unit-error integrals of one run, split by table phase (stop / turn)."""
    s, table = case_run["scenario"], case_run["table"]
    # Table and vehicle rates only: the Earth-rate part of K w behaves like a bias.
    ei = error_integrals(
        table, s.motion, np.zeros(3), s.duration, dt=0.25, t_out=np.linspace(0.0, s.duration, 145)
    )
    out = {}
    for name, (channel, _) in DIAGNOSED.items():
        j = ei.names.index(name)
        comp = (
            (lambda v: float(np.linalg.norm(v[:2])))
            if channel == "horizontal"
            else (lambda v: float(v[2]))
        )
        run = ei.running[:, j]
        mag = np.linalg.norm(run[:, :2], axis=1) if channel == "horizontal" else np.abs(run[:, 2])
        out[name] = {
            "channel": channel,
            "stops": comp(ei.by_phase["stop"][j]),
            "turns": comp(ei.by_phase["turn"][j]),
            "end": comp(run[-1]),
            "time_mean": comp(run.mean(axis=0)),
            "max_abs": float(mag.max()),
            "half_way_abs": float(mag[len(mag) // 2]),
        }
    return out


# --- figures ----------------------------------------------------------------------------
def horizontal_figure(runs: dict[str, dict], budget: str, title: str) -> Figure:
    """RMS (unknown signs) horizontal error of every scheme for one budget."""
    fig = style.new_figure(style.WIDTH, 4.5)
    ax = fig.subplots()
    for i, (label, r) in enumerate(runs.items()):
        res = r["result"]
        exclude = UNMODULATED if budget == "horizontal" else ()
        keep = [j for j, s in enumerate(res.sources) if s.name not in exclude]
        ax.plot(
            res.t_cov / HOUR,
            rms_norm(res.source_horizontal[:, keep]) / NMI,
            color=style.scheme_color(label, i),
            lw=1.0,
            label=label,
        )
    ax.set_xlabel("time (h)")
    ax.set_ylabel("RMS horizontal error, unknown signs (nmi)")
    ax.set_title(title)
    style.grid(ax)
    ax.legend()
    return style.finish(fig)


def table_angle_figure(runs: dict[str, dict], hours: float = 2.0) -> Figure:
    """Outer-gimbal angle over the first hours: where the flexible rule drifts away."""
    fig = style.new_figure(style.WIDTH, 4.0)
    ax = fig.subplots()
    for i, (label, r) in enumerate(runs.items()):
        if label == "none":
            continue
        s, table = r["scenario"], r["table"]
        t = np.linspace(0.0, min(hours * HOUR, s.duration), 4000)
        a, _ = table.angles_at(t, s.motion)
        ax.plot(t / 60.0, a / DEG, color=style.scheme_color(label, i), lw=0.9, label=label)
    ax.set_xlabel("time (min)")
    ax.set_ylabel("table (outer) angle (deg)")
    ax.set_title("Table angle, first hours of experiment 1")
    style.grid(ax)
    ax.legend()
    return style.finish(fig)


def sweep_figure(points: list[dict], amplitudes) -> Figure:
    """RMS horizontal error against swing period, one panel per yaw-rate amplitude."""
    fig = style.new_figure(style.WIDTH, 3.2 * len(amplitudes))
    axes = np.atleast_1d(fig.subplots(len(amplitudes), 1, sharex=True))
    labels = list(dict.fromkeys(p["label"] for p in points))
    for ax, amp in zip(axes, amplitudes, strict=True):
        for i, label in enumerate(labels):
            pts = sorted(
                (p for p in points if p["label"] == label and p["amplitude_deg_s"] == amp),
                key=lambda p: p["period_s"],
            )
            ax.plot(
                [p["period_s"] for p in pts],
                [p["rms_horizontal_nmi"] for p in pts],
                "o-",
                color=style.scheme_color(label, i),
                ms=3,
                lw=1,
                label=label,
            )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_ylabel("RMS horiz. (nmi)")
        ax.set_title(f"yaw-rate amplitude {amp} deg/s (z-gyro bias removed)")
        style.grid(ax, which="both")
    axes[0].legend()
    axes[-1].set_xlabel("swing period (s)")
    return style.finish(fig)


# --- verdicts ---------------------------------------------------------------------------
def sweep_verdict(points: list[dict]) -> dict:
    """For each scheme: against the traditional cycle over the sweep (RMS, horizontal budget)."""
    trad = {
        (p["period_s"], p["amplitude_deg_s"]): p["rms_horizontal_nmi"]
        for p in points
        if p["label"] == TRADITIONAL
    }
    out = {}
    for label in dict.fromkeys(p["label"] for p in points):
        if label == TRADITIONAL:
            continue
        ratios = {
            (p["period_s"], p["amplitude_deg_s"]): p["rms_horizontal_nmi"]
            / trad[(p["period_s"], p["amplitude_deg_s"])]
            for p in points
            if p["label"] == label
        }
        worse = sorted(k for k, r in ratios.items() if r > 1.0)
        vals = np.array(list(ratios.values()))
        worst = max(ratios, key=ratios.get)
        best = min(ratios, key=ratios.get)
        out[label] = {
            "cases": len(ratios),
            "better_or_equal": len(ratios) - len(worse),
            "worse_cases": [
                {"period_s": k[0], "amplitude_deg_s": k[1], "ratio": ratios[k]} for k in worse
            ],
            "largest_ratio": {
                "period_s": worst[0],
                "amplitude_deg_s": worst[1],
                "ratio": ratios[worst],
            },
            "smallest_ratio": {
                "period_s": best[0],
                "amplitude_deg_s": best[1],
                "ratio": ratios[best],
            },
            "median_ratio": float(np.median(list(ratios.values()))),
            "better_2pct": int(np.sum(vals < 0.98)),
            "level_2pct": int(np.sum((vals >= 0.98) & (vals <= 1.02))),
            "worse_2pct": int(np.sum(vals > 1.02)),
        }
    return out


def experiment_verdict(name: str, rows: dict[str, dict]) -> str:
    """P0's claim (flexible beats traditional) checked on one experiment."""
    t, f = rows[TRADITIONAL], rows["flexible (threshold)"]
    n = rows[NULLING]

    def cmp(key: str, budget: str) -> str:
        a, b = t[budget][key], f[budget][key]
        word = "better" if b < a else "worse"
        return f"{b:.2f} (flexible) vs {a:.2f} nmi (traditional), {word}"

    keys = [(b, k) for _, b, k in ROW_KEYS]
    wins = sum(f[b][k] < t[b][k] for b, k in keys)
    claim = (
        "supports"
        if wins == len(keys)
        else "contradicts"
        if wins == 0
        else f"only partly supports ({wins} of {len(keys)} figures better)"
    )
    return (
        f"**{name}: the model {claim} P0's claim that the flexible rule beats the traditional "
        f"one.** Flexible (threshold) against traditional, full budget: all-positive "
        f"{cmp('all_positive_nmi', 'full')}, RMS {cmp('rms_nmi', 'full')}, worst "
        f"{cmp('worst_nmi', 'full')}; without the z-gyro bias: all-positive "
        f"{cmp('all_positive_nmi', 'horizontal')}, RMS {cmp('rms_nmi', 'horizontal')}. "
        f"The nulling rule gives RMS {n['horizontal']['rms_nmi']:.2f} nmi without the z-gyro bias "
        f"({n['full']['rms_nmi']:.2f} nmi full) at {n['motor_starts_per_hour']:.2f} motor "
        f"starts/h (traditional {t['motor_starts_per_hour']:.2f})."
    )


def _initial_errors(scen: Scenario) -> str:
    """The scenario's initial errors, in the units a reader expects."""
    a, v, r = scen.init.attitude, scen.init.velocity, scen.init.position
    arcsec = DEG / 3600.0
    return (
        f"tilts {a[0] / arcsec:g}, {a[1] / arcsec:g} arcsec, heading {a[2] / (60 * arcsec):g} "
        f"arcmin; velocity {', '.join(f'{x:g}' for x in v)} m/s; position "
        f"{', '.join(f'{x:g}' for x in r)} m"
    )


def _resonance(step: float, period: float) -> tuple[float, bool]:
    """Step in swing periods, and whether it is within 5 % of a whole or half number."""
    k = step / period
    half = round(2 * k) / 2
    return k, half > 0 and abs(k - half) <= 0.05 * half


def traditional_diagnosis(scens: dict[str, Scenario], rows, diag) -> str:
    """Why the fixed step of the traditional cycle hurts on some swings (from the numbers)."""
    s1 = scens["exp1"]
    step = s1.scheme_stop + math.pi / s1.scheme_rate
    parts, resonant = [], []
    for key, scen in scens.items():
        k, res = _resonance(step, scen.motion.period)
        parts.append(f"{key}: {step:.0f} s = {k:.2f} swing periods")
        if res:
            resonant.append(key)
    text = (
        "**What the traditional cycle suffers from.** Its step (stop + turn) is fixed, so on a "
        "periodic swing the turns fall at a fixed progression of swing phases; when the step is "
        "a whole or half number of swing periods (within 5 %) the small error kick each turn "
        "leaves adds up instead of averaging out (" + "; ".join(parts) + "). "
    )
    if not resonant:
        return text + "Neither experiment is at such a resonance."
    key = resonant[0]
    t_rows = rows[key][TRADITIONAL]["horizontal"]["budget_nmi"]
    top = list(t_rows.items())[:2]
    name = "mis_xz"
    return text + (
        f"{key} is such a resonance: its largest sources (z-gyro bias removed) are "
        + ", ".join(f"{k} {v:.2f} nmi" for k, v in top)
        + f", and the tilt x yaw-rate integral ({name}) reaches "
        f"{diag[key][TRADITIONAL][name]['end']:+.2f} rad per rad at the end against "
        f"{diag[key][NULLING][name]['end']:+.3f} for the nulling rule, which lengthens each "
        "stop so that the swing phase advances by a golden section of a half period per step "
        "(docs/nulling.md)."
    )


def nulling_verdict(rows, sweep_v: dict | None) -> str:
    """The improved rule against the traditional one, every figure, plainly."""
    parts = []
    for key in ("exp1", "exp2"):
        t, n = rows[key][TRADITIONAL], rows[key][NULLING]
        figs = []
        for head, b, k in ROW_KEYS:
            ratio = n[b][k] / t[b][k]
            word = "better" if ratio < 0.98 else "worse" if ratio > 1.02 else "level"
            figs.append(f"{head.replace(' (nmi)', '')} {ratio:.2f} ({word})")
        parts.append(f"{key}: " + ", ".join(figs))
    text = (
        "**The nulling rule against the traditional cycle, every figure** (ratio nulling / "
        "traditional; within 2 % counts as level). " + "; ".join(parts) + ". "
    )
    if sweep_v:
        ratios = [sweep_v["smallest_ratio"]["ratio"], sweep_v["largest_ratio"]["ratio"]]
        text += (
            f"Over the sweep (RMS, z-gyro bias removed) it is better by more than 2 % in "
            f"{sweep_v['better_2pct']} of {sweep_v['cases']} cases, level in "
            f"{sweep_v['level_2pct']} and worse by more than 2 % in {sweep_v['worse_2pct']} "
            f"(ratios {min(ratios):.3f} to {max(ratios):.3f}). "
        )
    if any("(worse)" in p for p in parts):
        text += (
            "It is not better on every figure: each one marked worse is a sign pattern "
            "(all-positive or worst case) or budget where it loses, which is why the RMS over "
            "unknown signs, not one sign pattern, is the figure of merit here."
        )
    else:
        text += "It is better or level on every figure of both experiments."
    return text


def motor_start_check(rows, points: list[dict]) -> str:
    """P0's claim that the flexible rule starts the motor no more often than traditional."""
    out = []
    for key in ("exp1", "exp2"):
        t = rows[key][TRADITIONAL]["motor_starts_per_hour"]
        for label in ("flexible (threshold)", "flexible (crossing)", NULLING):
            if label in rows[key]:
                f = rows[key][label]["motor_starts_per_hour"]
                out.append(f"{key} {label} {f:.2f} ({'<=' if f <= t + 1e-9 else '>'} {t:.2f})")
    sweep_max = {}
    for p in points:
        sweep_max[p["label"]] = max(sweep_max.get(p["label"], 0.0), p["motor_starts_per_hour"])
    trad = sweep_max.get(TRADITIONAL)
    extra = ", ".join(f"{k} {v:.2f}" for k, v in sweep_max.items())
    over = [k for k, v in sweep_max.items() if trad is not None and v > trad + 1e-9]
    return (
        "**Motor starts per hour** (P0 claims the flexible rule needs no more than the "
        "traditional cycle): "
        + "; ".join(out)
        + f". Largest over the sweep: {extra}. "
        + (
            f"More than the traditional cycle somewhere: {', '.join(over)} (a variable turn "
            "is shorter than 180 deg at times, so more stops fit into an hour)."
            if over
            else "None exceeds the traditional cycle anywhere in the sweep."
        )
    )


def flexible_diagnosis(rows: dict[str, dict], diag: dict[str, dict]) -> str:
    """Why the flexible rule does what it does, from the budgets, phases and integrals."""
    f, t, n = rows["flexible (threshold)"], rows[TRADITIONAL], rows[NULLING]
    top = list(f["horizontal"]["budget_nmi"].items())[:4]
    d_f, d_t = diag["flexible (threshold)"], diag[TRADITIONAL]
    mis = max(("mis_xz", "mis_zx", "mis_yz", "mis_zy"), key=lambda k: abs(d_f[k]["end"]))

    def coh(r: dict) -> str:
        c = r["turn_phase_coherence"]
        return "-" if c is None else f"{c['value']:.2f} (m = {c['m']})"

    ta = f["table_angle"]
    return (
        "Its largest sources (z-gyro bias removed) are "
        + ", ".join(f"{k} {v:.2f} nmi" for k, v in top)
        + f". Its stop angles follow the heading, so its schedule settles into a pattern tied "
        f"to the swing: the turn-phase coherence is {coh(f)} (traditional {coh(t)}, nulling "
        f"{coh(n)}; 1 = the turns keep one phase relation to the swing for some sign pattern, "
        "so that pattern's kicks add up instead of cancelling; whether it hurts depends on how "
        "strong that family of kicks is, which the integrals show). The tilt x yaw-rate term "
        f"({mis}) "
        f"ends at {d_f[mis]['end']:+.3f} rad per rad of misalignment ({d_f[mis]['turns']:+.3f} "
        f"from the turns, {d_f[mis]['stops']:+.3f} from the stops; traditional "
        f"{d_t[mis]['end']:+.3f}). Its table angle has mean {ta['mean_deg']:.0f} deg, largest "
        f"|angle| {ta['max_abs_deg']:.0f} deg and final {ta['final_deg']:.0f} deg (the two "
        "variable turns need not add up to zero); the z-gyro scale factor turns the table "
        "angle into a heading error whose time-mean is "
        f"{d_f['sf_z']['time_mean']:+.2f} rad per unit scale factor (traditional "
        f"{d_t['sf_z']['time_mean']:+.2f}, nulling {diag[NULLING]['sf_z']['time_mean']:+.2f}). "
        f"Fallbacks: {f['fallbacks']}."
    )


def nonlinear_section(rep: Report, results_dir: Path, rows: dict[str, dict[str, dict]]) -> dict:
    """Linear vs nonlinear, from ``results/nonlinear.json`` when the reference has been run."""
    path = results_dir / "nonlinear.json"
    rep.heading("Linear vs nonlinear")
    if not path.is_file():
        rep.paragraph(
            "Not yet available: `results/nonlinear.json` (written by `nonlinear.py`, the full "
            "nonlinear reference with inverse-navigation IMU data as in P0) does not exist yet. "
            "Run it, then run this script again to get the side-by-side table."
        )
        return {"available": False}
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        rep.paragraph(f"`results/nonlinear.json` could not be read ({exc}); no comparison.")
        return {"available": False, "error": str(exc)}
    cases = [c for c in data.get("cases", []) if isinstance(c, dict)]
    by_file = {v: k for k, v in EXPERIMENTS.items()}
    table = []
    for c in cases:
        exp = by_file.get(c.get("scenario_file", ""), c.get("experiment", "?"))
        label = next(
            (
                lab
                for lab, r in rows.get(exp, {}).items()
                if r["scheme"] == c.get("scheme") and "crossing" not in lab
            ),
            None,
        )
        mine = rows.get(exp, {}).get(label, {}).get("full", {}).get("all_positive_nmi")
        table.append(
            [
                exp,
                c.get("scheme", "?"),
                c.get("status", "?"),
                mine if mine is not None else "-",
                c.get("linear_max_horizontal_error_nmi", "-"),
                c.get("nonlinear_max_horizontal_error_nmi", "-"),
                c.get("relative_difference", "-"),
            ]
        )
    rel = [
        c["relative_difference"]
        for c in cases
        if isinstance(c.get("relative_difference"), (int, float))
    ]
    if rel:
        rep.paragraph(
            f"**Linear and nonlinear agree**: over the {len(rel)} cases the largest relative "
            f"difference of the maximum horizontal error is {max(rel):.1e} (median "
            f"{float(np.median(rel)):.1e}), so the scheme ranking above is not an artefact "
            "of the linear error model."
        )
    rep.paragraph(
        f"From `results/nonlinear.json` ({data.get('hours', '?')} h runs, IMU at "
        f"{data.get('imu_rate_hz', '?')} Hz; see `results/NONLINEAR.md`). 'this report' is the "
        "all-positive maximum of the full budget above."
    )
    rep.table(
        [
            "experiment",
            "scheme",
            "status",
            "this report (nmi)",
            "linear there (nmi)",
            "nonlinear (nmi)",
            "relative difference",
        ],
        table,
    )
    return {"available": True, "cases": len(cases)}


# --- report -----------------------------------------------------------------------------
ROW_KEYS = (
    ("all-positive full (nmi)", "full", "all_positive_nmi"),
    ("RMS full (nmi)", "full", "rms_nmi"),
    ("worst full (nmi)", "full", "worst_nmi"),
    ("all-positive horiz. (nmi)", "horizontal", "all_positive_nmi"),
    ("RMS horiz. (nmi)", "horizontal", "rms_nmi"),
    ("worst horiz. (nmi)", "horizontal", "worst_nmi"),
)


def experiment_table(rows: dict[str, dict]) -> tuple[list[str], list[list]]:
    header = [
        "scheme",
        *(h for h, _, _ in ROW_KEYS),
        "motor starts/h",
        "fallbacks",
        "mean / max abs table angle (deg)",
        "turn-phase coherence (m, nu)",
    ]
    body = []
    for label, r in rows.items():
        ta = r["table_angle"]
        pc = r["turn_phase_coherence"]
        coh = "-" if pc is None else f"{pc['value']:.2f} ({pc['m']}, {pc['nu_quarter_turns']}pi/2)"
        body.append(
            [
                label,
                *(r[b][k] for _, b, k in ROW_KEYS),
                r["motor_starts_per_hour"],
                "-" if r["fallbacks"] is None else r["fallbacks"],
                f"{ta['mean_deg']:.0f} / {ta['max_abs_deg']:.0f}",
                coh,
            ]
        )
    return header, body


def sweep_tables(rep: Report, points: list[dict], amplitudes, periods) -> None:
    labels = list(dict.fromkeys(p["label"] for p in points))
    idx = {(p["label"], p["period_s"], p["amplitude_deg_s"]): p for p in points}
    for amp in amplitudes:
        rows = []
        for per in periods:
            rows.append(
                [
                    per,
                    amp * per / (2 * math.pi),
                    *(idx[(lab, per, amp)]["rms_horizontal_nmi"] for lab in labels),
                ]
            )
        rep.paragraph(
            f"RMS horizontal error (nmi, z-gyro bias removed), yaw-rate amplitude {amp} deg/s:"
        )
        rep.table(["period (s)", "heading half-range (deg)", *labels], rows)


def build_report(
    scens: dict[str, Scenario],
    rows,
    runs,
    diag,
    points,
    verdict,
    timing,
    results_dir,
    amplitudes,
    periods,
) -> Report:
    rep = Report("P0 reproduction: indexing on a swinging base")
    s1 = scens["exp1"]
    hours = s1.duration / HOUR
    rep.heading("Set-up")
    rep.table(
        ["item", "value"],
        [list(r) for r in describe(s1)]
        + [
            ["experiment 2 motion", scens["exp2"].motion.describe()],
            ["initial errors (E, N, U)", _initial_errors(s1)],
        ],
    )
    rep.paragraph(
        "Two budgets, both from the same runs: **full** (P0's IMU) and **horizontal** (the "
        f"z-gyro bias removed: {', '.join(UNMODULATED)}; nothing else). The z-gyro bias is the "
        "one error that rotation about the up axis cannot modulate; the z-gyro scale factor and "
        "misalignments stay because the table angle and the vehicle tilt make them depend on the "
        "scheme. 'All-positive' is every error with a + sign (P0's kind of figure); 'RMS' treats "
        "each constant error as a random constant of that size (the fair figure of merit); "
        f"'worst' is the worst sign pattern. All are maxima over the {hours:g} h. Noise (ARW, VRW) "
        f"is isotropic and so scheme-independent: its 1-sigma at {hours:g} h is "
        f"{rows['exp1'][TRADITIONAL]['noise_1sigma_final_nmi']:.2f} nmi for every scheme and is "
        "not in the tables."
    )
    rep.heading("Verdicts")
    rep.paragraph(experiment_verdict("Experiment 1 (period 120 s)", rows["exp1"]))
    rep.paragraph(experiment_verdict("Experiment 2 (period 60 s)", rows["exp2"]))
    for label, v in verdict.items():
        worse = (
            ", ".join(
                f"{w['period_s']} s / {w['amplitude_deg_s']} deg/s ({w['ratio']:.3f})"
                for w in v["worse_cases"]
            )
            or "none"
        )
        rep.paragraph(
            f"**Sweep, {label} vs traditional** (RMS, z-gyro bias removed): better or equal in "
            f"{v['better_or_equal']} of {v['cases']} (period, amplitude) cases; median ratio "
            f"{v['median_ratio']:.3f}, from {v['smallest_ratio']['ratio']:.3f} "
            f"({v['smallest_ratio']['period_s']} s, {v['smallest_ratio']['amplitude_deg_s']} "
            f"deg/s) to {v['largest_ratio']['ratio']:.3f} ({v['largest_ratio']['period_s']} s, "
            f"{v['largest_ratio']['amplitude_deg_s']} deg/s). Worse in: {worse}."
        )
    for key, name in (("exp1", "experiment 1"), ("exp2", "experiment 2")):
        f, t = rows[key]["flexible (threshold)"], rows[key][TRADITIONAL]
        word = "loses to" if f["horizontal"]["rms_nmi"] > t["horizontal"]["rms_nmi"] else "beats"
        rep.paragraph(
            f"**The flexible rule {word} the traditional one in {name} (RMS, z-gyro "
            "bias removed).** " + flexible_diagnosis(rows[key], diag[key])
        )
    rep.paragraph(traditional_diagnosis(scens, rows, diag))
    rep.paragraph(nulling_verdict(rows, verdict.get(NULLING)))
    rep.paragraph(motor_start_check(rows, points))
    for key, title in (
        ("exp1", "Experiment 1: yaw period 120 s"),
        ("exp2", "Experiment 2: yaw period 60 s"),
    ):
        rep.heading(title)
        header, body = experiment_table(rows[key])
        rep.table(header, body)
        rep.heading(f"Per-source budget (RMS at {hours:g} h, nmi, z-gyro bias removed)", 3)
        for label, r in rows[key].items():
            items = list(r["horizontal"]["budget_nmi"].items())[:6]
            rep.paragraph(f"*{label}*: " + ", ".join(f"{k} {v:.3f}" for k, v in items))
        z = rows[key][TRADITIONAL]["full"]["budget_nmi"].get("gyro_bias_z", 0.0)
        rep.paragraph(
            f"The z-gyro bias alone gives {z:.2f} nmi RMS at {hours:g} h with every scheme."
        )
        rep.heading(f"Accumulated unit-error integrals, by table phase ({hours:g} h)", 3)
        drows = []
        for label, d in diag[key].items():
            for name in ("bias_x", "mis_xz", "mis_yz", "sf_z"):
                v = d[name]
                drows.append(
                    [
                        label,
                        name,
                        v["channel"],
                        v["stops"],
                        v["turns"],
                        v["end"],
                        v["time_mean"],
                        v["max_abs"],
                    ]
                )
        rep.table(
            ["scheme", "source", "channel", "stops", "turns", "end", "time mean", "max abs"], drows
        )
        rep.paragraph(
            "Per unit error: biases in s (horizontal magnitude), the others in rad per unit "
            "(heading channel), driven by the table and vehicle rates only (the Earth-rate part "
            "acts like a bias). A bounded integral is harmless; one that grows with time drifts. "
            + "; ".join(f"{k}: {v[1]}" for k, v in DIAGNOSED.items())
            + "."
        )
    for key in ("exp1", "exp2"):
        rep.figure(
            horizontal_figure(runs[key], "full", f"{key}: full budget"),
            f"rms_{key}_full",
            f"RMS horizontal error, {key}, full budget",
        )
        rep.figure(
            horizontal_figure(runs[key], "horizontal", f"{key}: z-gyro bias removed"),
            f"rms_{key}_horizontal",
            f"RMS horizontal error, {key}, z-gyro bias removed",
        )
    rep.figure(
        plots.horizontal_error(
            {k: v["result"] for k, v in runs["exp1"].items()},
            title="Experiment 1, all errors positive (full budget)",
        ),
        "allpositive_exp1",
        "Experiment 1, all errors positive",
    )
    rep.figure(table_angle_figure(runs["exp1"]), "table_angle_exp1", "Table angle, experiment 1")
    rep.heading("Sweep of swing period and amplitude")
    rep.paragraph(
        f"P0's motion (yaw rate A cos(2 pi t / T), pitch 1 deg, roll -2 deg) for T in "
        f"{', '.join(str(p) for p in periods)} s and A in "
        f"{', '.join(str(a) for a in amplitudes)} deg/s; full budget without noise, RMS over "
        "unknown signs with the z-gyro bias removed, maximum over the run (600 s grid)."
    )
    rep.figure(sweep_figure(points, amplitudes), "sweep", "RMS horizontal error over the sweep")
    sweep_tables(rep, points, amplitudes, periods)
    rep.heading("Speed")
    rep.table(
        ["scheme", "plan (s)", "timeline (s)", "analysis with noise (s)", "total (s)"],
        [[k, v["plan"], v["timeline"], v["analysis"], sum(v.values())] for k, v in timing.items()],
    )
    rep.paragraph(
        f"Experiment 1, {hours:g} h, on this machine (shared; wall-clock). The analysis includes "
        "the deterministic run at 10 s, the random-constant superposition and the ARW/VRW "
        "covariances at 60 s."
    )
    nl = nonlinear_section(rep, results_dir, rows)
    rep.results = {
        "experiments": rows,
        "diagnosis": diag,
        "sweep": points,
        "sweep_verdict": verdict,
        "timing_s": timing,
        "nonlinear": nl,
        "budgets": {"horizontal_removes": list(UNMODULATED)},
    }
    return rep


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="6 h cases, 3-point sweep, results/quick/")
    ap.add_argument("--jobs", type=int, default=1, help="parallel processes for the sweep")
    ap.add_argument("--out", default=None, help="output directory (default results/)")
    ap.add_argument(
        "--reuse-sweep",
        action="store_true",
        help="take the sweep from the output's sweep.json when its grid matches",
    )
    args = ap.parse_args(argv)
    out = Path(args.out) if args.out else HERE / "results" / ("quick" if args.quick else "")
    hours = QUICK_HOURS if args.quick else None
    periods = (60, 120, 660) if args.quick else SWEEP_PERIODS_S
    amplitudes = (6,) if args.quick else SWEEP_AMPLITUDES_DEG_S
    scens, rows, runs, diag, timing = {}, {}, {}, {}, {}
    for key, fname in EXPERIMENTS.items():
        scen = load_scenario(HERE / fname)
        if hours is not None:
            scen = scen.with_changes({"scenario.duration": f"{hours} h"})
        scens[key] = scen
        rows[key], runs[key], diag[key] = {}, {}, {}
        for case in CASES:
            r = run_case(scen, case, noise=True, dt_out=10.0, dt_cov=60.0)
            rows[key][case.label] = r["summary"]
            runs[key][case.label] = r
            if case.label != "none":
                diag[key][case.label] = diagnose(r)
            if key == "exp1":
                timing[case.label] = r["summary"]["time_s"]
            print(
                f"{key} {case.label}: RMS horiz {r['summary']['horizontal']['rms_nmi']:.3f} nmi "
                f"({sum(r['summary']['time_s'].values()):.1f} s)",
                file=sys.stderr,
                flush=True,
            )
    grid = {
        "hours": hours,
        "periods_s": list(periods),
        "amplitudes_deg_s": list(amplitudes),
        "cases": [c.label for c in SWEEP_CASES],
    }
    cache = out / "sweep.json"
    points = None
    if args.reuse_sweep and cache.is_file():
        saved = json.loads(cache.read_text(encoding="utf-8"))
        points = saved["points"] if saved.get("grid") == grid else None
    if points is None:
        points = sweep(HERE / EXPERIMENTS["exp1"], hours, periods, amplitudes, args.jobs)
        out.mkdir(parents=True, exist_ok=True)
        write_text_atomic(cache, dumps({"grid": grid, "points": points}))
    verdict = sweep_verdict(points)
    rep = build_report(
        scens, rows, runs, diag, points, verdict, timing, HERE / "results", amplitudes, periods
    )
    rep.write_into(out, markdown_name="REPORT.md")
    print(out / "REPORT.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
