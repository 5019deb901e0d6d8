"""The one exception type for bad user input.

Every check of user input (CLI flag, scenario file, API argument that a user types)
raises :class:`InputError`, which names the offending field and says how to fix it.
The CLI turns it into a single line on stderr and a non-zero exit status, before any
output file is written.
"""

from __future__ import annotations

import math


class InputError(ValueError):
    """Bad input, reported as ``<field>: <problem>. Fix: <fix>``.

    Parameters
    ----------
    field : str
        The scenario key or argument at fault (e.g. ``"imu.gyro_bias"``); the CLI
        adds the flag when the value came from one (``"--lat (site.latitude)"``).
    problem : str
        What is wrong with it.
    fix : str, optional
        What the user should do instead.
    """

    def __init__(self, field: str, problem: str, fix: str | None = None):
        self.field = field
        self.problem = problem
        self.fix = fix
        msg = f"{field}: {problem}"
        if fix:
            msg += f". Fix: {fix}"
        super().__init__(msg)


def require_finite(value: float, field: str) -> float:
    """Return ``float(value)`` or raise :class:`InputError` if it is NaN or infinite.

    A string is a TypeError, not a number: the library takes SI floats, and ``"34"``
    would otherwise pass as 34 rad (units are read at the edge, by the scenario).
    """
    if isinstance(value, (str, bytes)):
        raise TypeError(f"{field}: expected a number in SI units, got the string {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(field, f"expected a number, got {value!r}") from None
    if not math.isfinite(v):
        raise InputError(field, f"{value!r} is not a finite number", "give a finite number")
    return v


def require_latitude(lat_rad: float, field: str = "site.latitude") -> float:
    """Check a latitude in radians is finite and strictly inside (-90 deg, 90 deg).

    At the poles the local-level navigation frame has no defined north, the east
    radius of curvature times cos(latitude) vanishes and longitude errors are
    undefined, so the error model does not apply there.
    """
    v = require_finite(lat_rad, field)
    if abs(v) >= math.pi / 2:
        raise InputError(
            field,
            f"latitude {math.degrees(v):g} deg is at or beyond a pole, "
            "where north and east are undefined",
            "give |latitude| < 90 deg, e.g. 89.9",
        )
    return v
