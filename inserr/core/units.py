"""Named unit constants and the parser for quantities written with units.

Everything inside inserr is SI: radians, seconds, metres, m/s, m/s^2, rad/s.
Engineering units appear only at the edges (CLI flags, scenario files, reports),
always through the constants and :func:`parse_quantity` below, so a conversion is
written exactly once.

Conventions stated once:

* ``G0`` = 9.80665 m/s^2 (standard gravity) defines g, mg and micro-g. Local gravity
  (Somigliana, :mod:`inserr.core.earth`) is used for the physics, never for unit conversion.
* A *mil* is the NATO mil, 2*pi/6400 rad.
* Angle random walk in deg/sqrt(h) converts to rad/sqrt(s); velocity random walk in
  micro-g/sqrt(Hz) converts to (m/s^2)/sqrt(Hz) = m/s/sqrt(s). Both are the
  square roots of two-sided white-noise power spectral densities.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence

import numpy as np

from inserr.core.errors import InputError

# --- angle -------------------------------------------------------------------
RAD = 1.0
DEG = math.pi / 180.0
ARCMIN = DEG / 60.0
ARCSEC = DEG / 3600.0
MIL = 2.0 * math.pi / 6400.0  # NATO mil

# --- time --------------------------------------------------------------------
SECOND = 1.0
MINUTE = 60.0
HOUR = 3600.0
DAY = 86400.0

# --- length ------------------------------------------------------------------
METRE = 1.0
KM = 1000.0
NMI = 1852.0  # international nautical mile

# --- acceleration ------------------------------------------------------------
G0 = 9.80665  # standard gravity, m/s^2; the "g" of mg and micro-g
MILLI_G = 1e-3 * G0
MICRO_G = 1e-6 * G0

# --- angular rate ------------------------------------------------------------
DEG_PER_S = DEG
DEG_PER_HOUR = DEG / HOUR

# --- dimensionless -----------------------------------------------------------
PPM = 1e-6

# --- noise densities ---------------------------------------------------------
DEG_PER_SQRT_HOUR = DEG / math.sqrt(HOUR)  # ARW -> rad/sqrt(s)
MICRO_G_PER_SQRT_HZ = MICRO_G  # VRW -> (m/s^2)/sqrt(Hz) = m/s/sqrt(s)
M_PER_S_PER_SQRT_HOUR = 1.0 / math.sqrt(HOUR)

#: Units accepted for each physical kind, as factor to SI.
UNITS: dict[str, dict[str, float]] = {
    "angle": {"rad": RAD, "deg": DEG, "arcmin": ARCMIN, "arcsec": ARCSEC, "mil": MIL},
    "angular_rate": {
        "rad/s": 1.0,
        "deg/s": DEG_PER_S,
        "deg/h": DEG_PER_HOUR,
        "deg/hr": DEG_PER_HOUR,
    },
    "acceleration": {
        "m/s^2": 1.0,
        "m/s2": 1.0,
        "g": G0,
        "mg": MILLI_G,
        "ug": MICRO_G,
        "µg": MICRO_G,
        "micro-g": MICRO_G,
    },
    "ratio": {"ppm": PPM, "1": 1.0, "": 1.0},
    "arw": {"deg/sqrt(h)": DEG_PER_SQRT_HOUR, "deg/√h": DEG_PER_SQRT_HOUR, "rad/sqrt(s)": 1.0},
    "vrw": {
        "ug/sqrt(Hz)": MICRO_G_PER_SQRT_HZ,
        "µg/√Hz": MICRO_G_PER_SQRT_HZ,
        "m/s/sqrt(h)": M_PER_S_PER_SQRT_HOUR,
        "m/s/sqrt(s)": 1.0,
    },
    "time": {"s": SECOND, "min": MINUTE, "h": HOUR, "d": DAY},
    "length": {"m": METRE, "km": KM, "nmi": NMI},
    "velocity": {"m/s": 1.0},
    "frequency": {"Hz": 1.0},
}

_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?nan|[-+]?inf"
_QUANTITY = re.compile(
    rf"^\s*(?P<values>(?:{_NUMBER})(?:\s*,\s*(?:{_NUMBER}))*)\s*(?P<unit>\S*)\s*$",
    re.IGNORECASE,
)


def _article(word: str) -> str:
    return "an" if word[:1] in "aeiou" else "a"


def units_for(kind: str) -> list[str]:
    """Names of the units accepted for a physical kind (for error messages)."""
    return [u for u in UNITS[kind] if u]


def parse_quantity(
    text: str | float | int | Sequence[float],
    kind: str,
    field: str,
    *,
    default_unit: str | None = None,
    size: int | None = None,
) -> float | np.ndarray:
    """Parse ``"0.02 deg/h"`` or ``"0.01,0.02,0.03 deg/h"`` into SI.

    Parameters
    ----------
    text : str or number or sequence of numbers
        The quantity as written by a user. A bare number (or a string without a
        unit) is only accepted when ``default_unit`` is given (CLI flags have a
        documented unit; scenario files must carry one).
    kind : str
        Key of :data:`UNITS` (``"angular_rate"``, ``"acceleration"``, ...).
    field : str
        Name of the field, used in the error message.
    default_unit : str, optional
        Unit assumed when none is written.
    size : int, optional
        If 3, a single value is broadcast to the three IMU axes and exactly one or
        three values are accepted. If None, exactly one value is accepted.

    Returns
    -------
    float or ndarray
        SI value (float), or an array of shape (size,).

    Raises
    ------
    InputError
        Naming ``field``, for a wrong unit, a wrong count, or a non-finite value.
    """
    table = UNITS[kind]
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        values, unit = [float(text)], None
    elif isinstance(text, (list, tuple, np.ndarray)):
        try:
            values, unit = [float(v) for v in text], None
        except (TypeError, ValueError):
            raise InputError(field, f"expected numbers, got {text!r}") from None
    elif isinstance(text, str):
        m = _QUANTITY.match(text)
        if not m:
            raise InputError(
                field,
                f"cannot read {text!r} as a quantity",
                f"write a number (or x,y,z) followed by one of: {', '.join(units_for(kind))}",
            )
        values = [float(v) for v in m.group("values").split(",")]
        unit = m.group("unit") or None
    else:
        raise InputError(field, f"expected a quantity, got {type(text).__name__}")

    if unit is None:
        if default_unit is None:
            raise InputError(
                field,
                f"{text!r} has no unit",
                f"append one of: {', '.join(units_for(kind))}",
            )
        unit = default_unit
    if unit not in table:
        raise InputError(
            field,
            f"unknown unit {unit!r} for {_article(kind)} {kind.replace('_', ' ')}",
            f"use one of: {', '.join(units_for(kind))}",
        )
    if not all(math.isfinite(v) for v in values):
        raise InputError(field, f"value {text!r} is not finite", "give a finite number")
    factor = table[unit]
    if size is None:
        if len(values) != 1:
            raise InputError(field, f"expected one value, got {len(values)}")
        return values[0] * factor
    if len(values) == 1:
        values = values * size
    if len(values) != size:
        example = "x or x,y,z" if size == 3 else "one value or xy,xz,yx,yz,zx,zy"
        raise InputError(
            field, f"expected 1 or {size} values, got {len(values)}", f"give {example}"
        )
    return np.array(values) * factor
