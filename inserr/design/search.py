"""The search: candidates evaluated in batches on Dask through the cache, and the optimizer.

Optimizer
---------
:func:`optimize` runs :func:`scipy.optimize.differential_evolution`. It fits the
problem: the objective (the worst RMS over a motion set) is a black box with no
gradient and many local minima (every resonance of a turn sequence with a swing is
one); DE needs only bounds, takes integer variables (table positions, dual-axis
moves, the flexible rule's variant) through ``integrality``, and with
``updating="deferred"`` evaluates a whole generation at once through its ``workers``
map, which is where the Dask engine comes in. Seeded, without polishing (a gradient
step would make no sense on integer variables and piecewise objectives), it is
deterministic: the same seed gives the same generations.

Early exit. A trial of DE replaces its population member only if it is no worse
(deferred updating), so once the worst RMS over the motions evaluated so far exceeds
the member's value the other motions cannot change the decision: the evaluation
stops there (``threshold``). The members' values come from DE's own callback
(``population_energies``), so the run is exactly the one a full evaluation would
give, at a fraction of the cost. Motions are evaluated hardest first (the order of
the best complete candidate so far), which makes the exits early.

Constraints (motor starts per hour, turning fraction, table range) and a family's
own rules are a penalty: a candidate that breaks one is worth
:data:`~inserr.design.objective.PENALTY` plus its total relative violation, without
any drift analysis.
"""

from __future__ import annotations

import json
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from inserr.design.cache import EvaluationCache, evaluation_key
from inserr.design.families import Family
from inserr.design.motions import MotionCase, canonical
from inserr.design.objective import PENALTY, Horizon, Limits, evaluate_task
from inserr.output.progress import Bar
from inserr.scenario.schema import Scenario


class EvaluationFailed(RuntimeError):
    """An evaluation raised on a worker (the message says which and why)."""


@dataclass
class Candidate:
    """A schedule to evaluate.

    Attributes
    ----------
    desc : dict
        What names it in the cache and rebuilds it on a worker:
        ``{"family": spec, "vars": [...]}`` or ``{"catalogue": name, ...}``.
    label : str
        Short name for tables.
    rules : dict
        Violations of its family's rules (no evaluation when any).
    """

    desc: dict[str, Any]
    label: str
    rules: dict[str, float] = field(default_factory=dict)


@dataclass
class Outcome:
    """What is known of a candidate on a motion set.

    Attributes
    ----------
    value : float
        The objective: worst RMS over the motions (nmi) when ``complete``; a lower
        bound above the threshold when stopped early; :data:`PENALTY` plus the total
        violation when infeasible.
    complete : bool
        Every motion's RMS is known.
    feasible : bool
    violation : dict
        Relative excess per broken rule or constraint (max over motions).
    metrics : dict
        Schedule metrics, maximum over the motions planned (``starts_per_hour``,
        ``turning_fraction``, ``range_deg``).
    rms : dict
        Motion index -> RMS (nmi), for the motions evaluated.
    """

    value: float
    complete: bool
    feasible: bool
    violation: dict[str, float]
    metrics: dict[str, float]
    rms: dict[int, float]


@dataclass
class Request:
    """One candidate on a motion set at a horizon (see :meth:`Evaluator.run`)."""

    candidate: Candidate
    motions: list[MotionCase]
    horizon: Horizon
    limits: Limits | None
    threshold: float | None = None
    order: list[int] | None = None


class Evaluator:
    """Evaluates requests through the cache, sending what is missing to the engine.

    Parameters
    ----------
    scen : Scenario
        The design scenario (its tables travel to the workers).
    engine : LocalEngine or ClusterEngine
        :func:`inserr.sweep.runner.open_engine`.
    cache : EvaluationCache
    """

    def __init__(self, scen: Scenario, engine, cache: EvaluationCache):
        from inserr.design.objective import error_model_key

        self.engine = engine
        self.cache = cache
        self.base = {
            "scenario": _plain(scen.raw),
            "base_dir": str(scen.base_dir) if scen.base_dir is not None else None,
        }
        self.model = canonical(error_model_key(scen))
        self.computed = 0  # motion evaluations sent to the engine by this process
        self.elapsed = 0.0  # their worker time, s
        self.batches = 0

    def _context(self, horizon: Horizon) -> str:
        return canonical({"horizon": horizon.as_dict(), "model": self.model})

    def keys(self, req: Request) -> list[str]:
        ctx = self._context(req.horizon)
        return [evaluation_key(req.candidate.desc, m.key, ctx) for m in req.motions]

    def run(self, requests: list[Request], desc: str = "") -> list[Outcome]:
        """Outcomes of ``requests``, in order; computes what the cache lacks in one batch.

        Raises
        ------
        EvaluationFailed
            A worker reported an error (the finished evaluations are kept).
        """
        keys = [self.keys(r) for r in requests]
        tasks: dict[str, str] = {}
        # Task ids unique to the batch: a cluster keeps finished results by key for a while,
        # and must not hand an earlier batch's result to a new task.
        self.batches += 1
        for i, (req, ks) in enumerate(zip(requests, keys, strict=True)):
            out = self._outcome(req, ks)
            if out is None:
                tasks[f"b{self.batches}-{i}"] = self._payload(req, ks)
        if tasks:
            with Bar(total=len(tasks), desc=desc or "design", unit="candidate") as bar:

                def on_result(tid: str, result: dict[str, Any]) -> None:
                    i = int(tid.rsplit("-", 1)[1])
                    self._store(requests[i], keys[i], result)
                    bar.update()

                try:
                    self.engine.run(tasks, on_result, fn=evaluate_task)
                finally:
                    self.cache.sync()
        outs = []
        for req, ks in zip(requests, keys, strict=True):
            out = self._outcome(req, ks)
            if out is None:  # pragma: no cover - a task always settles its candidate
                raise EvaluationFailed(f"{req.candidate.label}: evaluation incomplete")
            outs.append(out)
        return outs

    def _payload(self, req: Request, ks: list[str]) -> str:
        order = req.order if req.order is not None else list(range(len(req.motions)))
        todo = [i for i in order if "rms_nmi" not in (self.cache.get(ks[i]) or {})]
        known = [self.cache.get(k)["rms_nmi"] for k in ks if "rms_nmi" in (self.cache.get(k) or {})]
        return json.dumps(
            {
                **self.base,
                "candidate": req.candidate.desc,
                "horizon": req.horizon.as_dict(),
                "limits": None if req.limits is None else req.limits.as_dict(),
                "motions": [req.motions[i].spec for i in todo],
                "index": todo,
                "partial": max(known) if known else None,
                "threshold": req.threshold,
            }
        )

    def _store(self, req: Request, ks: list[str], result: dict[str, Any]) -> None:
        if result.get("status") != "ok":
            raise EvaluationFailed(
                f"{req.candidate.label}: {result.get('error', 'unknown error')}; "
                "rerun with the same output directory to resume"
            )
        todo = result["index"]
        self.elapsed += result.get("elapsed_s", 0.0)
        for j, i in enumerate(todo):
            rec: dict[str, Any] = {"metrics": result["plans"][j], "motion": req.motions[i].label}
            if j in result["rms"]:
                rec["rms_nmi"] = result["rms"][j]
                self.computed += 1
            self.cache.put(ks[i], rec)

    def _outcome(self, req: Request, ks: list[str]) -> Outcome | None:
        """The outcome from the cache alone, or None if a task is needed."""
        if req.candidate.rules:
            v = dict(req.candidate.rules)
            return Outcome(PENALTY + sum(v.values()), False, False, v, {}, {})
        recs = [self.cache.get(k) or {} for k in ks]
        if not all("metrics" in r for r in recs):
            return None
        metrics = {
            name: max(r["metrics"][name] for r in recs)
            for name in ("starts_per_hour", "turning_fraction", "range_deg")
        }
        violation = req.limits.violation(metrics) if req.limits is not None else {}
        if violation:
            return Outcome(PENALTY + sum(violation.values()), False, False, violation, metrics, {})
        rms = {i: r["rms_nmi"] for i, r in enumerate(recs) if "rms_nmi" in r}
        worst = max(rms.values()) if rms else 0.0
        if len(rms) == len(recs):
            return Outcome(worst, True, True, {}, metrics, rms)
        if req.threshold is not None and rms and worst > req.threshold:
            return Outcome(worst, False, True, {}, metrics, rms)
        return None


def _plain(raw: dict[str, Any]) -> dict[str, Any]:
    """The scenario's tables as plain JSON (what the file held, re-validated on the worker)."""
    return json.loads(json.dumps(raw))


# --- the optimizer ----------------------------------------------------------------------
@dataclass
class Generation:
    """One generation of the search: best value so far, candidates and motions evaluated."""

    index: int
    best: float
    candidates: int
    motion_evaluations: int
    seconds: float


@dataclass
class SearchResult:
    """What :func:`optimize` found.

    Attributes
    ----------
    best : list of float
        Rounded variables of the best member.
    best_value : float
    evaluated : dict
        Canonical JSON of rounded variables -> (variables, Outcome) for every candidate
        evaluated (complete or not).
    generations : list of Generation
    message : str
        The optimizer's stop message.
    """

    best: list[float]
    best_value: float
    evaluated: dict[str, tuple[list[float], Outcome]]
    generations: list[Generation]
    message: str


def family_candidate(family: Family, x) -> Candidate:
    """The candidate of variables ``x`` (rounded first) of ``family``."""
    v = family.round(x)
    dec = family.decode(v)
    return Candidate({"family": family.spec, "vars": v}, dec.summary, dict(dec.violation))


def _never_called(x):  # pragma: no cover - the workers map computes every value
    raise RuntimeError("the objective is evaluated through the workers map")


class _Map:
    """The ``workers`` map handed to differential evolution: one engine batch per generation."""

    def __init__(self, family, evaluator, motions, horizon, limits, started):
        self.family, self.evaluator = family, evaluator
        self.motions, self.horizon, self.limits = motions, horizon, limits
        self.thresholds: np.ndarray | None = None
        self.order: list[int] | None = None
        self.best: tuple[float, dict[int, float]] | None = None
        self.evaluated: dict[str, tuple[list[float], Outcome]] = {}
        self.calls = 0
        self.started = started
        self.generations: list[Generation] = []
        self.motion_evals = 0
        self.feasible = 0  # candidates that reached the drift engine
        self.budget: int | None = None

    def __call__(self, func, population):
        xs = [np.asarray(x, dtype=float) for x in population]
        cands = [family_candidate(self.family, x) for x in xs]
        th = self.thresholds
        reqs = [
            Request(
                c,
                self.motions,
                self.horizon,
                self.limits,
                None if th is None else float(th[i]),
                self.order,
            )
            for i, c in enumerate(cands)
        ]
        before = self.evaluator.computed
        outs = self.evaluator.run(reqs, desc=f"design generation {self.calls}")
        self.motion_evals += self.evaluator.computed - before
        values = []
        for c, o in zip(cands, outs, strict=True):
            self.evaluated[canonical(c.desc["vars"])] = (c.desc["vars"], o)
            values.append(o.value)
            self.feasible += bool(o.feasible)
            if o.complete and (self.best is None or o.value < self.best[0]):
                self.best = (o.value, o.rms)
        if self.best is not None:  # hardest motions first: exits come sooner
            r = self.best[1]
            self.order = sorted(range(len(self.motions)), key=lambda i: (-r[i], i))
        if self.calls == 0:
            # Before DE's first callback: its members are these values, except that the
            # best was swapped into slot 0 -- max(E_i, E_0) bounds every member's value.
            e = np.array(values)
            self.thresholds = np.maximum(e, e[0])
        self.calls += 1
        return values

    def callback(self, intermediate_result) -> bool:
        """DE's callback: the members' values are the next generation's thresholds; stop
        (return True) once the budget of feasible candidates is spent."""
        self.thresholds = np.array(intermediate_result.population_energies, dtype=float)
        self.generations.append(
            Generation(
                len(self.generations) + 1,
                float(intermediate_result.fun),
                len(self.evaluated),
                self.motion_evals,
                time.perf_counter() - self.started,
            )
        )
        return self.budget is not None and self.feasible >= self.budget


def initial_population(family: Family, population: int, seed: int) -> np.ndarray:
    """The first population: seeded Latin-hypercube members that obey the family's rules.

    A family's rules (a balanced single-axis cycle within the stop range, a closed
    dual-axis cycle) hold for a fraction of the box only; starting from members that
    obey them spends no generation on finding that set. ``20 population`` members of a
    seeded Latin hypercube are decoded, and the first ``population`` that obey the
    rules are kept, in the hypercube's order (then the least violating ones, if fewer
    do).
    """
    from scipy.stats import qmc

    variables = family.variables()
    lo = np.array([v.lower for v in variables], dtype=float)
    hi = np.array([v.upper for v in variables], dtype=float)
    integer = np.array([v.integer for v in variables])
    rng = np.random.default_rng([seed, 2])
    sample = lo + qmc.LatinHypercube(d=len(variables), rng=rng).random(20 * population) * (hi - lo)
    sample[:, integer] = np.clip(np.round(sample[:, integer]), lo[integer], hi[integer])
    cost = np.array([sum(family.decode(family.round(x)).violation.values()) for x in sample])
    order = np.argsort(cost, kind="stable")  # zero cost first, in the hypercube's order
    return sample[order[:population]]


def optimize(
    family: Family,
    evaluator: Evaluator,
    motions: list[MotionCase],
    horizon: Horizon,
    limits: Limits,
    *,
    budget: int,
    population: int,
    seed: int,
) -> SearchResult:
    """Minimise the worst RMS over ``motions`` within ``limits`` by differential evolution.

    Parameters
    ----------
    family : Family
    evaluator : Evaluator
    motions : list of MotionCase
    horizon : Horizon
        The search horizon (the screening horizon when shorter than the run).
    limits : Limits
    budget : int
        Candidates that obey the family's rules and the constraints to evaluate (with
        the drift engine) before the search stops, at the end of a generation; the
        others cost no drift analysis. At most ``20 budget / population`` generations.
    population : int
        Members of the population (>= 5).
    seed : int
        Seed of the initial population and of the optimizer.

    Returns
    -------
    SearchResult
    """
    from scipy.optimize import differential_evolution

    variables = family.variables()
    lo = np.array([v.lower for v in variables], dtype=float)
    hi = np.array([v.upper for v in variables], dtype=float)
    integrality = np.array([v.integer for v in variables])
    init = initial_population(family, population, seed)
    start = family.start()
    x0 = None if start is None else np.array(family.round(start), dtype=float)
    generations = max(1, 20 * budget // population)
    mapper = _Map(family, evaluator, motions, horizon, limits, time.perf_counter())
    mapper.budget = budget
    res = differential_evolution(
        _never_called,
        list(zip(lo, hi, strict=True)),
        integrality=integrality,
        init=init,
        x0=x0,
        seed=seed,
        workers=mapper,
        updating="deferred",
        polish=False,
        maxiter=generations,
        tol=0.0,
        atol=0.0,
        callback=mapper.callback,
    )
    best = family.round(res.x)
    return SearchResult(
        best, float(res.fun), mapper.evaluated, mapper.generations, str(res.message)
    )
