"""The suite's guard against comparisons that cannot fail (``tests/conftest.py``)."""

import pytest


def test_the_approx_guard_refuses_a_comparison_that_cannot_fail():
    # rel alone on a value of 5e-18: the default abs (1e-12) would accept 8e-18.
    with pytest.raises(AssertionError, match="abs=0"):
        pytest.approx(5e-18, rel=1e-3)
    assert 8e-18 != pytest.approx(5e-18, rel=1e-3, abs=0)
    # Ordinary sizes and zeros are left alone.
    assert 1.0 == pytest.approx(1.0 + 1e-9, rel=1e-6)
    assert 0.0 == pytest.approx(0.0, rel=1e-6)
