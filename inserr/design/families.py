"""Families of schedules: the design variables, and a candidate as a scheme and a scenario table.

A family turns a vector of design variables into a scheme (any object with
``plan(motion, duration)``), the ``[scheme]`` table of a scenario file that
``inserr run`` accepts for it, and the violations of the family's own rules
(:class:`Decoded`). Variables are rounded to a resolution a table controller can
hold (0.1 s, 0.01 deg/s) before decoding, so that a candidate is named exactly by
its rounded variables (the evaluation cache's key).

Families (``design.family``)
----------------------------
``single-axis``
    An open-loop cycle of ``N = design.stops`` stops about the outer (azimuth) axis:
    the table positions ``p_1 .. p_{N-1}`` (integer multiples of
    ``design.angle_step`` within ``+- design.table_range``; the cycle starts and
    closes at 0, so its net turn is zero), the stop times ``d_0 .. d_{N-1}`` (within
    ``design.stop_range``) and the table rate (``design.rate_range``). Each turn goes
    straight from one position to the next, so its direction and angle follow from
    the positions and the table never leaves the range. Two equal positions in a
    row are one longer stop (one motor start fewer). The stop times are *balanced*
    before use: the smallest change (least squares) that makes the cycle integral
    of ``(cos a, sin a)`` vanish, turns included, i.e. that cancels every
    horizontal constant bias over a cycle on a static base. A cycle whose balanced
    stops leave the stop range, or that cannot be balanced, violates the rules.
``nulling``
    The nulling two-position rule with its minimum stop, longest lengthening
    (``design.extension_range``), phase rule (golden or synchronous) and rate free.
``flexible``
    P0's flexible rule with its stop, rate, threshold (``design.delta_range``) and
    variant free.
``dual-axis``
    An open-loop cycle of ``N`` 180 deg turns, each of the outer or the inner gimbal,
    either way, with one stop time and the rate; the cycle must close (each gimbal's
    net turn zero).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from inserr.core.errors import InputError
from inserr.core.units import DEG
from inserr.scenario.schema import Scenario
from inserr.schemes.open_loop import Step, TableScheme

FAMILIES = ("single-axis", "single-axis-golden", "nulling", "flexible", "dual-axis")
#: Largest cycle integral of ``exp(i a)`` (s) a balanced single-axis cycle may leave: a
#: millisecond of a bias per cycle, some 0.1 s over 72 h, far below anything reported.
BALANCE_TOLERANCE = 1e-3


@dataclass(frozen=True)
class Variable:
    """One design variable.

    Attributes
    ----------
    name : str
    lower, upper : float
        Bounds, in ``unit``.
    unit : str
        Unit of the value as the optimizer sees it (``"s"``, ``"deg/s"``, ``""``).
    digits : int or None
        Decimal digits kept (None: an integer variable).
    """

    name: str
    lower: float
    upper: float
    unit: str = ""
    digits: int | None = None

    @property
    def integer(self) -> bool:
        """Whether the variable takes integer values only."""
        return self.digits is None


@dataclass(frozen=True)
class Decoded:
    """A candidate as a scheme.

    Attributes
    ----------
    scheme : object
        Has ``plan(motion, duration) -> TableSchedule``.
    table : dict
        The ``[scheme]`` table of a scenario file for it (values as a file holds them;
        ``steps`` the rows of ``[[scheme.steps]]``).
    violation : dict
        Violations of the family's rules, dimensionless, > 0 when broken.
    summary : str
        One line describing it.
    """

    scheme: Any
    table: dict[str, Any]
    violation: dict[str, float] = field(default_factory=dict)
    summary: str = ""


def _fmt(value: float) -> str:
    """Shortest text of a float that reads back as the same float."""
    return repr(float(value))


class Family:
    """Base class: a named set of variables and a decoder (see the module docstring)."""

    name = ""

    def __init__(self, settings: dict[str, Any]):
        self.settings = settings

    @property
    def spec(self) -> dict[str, Any]:
        """JSON-able description (family name and settings): rebuilds it on a worker."""
        return {"family": self.name, "settings": self.settings}

    def variables(self) -> list[Variable]:
        """The design variables, in optimizer order."""
        raise NotImplementedError

    def decode(self, x) -> Decoded:
        """The candidate of the (rounded) variables ``x``."""
        raise NotImplementedError

    def start(self) -> list[float] | None:
        """A member close to the catalogue's counterpart, to seed the search (or None)."""
        return None

    def round(self, x) -> list[float]:
        """``x`` rounded to the variables' resolution and clipped to their bounds."""
        out = []
        for v, value in zip(self.variables(), x, strict=True):
            r = float(round(float(value))) if v.integer else round(float(value), v.digits)
            out.append(min(max(r, v.lower), v.upper))
        return out

    def _mounting(self):
        m = self.settings.get("mounting")
        return None if m is None else np.array(m, dtype=float)


def _range_setting(scen: Scenario, key: str, default: tuple[float, float]) -> tuple[float, float]:
    values = scen.value(key)
    if values is None:
        return default
    if len(values) == 1:
        return float(values[0]), float(values[0])
    if len(values) != 2 or values[0] > values[1]:
        raise InputError(key, f"expected LOW, HIGH, got {values}", "e.g. 300, 600 s")
    return float(values[0]), float(values[1])


# --- single-axis ------------------------------------------------------------------------
class SingleAxis(Family):
    """Open-loop single-axis cycle with free positions, stop times and rate."""

    name = "single-axis"

    @property
    def n(self) -> int:
        return int(self.settings["stops"])

    @property
    def k_max(self) -> int:
        """Largest |position| in angle steps within the table range."""
        return int(math.floor(self.settings["table_range_deg"] / self.settings["step_deg"] + 1e-9))

    def variables(self) -> list[Variable]:
        s = self.settings
        out = [Variable(f"p{k}", -self.k_max, self.k_max) for k in range(1, self.n)]
        out += [Variable(f"d{k}", *s["stop_range"], "s", 1) for k in range(self.n)]
        if s["rate_range_deg"][0] < s["rate_range_deg"][1]:
            out.append(Variable("rate", *s["rate_range_deg"], "deg/s", 2))
        return out

    def start(self) -> list[float]:
        """The mean-zero two-position order 0, +180, 0, -180 (as far as the step allows)."""
        s = self.settings
        half = min(round(180.0 / s["step_deg"]), self.k_max)
        out = [float((half, 0, -half, 0)[k % 4]) for k in range(self.n - 1)]
        out += [s["stop_range"][0]] * self.n
        if len(SingleAxis.variables(self)) > len(out):  # a free rate
            out.append(min(max(s["rate"], s["rate_range_deg"][0]), s["rate_range_deg"][1]))
        return out

    def _cycle(self, x) -> tuple[np.ndarray, np.ndarray, float, dict[str, float]]:
        """The balanced cycle of ``x``: stop positions (deg), stop times (s), rate (deg/s)
        and the violations of the rules (positions empty when there is no turn)."""
        s = self.settings
        n = self.n
        x = list(x)
        step = s["step_deg"]
        codes = [0] + [int(round(v)) for v in x[: n - 1]] + [0]
        pos_deg = [c * step for c in codes]  # positions at stops 0..n-1, then the closing 0
        dwell = np.array(x[n - 1 : 2 * n - 1], dtype=float)
        rate_deg = x[2 * n - 1] if len(x) > 2 * n - 1 else s["rate_range_deg"][0]
        violation: dict[str, float] = {}
        # Merge stops at the same position (no turn between them).
        stops: list[list[float]] = []  # [position deg, dwell]
        for k in range(n):
            if stops and pos_deg[k] == stops[-1][0]:
                stops[-1][1] += dwell[k]
            else:
                stops.append([pos_deg[k], float(dwell[k])])
        if len(stops) > 1 and stops[-1][0] == 0.0:  # the last stop runs into the first
            stops[0][1] += stops.pop()[1]
        if len(stops) < 2:
            violation["no_turn"] = 1.0
            return np.zeros(0), np.zeros(0), rate_deg, violation
        p = np.array([q for q, _ in stops])
        d = np.array([w for _, w in stops])
        d = self._balanced(p, d, rate_deg, violation)
        return p, d, rate_deg, violation

    def _balanced(
        self, p: np.ndarray, d: np.ndarray, rate_deg: float, violation: dict[str, float]
    ) -> np.ndarray:
        """Stop times ``d`` at positions ``p`` (deg) balanced; violations added in place."""
        lo, hi = self.settings["stop_range"]
        d, resid = balance(p * DEG, d, rate_deg * DEG, lo, hi)
        if resid > BALANCE_TOLERANCE:
            violation["balance"] = violation.get("balance", 0.0) + resid / lo
        excess = float(np.sum(np.maximum(lo - d, 0.0)) + np.sum(np.maximum(d - hi, 0.0)))
        if excess > 1e-9:
            violation["stop_range"] = violation.get("stop_range", 0.0) + excess / lo
        return d

    def decode(self, x) -> Decoded:
        p, d, rate_deg, violation = self._cycle(x)
        if len(p) == 0:
            return Decoded(None, {}, violation, "no turn")
        scheme, table = _table_of([(p, d)], rate_deg, self._mounting())
        order = " ".join(f"{q:g}" for q in p)
        summary = (
            f"positions {order} deg, stops {' '.join(f'{v:.1f}' for v in d)} s, {rate_deg:g} deg/s"
        )
        return Decoded(scheme, table, violation, summary)


def _table_of(
    cycles: list[tuple[np.ndarray, np.ndarray]], rate_deg: float, mounting
) -> tuple[TableScheme, dict[str, Any]]:
    """A single-axis table flying ``cycles`` (positions deg, stop times s) in turn, then
    again from the first: each turn goes straight to the next position; every cycle
    starts at position 0 (its first stop), so cycles join without an extra turn."""
    seq = [(float(q), float(w)) for p, d in cycles for q, w in zip(p, d, strict=True)]
    m = len(seq)
    steps, rows = [], []
    for k in range(m):
        nxt, dw = seq[(k + 1) % m]
        angle_deg = nxt - seq[k][0]
        steps.append(Step("outer", angle_deg * DEG, dw, label=f"{nxt:g}"))
        rows.append(
            {
                "gimbal": "outer",
                "angle": f"{_fmt(angle_deg)} deg",
                "dwell": f"{_fmt(dw)} s",
                "label": f"{nxt:g}",
            }
        )
    scheme = TableScheme(
        "custom", tuple(steps), rate_deg * DEG, seq[0][1], start_label="0", mounting=mounting
    )
    table = {
        "name": "custom",
        "rate": f"{_fmt(rate_deg)} deg/s",
        "stop": f"{_fmt(seq[0][1])} s",
        "steps": rows,
    }
    return scheme, table


#: Fraction of the cycles of a two-length sequence that are the stretched one: 1 / phi^2,
#: the most irrational slope (its Sturmian word is the Fibonacci word).
GOLDEN_SLOPE = (3.0 - math.sqrt(5.0)) / 2.0


def golden_word(count: int) -> list[int]:
    """The first ``count`` letters (0 or 1) of the Sturmian word of slope 1/phi^2.

    Letter ``c`` is ``floor((c + 1) s) - floor(c s)`` (``s`` = :data:`GOLDEN_SLOPE`):
    a 1 in a fraction ``s`` of the places, never periodic, every block of letters
    recurring at irregular distances (the Fibonacci word, 0 and 1 swapped).
    """
    return [math.floor((c + 1) * GOLDEN_SLOPE) - math.floor(c * GOLDEN_SLOPE) for c in range(count)]


class SingleAxisGolden(SingleAxis):
    """Two balanced cycles of the same positions flown in the golden (Fibonacci) order.

    Why: a repeated cycle of length ``L`` meets every swing whose period is ``L / k``
    at the same phase cycle after cycle, and the swing-induced errors (the
    misalignments of the horizontal gyros to the yaw rate above all) add up cycle
    after cycle. Here cycle A (the designed stops) and cycle B (the same positions,
    stops ``stretch`` times longer, balanced again) follow the Sturmian word of
    slope 1/phi^2: the cycle starts are ``c L_A + n_B(c) (L_B - L_A)``; a swing meets
    every cycle at the same phase only if its period divides both ``L_A`` and ``L_B``,
    which the stretch keeps away from the long periods that matter. The variables are
    the single-axis ones plus ``stretch``; the table lists every cycle of the run
    (``horizon`` s) and is still an open-loop table. A B cycle stretched by less than
    half the asked ``stretch - 1`` (stops at the top of the range cannot grow) breaks
    the family's rules.
    """

    name = "single-axis-golden"

    def variables(self) -> list[Variable]:
        lo, hi = self.settings["stretch_range"]
        return super().variables() + [Variable("stretch", lo, hi, "", 3)]

    def start(self) -> list[float]:
        lo, hi = self.settings["stretch_range"]
        return super().start() + [min(max(1.0 + GOLDEN_SLOPE, lo), hi)]

    def decode(self, x) -> Decoded:
        x = list(x)
        stretch = float(x[-1])
        p, d, rate_deg, violation = self._cycle(x[:-1])
        if len(p) == 0:
            return Decoded(None, {}, violation, "no turn")
        d_b = self._balanced(p, d * stretch, rate_deg, violation)
        # Stops at the top of the range cannot stretch, and balancing may pull B back onto
        # A: a B cycle less than half as stretched as asked is the repeated cycle again.
        gain = float(np.sum(d_b) / np.sum(d)) - 1.0
        if gain < 0.5 * (stretch - 1.0):
            violation["stretch"] = 1.0 - gain / (0.5 * (stretch - 1.0))
        turn = float(np.sum(np.abs(np.diff(np.append(p, p[0]))))) / rate_deg
        shortest = min(float(np.sum(d)), float(np.sum(d_b))) + turn
        count = int(math.ceil(self.settings["horizon"] / shortest)) + 1
        word = golden_word(count)
        scheme, table = _table_of(
            [(p, d_b) if w else (p, d) for w in word], rate_deg, self._mounting()
        )
        order = " ".join(f"{q:g}" for q in p)
        summary = (
            f"golden: positions {order} deg, stops {' '.join(f'{v:.1f}' for v in d)} s "
            f"and x{stretch:g} ({' '.join(f'{v:.1f}' for v in d_b)} s), {rate_deg:g} deg/s"
        )
        return Decoded(scheme, table, violation, summary)


def balance(
    a: np.ndarray, d: np.ndarray, rate: float, lo: float, hi: float
) -> tuple[np.ndarray, float]:
    """Stop times in ``[lo, hi]`` closest to ``d`` that cancel the cycle integral of ``exp(i a)``.

    A cycle stops ``d_k`` seconds at table angle ``a_k`` and turns straight from each
    position to the next (the last back to the first) at ``rate``. Its integral of
    ``exp(i a(t))`` is ``sum_k d_k exp(i a_k) + sum_turns -i (exp(i a2) - exp(i a1)) / (s
    rate)`` (``s`` the turn's sign). Where it vanishes, every horizontal constant bias
    cancels over the cycle on a static base (turns included), whatever the vehicle's
    attitude. Two linear conditions on the stop times: the least-squares (minimum-norm)
    correction when it stays within the bounds; otherwise the bounded least-squares
    point (stiff weight on the conditions, ``scipy.optimize.lsq_linear``), then the
    minimum-norm correction of the stops it left strictly inside the bounds.

    Parameters
    ----------
    a : (m,) rad
        Stop angles (consecutive ones differ).
    d : (m,) s
        Stop times before balancing.
    rate : float, rad/s
        Table rate.
    lo, hi : float, s
        Bounds of a stop time.

    Returns
    -------
    d : (m,) s
        Balanced stop times (within the bounds up to round-off).
    residual : float, s
        What could not be cancelled (0 up to round-off when a balance exists).
    """
    turns = 0j
    m = len(a)
    for k in range(m):
        a1, a2 = a[k], a[(k + 1) % m]
        if a1 != a2:
            sign = math.copysign(1.0, a2 - a1)
            turns += -1j * (np.exp(1j * a2) - np.exp(1j * a1)) / (sign * rate)
    mat = np.vstack([np.cos(a), np.sin(a)])
    target = -np.array([turns.real, turns.imag])

    def residual(x):
        return float(np.linalg.norm(mat @ x - target))

    out = d + np.linalg.pinv(mat) @ (target - mat @ d)
    if np.all(out >= lo) and np.all(out <= hi):
        return out, residual(out)
    from scipy.optimize import lsq_linear

    weight = 1.0e3  # the conditions (s) over closeness (s): balance first
    stacked = np.vstack([weight * mat, np.eye(m)])
    rhs = np.concatenate([weight * target, d])
    out = lsq_linear(stacked, rhs, bounds=(lo, hi), method="bvls").x
    free = (out > lo + 1e-9) & (out < hi - 1e-9)
    if np.any(free):
        fix = out.copy()
        fix[free] += np.linalg.pinv(mat[:, free]) @ (target - mat @ out)
        if np.all(fix >= lo) and np.all(fix <= hi) and residual(fix) <= residual(out):
            out = fix
    return np.clip(out, lo, hi), residual(np.clip(out, lo, hi))


# --- closed-loop rules ------------------------------------------------------------------
def _rate_variable(settings: dict[str, Any]) -> list[Variable]:
    lo, hi = settings["rate_range_deg"]
    return [Variable("rate", lo, hi, "deg/s", 2)] if lo < hi else []


def _rate_of(x: list[float], index: int, settings: dict[str, Any]) -> float:
    return x[index] if len(x) > index else settings["rate_range_deg"][0]


def _start_rate(settings: dict[str, Any]) -> list[float]:
    lo, hi = settings["rate_range_deg"]
    return [min(max(settings["rate"], lo), hi)] if lo < hi else []


def _clip(v: float, bounds: tuple[float, float]) -> float:
    return min(max(v, bounds[0]), bounds[1])


class Nulling(Family):
    """The nulling two-position rule: minimum stop, longest lengthening, phase rule
    (golden or synchronous, :data:`inserr.schemes.nulling.PHASES`), rate."""

    name = "nulling"

    def variables(self) -> list[Variable]:
        s = self.settings
        return [
            Variable("stop", *s["stop_range"], "s", 1),
            Variable("extension", *s["extension_range"], "s", 1),
            Variable("phase", 0, 1),
            *_rate_variable(s),
        ]

    def start(self) -> list[float]:
        s = self.settings
        return [
            s["stop_range"][0],
            _clip(s["stop_range"][0], s["extension_range"]),
            0.0,  # the catalogue rule's golden phase
            *_start_rate(s),
        ]

    def decode(self, x) -> Decoded:
        from inserr.schemes.nulling import PHASES, NullingTwoPosition

        s = self.settings
        x = list(x)
        phase = PHASES[int(round(x[2]))]
        rate_deg = _rate_of(x, 3, s)
        scheme = NullingTwoPosition(
            rate_deg * DEG,
            x[0],
            mounting=self._mounting(),
            f=s["decision_rate"],
            delta=s["delta"],
            extension=x[1],
            phase=phase,
        )
        table = {
            "name": "nulling-two-position",
            "rate": f"{_fmt(rate_deg)} deg/s",
            "stop": f"{_fmt(x[0])} s",
            "extension": f"{_fmt(x[1])} s",
            "phase": phase,
            "delta": s["delta"],
            "decision_rate": f"{_fmt(s['decision_rate'])} Hz",
        }
        summary = f"nulling ({phase}), stop {x[0]:g} s, extension {x[1]:g} s, {rate_deg:g} deg/s"
        return Decoded(scheme, table, {}, summary)


VARIANTS = ("threshold", "crossing")


class Flexible(Family):
    """P0's flexible two-position rule: stop, rate, threshold, variant."""

    name = "flexible"

    def variables(self) -> list[Variable]:
        s = self.settings
        return [
            Variable("stop", *s["stop_range"], "s", 1),
            Variable("delta", *s["delta_range"], "", 4),
            Variable("variant", 0, 1),
            *_rate_variable(s),
        ]

    def start(self) -> list[float]:
        s = self.settings
        return [
            s["stop_range"][0],
            _clip(s["delta"], s["delta_range"]),
            float(VARIANTS.index(s["variant"])),
            *_start_rate(s),
        ]

    def decode(self, x) -> Decoded:
        from inserr.schemes.closed_loop import FlexibleTwoPosition

        s = self.settings
        x = list(x)
        variant = VARIANTS[int(round(x[2]))]
        rate_deg = _rate_of(x, 3, s)
        scheme = FlexibleTwoPosition(
            rate_deg * DEG,
            x[0],
            delta=x[1],
            f=s["decision_rate"],
            variant=variant,
            mounting=self._mounting(),
        )
        table = {
            "name": "flexible-two-position",
            "rate": f"{_fmt(rate_deg)} deg/s",
            "stop": f"{_fmt(x[0])} s",
            "delta": x[1],
            "variant": variant,
            "decision_rate": f"{_fmt(s['decision_rate'])} Hz",
        }
        summary = f"flexible ({variant}), stop {x[0]:g} s, delta {x[1]:g}, {rate_deg:g} deg/s"
        return Decoded(scheme, table, {}, summary)


# --- dual-axis --------------------------------------------------------------------------
#: The four moves of a dual-axis cycle: (gimbal, sign of the 180 deg turn).
MOVES = (("outer", 1), ("outer", -1), ("inner", 1), ("inner", -1))
#: The eight-position order of the catalogue (z+ x+ z+ x+ z- x- z- x-) as move codes.
EIGHT = (0, 2, 0, 2, 1, 3, 1, 3)


class DualAxis(Family):
    """Open-loop dual-axis cycle of 180 deg turns: the order, one stop time, the rate."""

    name = "dual-axis"

    @property
    def n(self) -> int:
        return int(self.settings["stops"])

    def variables(self) -> list[Variable]:
        s = self.settings
        out = [Variable(f"m{k}", 0, len(MOVES) - 1) for k in range(self.n)]
        out.append(Variable("stop", *s["stop_range"], "s", 1))
        return out + _rate_variable(s)

    def start(self) -> list[float]:
        s = self.settings
        codes = [float(EIGHT[k % len(EIGHT)]) for k in range(self.n)]
        return codes + [s["stop_range"][0], *_start_rate(s)]

    def decode(self, x) -> Decoded:
        s = self.settings
        x = list(x)
        n = self.n
        moves = [MOVES[int(round(v))] for v in x[:n]]
        stop = x[n]
        rate_deg = _rate_of(x, n + 1, s)
        net = {"outer": 0, "inner": 0}
        for g, sign in moves:
            net[g] += sign
        violation = {}
        closure = abs(net["outer"]) + abs(net["inner"])  # half turns left over per cycle
        if closure:
            violation["closure"] = float(closure)
        steps = tuple(
            Step(g, sign * math.pi, stop, label=f"{g[0]}{'+' if sign > 0 else '-'}{k + 1}")
            for k, (g, sign) in enumerate(moves)
        )
        scheme = TableScheme(
            "custom", steps, rate_deg * DEG, stop, start_label="P0", mounting=self._mounting()
        )
        rows = [
            {
                "gimbal": g,
                "angle": f"{180 * sign} deg",
                "dwell": f"{_fmt(stop)} s",
                "label": st.label,
            }
            for (g, sign), st in zip(moves, steps, strict=True)
        ]
        table = {
            "name": "custom",
            "rate": f"{_fmt(rate_deg)} deg/s",
            "stop": f"{_fmt(stop)} s",
            "steps": rows,
        }
        order = " ".join(st.label.rstrip("0123456789") for st in steps)
        summary = f"dual-axis {order}, stops {stop:g} s, {rate_deg:g} deg/s"
        return Decoded(scheme, table, violation, summary)


_CLASSES = {c.name: c for c in (SingleAxis, SingleAxisGolden, Nulling, Flexible, DualAxis)}


def family_from_spec(spec: dict[str, Any]) -> Family:
    """Rebuild a family from :attr:`Family.spec` (on a worker)."""
    return _CLASSES[spec["family"]](spec["settings"])


def build_family(scen: Scenario, name: str | None = None) -> Family:
    """The family ``name`` (default ``design.family``) with the scenario's settings.

    Parameters
    ----------
    scen : Scenario
        Supplies ``[design]`` and the ``[scheme]`` values the family starts from
        (stop, rate, threshold, variant, decision rate, mounting).
    name : str, optional
        A family of :data:`FAMILIES`.

    Raises
    ------
    InputError
        Unknown family, bad ranges or step.
    """
    name = name or scen.value("design.family")
    if name not in FAMILIES:
        raise InputError(
            "design.family", f"unknown family {name!r}", f"use one of: {', '.join(FAMILIES)}"
        )
    stop, rate = scen.scheme_stop, scen.scheme_rate
    if stop <= 0:
        raise InputError("scheme.stop", "a design needs stops > 0 s", "give e.g. 300 s")
    stop_range = _range_setting(scen, "design.stop_range", (stop, 2.0 * stop))
    if stop_range[0] <= 0:
        raise InputError("design.stop_range", "stops must be > 0 s", "e.g. 300, 600 s")
    rr = _range_setting(scen, "design.rate_range", (rate, rate))
    if rr[0] <= 0:
        raise InputError("design.rate_range", "rates must be > 0", "e.g. 6, 12 deg/s")
    mounting = scen.scheme_options.get("mounting")
    settings: dict[str, Any] = {
        "stop_range": [round(stop_range[0], 1), round(stop_range[1], 1)],
        "rate_range_deg": [round(rr[0] / DEG, 2), round(rr[1] / DEG, 2)],
        "rate": round(rate / DEG, 2),
        "mounting": None if mounting is None else np.asarray(mounting).tolist(),
    }
    table_range = scen.value("design.table_range") / DEG
    if name in ("single-axis", "single-axis-golden", "dual-axis"):
        n = scen.value("design.stops")
        if not 2 <= n <= 64:
            raise InputError("design.stops", f"must be 2 to 64, got {n}", "e.g. 8")
        settings["stops"] = n
        settings["table_range_deg"] = round(table_range, 9)
    if name == "single-axis-golden":
        sr = _range_setting(scen, "design.stretch_range", (1.2, 2.0))
        if sr[0] <= 1.0:
            raise InputError("design.stretch_range", "must be > 1 (B longer than A)", "1.2, 2")
        settings["stretch_range"] = [round(sr[0], 3), round(sr[1], 3)]
        settings["horizon"] = float(scen.duration)
    if name in ("single-axis", "single-axis-golden"):
        step = round(scen.value("design.angle_step") / DEG, 9)
        if not 0 < step <= table_range:
            raise InputError(
                "design.angle_step", f"must be > 0 and <= design.table_range, got {step:g} deg"
            )
        settings["step_deg"] = step
    if name in ("nulling", "flexible"):
        settings["decision_rate"] = float(scen.value("scheme.decision_rate"))
        settings["delta"] = float(scen.value("scheme.delta"))
    if name == "nulling":
        ext = _range_setting(scen, "design.extension_range", (0.0, 2.0 * stop))
        if ext[0] < 0:
            raise InputError("design.extension_range", "must be >= 0 s", "e.g. 0, 600 s")
        settings["extension_range"] = [round(ext[0], 1), round(ext[1], 1)]
    if name == "flexible":
        dr = scen.value("design.delta_range")
        if len(dr) != 2 or not 0 <= dr[0] <= dr[1]:
            raise InputError("design.delta_range", f"expected LOW, HIGH >= 0, got {list(dr)}")
        settings["delta_range"] = [float(dr[0]), float(dr[1])]
        settings["variant"] = scen.value("scheme.variant")
    return _CLASSES[name](settings)
