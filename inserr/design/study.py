"""A whole design: search, verification, the catalogue compared, the front, the report.

:func:`run_design` does, in order:

1. **Search** (:func:`inserr.design.search.optimize`) over the family's variables
   for the least worst RMS over the motion set within the constraints, at the
   search horizon (``design.screen_duration``, output step ``design.screen_step``).
2. **Verification** of the best candidates and of the search's Pareto front (worst
   RMS against motor starts per hour) at the full horizon and the report's output
   step (``scenario.duration``, ``output.covariance_step``), where the constraints
   are checked again. The chosen schedule is the verified candidate with the least
   worst RMS that meets them. Every figure reported is a verified one.
3. **Comparison** with every scheme of the catalogue (at ``scheme.rate`` and
   ``scheme.stop``) on the motion set and, with the chosen schedule, on the held-out
   motions, at the full horizon.
4. **Output** into the design directory: ``report.md`` (or ``REPORT.md``),
   ``report.html``, ``results.json``, the figures, ``chosen_scheme.toml`` (a
   scenario file with the chosen schedule that ``inserr run`` accepts) and
   ``evaluations.jsonl`` (the cache, :mod:`inserr.design.cache`): a rerun with the
   same directory resumes from it and gives the same result.
"""

from __future__ import annotations

import json
import math
import re
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from inserr.core.errors import InputError
from inserr.core.units import DEG, HOUR
from inserr.design.cache import EvaluationCache
from inserr.design.families import Family, build_family
from inserr.design.motions import MotionCase, canonical, design_motions, held_out_motions
from inserr.design.objective import Horizon, Limits, schedule_metrics, source_names
from inserr.design.search import (
    Candidate,
    Evaluator,
    Outcome,
    Request,
    SearchResult,
    family_candidate,
    optimize,
)
from inserr.output.report import Report, dumps, write_text_atomic
from inserr.scenario.schema import Scenario

#: Written first into a design directory: what it is (and that inserr may reuse it).
MARKER = "design.json"
#: The chosen schedule as a scenario file.
CHOSEN_TOML = "chosen_scheme.toml"
#: Steps of the chosen table listed in the report (a golden-order table lists every cycle).
STEPS_SHOWN = 24


class DesignFailed(RuntimeError):
    """No candidate met the constraints (or an evaluation failed): nothing to choose."""


def check_design_dir(out_dir: str | Path, field: str = "out") -> Path:
    """Check, before any work, that ``out_dir`` can hold this design.

    A design appends to ``evaluations.jsonl`` and rewrites its report files, so the
    directory must be new, empty, or an earlier design's (it holds ``design.json``
    or ``evaluations.jsonl``); see :func:`inserr.output.report.check_output_dir`.
    """
    from inserr.output.report import check_output_dir

    return check_output_dir(
        out_dir,
        field,
        lambda p: (p / MARKER).is_file() or (p / "evaluations.jsonl").is_file(),
        "an inserr design",
        "name a new directory, or the directory of an earlier design to resume it",
    )


def default_out_dir(scen: Scenario, scenario_path: str | None = None) -> str:
    """``design-<scenario file stem or name>``: lowercase letters, digits, - and _ only."""
    stem = Path(scenario_path).stem if scenario_path else scen.name
    slug = re.sub(r"[^a-z0-9_-]+", "-", stem.lower()).strip("-") or "scenario"
    return f"design-{slug}"


@dataclass(frozen=True)
class Settings:
    """The design's settings, validated from the scenario (see ``docs/design.md``)."""

    family: Family
    motions: list[MotionCase]
    held_out: list[MotionCase]
    full: Horizon
    screen: Horizon
    limits: Limits
    budget: int
    population: int
    verify: int
    seed: int
    #: ``grid+draws``: how many of ``motions`` (the first) are the grid, reported apart.
    grid: int | None = None

    def describe(self) -> dict[str, Any]:
        return {
            "family": self.family.spec,
            "variables": [v.__dict__ for v in self.family.variables()],
            "motions": [m.label for m in self.motions],
            "held_out": [m.label for m in self.held_out],
            "grid_motions": self.grid,
            "full_horizon": self.full.as_dict(),
            "search_horizon": self.screen.as_dict(),
            "limits": self.limits.as_dict(),
            "budget": self.budget,
            "population": self.population,
            "verify": self.verify,
            "seed": self.seed,
        }


def traditional_starts(scen: Scenario, duration: float) -> float:
    """Motor starts per hour of the two-position cycle at the scenario's stop and rate."""
    from inserr.schemes.catalogue import build_scheme

    table = build_scheme("two-position", scen.scheme_rate, scen.scheme_stop).plan(
        scen.motion, duration
    )
    return schedule_metrics(table, duration)["starts_per_hour"]


def design_settings(
    scen: Scenario, family: str | None = None, budget: int | None = None
) -> Settings:
    """Validate the ``[design]`` section (``family``, ``budget``: overrides) into :class:`Settings`.

    Raises
    ------
    InputError
        Naming the scenario key at fault.
    """
    fam = build_family(scen, family)
    motions = design_motions(scen)
    held = held_out_motions(scen)
    exclude = tuple(scen.value("design.exclude"))
    known = set(source_names(scen))
    for name in exclude:
        if name not in known:
            raise InputError("design.exclude", f"unknown error source {name!r}", "e.g. gyro_bias_z")
    full = Horizon(scen.duration, scen.dt_cov, exclude)
    sd = scen.value("design.screen_duration") or scen.duration
    if not 0 < sd <= scen.duration:
        raise InputError(
            "design.screen_duration", "must be > 0 and at most scenario.duration", "e.g. 24 h"
        )
    step = scen.value("design.screen_step")
    if step <= 0:
        raise InputError("design.screen_step", "must be > 0 s", "e.g. 600 s")
    screen = Horizon(sd, step, exclude)
    max_starts = scen.value("design.max_starts")
    if max_starts is None:
        max_starts = traditional_starts(scen, scen.duration)
    if max_starts <= 0:
        raise InputError("design.max_starts", "must be > 0", "e.g. 10.9")
    max_turning = scen.value("design.max_turning")
    if not 0 < max_turning <= 1:
        raise InputError("design.max_turning", "must be in (0, 1]", "e.g. 0.25")
    table_range = scen.value("design.table_range") / DEG
    if table_range <= 0:
        raise InputError("design.table_range", "must be > 0 deg", "e.g. 360 deg")
    limits = Limits(float(max_starts), float(max_turning), float(table_range))
    budget = scen.value("design.budget") if budget is None else budget
    population = scen.value("design.population")
    if population < 5:
        raise InputError("design.population", f"must be >= 5, got {population}", "e.g. 30")
    if budget < population:
        raise InputError(
            "design.budget",
            f"must be at least the population ({population}), got {budget}",
            "e.g. 600",
        )
    verify = scen.value("design.verify")
    if verify < 1:
        raise InputError("design.verify", f"must be >= 1, got {verify}", "e.g. 8")
    grid = None
    if scen.value("design.motions") == "grid+draws":
        grid = len(motions) - scen.value("design.draws")
    return Settings(
        fam, motions, held, full, screen, limits, budget, population, verify, scen.seed, grid
    )


# --- results ----------------------------------------------------------------------------
@dataclass
class Scored:
    """A schedule's results on a motion set (and the held-out motions) at the full horizon."""

    label: str
    kind: str  # "designed", "candidate" or "catalogue"
    outcome: Outcome
    held: Outcome | None = None
    table: dict[str, Any] = field(default_factory=dict)
    desc: dict[str, Any] = field(default_factory=dict)

    @property
    def values(self) -> list[float]:
        return [self.outcome.rms[i] for i in sorted(self.outcome.rms)]

    @property
    def worst(self) -> float:
        return max(self.values) if self.values else math.nan

    def summary(
        self, motions: list[MotionCase], held: list[MotionCase], grid: int | None = None
    ) -> dict[str, Any]:
        """Figures of the schedule; ``grid``: the first ``grid`` motions are also reported
        apart (``grid_*``: the grid of a ``grid+draws`` set)."""
        v = self.values
        out = {
            "label": self.label,
            "kind": self.kind,
            "worst_nmi": self.worst,
            "mean_nmi": float(np.mean(v)) if v else math.nan,
            "worst_motion": motions[int(np.argmax(v))].label if v else "",
            "rms_nmi": v,
            "starts_per_hour": self.outcome.metrics.get("starts_per_hour"),
            "turning_fraction": self.outcome.metrics.get("turning_fraction"),
            "range_deg": self.outcome.metrics.get("range_deg"),
            "violation": self.outcome.violation,
            "meets_constraints": not self.outcome.violation,
        }
        if grid and len(v) == len(motions):
            out["grid_worst_nmi"] = max(v[:grid])
            out["grid_mean_nmi"] = float(np.mean(v[:grid]))
            out["grid_worst_motion"] = motions[int(np.argmax(v[:grid]))].label
        if self.held is not None and self.held.rms:
            hv = [self.held.rms[i] for i in sorted(self.held.rms)]
            out["held_out_worst_nmi"] = max(hv)
            out["held_out_mean_nmi"] = float(np.mean(hv))
            out["held_out_worst_motion"] = held[int(np.argmax(hv))].label
            out["held_out_rms_nmi"] = hv
        if self.table:
            out["scheme"] = self.table
        return out


@dataclass
class DesignOutcome:
    """What :func:`run_design` did (see its docstring)."""

    out_dir: Path | None
    settings: Settings
    search: SearchResult
    verified: list[Scored]
    chosen: Scored | None
    front: list[Scored]
    catalogue: list[Scored]
    engine: str
    seconds: float
    computed: int
    cached: int
    files: list[Path]
    results: dict[str, Any]


def catalogue_candidates(scen: Scenario) -> list[Candidate]:
    """Every catalogue scheme (but ``custom``) at the scenario's stop and rate."""
    from inserr.schemes.catalogue import SCHEMES

    out = []
    for name in SCHEMES:
        if name == "custom":
            continue
        opts = scen.scheme_options if name == scen.scheme_name else {}
        desc = {
            "catalogue": name,
            "rate": scen.scheme_rate,
            "stop": scen.scheme_stop,
            # what the scheme's build may read (the scenario's own options apply to its
            # own scheme only; the mounting to every scheme)
            "options": _jsonable({**opts, "mounting": scen.scheme_options.get("mounting")}),
        }
        out.append(Candidate(desc, name))
    return out


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in sorted(obj.items())}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if hasattr(obj, "__dataclass_fields__"):
        return {k: _jsonable(getattr(obj, k)) for k in obj.__dataclass_fields__}
    return obj


def pareto(points: list[tuple[float, float]]) -> list[int]:
    """Indices of the non-dominated points (minimise both), by the first coordinate."""
    order = sorted(range(len(points)), key=lambda i: (points[i][0], points[i][1]))
    out, best = [], math.inf
    for i in order:
        if points[i][1] < best:
            out.append(i)
            best = points[i][1]
    return out


def _verify_set(search: SearchResult, n: int) -> list[list[float]]:
    """The best ``n`` complete feasible candidates of the search, front members first."""
    done = [(v, o) for v, o in search.evaluated.values() if o.complete and o.feasible]
    if not done:
        return []
    pts = [(o.metrics["starts_per_hour"], o.value) for _, o in done]
    front = [done[i][0] for i in pareto(pts)]
    front = sorted(front, key=lambda v: search.evaluated[canonical(v)][1].value)
    ranked = [v for v, _ in sorted(done, key=lambda p: p[1].value)]
    picked: list[list[float]] = []
    for v in front[: max(1, n // 2)] + ranked:
        if v not in picked:
            picked.append(v)
        if len(picked) >= n:
            break
    return picked


def run_design(
    scen: Scenario,
    *,
    out_dir: str | Path | None,
    family: str | None = None,
    budget: int | None = None,
    scheduler: Any = None,
    workers: int | None = None,
    markdown_name: str = "report.md",
    title: str | None = None,
    compare: bool = True,
) -> DesignOutcome:
    """Design a schedule for ``scen`` (see the module docstring) and write ``out_dir``.

    Parameters
    ----------
    scen : Scenario
        The scenario with its ``[design]`` section.
    out_dir : str or Path or None
        The design directory (resumable); None keeps everything in memory and writes
        nothing.
    family, budget : optional
        Override ``design.family`` and ``design.budget``.
    scheduler, workers : optional
        The Dask engine (:func:`inserr.sweep.runner.open_engine`): local processes by
        default, ``tcp://HOST:PORT`` for a cluster.
    markdown_name : str
        Name of the Markdown report (analyses use ``REPORT.md``).
    title : str, optional
        Report title.
    compare : bool
        Compare with the catalogue (and evaluate the held-out motions).

    Returns
    -------
    DesignOutcome

    Raises
    ------
    InputError
        Bad settings or an unreachable cluster, before anything is written.
    DesignFailed
        No verified candidate met the constraints, or an evaluation failed.
    """
    from inserr.design.search import EvaluationFailed
    from inserr.sweep.runner import open_engine

    t_start = time.perf_counter()
    st = design_settings(scen, family, budget)
    root = None if out_dir is None else check_design_dir(out_dir)
    engine = open_engine(scheduler, workers, keep_pool=True)
    engine_text = engine.describe()
    cache = EvaluationCache(root)
    cached_before = cache.loaded
    try:
        if root is not None:
            root.mkdir(parents=True, exist_ok=True)
            write_text_atomic(root / MARKER, dumps(st.describe()) + "\n")
        ev = Evaluator(scen, engine, cache)
        try:
            search = optimize(
                st.family,
                ev,
                st.motions,
                st.screen,
                st.limits,
                budget=st.budget,
                population=st.population,
                seed=st.seed,
            )
            verified = _verify(st, ev, search)
            chosen = _choose(verified)
            catalogue: list[Scored] = []
            if compare:
                catalogue = _compare(scen, st, ev, chosen)
        except EvaluationFailed as exc:
            raise DesignFailed(str(exc)) from None
    finally:
        cache.close()
        engine.close()
    for s in verified:
        s.kind = "designed" if s is chosen else "candidate"
    front_idx = pareto([(s.outcome.metrics["starts_per_hour"], s.worst) for s in verified])
    front = [verified[i] for i in front_idx]
    seconds = time.perf_counter() - t_start
    outcome = DesignOutcome(
        root, st, search, verified, chosen, front, catalogue, engine_text, seconds,
        ev.computed, cached_before, [], {},
    )  # fmt: skip
    outcome.results = _results(scen, outcome)
    if root is not None:
        outcome.files = _write(scen, outcome, root, markdown_name, title)
    if chosen is None:
        raise DesignFailed(
            "no verified candidate met the constraints; raise design.budget or relax "
            "design.max_starts / design.max_turning / design.table_range"
        )
    return outcome


def _verify(st: Settings, ev: Evaluator, search: SearchResult) -> list[Scored]:
    picks = _verify_set(search, st.verify)
    cands = [family_candidate(st.family, v) for v in picks]
    outs = ev.run(
        [Request(c, st.motions, st.full, st.limits) for c in cands], desc="design verification"
    )
    out = []
    for c, o in zip(cands, outs, strict=True):
        dec = st.family.decode(c.desc["vars"])
        out.append(Scored(c.label, "candidate", o, None, dec.table, c.desc))
    return out


def _choose(verified: list[Scored]) -> Scored | None:
    ok = [s for s in verified if s.outcome.complete and s.outcome.feasible]
    return min(ok, key=lambda s: s.worst) if ok else None


def _compare(scen: Scenario, st: Settings, ev: Evaluator, chosen: Scored | None) -> list[Scored]:
    cat = catalogue_candidates(scen)
    # No limits: every catalogue scheme is evaluated; whether it meets them is reported.
    reqs = [Request(c, st.motions, st.full, None) for c in cat]
    held_reqs = [Request(c, st.held_out, st.full, None) for c in cat] if st.held_out else []
    if chosen is not None and st.held_out:
        c = Candidate(chosen.desc, chosen.label)
        held_reqs.append(Request(c, st.held_out, st.full, None))
    outs = ev.run(reqs + held_reqs, desc="catalogue and held-out motions")
    design_outs, held_outs = outs[: len(reqs)], outs[len(reqs) :]
    scored = []
    for i, (c, o) in enumerate(zip(cat, design_outs, strict=True)):
        o.violation = st.limits.violation(o.metrics)
        o.feasible = not o.violation
        held = held_outs[i] if held_outs else None
        scored.append(Scored(c.label, "catalogue", o, held, {"name": c.label}, c.desc))
    if chosen is not None and st.held_out:
        chosen.held = held_outs[-1]
    return scored


# --- results, report, files -------------------------------------------------------------
def _results(scen: Scenario, o: DesignOutcome) -> dict[str, Any]:
    st = o.settings
    ms, hs = st.motions, st.held_out
    res: dict[str, Any] = {
        "scenario": scen.name,
        "settings": st.describe(),
        "engine": o.engine,
        "seconds": o.seconds,
        "motion_evaluations_computed": o.computed,
        "evaluations_in_cache_at_start": o.cached,
        "search": {
            "best_value": o.search.best_value,
            "best_vars": o.search.best,
            "message": o.search.message,
            "candidates": len(o.search.evaluated),
            "generations": [g.__dict__ for g in o.search.generations],
        },
        "verified": [s.summary(ms, hs, st.grid) for s in o.verified],
        "front": [s.summary(ms, hs, st.grid) for s in o.front],
        "chosen": None if o.chosen is None else o.chosen.summary(ms, hs, st.grid),
        "catalogue": [s.summary(ms, hs, st.grid) for s in o.catalogue],
    }
    return res


def _schedule_figure(scen: Scenario, st: Settings, chosen: Scored):
    from inserr.design import figures  # matplotlib only when a figure is drawn
    from inserr.design.motions import build_motion
    from inserr.design.objective import candidate_scheme

    motion = build_motion(st.motions[0].spec)
    scheme = candidate_scheme(chosen.desc, scen)
    span = min(st.full.duration, 4 * HOUR)
    table = scheme.plan(motion, span)
    t = np.linspace(0.0, span, 4001)
    a, b = table.angles_at(t, motion)
    inner = b / DEG if np.any(b != 0) else None
    return figures.schedule(
        t / HOUR,
        a / DEG,
        inner,
        f"Chosen schedule, first {span / HOUR:g} h ({st.motions[0].label})",
    )


def _write(
    scen: Scenario, o: DesignOutcome, root: Path, markdown_name: str, title: str | None
) -> list[Path]:
    st = o.settings
    rep = build_report(scen, o, title)
    files = []
    if o.chosen is not None:
        text = chosen_toml(scen, o.chosen.table, st)
        write_text_atomic(root / CHOSEN_TOML, text)
        files.append(root / CHOSEN_TOML)
    rep.write_into(root, markdown_name)
    write_text_atomic(root / "report.html", rep.html())
    files += [root / markdown_name, root / "report.html", root / "results.json"]
    return files


def _fmt_motion_set(ms: list[MotionCase]) -> str:
    if not ms:
        return "none"
    if all(m.period is not None for m in ms):
        p = sorted({m.period for m in ms})
        a = sorted({round(m.amplitude / DEG, 6) for m in ms})
        return (
            f"{len(ms)} yaw swings, periods {p[0]:g} to {p[-1]:g} s ({len(p)} values), "
            f"peak yaw rates {a[0]:g} to {a[-1]:g} deg/s ({len(a)} values)"
        )
    return (
        f"{len(ms)} motions: "
        + "; ".join(m.label for m in ms[:4])
        + (" ..." if len(ms) > 4 else "")
    )


def build_report(scen: Scenario, o: DesignOutcome, title: str | None = None) -> Report:
    """The design report: settings, the chosen schedule, comparisons, front, search."""
    from inserr.design import figures  # matplotlib only when a report is built
    from inserr.drift.study import describe

    st = o.settings
    rep = Report(title or f"inserr design: {scen.name}")
    rep.results = o.results
    full, screen, lim = st.full, st.screen, st.limits
    rep.heading("What was designed")
    rep.paragraph(
        f"Family **{st.family.name}** ({len(st.family.variables())} variables), searched by "
        f"differential evolution (scipy, seed {st.seed}, population {st.population}, "
        f"budget {st.budget} candidates) for the least *worst* RMS horizontal error over "
        f"unknown signs over the motion set, without "
        f"{', '.join(full.exclude) if full.exclude else 'no source'}; "
        f"constraints: at most {lim.max_starts:.4g} motor starts per hour, at most "
        f"{100 * lim.max_turning:g} % of the time turning, gimbal angles within "
        f"+-{lim.table_range_deg:g} deg. Search horizon {screen.duration / HOUR:g} h (output "
        f"step {screen.step:g} s); every figure below is verified at the full horizon "
        f"{full.duration / HOUR:g} h with output step {full.step:g} s (the report's "
        f"covariance step)."
    )
    rep.table(
        ["item", "value"],
        [list(r) for r in describe(scen)]
        + [
            [
                "motion set",
                _fmt_motion_set(st.motions)
                if not st.grid
                else f"the grid ({_fmt_motion_set(st.motions[: st.grid])}) and "
                f"{len(st.motions) - st.grid} training draws "
                f"({_fmt_motion_set(st.motions[st.grid :])}, another seed stream than the "
                "held-out motions)",
            ],
            ["held-out motions", _fmt_motion_set(st.held_out)],
            ["evaluations run on", o.engine],
            [
                "time",
                f"{o.seconds:.0f} s ({o.computed} motion evaluations computed, "
                f"{o.cached} found in the cache)",
            ],
        ],  # fmt: skip
    )
    ms, hs = st.motions, st.held_out
    rep.heading("The chosen schedule")
    if o.chosen is None:
        rep.paragraph("No verified candidate met the constraints: nothing was chosen.")
    else:
        ch = o.chosen.summary(ms, hs)
        rep.paragraph(
            f"{o.chosen.label}. Worst RMS over the motion set {ch['worst_nmi']:.4g} nmi "
            f"(mean {ch['mean_nmi']:.4g}, worst at {ch['worst_motion']}); "
            f"{ch['starts_per_hour']:.4g} motor starts per hour, "
            f"{100 * ch['turning_fraction']:.3g} % of the time turning, gimbal range "
            f"{ch['range_deg']:.4g} deg. Written as `{CHOSEN_TOML}` (run it with "
            f"`inserr run {CHOSEN_TOML}`)."
        )
        steps = o.chosen.table.get("steps")
        if steps:
            shown = steps[:STEPS_SHOWN]
            rep.table(
                ["step", "gimbal", "turn", "then stop"],
                [[i + 1, s["gimbal"], s["angle"], s["dwell"]] for i, s in enumerate(shown)],
            )
            if len(steps) > len(shown):
                rep.paragraph(
                    f"The first {len(shown)} of the table's {len(steps)} steps (every step "
                    f"in `{CHOSEN_TOML}`)."
                )
            rep.paragraph(
                f"The run opens with a stop of {o.chosen.table['stop']} at 0 deg; the table "
                f"turns at {o.chosen.table['rate']}."
            )
        rep.figure(
            _schedule_figure(scen, st, o.chosen), "schedule", "Gimbal angles of the chosen schedule"
        )

    rows = [s for s in [o.chosen] if s is not None] + list(o.catalogue)
    best_cat = min(
        (s for s in o.catalogue if s.outcome.feasible), key=lambda s: s.worst, default=None
    )
    rep.heading("Compared with the catalogue, on the motion set")
    grid = st.grid
    if grid:
        rep.paragraph(
            f"The motion set is the grid ({grid} motions) and {len(ms) - grid} training "
            "draws; *grid worst* is the worst over the grid alone, *worst RMS* over the "
            "whole set the search minimised."
        )
    rep.table(
        ["scheme", *(["grid worst (nmi)"] if grid else []), "worst RMS (nmi)",
         "mean RMS (nmi)", "worst at", "starts/h", "turning (%)", "range (deg)",
         "meets constraints"],
        [
            [
                ("designed: " if s is o.chosen else "") + s.label[:60],
                *([max(s.values[:grid])] if grid else []),
                s.worst,
                float(np.mean(s.values)),
                ms[int(np.argmax(s.values))].label,
                s.outcome.metrics["starts_per_hour"],
                100 * s.outcome.metrics["turning_fraction"],
                s.outcome.metrics["range_deg"],
                "yes" if not s.outcome.violation else "no: " + ", ".join(s.outcome.violation),
            ]
            for s in sorted(rows, key=lambda s: s.worst)
        ],
    )  # fmt: skip
    if rows:
        rep.figure(
            figures.comparison(
                [_fig_row(s, o.chosen) for s in rows],
                f"Motion set ({len(ms)} motions), {full.duration / HOUR:g} h",
                None if best_cat is None else best_cat.worst,
            ),
            "compare_motion_set",
            "RMS horizontal error of the designed schedule and of every catalogue scheme on "
            "every motion of the set (dashed: best worst case of the catalogue schemes that "
            "meet the constraints)",
        )
    if hs and rows:
        rep.heading("Compared with the catalogue, on held-out motions")
        rep.paragraph(
            f"{len(hs)} motions drawn at random (another seed stream) from the ranges of the "
            "`[design]` section; the search never saw them."
        )
        hrows = [s for s in rows if s.held is not None]
        rep.table(
            ["scheme", "worst RMS (nmi)", "mean RMS (nmi)", "worst at"],
            [
                [
                    ("designed: " if s is o.chosen else "") + s.label[:60],
                    max(s.held.rms.values()),
                    float(np.mean(list(s.held.rms.values()))),
                    hs[max(s.held.rms, key=s.held.rms.get)].label,
                ]
                for s in sorted(hrows, key=lambda s: max(s.held.rms.values()))
            ],
        )
        best_h = min(
            (s for s in o.catalogue if s.outcome.feasible and s.held is not None),
            key=lambda s: max(s.held.rms.values()),
            default=None,
        )
        rep.figure(
            figures.comparison(
                [_fig_row(s, o.chosen, held=True) for s in hrows],
                f"Held-out motions ({len(hs)}), {full.duration / HOUR:g} h",
                None if best_h is None else max(best_h.held.rms.values()),
            ),
            "compare_held_out",
            "The same comparison on motions the search never saw",
        )
    rep.heading("Pareto front: worst RMS against motor starts")
    pts = [
        {
            "starts": s.outcome.metrics["starts_per_hour"],
            "worst": s.worst,
            "front": s in o.front,
            "chosen": s is o.chosen,
        }
        for s in o.verified
        if s.outcome.complete
    ]
    rep.table(
        ["candidate", "starts/h", "worst RMS (nmi)", "on the front", "meets constraints"],
        [
            [
                s.label[:70],
                s.outcome.metrics["starts_per_hour"],
                s.worst,
                "yes" if s in o.front else "",
                "yes" if s.outcome.feasible else "no",
            ]
            for s in sorted(o.verified, key=lambda s: s.outcome.metrics["starts_per_hour"])
            if s.outcome.complete
        ],  # fmt: skip
    )
    rep.figure(
        figures.front(
            pts,
            [
                {"label": s.label, "starts": s.outcome.metrics["starts_per_hour"], "worst": s.worst}
                for s in o.catalogue
                if s.outcome.metrics["turning_fraction"] <= lim.max_turning and s.worst < 50
            ],
            lim.max_starts,
            f"Verified candidates, full horizon ({full.duration / HOUR:g} h)",
        ),
        "front",
        "Worst RMS over the motion set against motor starts per hour: the verified "
        "candidates, their Pareto front and the catalogue schemes (those with a worst case "
        "under 50 nmi that turn within the limit)",
    )
    rep.heading("The search")
    gens = [g.__dict__ for g in o.search.generations]
    rep.paragraph(
        f"{len(o.search.evaluated)} candidates evaluated over {len(gens)} generations "
        f"({o.search.message}); best search objective {o.search.best_value:.4g} "
        f"(at the search horizon, {screen.duration / HOUR:g} h). Candidates are stopped "
        "early once they are worse than the population member they compete with, which "
        "changes no decision of the optimizer."
    )
    if gens:
        rep.figure(figures.search_history(gens, "Best search objective"), "search", "")
    return rep


def _fig_row(s: Scored, chosen: Scored | None, held: bool = False) -> dict[str, Any]:
    o = s.held if held else s.outcome
    return {
        "label": ("designed" if s is chosen else s.label),
        "values": [o.rms[i] for i in sorted(o.rms)],
        "designed": s is chosen,
        "feasible": s.outcome.feasible,
    }


# --- the chosen schedule as a scenario file ---------------------------------------------
#: Sections of the design scenario copied into the chosen schedule's file.
KEPT_SECTIONS = ("scenario", "site", "imu", "initial", "motion", "output")


def chosen_toml(scen: Scenario, table: dict[str, Any], st: Settings) -> str:
    """A scenario file with the chosen schedule as ``[scheme]`` (``inserr run`` accepts it).

    The scenario's own sections are kept (a relative ``motion.file`` made absolute);
    ``[design]``, ``[compare]`` and the other studies' sections are left out.
    """
    lines = [
        "# Schedule chosen by `inserr design` (written by inserr).",
        f"# Family {st.family.name}; worst RMS horizontal error over the design's motion set,",
        f"# full horizon {st.full.duration / HOUR:g} h: see the design report.",
        "",
    ]
    raw = scen.raw
    for section in KEPT_SECTIONS:
        tab = dict(raw.get(section, {}))
        if section == "motion" and tab.get("file") and scen.base_dir is not None:
            p = Path(tab["file"])
            if not p.is_absolute():
                tab["file"] = str((scen.base_dir / p).resolve())
        if section == "scenario":
            tab["name"] = f"{scen.name}: designed schedule"
        if not tab:
            continue
        lines.append(f"[{section}]")
        lines += [f"{k} = {_toml_value(v)}" for k, v in tab.items()]
        lines.append("")
    sch = {k: v for k, v in table.items() if k != "steps"}
    mounting = raw.get("scheme", {}).get("mounting")
    if mounting is not None:
        sch["mounting"] = mounting
    lines.append("[scheme]")
    lines += [f"{k} = {_toml_value(v)}" for k, v in sch.items()]
    lines.append("")
    for row in table.get("steps", []):
        lines.append("[[scheme.steps]]")
        lines += [f"{k} = {_toml_value(v)}" for k, v in row.items()]
        lines.append("")
    return "\n".join(lines)


def _toml_value(v: Any) -> str:
    """TOML text of a scenario value (strings, numbers, booleans, lists of them)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if not math.isfinite(v):
            raise ValueError(f"cannot write {v!r} to a scenario file")
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v, ensure_ascii=False)  # a TOML basic string
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise ValueError(f"cannot write {type(v).__name__} to a scenario file")
