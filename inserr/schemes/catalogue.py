"""The scheme catalogue: every indexing scheme by name, and :func:`build_scheme`.

Open-loop schemes (rotation tables) are in :mod:`inserr.schemes.open_loop`,
closed-loop rules in :mod:`inserr.schemes.closed_loop` and
:mod:`inserr.schemes.nulling`. Every scheme turns a vehicle motion and a duration
into a :class:`~inserr.schemes.turntable.TableSchedule` with its one method
``plan(motion, duration)``.
"""

from __future__ import annotations

import math

from inserr.core.errors import InputError
from inserr.schemes.closed_loop import FlexibleTwoPosition, HeadingIsolation
from inserr.schemes.open_loop import (
    SCHEME_STARTS,
    TableScheme,
    continuous,
    eight_position,
    four_position,
    none_scheme,
    sixteen_position,
    sixteen_position_inserr,
    two_position,
    with_start,
)

SCHEMES = (
    "none",
    "continuous",
    "two-position",
    "four-position",
    "four-position-modified",
    "flexible-two-position",
    "heading-isolation",
    "nulling-two-position",
    "eight-position",
    "sixteen-position",
    "sixteen-position-inserr",
    "custom",
)


def build_scheme(name: str, rate: float, stop: float, **options):
    """Build a scheme by name.

    Parameters
    ----------
    name : str
        One of :data:`SCHEMES`.
    rate : float, rad/s
        Table rate (> 0).
    stop : float, s
        Stop (dwell) time (> 0; 0 allowed for ``continuous``).
    **options
        ``reversal`` (continuous, s), ``delta``/``variant``/``f`` (flexible),
        ``steps`` (custom: list of Step), ``mounting`` (3x3), ``start`` (every
        scheme: ``"stop"``, the default, or ``"turn"``: open with the first turn).

    Raises
    ------
    InputError
        Unknown scheme or bad parameters.
    """
    if name not in SCHEMES:
        raise InputError(
            "scheme.name",
            f"unknown scheme {name!r}",
            f"use one of: {', '.join(SCHEMES)}",
        )
    if not (math.isfinite(rate) and rate > 0):
        raise InputError("scheme.rate", f"table rate must be > 0, got {rate!r}")
    # A custom table's stop is only its opening stop (each step has its own dwell), so
    # zero is allowed there: the run then opens with the table's first turn.
    if not (math.isfinite(stop) and stop >= 0) or (
        stop == 0 and name not in ("continuous", "none", "custom")
    ):
        raise InputError("scheme.stop", f"stop time must be > 0 s, got {stop!r}")
    mounting = options.pop("mounting", None)
    start = options.pop("start", "stop")
    if start not in SCHEME_STARTS:
        raise InputError(
            "scheme.start",
            f"unknown opening phase {start!r}",
            f"use one of: {', '.join(SCHEME_STARTS)}",
        )
    if name == "none":
        s = none_scheme(rate, stop)
    elif name == "continuous":
        s = continuous(rate, stop, options.pop("reversal", 0.0))
    elif name == "two-position":
        s = two_position(rate, stop)
    elif name in ("four-position", "four-position-modified"):
        s = four_position(rate, stop, modified=name.endswith("modified"))
    elif name == "eight-position":
        s = eight_position(rate, stop)
    elif name == "sixteen-position":
        s = sixteen_position(rate, stop)
    elif name == "sixteen-position-inserr":
        s = sixteen_position_inserr(rate, stop)
    elif name == "flexible-two-position":
        return FlexibleTwoPosition(rate, stop, mounting=mounting, start=start, **options)
    elif name == "heading-isolation":
        return HeadingIsolation(rate, stop, mounting=mounting, start=start)
    elif name == "nulling-two-position":
        from inserr.schemes.nulling import NullingTwoPosition

        return NullingTwoPosition(rate, stop, mounting=mounting, start=start, **options)
    else:  # custom
        steps = options.pop("steps", None)
        if not steps:
            raise InputError(
                "scheme.steps",
                "a custom scheme needs a table of steps",
                "add [[scheme.steps]] rows",
            )
        s = TableScheme("custom", tuple(steps), rate, stop)
    if options:
        raise InputError("scheme", f"option(s) {sorted(options)} do not apply to {name}")
    if mounting is not None:
        s = TableScheme(s.name, s.steps, s.rate, s.first_dwell, s.start, s.start_label, mounting)
    return with_start(s, start)
