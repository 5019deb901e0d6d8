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
    """Silence (or re-enable) every progress bar of this process (``--json`` sets it).

    Parameters
    ----------
    quiet : bool
        True to silence the bars, False to allow them again.
    """
    global _QUIET
    _QUIET = bool(quiet)


def enabled() -> bool:
    """True when progress bars should be drawn.

    That is when stderr is a TTY, :func:`set_quiet` has not silenced them, and the
    environment variable ``INSERR_NO_PROGRESS`` is unset or empty.

    Returns
    -------
    bool
    """
    if _QUIET or os.environ.get("INSERR_NO_PROGRESS"):
        return False
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


def progress(iterable: Iterable[T], *, total: int | None = None, desc: str = "") -> Iterator[T]:
    """Iterate over ``iterable``, through a tqdm bar on stderr when :func:`enabled`.

    Parameters
    ----------
    iterable : iterable
        The items to iterate over.
    total : int, optional
        Number of items, for the bar when ``iterable`` has no ``len``.
    desc : str
        Label of the bar.

    Yields
    ------
    object
        The items of ``iterable``, unchanged (this is a generator in both cases).
    """
    if not enabled():
        yield from iterable
        return
    from tqdm import tqdm

    yield from tqdm(iterable, total=total, desc=desc, file=sys.stderr, leave=False)


class Bar:
    """A manual progress bar (``update(n)``) with the same terminal rule as :func:`progress`.

    Usable as a context manager (closes on exit); does nothing when not :func:`enabled`.

    Parameters
    ----------
    total : float
        Total amount of work, in ``unit``.
    desc : str
        Label of the bar.
    unit : str
        Name of the unit of work shown by tqdm.
    """

    def __init__(self, total: float, desc: str = "", unit: str = "it"):
        self._bar = None
        if enabled():
            from tqdm import tqdm

            self._bar = tqdm(total=total, desc=desc, unit=unit, file=sys.stderr, leave=False)

    def update(self, n: float = 1) -> None:
        """Advance the bar.

        Parameters
        ----------
        n : float
            Amount of work done since the last update, in the bar's unit.
        """
        if self._bar is not None:
            self._bar.update(n)

    def close(self) -> None:
        """Close the bar (it is removed from the terminal: ``leave=False``)."""
        if self._bar is not None:
            self._bar.close()

    def __enter__(self) -> Bar:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
