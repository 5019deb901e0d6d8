"""Every path of the public ``Discretizer.transition`` / ``noise`` against scipy's expm.

``transitions`` (the batched call the engine uses) is checked in tests/test_model.py;
here the single-segment methods, which choose the same paths one key at a time: the
structured quadrature for short turning steps and short stop pieces, python-control
for whole stops, long turns and models without rotating states, and the zero-length
step. The truth is ``scipy.linalg.expm(A(w) h)`` of the full augmented matrix and, for
the noise, Van Loan's exponential written here.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sl

from inserr.core.earth import Site
from inserr.model.discretization import Discretizer
from inserr.model.psi_model import ErrorModel, Layout

SITE = Site.from_degrees(34.0)


@pytest.mark.parametrize(
    "w, h, structured",
    [
        ([0.02, -0.01, 0.1], 0.5, True),  # a turning sub-step
        ([0.0, 0.0, 0.0], 10.0, True),  # a short piece of a stop
        ([0.0, 0.0, 0.0], 300.0, False),  # a whole stop
        ([0.0, 0.0, 0.1], 30.0, False),  # a whole 172 deg turn
    ],
)
def test_single_transition_equals_expm_on_every_path(w, h, structured):
    model = ErrorModel(SITE, Layout(scale_misalignment=True, bias_instability=True))
    d = Discretizer(model)
    w = np.array(w)
    assert d._use_structured(d.key(w, h)) is structured
    ref = sl.expm(model.matrix(w) * h)
    got = d.transition(w, h)
    # Scaling-and-squaring against quadrature or python-control: ~1e-14 of the largest
    # entry (which reaches ~1e5 for position per bias over 300 s).
    assert np.allclose(got, ref, rtol=0, atol=1e-12 * np.abs(ref).max())
    assert d.transition(w, h) is got  # cached: the same array again


def test_non_rotating_model_and_zero_length_steps():
    model = ErrorModel(SITE, Layout(bias=False))
    d = Discretizer(model, model.noise_intensity(1e-6, 1e-5))
    for h in (1.0, 7.5):
        ref = sl.expm(model.matrix() * h)
        # Entries reach g h ~ 70: roundoff ~1e-14 of the largest.
        assert np.allclose(
            d.transition(np.zeros(3), h), ref, rtol=0, atol=1e-13 * np.abs(ref).max()
        )
    assert np.array_equal(d.transition(np.zeros(3), 0.0), np.eye(9))
    assert np.array_equal(d.noise(np.zeros(3), 0.0), np.zeros((9, 9)))


def test_single_noise_equals_van_loan_written_here():
    model = ErrorModel(
        SITE,
        Layout(bias=False, bias_instability=True),
        gyro_correlation_time=400.0,
        accel_correlation_time=700.0,
    )
    q = model.noise_intensity(2e-6, 3e-5, 1e-7, 2e-5)
    d = Discretizer(model, q)
    w, h = np.array([0.0, 0.05, 0.02]), 12.0
    a, g = model.matrix(w), model.noise_input()
    n = model.layout.n
    m = sl.expm(np.block([[-a, g @ q @ g.T], [np.zeros((n, n)), a.T]]) * h)
    ref = m[n:, n:].T @ m[:n, n:]
    got = d.noise(w, h)
    # Two Van Loan exponentials of the same blocks: ~1e-12 of the largest entry.
    assert np.allclose(got, ref, rtol=0, atol=1e-10 * np.abs(ref).max())
    assert np.allclose(got, got.T, rtol=0, atol=0)


def test_state_space_views_carry_the_layout_names_and_noise_channels():
    model = ErrorModel(SITE, Layout(scale_misalignment=True, bias_instability=True))
    sys = model.state_space(np.array([0.0, 0.0, 0.1]))
    assert list(sys.state_labels) == list(model.layout.names)
    assert list(sys.output_labels) == list(model.layout.names)
    # Noise inputs: white gyro, white accelerometer, GM gyro drive, GM accel drive (x, y, z).
    assert list(sys.input_labels) == [f"w_{k}{a}" for k in ("g", "a", "bg", "ba") for a in "xyz"]
    c = sl.expm(np.cross(np.eye(3), [0.1, -0.2, 0.3]))
    imu = model.state_space_imu(c)
    assert list(imu.state_labels) == list(model.layout.names)
