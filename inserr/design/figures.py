"""Figures of a design: schemes compared over a motion set, the Pareto front, the schedule.

Every function returns a :class:`matplotlib.figure.Figure` (no pyplot state, nothing
shown); the report writer saves it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.figure import Figure

#: Colour of the designed schedule; the catalogue is grey, its best scheme blue.
DESIGNED = "tab:red"
BEST_CATALOGUE = "tab:blue"


def comparison(rows: list[dict[str, Any]], title: str, floor: float | None = None) -> Figure:
    """Each scheme's RMS on every motion of a set (dots) and its worst (bar), log scale.

    Parameters
    ----------
    rows : list of dict
        One per scheme: ``label``, ``values`` (RMS per motion, nmi), ``designed``
        (bool), ``feasible`` (meets the design's constraints).
    title : str
    floor : float, optional
        A reference level to draw (nmi), e.g. the best worst case of the catalogue.
    """
    fig = Figure(figsize=(9.0, 4.8))
    ax = fig.add_subplot(1, 1, 1)
    rows = sorted(rows, key=lambda r: max(r["values"]))
    best_cat = next((r for r in rows if not r["designed"] and r["feasible"]), None)
    rng = np.random.default_rng(0)  # jitter of the dots only, fixed for identical figures
    for i, r in enumerate(rows):
        v = np.asarray(r["values"], dtype=float)
        color = DESIGNED if r["designed"] else BEST_CATALOGUE if r is best_cat else "0.45"
        ax.bar(i, v.max(), width=0.7, color=color, alpha=0.25 if r["feasible"] else 0.08,
               edgecolor=color, hatch=None if r["feasible"] else "//")  # fmt: skip
        ax.scatter(i + rng.uniform(-0.22, 0.22, len(v)), v, s=9, color=color, zorder=3)
        ax.text(i, v.max() * 1.04, f"{v.max():.3g}", ha="center", va="bottom", fontsize=7)
    if floor is not None:
        ax.axhline(floor, color=BEST_CATALOGUE, lw=0.8, ls="--")
    ax.set_yscale("log")
    ax.set_xticks(range(len(rows)))
    ax.set_xticklabels(
        [r["label"] + ("" if r["feasible"] else " *") for r in rows],
        rotation=35,
        ha="right",
        fontsize=8,
    )
    ax.set_ylabel("RMS horizontal error, unknown signs, max over run (nmi)")
    ax.set_title(title, fontsize=10)
    ax.grid(True, axis="y", which="both", alpha=0.3)
    fig.text(
        0.01,
        0.01,
        "bar: worst over the motions; dots: each motion; * breaks a constraint of the design",
        fontsize=7,
    )
    fig.tight_layout(rect=(0, 0.03, 1, 1))
    return fig


def front(
    points: list[dict[str, Any]],
    catalogue: list[dict[str, Any]],
    max_starts: float,
    title: str,
) -> Figure:
    """Worst RMS against motor starts per hour: verified candidates, their front, the catalogue.

    Parameters
    ----------
    points : list of dict
        Verified candidates: ``starts`` (per hour), ``worst`` (nmi), ``front`` (bool),
        ``chosen`` (bool).
    catalogue : list of dict
        ``label``, ``starts``, ``worst`` of each catalogue scheme.
    max_starts : float
        The design's limit (vertical line).
    title : str
    """
    fig = Figure(figsize=(7.5, 4.8))
    ax = fig.add_subplot(1, 1, 1)
    if points:
        s = np.array([p["starts"] for p in points])
        w = np.array([p["worst"] for p in points])
        ax.scatter(s, w, s=16, color="0.6", label="verified candidates")
        f = sorted((p for p in points if p["front"]), key=lambda p: p["starts"])
        if f:
            ax.plot([p["starts"] for p in f], [p["worst"] for p in f], "-o", color=DESIGNED,
                    ms=4, label="Pareto front")  # fmt: skip
        for p in points:
            if p["chosen"]:
                ax.scatter([p["starts"]], [p["worst"]], s=90, facecolors="none",
                           edgecolors=DESIGNED, lw=1.5, label="chosen")  # fmt: skip
    for c in catalogue:
        ax.scatter([c["starts"]], [c["worst"]], marker="s", s=22, color=BEST_CATALOGUE)
        ax.annotate(c["label"], (c["starts"], c["worst"]), fontsize=7, xytext=(3, 3),
                    textcoords="offset points")  # fmt: skip
    ax.axvline(max_starts, color="k", lw=0.8, ls=":", label="motor-start limit")
    ax.set_yscale("log")
    ax.set_xlabel("motor starts per hour")
    ax.set_ylabel("worst RMS horizontal error over the motion set (nmi)")
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    return fig


def schedule(t: np.ndarray, outer: np.ndarray, inner: np.ndarray | None, title: str) -> Figure:
    """Gimbal angles (deg) against time (h) of the chosen schedule."""
    fig = Figure(figsize=(8.0, 3.2))
    ax = fig.add_subplot(1, 1, 1)
    ax.plot(t, outer, lw=1.0, color=DESIGNED, label="outer (azimuth)")
    if inner is not None:
        ax.plot(t, inner, lw=1.0, color=BEST_CATALOGUE, label="inner")
        ax.legend(fontsize=7)
    ax.set_xlabel("time (h)")
    ax.set_ylabel("gimbal angle (deg)")
    ax.set_title(title, fontsize=10)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    return fig


def search_history(generations: list[dict[str, Any]], title: str) -> Figure:
    """Best objective of the search against the generation."""
    fig = Figure(figsize=(6.0, 3.2))
    ax = fig.add_subplot(1, 1, 1)
    g = [x["index"] for x in generations]
    b = [x["best"] for x in generations]
    ax.plot(g, b, "-o", ms=3, color=DESIGNED)
    ax.set_yscale("log")
    ax.set_xlabel("generation")
    ax.set_ylabel("best objective (nmi; > 1000: no feasible member)")
    ax.set_title(title, fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    return fig
