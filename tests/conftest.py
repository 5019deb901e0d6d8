"""Suite-wide guard: no ``pytest.approx`` that cannot fail.

``pytest.approx(expected, rel=r)`` still accepts anything within the default absolute
tolerance of 1e-12. Many of inserr's quantities are far smaller than that in SI
(variances of rad/s, PSDs, Q entries: 1e-20 to 1e-11), and such a comparison passes
whatever the code computes: a north-finder Q entry three times too large did. Every
``approx`` given ``rel`` alone is therefore checked here: if its expected values are
non-zero and all below 1e-10 in size, the test fails and asks for ``abs=0`` (or an
``abs`` chosen for the quantity).
"""

from __future__ import annotations

import numpy as np
import pytest

_APPROX = pytest.approx
#: Smallest expected size for which the default abs (1e-12) is harmless: 1e-10 keeps it
#: at 1 % of the value or less.
SMALLEST = 1e-10


def _guarded_approx(expected, rel=None, abs=None, nan_ok=False):  # noqa: A002 (pytest's name)
    if rel is not None and abs is None:
        try:
            size = np.abs(np.asarray(expected, dtype=float))
        except (TypeError, ValueError):
            size = np.zeros(0)
        # Judged on the largest expected value: an array whose entries are all tiny is a
        # comparison at that scale; zeros and a few near-zero entries of an array of
        # ordinary size are what the default abs is for.
        if size.size and 0 < size.max() < SMALLEST:
            raise AssertionError(
                f"pytest.approx(..., rel={rel}) of values no larger than {size.max():.3g}: "
                "the default abs=1e-12 decides the comparison; pass abs=0 (or an abs "
                "chosen for the quantity)"
            )
    return _APPROX(expected, rel=rel, abs=abs, nan_ok=nan_ok)


def pytest_configure(config):
    pytest.approx = _guarded_approx
