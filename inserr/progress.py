"""Progress bars that show on a terminal and stay silent otherwise.

Long work (Monte Carlo, 72 h nonlinear runs, sweeps) reports progress with
:func:`progress`, which returns a tqdm bar writing to stderr only when stderr is a
terminal and the caller has not asked for quiet output (``--json``).
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterable, Iterator
from typing import TypeVar

T = TypeVar("T")

_QUIET = False


def set_quiet(quiet: bool) -> None:
    """Silence (or re-enable) every progress bar of this process (``--json`` sets it)."""
    global _QUIET
    _QUIET = bool(quiet)


def enabled() -> bool:
    """True when progress bars should be drawn: stderr is a TTY and not quiet."""
    if _QUIET or os.environ.get("INSERR_NO_PROGRESS"):
        return False
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


def progress(iterable: Iterable[T], *, total: int | None = None, desc: str = "") -> Iterator[T]:
    """Wrap ``iterable`` in a tqdm bar when :func:`enabled`, else return it unchanged."""
    if not enabled():
        yield from iterable
        return
    from tqdm import tqdm

    yield from tqdm(iterable, total=total, desc=desc, file=sys.stderr, leave=False)


class Bar:
    """A manual progress bar (``update(n)``) with the same terminal rule as :func:`progress`."""

    def __init__(self, total: float, desc: str = "", unit: str = "it"):
        self._bar = None
        if enabled():
            from tqdm import tqdm

            self._bar = tqdm(total=total, desc=desc, unit=unit, file=sys.stderr, leave=False)

    def update(self, n: float = 1) -> None:
        if self._bar is not None:
            self._bar.update(n)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()

    def __enter__(self) -> Bar:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
