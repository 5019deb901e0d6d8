"""Tests of the piecewise-constant observability analysis (issue #5).

Independent truth used here: the classic unobservable directions of zero-velocity
alignment written out by hand from the psi-angle equations (a state that keeps the
velocity error at zero for ever: ``dv' = f x phi + nabla = 0`` and
``phi' = -Omega x phi - eps = 0``), python-control's ``obsv``, toy systems whose
observability is obvious, and the geometric fact that an east position (longitude)
error cannot be seen by zero-velocity updates.
"""

from __future__ import annotations

import json
import math

import control
import numpy as np
import pytest

from inserr.alignment.observability import (
    Pwcs,
    Segment,
    Vocabulary,
    alignment10,
    analyze,
    full_headings,
    full_timeline,
    segment_observability,
    stacked_observability,
)
from inserr.cli.main import main
from inserr.core import earth
from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.core.rotations import rot_z
from inserr.core.units import DEG
from inserr.model.psi_model import ErrorModel, Layout
from inserr.schemes.catalogue import build_scheme
from inserr.schemes.composition import build_timeline
from inserr.schemes.vehicle_motion import Motion

LAT = 34.0 * DEG
SITE = Site(LAT)
CLASSIC = {"∇E = g·φN", "∇N = −g·φE", "ε = −Ω×φ"}


def _classic_null_vectors(lat: float, heading: float = 0.0) -> np.ndarray:
    """The three hand-derived unobservable states of alignment10 (columns, SI).

    For an attitude error phi (ENU): nabla^n_E = g phi_N, nabla^n_N = -g phi_E (so
    f x phi + nabla = 0 with f = [0, 0, g]) and eps^n = -Omega x phi (so phi stays
    constant). IMU-frame biases of a level IMU at ``heading``: b = C_n^s x^n.
    """
    g = earth.gravity(lat)
    om = earth.OMEGA_IE * np.array([0.0, math.cos(lat), math.sin(lat)])
    c_ns = rot_z(-heading).T  # level IMU with y at `heading` (clockwise from north)
    cols = []
    for phi in np.eye(3):
        nabla_n = np.array([g * phi[1], -g * phi[0], 0.0])
        eps_n = -np.cross(om, phi)
        x = np.zeros(10)
        x[2:5] = phi
        x[5:7] = (c_ns @ nabla_n)[:2]
        x[7:10] = c_ns @ eps_n
        cols.append(x)
    return np.array(cols).T


def _angle_between(span_a: np.ndarray, span_b: np.ndarray) -> float:
    """Largest principal angle (rad) between two column spans."""
    qa, _ = np.linalg.qr(span_a)
    qb, _ = np.linalg.qr(span_b)
    s = np.linalg.svd(qa.T @ qb, compute_uv=False)
    return float(np.arccos(np.clip(s.min(), -1.0, 1.0)))


# --- building blocks --------------------------------------------------------------------


def test_segment_matrix_is_row_scaled_python_control_obsv():
    rng = np.random.default_rng(1)
    a = rng.normal(size=(5, 5))
    c = rng.normal(size=(2, 5))
    t = 0.7
    ref = np.asarray(control.obsv(a, c))
    scale = np.repeat([t**k / math.factorial(k) for k in range(5)], 2)
    np.testing.assert_allclose(
        segment_observability(a, c, t), ref * scale[:, None], rtol=1e-12, atol=1e-12
    )


def _toy(segments, names=("x", "y")) -> Pwcs:
    n = len(names)
    vocab = Vocabulary(
        display=np.eye(n),
        symbols=tuple(names),
        units=("m",) * n,
        groups={},
        free_order=(tuple(range(n)),),
        constants={},
        matrices={},
    )
    return Pwcs(tuple(segments), tuple(names), np.ones(n), np.ones(segments[0].c.shape[0]), vocab)


def test_toy_systems_have_the_obvious_rank():
    zero = np.zeros((2, 2))
    see_x = np.array([[1.0, 0.0]])
    see_y = np.array([[0.0, 1.0]])
    # Two constant states, each segment sees one: together both.
    assert analyze(_toy([Segment(zero, see_x, 1.0)])).rank == 1
    assert analyze(_toy([Segment(zero, see_x, 1.0)])).unobservable == ("y alone",)
    assert analyze(_toy([Segment(zero, see_x, 1.0), Segment(zero, see_y, 1.0)])).rank == 2
    # Double integrator x' = y: position measurements see the velocity, not the reverse.
    dbl = np.array([[0.0, 1.0], [0.0, 0.0]])
    assert analyze(_toy([Segment(dbl, see_x, 1.0)])).rank == 2
    r = analyze(_toy([Segment(dbl, see_y, 1.0)]))
    assert r.rank == 1 and r.unobservable == ("x alone",)
    # A jump that swaps the states lets the same measurement see both; the stripped
    # matrix (no transitions, no jumps) cannot know that and is flagged invalid.
    swap = np.array([[0.0, 1.0], [1.0, 0.0]])
    r = analyze(_toy([Segment(zero, see_x, 1.0), Segment(zero, see_x, 1.0, jump=swap)]))
    assert r.rank == 2 and r.som_rank == 1 and not r.som_valid


def test_relation_with_a_coefficient_is_written_out():
    # x + 2 y is seen, so x = -2 y is the unobservable direction.
    r = analyze(_toy([Segment(np.zeros((2, 2)), np.array([[1.0, 2.0]]), 1.0)]))
    assert r.rank == 1
    assert r.unobservable == ("y = −(0.5)·x",)


# --- the classic 10-state alignment model --------------------------------------------------


@pytest.mark.parametrize("heading_deg", [0.0, 30.0, 137.0])
def test_static_alignment10_rank_seven_with_the_classic_directions(heading_deg):
    h = heading_deg * DEG
    sysm = alignment10(SITE, [h])
    r = analyze(sysm)
    assert (r.n_states, r.rank) == (10, 7)
    # Relations are written in n (biases resolved at the first heading): any heading
    # gives the same three words.
    assert set(r.unobservable) == CLASSIC
    assert len(r.unobservable) == 3
    # The numerical null space is exactly the span of the hand-derived directions
    # (compared in scaled units, where all states are of comparable size).
    hand = _classic_null_vectors(LAT, h) / sysm.scale[:, None]
    found = r.null_space / sysm.scale[:, None]
    assert _angle_between(hand, found) < 1e-6
    # ... and the stacked matrix annihilates them (relative to its size).
    q = stacked_observability(sysm)
    assert np.linalg.norm(q @ hand) < 1e-10 * np.linalg.norm(q) * np.linalg.norm(hand)


def test_rank_decision_is_clear():
    r = analyze(alignment10(SITE, [0.0]))
    s = r.singular_values
    # The weakest observable direction sits far above the tolerance, the null
    # directions far below it.
    assert s[r.rank - 1] > 1e4 * r.tolerance
    assert s[r.rank] < 1e-4 * r.tolerance
    assert r.gap > 1e8
    assert r.som_valid and r.som_rank == r.rank


@pytest.mark.parametrize("headings", [(0.0, 180.0), (45.0, 225.0), (0.0, 90.0)])
def test_two_headings_make_everything_observable(headings):
    r = analyze(alignment10(SITE, np.radians(headings)))
    assert r.rank == 10 and r.unobservable == ()


def test_returning_to_the_same_heading_adds_nothing():
    r = analyze(alignment10(SITE, np.radians([10.0, 370.0])))
    assert r.rank == 7 and set(r.unobservable) == CLASSIC


@pytest.mark.parametrize("dwell", [10.0, 3600.0, 72 * 3600.0])
def test_rank_is_stable_from_short_to_very_long_dwells(dwell):
    assert analyze(alignment10(SITE, [0.0], dwell)).rank == 7
    assert analyze(alignment10(SITE, np.radians([0.0, 180.0]), dwell)).rank == 10


# --- the full core model ------------------------------------------------------------------


def test_full_model_at_a_known_position_has_the_same_three_directions():
    r = analyze(full_headings(SITE, [0.0], position=True, vertical="free"))
    assert (r.n_states, r.rank) == (15, 12)
    # At a known position psi = phi: the same relations, written in psi.
    assert set(r.unobservable) == {"∇E = g·ψN", "∇N = −g·ψE", "ε = −Ω×ψ"}


def test_longitude_error_is_invisible_to_zero_velocity_updates():
    sysm = full_headings(SITE, np.radians([0.0, 180.0]), position=False, vertical="free")
    r = analyze(sysm)
    # An east position error with psi = -dtheta (zero true attitude error): the
    # computed frame is the true one shifted along a parallel, Earth rate and gravity
    # look the same, nothing moves. Written out by hand:
    x = np.zeros(15)
    x[6] = 1.0  # dr_E, m
    x[1] = -1.0 / SITE.r_n  # psi_N
    x[2] = -math.tan(LAT) / SITE.r_n  # psi_U
    xs = x / sysm.scale
    q = stacked_observability(sysm)
    assert np.linalg.norm(q @ xs) < 1e-10 * np.linalg.norm(q) * np.linalg.norm(xs)
    assert r.rank == 13
    assert "ψN = −1/R_N·δrE" in r.unobservable
    assert "ψU = −tanL/R_N·δrE" in r.unobservable


def test_indexing_with_position_updates_observes_all_fifteen_states():
    motion = Motion(15 * DEG, 1 * DEG, -2 * DEG)
    table = build_scheme("two-position", 6 * DEG, 60.0).plan(motion, 600.0)
    tl = build_timeline(table, motion, 600.0)
    model = ErrorModel(SITE, Layout(bias=True), vertical="free")
    assert analyze(full_timeline(model, tl, position=True)).rank == 15
    static = build_timeline(build_scheme("none", 6 * DEG, 60.0).plan(motion, 600.0), motion, 600.0)
    assert analyze(full_timeline(model, static, position=True)).rank == 12


# --- command line ---------------------------------------------------------------------------


def _json(capsys, argv) -> dict:
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_cli_static_rank_seven(capsys):
    out = _json(capsys, ["observability", "--lat", "34", "--headings", "0", "--json"])
    assert out["n_states"] == 10 and out["rank"] == 7
    assert len(out["singular_values"]) == 10
    assert set(out["unobservable"]) == CLASSIC


def test_cli_two_headings_rank_ten(capsys):
    out = _json(capsys, ["observability", "--lat", "34", "--headings", "0,180", "--json"])
    assert (out["n_states"], out["rank"], out["unobservable"]) == (10, 10, [])


def test_cli_full_model_over_a_scheme(capsys):
    out = _json(
        capsys,
        [
            "observability",
            "--scheme",
            "four-position",
            "--duration",
            "6 min",
            "--position-updates",
            "--json",
        ],
    )
    assert out["n_states"] == 15 and out["rank"] == 15


@pytest.mark.parametrize(
    "argv",
    [
        ["observability", "--headings", "north"],
        ["observability", "--lat", "90", "--headings", "0"],
        ["observability"],
        ["observability", "--headings", "0", "--scheme", "none"],
        ["observability", "--headings", "0", "--position-updates"],
        ["observability", "--headings", "0", "--stop", "-1"],
        ["observability", "--headings", "0", "--stop", "0"],
        ["observability", "--scheme", "none", "--model", "alignment10"],
    ],
)
def test_cli_bad_input_exits_2(argv, capsys):
    assert main(argv) == 2
    assert "error" in capsys.readouterr().err


def test_api_rejects_empty_headings():
    with pytest.raises(InputError):
        alignment10(SITE, [])
