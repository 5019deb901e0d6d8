"""A paper's published figures beside the model's: readings of its set-up, sign ranges, claims.

A reproduction should set the paper's own numbers beside the model's without tuning
the model to them. What this module does for a scheme comparison:

* :func:`readings` — every combination of answers to the set-up's open questions
  (heading convention, opening phase, stop time, ...), each a set of scenario changes;
* :func:`paper_comparison` — the model's figures under every reading, and at the
  stated readings the range of the figure over all sign patterns of the errors
  (:func:`~inserr.drift.unknown_signs.figure_reach`: can *some* sign pattern give the
  paper's number?);
* :func:`closest_reading` — which reading comes closest to each number;
* :func:`check_claims` — the paper's qualitative claims under each answer of one
  question (which hold under every answer: those verdicts do not depend on it);
* :func:`paper_section` — the generated "Against the paper" section of a write-up.

The P0 reproduction (``analyses/p0_swinging_base``) uses it for the heading convention.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from inserr.core.units import NMI
from inserr.drift.comparison import ERROR_SETS, Case, budget_figures, run_case, source_vectors
from inserr.drift.unknown_signs import figure_reach
from inserr.output.report import Report
from inserr.scenario.schema import Scenario


@dataclass(frozen=True)
class Reading:
    """One reading of a paper's set-up: a choice on each open question, and what it changes.

    Attributes
    ----------
    choices : tuple of (str, str)
        ``(question, answer)`` pairs, e.g. ``("convention", "counter-clockwise")``.
    changes : dict
        The scenario changes (dotted keys) the answers make.
    """

    choices: tuple[tuple[str, str], ...]
    changes: dict

    @property
    def label(self) -> str:
        """The answers, comma-separated."""
        return ", ".join(answer for _, answer in self.choices)


def readings(questions: dict[str, dict[str, dict]]) -> list[Reading]:
    """Every combination of answers: question -> answer -> scenario changes.

    Answers that change nothing (``{}``) are allowed: a question answered after the
    run (which error set, which figure) is one with empty changes.
    """
    combos = [((), {})]
    for question, answers in questions.items():
        combos = [
            (choices + ((question, answer),), {**changes, **more})
            for choices, changes in combos
            for answer, more in answers.items()
        ]
    return [Reading(choices, changes) for choices, changes in combos]


def closest_reading(values: dict[str, float], target: float) -> tuple[str, float, float]:
    """The reading (by label) whose value is closest to ``target``, its value and relative gap.

    Raises
    ------
    ValueError
        With no values, or a zero target (no relative gap).
    """
    if not values or target == 0:
        raise ValueError("closest_reading needs values and a non-zero target")
    label = min(values, key=lambda k: (abs(values[k] - target), k))
    return label, values[label], (values[label] - target) / abs(target)


#: The figures of :func:`~inserr.drift.comparison.budget_figures` a paper's number may be.
FIGURE_KEYS = {"all-positive": "all_positive_nmi", "RMS": "rms_nmi", "worst": "worst_nmi"}


def paper_comparison(
    scen: Scenario,
    cases: Sequence[Case],
    paper: dict[str, float],
    questions: dict[str, dict[str, dict]],
    detailed: Callable[[Reading], bool],
    error_sets: Sequence[str] = tuple(ERROR_SETS),
) -> dict:
    """A paper's figures (nmi) beside every reading of its set-up, and the closest reading.

    Parameters
    ----------
    scen : Scenario
        The stated set-up.
    cases : sequence of Case
        The schemes the paper compares (labels as the keys of ``paper``).
    paper : dict
        Case label -> the paper's maximum horizontal error, nmi.
    questions : dict
        Open questions of the set-up (:func:`readings`); a change may be a callable of
        the scenario (``lambda s: f"{s.motion.period:g} s"``).
    detailed : callable
        Readings at which the sign-pattern range (:func:`~inserr.drift.unknown_signs.figure_reach`,
        full error set), the noise 1 sigma and the motor starts are computed too.
    error_sets : sequence of str
        Keys of :data:`ERROR_SETS` (the error-set question, answered after the run).

    Returns
    -------
    dict
        ``values``: label -> "reading, error set, figure" -> nmi (every figure of
        :data:`FIGURE_KEYS`); ``detail``: label -> reading label -> the figures of the
        full set, ``lowest_bound``, ``lowest``, ``highest``, ``closest_nmi`` and
        ``reach`` (verdict), ``noise_1sigma_nmi``, ``motor_starts_per_hour``;
        ``closest``: label -> ``reading``, ``nmi``, ``gap`` (relative, signed).
    """
    out: dict = {"values": {}, "detail": {}, "closest": {}}
    for rd in readings(questions):
        changes = {k: v(scen) if callable(v) else v for k, v in rd.changes.items()}
        for case in cases:
            run = run_case(scen.with_changes(changes), case).run
            vals = out["values"].setdefault(case.label, {})
            for es in error_sets:
                fig = budget_figures(run, es)
                for name, key in FIGURE_KEYS.items():
                    vals[f"{rd.label}, {es}, {name}"] = fig[key]
            if detailed(rd):
                v, _ = source_vectors(run, "full")
                reach = figure_reach(v, paper[case.label] * NMI)
                fig = budget_figures(run, "full")
                out["detail"].setdefault(case.label, {})[rd.label] = {
                    **{name: fig[key] for name, key in FIGURE_KEYS.items()},
                    **{k: reach[k] / NMI for k in ("lowest_bound", "lowest", "highest")},
                    "closest_nmi": reach["closest"] / NMI,
                    "reach": reach["verdict"],
                    "noise_1sigma_nmi": float(run.result.noise_horizontal_sigma[-1] / NMI),
                    "motor_starts_per_hour": run.motor_starts_per_hour,
                }
    for label, vals in out["values"].items():
        name, value, gap = closest_reading(vals, paper[label])
        out["closest"][label] = {"reading": name, "nmi": value, "gap": gap}
    return out


def check_claims(
    tests: dict[str, Callable[[str], bool]], answers: Sequence[str]
) -> list[dict[str, object]]:
    """Each claim's test under each answer: ``{"claim": text, answer: bool, ...}``."""
    return [{"claim": text, **{a: bool(test(a)) for a in answers}} for text, test in tests.items()]


def stated_figures(detail: dict, question_index: int = 0) -> dict:
    """``detail`` of :func:`paper_comparison` keyed label -> answer of one question -> figures."""
    return {
        label: {rd.split(", ")[question_index]: d for rd, d in per.items()}
        for label, per in detail.items()
    }


def paper_section(
    rep: Report,
    paper: dict[str, dict[str, float]],
    comparisons: dict[str, dict],
    claims: list[dict],
    answers: Sequence[str],
    stated: str,
    questions: str,
) -> None:
    """Write the "Against the paper" section: figures, sign ranges, closest readings, claims.

    Parameters
    ----------
    rep : Report
    paper : dict
        Experiment -> case label -> the paper's figure, nmi.
    comparisons : dict
        Experiment -> :func:`paper_comparison` result.
    claims : list of dict
        :func:`check_claims` under ``answers``.
    answers : sequence of str
        The answers of the question the detailed readings differ in (the convention).
    stated : str
        The set-up the detailed readings share, in words.
    questions : str
        The open questions of the readings, in words.
    """
    fig = {k: stated_figures(c["detail"]) for k, c in comparisons.items()}
    flat = [
        (k, lab, a, f) for k, per in fig.items() for lab, by in per.items() for a, f in by.items()
    ]
    noise = flat[0][3]["noise_1sigma_nmi"]
    rep.heading("Against the paper")
    rep.paragraph(
        f"The paper's figures beside the model's at the set-up it states ({stated}), under each "
        f"of: {', '.join(answers)}. Every constant error with a + sign ('all-positive'), the "
        "RMS over unknown signs, the worst sign pattern, and the range of the figure over all "
        "sign patterns of the error magnitudes (highest exact; lowest found by a search and "
        "bracketed by a proved bound). 'Reach': a sign pattern gives the paper's figure within "
        "1 % ('reached'), or none can (proved). The model is not tuned to the paper."
    )
    head = [*FIGURE_KEYS, "range", "reach"]
    rows = []
    for k, per in fig.items():
        for lab, by in per.items():
            cells = [k, lab, paper[k][lab]]
            for a in answers:
                f = by[a]
                rng = f"{f['lowest']:.2f}-{f['highest']:.2f}"
                cells += [*(f[n] for n in FIGURE_KEYS), rng, f["reach"]]
            rows.append(cells)
    rep.table(
        ["exp.", "scheme", "paper", *(f"{h} ({a})" for a in answers for h in head)], rows, "{:.2f}"
    )
    below = [
        f"{k} {lab} {paper[k][lab]:g} nmi read {a} (proved bound {f['lowest_bound']:.2f}, "
        f"{(f['lowest_bound'] - paper[k][lab]) / noise:.1f} noise sigma above the paper)"
        for k, lab, a, f in flat
        if f["reach"] == "below every pattern"
    ]
    above = [
        f"{k} {lab} {paper[k][lab]:g} nmi read {a} (highest {f['highest']:.2f}, "
        f"{paper[k][lab] / f['highest']:.1f} x)"
        for k, lab, a, f in flat
        if f["reach"] == "above every pattern"
    ]
    reached = sum(f["reach"] == "reached" for *_, f in flat)
    gap = max(f["lowest"] - f["lowest_bound"] for *_, f in flat)
    rep.paragraph(
        f"{reached} of {len(flat)} (figure, convention) pairs are reached by some sign pattern. "
        "Above every sign pattern of the stated error magnitudes (proved: the highest is "
        "exact): "
        + ("; ".join(above) or "none")
        + ". Below every pattern (proved by the bound): "
        + ("; ".join(below) or "none")
        + f". The proved lower bounds lie within {gap:.2f} nmi of the lowest patterns found. "
        f"The paper's runs also carried one realisation of noise ({noise:.2f} nmi 1-sigma at "
        "the end here), which the ranges leave out."
    )
    rep.heading("Which reading comes closest", 3)
    counts = {len(v) for c in comparisons.values() for v in c["values"].values()}
    rep.paragraph(
        f"Readings: every combination of {questions} ({max(counts)} per scheme). Closest to "
        "each figure of the paper:"
    )
    rep.table(
        ["exp.", "scheme", "paper (nmi)", "closest reading", "model (nmi)", "gap"],
        [
            [k, lab, paper[k][lab], c["reading"], c["nmi"], f"{100 * c['gap']:+.1f} %"]
            for k, comp in comparisons.items()
            for lab, c in comp["closest"].items()
        ],
        "{:.2f}",
    )
    far = [
        f"{k} {lab} ({100 * c['gap']:+.0f} %)"
        for k, comp in comparisons.items()
        for lab, c in comp["closest"].items()
        if abs(c["gap"]) > 0.05
    ]
    firsts = {
        c["reading"].split(", ")[0]
        for comp in comparisons.values()
        for c in comp["closest"].values()
    }
    rep.paragraph(
        "Left unexplained, not within 5 % under any reading: "
        + (", ".join(far) or "nothing")
        + ". "
        + (
            f"The closest readings do not agree on one answer ({', '.join(sorted(firsts))}): a "
            "single close figure is weak evidence for a reading; the claims below weigh it."
            if len(firsts) > 1
            else f"Every closest reading answers '{firsts.pop()}'."
        )
    )
    rep.heading("The paper's claims under each reading", 3)
    word = {True: "holds", False: "fails"}
    rep.table(
        ["claim (model at the stated set-up)", *answers, "depends on it"],
        [
            [
                c["claim"],
                *(word[c[a]] for a in answers),
                "yes" if len({c[a] for a in answers}) > 1 else "no",
            ]
            for c in claims
        ],
    )
    held = {a: sum(c[a] for c in claims) for a in answers}
    top = sorted(held, key=held.get, reverse=True)
    support = (
        f"the model's results support the {top[0]} reading"
        if held[top[0]] > held[top[1]]
        else "the claims do not tell the readings apart"
    )
    rep.paragraph(
        f"Of {len(claims)} claims, "
        + ", ".join(f"{held[a]} hold read {a}" for a in answers)
        + f": {support}. A 'no' in the last column is a verdict that does not depend on the "
        "reading."
    )
