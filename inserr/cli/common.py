"""Helpers shared by the CLI commands: typed flags, unit-bearing values, output."""

from __future__ import annotations

import argparse
import math
import sys
from typing import Any

from inserr.core.errors import InputError
from inserr.core.units import parse_quantity


def finite_float(text: str) -> float:
    """argparse ``type=``: a finite float (rejects NaN and inf with a clear message)."""
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number")
    return v


def positive_float(text: str) -> float:
    """argparse ``type=``: a finite float > 0."""
    v = finite_float(text)
    if v <= 0:
        raise argparse.ArgumentTypeError(f"{text!r} must be > 0")
    return v


def positive_int(text: str) -> int:
    """argparse ``type=``: an integer >= 1."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"{text!r} must be >= 1")
    return v


def axes(text: str | None, kind: str, flag: str, unit: str):
    """Parse a flag holding one value (all three IMU axes) or ``x,y,z``, in ``unit``.

    Returns an SI ndarray of shape (3,), zeros when ``text`` is None. A unit may
    also be written explicitly (``--gyro-bias "0.02 deg/h"``).
    """
    import numpy as np

    if text is None:
        return np.zeros(3)
    return parse_quantity(text, kind, flag, default_unit=unit, size=3)


def parse_int(text: str, flag: str, minimum: int) -> int:
    """An integer flag value >= ``minimum``, or :class:`InputError` naming ``flag``."""
    try:
        v = int(str(text).strip())
    except ValueError:
        raise InputError(
            flag, f"{text!r} is not an integer", f"give an integer >= {minimum}"
        ) from None
    if v < minimum:
        raise InputError(flag, f"must be >= {minimum}, got {v}", f"give an integer >= {minimum}")
    return v


def add_json_flag(parser: argparse.ArgumentParser) -> None:
    """Add ``--json`` (machine-readable output on stdout, no progress bars)."""
    parser.add_argument("--json", action="store_true", help="print JSON on stdout")


def emit(args: argparse.Namespace, result: dict[str, Any], human: str) -> None:
    """Print ``result`` as JSON under ``--json``, else the human-readable text."""
    if getattr(args, "json", False):
        from inserr.output.report import dumps

        sys.stdout.write(dumps(result) + "\n")
    else:
        sys.stdout.write(human.rstrip() + "\n")


def format_table(header: list[str], rows: list[list[Any]], fmt: str = "{:.4g}") -> str:
    """Plain-text table with right-aligned columns."""

    def cell(v: Any) -> str:
        if isinstance(v, float):
            return fmt.format(v)
        return str(v)

    body = [[cell(v) for v in r] for r in rows]
    widths = [
        max(len(h), *(len(r[i]) for r in body)) if body else len(h) for i, h in enumerate(header)
    ]
    lines = ["  ".join(h.rjust(w) for h, w in zip(header, widths, strict=True))]
    lines.append("  ".join("-" * w for w in widths))
    lines += ["  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in body]
    return "\n".join(lines)


def require(cond: bool, field: str, problem: str, fix: str | None = None) -> None:
    """Raise :class:`InputError` unless ``cond``."""
    if not cond:
        raise InputError(field, problem, fix)
