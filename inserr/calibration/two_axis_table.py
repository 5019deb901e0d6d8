"""Two-axis indexing tables and the IMU position sets they reach.

Frames: n = local-level East-North-Up (ENU), s = IMU (sensor) frame. ``C_s^n`` maps
IMU components to ENU components (:mod:`inserr.core.rotations`).

Geometry of a two-axis table
----------------------------
The *outer* axis is fixed to the ground (direction ``a_out`` in ENU); it carries the
inner gimbal. The *inner* axis is fixed to the IMU mounting plate (direction ``a_in``
in IMU components, it never moves relative to the IMU). With gimbal angles
``outer`` = alpha and ``inner`` = beta (right hand, rad) the IMU attitude is::

    C_s^n(alpha, beta) = rot(a_out^n, alpha) @ C0 @ rot(a_in^s, beta)

where ``C0`` is the IMU attitude at zero gimbal angles. A turn about the ground-fixed
axis pre-multiplies, a turn about the IMU-fixed axis post-multiplies, so the order in
which the two gimbals are indexed does not change the attitude reached: a position is
a pair of gimbal angles.

Built-in position sets
----------------------
* :func:`offaxis_four_position` -- P1 (Miao et al. 2018): azimuth (vertical) outer
  axis carrying IMU z; inner axis horizontal at 45 deg to IMU x. The inner axis is
  placed along ``(1, -1, 0)/sqrt(2)`` in IMU components, i.e. from +x towards -y. With
  that sign the ideal Earth-rate inputs come out *exactly* as P1's p1..p4; with the
  mirror choice ``(1, 1, 0)/sqrt(2)`` p2 and p3 are swapped (a 180 deg turn does not
  depend on its sense, so this is the only convention left open by P1's text).
* :func:`six_position` -- the classical six-position (up/down) static test: each
  sensitive axis pointed up, then down (Titterton & Weston, *Strapdown Inertial
  Navigation Technology*, 2nd ed., IET 2004, ch. 8; Aggarwal et al., "A standard
  testing and calibration procedure for low cost MEMS inertial sensors and units",
  *J. Navigation* 61, 2008). Those references fix which axis is up; the headings of
  the horizontal axes are ours: each up/down pair is related by a 180 deg turn about
  the horizontal east axis, so gravity *and* Earth-rate inputs both reverse (biases are
  the mean of the six positions, the error matrix follows from the three up-minus-down
  differences). It is realised on a trunnion table: horizontal outer axis along east,
  inner axis along IMU z (the table-top normal), IMU = ENU at zero angles.

Custom sets are read from a TOML file (:func:`load_position_set`); see
``docs/tutorials/calibration.md`` for the format.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from inserr.core.errors import InputError, require_finite
from inserr.core.rotations import body_to_nav, rot_axis
from inserr.core.units import DEG, DEG_PER_S, parse_quantity

#: Named directions of the navigation frame (ENU components).
NAV_AXES: dict[str, tuple[float, float, float]] = {
    "east": (1.0, 0.0, 0.0),
    "north": (0.0, 1.0, 0.0),
    "up": (0.0, 0.0, 1.0),
    "west": (-1.0, 0.0, 0.0),
    "south": (0.0, -1.0, 0.0),
    "down": (0.0, 0.0, -1.0),
}
#: Named directions of the IMU frame.
IMU_AXES: dict[str, tuple[float, float, float]] = {
    "x": (1.0, 0.0, 0.0),
    "y": (0.0, 1.0, 0.0),
    "z": (0.0, 0.0, 1.0),
    "-x": (-1.0, 0.0, 0.0),
    "-y": (0.0, -1.0, 0.0),
    "-z": (0.0, 0.0, -1.0),
}

#: Default indexing rate of the table, rad/s (the 6 deg/s of P0/P2 in this project).
DEFAULT_RATE = 6.0 * DEG_PER_S
#: Default dwell per position, s (a 5-minute stop, as P0's stop time).
DEFAULT_DWELL = 300.0

# A table whose axes are not perpendicular is not a two-axis indexing table; the
# tolerance only absorbs rounding of user-typed direction cosines.
_PERPENDICULAR_TOL = 1e-6


def _unit(v: Sequence[float], field_name: str) -> np.ndarray:
    a = np.asarray(v, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise InputError(field_name, f"expected three finite numbers, got {v!r}")
    n = float(np.linalg.norm(a))
    if n == 0.0:
        raise InputError(field_name, "direction is the zero vector", "give a non-zero direction")
    return a / n


@dataclass(frozen=True)
class TwoAxisTable:
    """A two-axis indexing table and the IMU mounted on it.

    Parameters
    ----------
    outer_axis : (3,) array
        Ground-fixed outer axis, unit vector in ENU.
    inner_axis : (3,) array
        Inner axis, unit vector in IMU components (fixed to the IMU).
    zero_attitude : (3, 3) array
        ``C_s^n`` at zero gimbal angles.
    rate : float
        Indexing rate, rad/s; a move of the two gimbals takes
        ``(|d outer| + |d inner|) / rate`` (one gimbal after the other).
    settle : float
        Settling time added to every move, s.
    name : str
        Short label used in reports.
    """

    outer_axis: np.ndarray
    inner_axis: np.ndarray
    zero_attitude: np.ndarray = field(default_factory=lambda: np.eye(3))
    rate: float = DEFAULT_RATE
    settle: float = 0.0
    name: str = "table"

    def __post_init__(self) -> None:
        object.__setattr__(self, "outer_axis", _unit(self.outer_axis, "table.outer_axis"))
        object.__setattr__(self, "inner_axis", _unit(self.inner_axis, "table.inner_axis"))
        c0 = np.asarray(self.zero_attitude, dtype=float)
        if c0.shape != (3, 3) or not np.allclose(c0 @ c0.T, np.eye(3), atol=1e-9):
            raise InputError("table.zero_attitude", "is not a rotation matrix")
        object.__setattr__(self, "zero_attitude", c0)
        rate = require_finite(self.rate, "table.rate")
        if rate <= 0:
            raise InputError("table.rate", f"indexing rate must be > 0, got {rate:g} rad/s")
        settle = require_finite(self.settle, "table.settle")
        if settle < 0:
            raise InputError("table.settle", f"settling time must be >= 0, got {settle:g} s")
        object.__setattr__(self, "rate", rate)
        object.__setattr__(self, "settle", settle)
        # The gimbals of an indexing table are perpendicular; at zero angles the inner
        # axis (IMU-fixed) must therefore be perpendicular to the outer axis.
        if abs(float(self.outer_axis @ (c0 @ self.inner_axis))) > _PERPENDICULAR_TOL:
            raise InputError(
                "table.inner_axis",
                "is not perpendicular to the outer axis at zero gimbal angles",
                "give an inner axis perpendicular to the outer axis (e.g. horizontal "
                "for an azimuth outer axis)",
            )

    def attitude(self, outer: float, inner: float) -> np.ndarray:
        """IMU attitude ``C_s^n = rot(a_out, outer) @ C0 @ rot(a_in, inner)``.

        Parameters
        ----------
        outer, inner : float
            Gimbal angles, rad, right hand about the outer (ENU) and inner (IMU) axes.

        Returns
        -------
        ndarray, shape (3, 3)
            ``C_s^n`` (IMU components to ENU components).
        """
        return (
            rot_axis(self.outer_axis, outer) @ self.zero_attitude @ rot_axis(self.inner_axis, inner)
        )

    def inner_axis_nav(self, outer: float, inner: float) -> np.ndarray:
        """Direction of the inner axis in ENU at the given gimbal angles.

        Parameters
        ----------
        outer, inner : float
            Gimbal angles, rad.

        Returns
        -------
        ndarray, shape (3,)
            Unit vector, ENU components.
        """
        return self.attitude(outer, inner) @ self.inner_axis

    def move_time(self, start: tuple[float, float], end: tuple[float, float]) -> float:
        """Time, s, to index from gimbal angles ``start`` to ``end`` (rad, (outer, inner)).

        Each gimbal takes the shorter way round (the table is assumed to have slip
        rings); a move that changes nothing costs nothing, otherwise the settling time
        is added once.

        Parameters
        ----------
        start, end : (float, float)
            ``(outer, inner)`` gimbal angles, rad.

        Returns
        -------
        float
            Indexing time, s: ``(|d outer| + |d inner|) / rate + settle``.
        """
        travel = sum(abs(_wrap(e - s)) for s, e in zip(start, end, strict=True))
        if travel < 1e-12:
            return 0.0
        return travel / self.rate + self.settle


def _wrap(angle: float) -> float:
    """Angle wrapped to [-pi, pi) (rad)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


@dataclass(frozen=True)
class Position:
    """One stop of the table.

    Parameters
    ----------
    outer, inner : float
        Gimbal angles, rad.
    dwell : float
        Dwell (data-collection) time at this stop, s.
    name : str
        Label (``p1``...).
    """

    outer: float
    inner: float
    dwell: float
    name: str

    def __post_init__(self) -> None:
        require_finite(self.outer, f"{self.name}.outer")
        require_finite(self.inner, f"{self.name}.inner")
        d = require_finite(self.dwell, f"{self.name}.dwell")
        if d <= 0:
            raise InputError(f"{self.name}.dwell", f"dwell must be > 0 s, got {d:g}")


@dataclass(frozen=True)
class PositionSet:
    """A sequence of table stops visited in order.

    Parameters
    ----------
    name : str
        Label of the set.
    table : TwoAxisTable
        The mechanism.
    positions : tuple of Position
        The stops, in the order they are visited; the clock starts at the first stop
        (the table is set there before the calibration begins, as in P1).
    """

    name: str
    table: TwoAxisTable
    positions: tuple[Position, ...]

    def __post_init__(self) -> None:
        if len(self.positions) == 0:
            raise InputError("positions", "the position set is empty", "give at least one position")

    def __len__(self) -> int:
        return len(self.positions)

    @property
    def attitudes(self) -> np.ndarray:
        """Nominal ``C_s^n`` of every stop, shape (N, 3, 3)."""
        return np.stack([self.table.attitude(p.outer, p.inner) for p in self.positions])

    @property
    def dwells(self) -> np.ndarray:
        """Dwell time of every stop, s, shape (N,)."""
        return np.array([p.dwell for p in self.positions])

    @property
    def dwell_time(self) -> float:
        """Sum of the dwell times, s."""
        return float(self.dwells.sum())

    @property
    def indexing_time(self) -> float:
        """Time spent moving between consecutive stops, s."""
        stops = [(p.outer, p.inner) for p in self.positions]
        return float(
            sum(self.table.move_time(a, b) for a, b in zip(stops[:-1], stops[1:], strict=True))
        )

    @property
    def total_time(self) -> float:
        """Dwell plus indexing time, s."""
        return self.dwell_time + self.indexing_time

    def with_dwell(self, dwell: float) -> PositionSet:
        """A copy with every stop's dwell set to ``dwell``.

        Parameters
        ----------
        dwell : float
            Dwell per stop, s, > 0.

        Returns
        -------
        PositionSet
        """
        return PositionSet(
            self.name,
            self.table,
            tuple(Position(p.outer, p.inner, dwell, p.name) for p in self.positions),
        )

    def describe(self) -> list[dict[str, Any]]:
        """Per-stop summary: name, gimbal angles (deg), dwell (s), IMU axis pointing up.

        Returns
        -------
        list of dict
            Keys ``name``, ``outer_deg``, ``inner_deg``, ``dwell_s``, ``up_axis``
            (:func:`up_axis_label`).
        """
        out = []
        for p, c in zip(self.positions, self.attitudes, strict=True):
            out.append(
                {
                    "name": p.name,
                    "outer_deg": math.degrees(p.outer),
                    "inner_deg": math.degrees(p.inner),
                    "dwell_s": p.dwell,
                    "up_axis": up_axis_label(c),
                }
            )
        return out


def up_axis_label(c_sn: np.ndarray) -> str:
    """Signed IMU axis closest to the local up direction (``"+z"``, ``"-x"``...).

    The up direction in IMU components is the third row of ``C_s^n``; when no axis is
    within 1 deg of it the components are given instead.

    Parameters
    ----------
    c_sn : (3, 3) array
        IMU-to-ENU DCM ``C_s^n``.

    Returns
    -------
    str
        ``"+x"`` ... ``"-z"``, or ``"(ux, uy, uz)"`` (up in IMU components).
    """
    return _axis_label(np.asarray(c_sn)[2, :])


def _axis_label(v_s: np.ndarray) -> str:
    k = int(np.argmax(np.abs(v_s)))
    if abs(v_s[k]) > math.cos(DEG):
        return ("+" if v_s[k] > 0 else "-") + "xyz"[k]
    return "(" + ", ".join(f"{v:+.3f}" for v in v_s) + ")"


def pointing(c_sn: np.ndarray) -> dict[str, str]:
    """Signed IMU axis along east, north and up (labels as :func:`up_axis_label`).

    Row ``k`` of ``C_s^n`` is ENU axis ``k`` in IMU components.

    Parameters
    ----------
    c_sn : (3, 3) array
        IMU-to-ENU DCM ``C_s^n``.

    Returns
    -------
    dict
        ``{"east": "+x", "north": "+y", "up": "+z"}`` for ``C_s^n = I``.
    """
    c = np.asarray(c_sn)
    return {name: _axis_label(c[k, :]) for k, name in enumerate(("east", "north", "up"))}


# --- mechanisms ----------------------------------------------------------------


def azimuth_table(
    inner_axis_angle: float = 0.0, rate: float = DEFAULT_RATE, settle: float = 0.0
) -> TwoAxisTable:
    """Vertical (azimuth) outer axis carrying IMU z; inner axis horizontal in the IMU x-y plane.

    Parameters
    ----------
    inner_axis_angle : float
        Angle, rad, of the inner axis from IMU x about IMU z (right hand). 0 is the
        conventional mounting (inner axis = IMU x); -45 deg is P1's off-axis mounting.
    rate : float
        Indexing rate, rad/s.
    settle : float
        Settling time per move, s.

    Returns
    -------
    TwoAxisTable
        Outer axis = ENU up; inner axis ``(cos a, sin a, 0)`` in IMU components.

    Notes
    -----
    At zero gimbal angles the IMU frame is ENU (P1's p1: s = ENU).
    """
    a = inner_axis_angle
    label = "azimuth" if a == 0.0 else f"azimuth-offaxis({math.degrees(a):+.0f}deg)"
    return TwoAxisTable(
        outer_axis=np.array(NAV_AXES["up"]),
        inner_axis=np.array([math.cos(a), math.sin(a), 0.0]),
        rate=rate,
        settle=settle,
        name=label,
    )


def trunnion_table(rate: float = DEFAULT_RATE, settle: float = 0.0) -> TwoAxisTable:
    """Horizontal outer axis along east, inner axis along IMU z (table normal); IMU = ENU at zero.

    Unlike an azimuth table, every IMU axis can be pointed up, which the accelerometer
    calibration needs (on an azimuth table the up direction stays in the plane normal
    to the inner axis, so one accelerometer input direction is never excited).

    Parameters
    ----------
    rate : float
        Indexing rate, rad/s.
    settle : float
        Settling time per move, s.

    Returns
    -------
    TwoAxisTable
    """
    return TwoAxisTable(
        outer_axis=np.array(NAV_AXES["east"]),
        inner_axis=np.array(IMU_AXES["z"]),
        rate=rate,
        settle=settle,
        name="trunnion",
    )


#: P1's mounting: inner axis from IMU +x towards -y (see module docstring).
P1_INNER_AXIS_ANGLE = -45.0 * DEG


def _positions(angles_deg: Sequence[tuple[float, float]], dwell: float) -> tuple[Position, ...]:
    return tuple(
        Position(o * DEG, i * DEG, dwell, f"p{k + 1}") for k, (o, i) in enumerate(angles_deg)
    )


def offaxis_four_position(
    dwell: float = DEFAULT_DWELL, rate: float = DEFAULT_RATE, settle: float = 0.0
) -> PositionSet:
    """P1's off-axis four-position set.

    p1: s = ENU; p2: 180 deg about the inner axis; p3: then 180 deg about the azimuth
    axis; p4: then 180 deg about the inner axis. Ideal gyro inputs (rad/s, IMU frame):
    ``[0, wN, wU], [-wN, 0, -wU], [wN, 0, -wU], [0, -wN, wU]``.

    Parameters
    ----------
    dwell : float
        Dwell per position, s.
    rate : float
        Indexing rate, rad/s.
    settle : float
        Settling time per move, s.

    Returns
    -------
    PositionSet
        Four stops on :func:`azimuth_table` with :data:`P1_INNER_AXIS_ANGLE`.
    """
    table = azimuth_table(P1_INNER_AXIS_ANGLE, rate, settle)
    angles = [(0.0, 0.0), (0.0, 180.0), (180.0, 180.0), (180.0, 360.0)]
    return PositionSet("offaxis-four-position", table, _positions(angles, dwell))


def six_position(
    dwell: float = DEFAULT_DWELL, rate: float = DEFAULT_RATE, settle: float = 0.0
) -> PositionSet:
    """The classical six-position (up/down) set on a trunnion table.

    Visiting order and up axis: z up (0, 0), z down (180, 0), y down (270, 0),
    x down (270, 90), x up (90, 90), y up (90, 0) -- (outer, inner) in deg. Ideal gyro
    inputs: ``+-[0, wN, wU], +-[0, wU, -wN], +-[wU, 0, -wN]`` (rad/s, IMU frame).

    Parameters
    ----------
    dwell : float
        Dwell per position, s.
    rate : float
        Indexing rate, rad/s.
    settle : float
        Settling time per move, s.

    Returns
    -------
    PositionSet
        Six stops on :func:`trunnion_table`.
    """
    table = trunnion_table(rate, settle)
    angles = [(0.0, 0.0), (180.0, 0.0), (270.0, 0.0), (270.0, 90.0), (90.0, 90.0), (90.0, 0.0)]
    return PositionSet("six-position", table, _positions(angles, dwell))


#: Built-in sets by CLI name.
BUILTIN_SETS = {
    "offaxis-four-position": offaxis_four_position,
    "six-position": six_position,
}


def builtin_set(
    name: str, dwell: float = DEFAULT_DWELL, rate: float = DEFAULT_RATE, settle: float = 0.0
) -> PositionSet:
    """A built-in position set by name (``six-position``, ``offaxis-four-position``).

    Parameters
    ----------
    name : str
        A key of :data:`BUILTIN_SETS`.
    dwell : float
        Dwell per position, s.
    rate : float
        Indexing rate, rad/s.
    settle : float
        Settling time per move, s.

    Returns
    -------
    PositionSet

    Raises
    ------
    InputError
        For an unknown name.
    """
    if name not in BUILTIN_SETS:
        raise InputError(
            "calibration.method",
            f"unknown method {name!r}",
            f"use one of {', '.join(BUILTIN_SETS)} or a file",
        )
    return BUILTIN_SETS[name](dwell, rate, settle)


# --- scenario files -------------------------------------------------------------

_TOP_KEYS = {"name", "dwell", "table", "positions"}
_TABLE_KEYS = {"outer_axis", "inner_axis", "heading", "pitch", "roll", "rate", "settle"}
_POSITION_KEYS = {"name", "outer", "inner", "dwell"}


def _check_keys(table: Mapping[str, Any], allowed: set[str], where: str) -> None:
    for key in table:
        if key not in allowed:
            prefix = f"{where}." if where else ""
            raise InputError(
                f"{prefix}{key}", "unknown key", f"known keys here: {', '.join(sorted(allowed))}"
            )


def _direction(value: Any, names: Mapping[str, tuple[float, float, float]], field_name: str):
    if isinstance(value, str):
        if value.strip().lower() not in names:
            raise InputError(
                field_name,
                f"unknown direction {value!r}",
                f"use one of {', '.join(names)} or [a, b, c]",
            )
        return np.array(names[value.strip().lower()])
    if (
        isinstance(value, list)
        and len(value) == 3
        and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
    ):
        return _unit(value, field_name)
    raise InputError(
        field_name,
        f"cannot read {value!r} as a direction",
        f"use one of {', '.join(names)} or three direction cosines [a, b, c]",
    )


def position_set_from_dict(
    data: Mapping[str, Any],
    default_dwell: float = DEFAULT_DWELL,
    default_rate: float = DEFAULT_RATE,
    name: str = "custom",
) -> PositionSet:
    """Build a :class:`PositionSet` from a parsed scenario mapping (see :func:`load_position_set`).

    Parameters
    ----------
    data : mapping
        Keys ``name``, ``dwell``, ``table`` and ``positions`` (list of tables).
    default_dwell : float
        Dwell, s, for stops that give none when the file has no top-level ``dwell``.
    default_rate : float
        Indexing rate, rad/s, when ``table.rate`` is absent.
    name : str
        Label used when the file gives no ``name``.

    Returns
    -------
    PositionSet
        Angles in rad, dwells in s; the table's zero attitude from ``heading``,
        ``pitch``, ``roll`` via :func:`~inserr.core.rotations.body_to_nav`.

    Raises
    ------
    InputError
        Unknown key, missing unit, wrong unit, non-finite value, bad geometry.
    """
    _check_keys(data, _TOP_KEYS, "")
    label = str(data.get("name", name))
    dwell = default_dwell
    if "dwell" in data:
        dwell = parse_quantity(data["dwell"], "time", "dwell")
    table_data = data.get("table", {})
    if not isinstance(table_data, Mapping):
        raise InputError("table", "must be a table ([table])")
    _check_keys(table_data, _TABLE_KEYS, "table")
    outer = _direction(table_data.get("outer_axis", "up"), NAV_AXES, "table.outer_axis")
    inner = _direction(table_data.get("inner_axis", "x"), IMU_AXES, "table.inner_axis")
    hpr = [
        parse_quantity(table_data.get(k, "0 deg"), "angle", f"table.{k}")
        for k in ("heading", "pitch", "roll")
    ]
    rate = default_rate
    if "rate" in table_data:
        rate = parse_quantity(table_data["rate"], "angular_rate", "table.rate")
    settle = 0.0
    if "settle" in table_data:
        settle = parse_quantity(table_data["settle"], "time", "table.settle")
    table = TwoAxisTable(outer, inner, body_to_nav(*hpr), rate, settle, name=label)

    raw = data.get("positions")
    if not isinstance(raw, list) or not raw:
        raise InputError(
            "positions", "no [[positions]] given", "add at least one [[positions]] table"
        )
    positions = []
    outer_angle = inner_angle = 0.0
    for k, entry in enumerate(raw):
        where = f"positions[{k}]"
        if not isinstance(entry, Mapping):
            raise InputError(where, "must be a table ([[positions]])")
        _check_keys(entry, _POSITION_KEYS, where)
        # Omitted gimbal angles keep the previous stop's value, so a path reads as moves.
        if "outer" in entry:
            outer_angle = parse_quantity(entry["outer"], "angle", f"{where}.outer")
        if "inner" in entry:
            inner_angle = parse_quantity(entry["inner"], "angle", f"{where}.inner")
        d = dwell
        if "dwell" in entry:
            d = parse_quantity(entry["dwell"], "time", f"{where}.dwell")
        if d <= 0:
            raise InputError(f"{where}.dwell", f"dwell must be > 0 s, got {d:g} s")
        positions.append(Position(outer_angle, inner_angle, d, str(entry.get("name", f"p{k + 1}"))))
    return PositionSet(label, table, tuple(positions))


def load_position_set(
    path: str | Path,
    default_dwell: float = DEFAULT_DWELL,
    default_rate: float = DEFAULT_RATE,
    field_name: str = "calibration.method",
) -> PositionSet:
    """Read a custom position set from a TOML file.

    Format (every dimensional value carries its unit)::

        name = "my-set"
        dwell = "300 s"                 # default dwell of the stops
        [table]
        outer_axis = "up"               # ground-fixed, ENU: up/east/north/... or [a, b, c]
        inner_axis = [1, -1, 0]         # IMU-fixed: x/y/z/-x/... or direction cosines
        heading = "0 deg"               # IMU attitude at zero gimbal angles
        pitch = "0 deg"                 # (inserr.core.rotations.body_to_nav convention)
        roll = "0 deg"
        rate = "6 deg/s"                # indexing rate
        settle = "0 s"                  # settling time per move
        [[positions]]
        outer = "0 deg"                 # omitted angles keep the previous value
        inner = "0 deg"
        dwell = "300 s"                 # optional

    Parameters
    ----------
    path : str or Path
        The file.
    default_dwell : float
        Dwell, s, if neither the file nor the stop gives one.
    default_rate : float
        Indexing rate, rad/s, if the file gives none.
    field_name : str
        Name used in error messages about the file itself.

    Returns
    -------
    PositionSet
        Named after the file stem unless the file gives a ``name``.

    Raises
    ------
    InputError
        Missing or unreadable file, malformed TOML, or any bad entry.
    """
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except OSError as exc:
        raise InputError(field_name, f"cannot read {str(p)!r}: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise InputError(
            field_name, f"{p.name} is not a UTF-8 text file", "save it as UTF-8 TOML"
        ) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(
            field_name, f"{p.name} is not valid TOML ({exc})", "fix the file syntax"
        ) from None
    return position_set_from_dict(data, default_dwell, default_rate, name=p.stem)
