"""Tests of the north-finder accuracy study and its check against P3's published figures.

(:mod:`inserr.northfinder.accuracy`, :mod:`inserr.northfinder.published`: the study logic
behind ``analyses/p3_northfinder``.)

Truth used here is independent of the code under test: the scaling of every white-noise
bound with the noise amplitude, the Gauss-Markov PSD maximum ``sigma^2 / |w|`` at
``tau = 1 / |w|``, the information inequality (knowing the latitude cannot raise the
heading bound), the geometry ``sigma_L / sigma_psi ~ cot L`` (heading from the direction
of the horizontal Earth rate, latitude from its size), the definitions of the mil, and
the exactness of the exact inversion on noise-free data.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from inserr.core.units import DEG, DEG_PER_S, MIL
from inserr.northfinder.accuracy import (
    AccuracyStudy,
    bias_instability_table,
    heading_latitude_map,
    required_factor,
    scaled_gyro,
    small_angle_table,
    time_history,
)
from inserr.northfinder.bounds import crlb
from inserr.northfinder.instrument import Instrument, Pose, SensorGrade
from inserr.northfinder.published import (
    MIL_READINGS,
    PublishedRepeatability,
    against_published,
    consistent_latitude,
    gyro_class,
)

GRADE = SensorGrade()
POSE = Pose(lat=34 * DEG, heading=30 * DEG, pitch=0.5 * DEG, roll=-0.3 * DEG)
T = 60.0  # s: one minute (10 table turns); the properties tested do not depend on it


def _study(**kw) -> AccuracyStudy:
    base = dict(
        pose=POSE,
        instrument=Instrument(),
        grade=GRADE,
        hemisphere=1,
        runs=12,
        check_runs=12,
        seed=7,
        requirement=0.5 * MIL,
        time=T,
        history_duration=T,
        rates=(6 * DEG_PER_S,),
        stress_bi=0.05 * DEG / 3600,
        stress_tau=20.0,
        factors=(1.0,),
        grade_latitudes=(),
        bi_taus=(10.0, 100.0, 1000.0),
        map_heading_step=120 * DEG,
        map_lat_step=40 * DEG,
        map_lat_limit=60 * DEG,
        mc_headings=(),
        mc_latitudes=(),
        mc_map_runs=4,
        gyro_tilts=(1 * DEG, 2 * DEG),
        accel_azimuths=(),
        accel_tilts=(),
    )
    base.update(kw)
    return AccuracyStudy(**base)


def test_scaled_gyro_scales_every_gyro_error_and_nothing_else():
    g = scaled_gyro(GRADE, 2.5)
    assert g.gyro_arw == pytest.approx(2.5 * GRADE.gyro_arw, rel=1e-15)
    assert g.gyro_bias == pytest.approx(2.5 * GRADE.gyro_bias, rel=1e-15)
    assert g.gyro_bias_instability == pytest.approx(2.5 * GRADE.gyro_bias_instability, rel=1e-15)
    assert g.gyro_correlation_time == GRADE.gyro_correlation_time
    assert (g.accel_vrw, g.accel_bias) == (GRADE.accel_vrw, GRADE.accel_bias)


def test_required_factor_is_proportional_to_the_target():
    """Every gyro noise scales with the factor, so the bound does: the factor that meets k x
    the default's bound is k, up to the accelerometer's share of the heading bound (the
    accelerometer is not scaled; its share at this grade moves the ratio by < 1e-5)."""
    b1 = crlb(POSE, Instrument(), GRADE, T, bias_instability=True).heading[-1]
    for k in (0.5, 2.0):
        f = required_factor(POSE, Instrument(), GRADE, T, k * b1)
        assert f == pytest.approx(k, rel=1e-5)
    # The latitude bound likewise.
    bl = crlb(POSE, Instrument(), GRADE, T, bias_instability=True).lat[-1]
    assert required_factor(POSE, Instrument(), GRADE, T, 3 * bl, quantity="lat") == pytest.approx(
        3.0, rel=1e-5
    )
    with pytest.raises(ValueError, match="quantity"):
        required_factor(POSE, Instrument(), GRADE, T, b1, quantity="pitch")


def test_bias_instability_worst_case_is_the_gauss_markov_psd_maximum():
    """S(w) = 2 s^2 tau / (1 + w^2 tau^2) peaks at tau = 1/w with s^2 / w: the table's
    worst case is sqrt(1 + s^2 / (w ARW^2)), reached at tau = 1/w and never exceeded."""
    w = Instrument().table_rate
    sc = _study(bi_taus=(0.1 / w, 1.0 / w, 10.0 / w))
    out = bias_instability_table(sc)
    s, arw = GRADE.gyro_bias_instability, GRADE.gyro_arw
    worst = math.sqrt(1.0 + s**2 / abs(w) / arw**2)
    assert out["worst_case_inflation"] == pytest.approx(worst, rel=1e-12)
    infl = [r["sigma_inflation"] for r in out["rows"]]
    assert infl[1] == pytest.approx(worst, rel=1e-12)
    assert max(infl[0], infl[2]) < worst
    # tau = 0.1/w and 10/w are the same distance from the peak in log tau: equal PSD.
    assert infl[0] == pytest.approx(infl[2], rel=1e-12)


def test_knowing_the_latitude_never_raises_the_heading_bound():
    """Information inequality: one parameter fewer to estimate cannot cost accuracy."""
    out = heading_latitude_map(_study())
    known = np.asarray(out["crlb_heading_latitude_known_mil"])
    unknown = np.asarray(out["crlb_heading_mil"])
    assert known.shape == unknown.shape == (len(out["latitudes_deg"]), len(out["headings_deg"]))
    assert np.all(known <= unknown * (1 + 1e-12))
    np.testing.assert_allclose(out["latitudes_deg"], [-60, -20, 20, 60], atol=1e-12)


def test_exact_inversion_is_exact_and_p3_small_angle_model_is_not():
    """Noise-free data: the exact inversion returns the truth to round-off; P3's
    small-angle model leaves a heading error that grows with the gyro tilt."""
    rows = small_angle_table(_study(gyro_tilts=(1 * DEG, 2 * DEG, 4 * DEG)))["rows"]
    for r in rows:
        assert abs(r["exact_heading_mil"]) < 1e-6  # 1e-6 mil = 1e-9 rad: round-off
        assert abs(r["exact_latitude_deg"]) < 1e-7
    p3 = [abs(r["p3_heading_mil"]) for r in rows]
    assert p3[0] > 1e-4 and p3[0] < p3[1] < p3[2]


def test_bound_ratio_latitude_over_heading_is_about_cot_latitude():
    """Heading is the direction of the horizontal Earth rate Omega cos L; latitude its size
    (with Omega sin L): both set by the same amplitude noise, so sigma_L / sigma_psi ~ cot L.
    The tilt and the vertical share move this by a few per cent at most (5 % allowed)."""
    sc = _study()
    for lat in (15.0, 34.0, 60.0):
        b = crlb(replace(POSE, lat=lat * DEG), sc.instrument, GRADE, T, bias_instability=True)
        assert b.lat[-1] / b.heading[-1] == pytest.approx(1 / math.tan(lat * DEG), rel=0.05)
    # consistent_latitude inverts the ratio: a ratio read at 40 deg gives back 40 deg.
    b = crlb(replace(POSE, lat=40 * DEG), sc.instrument, GRADE, T, bias_instability=True)
    lat = consistent_latitude(sc, T, float(b.lat[-1] / b.heading[-1]))
    assert lat == pytest.approx(40 * DEG, abs=1e-9)
    assert consistent_latitude(sc, T, 1e3) is None  # cot L = 1000 only below 1 deg
    south = consistent_latitude(_study(pose=replace(POSE, lat=-34 * DEG)), T, 1.0)
    assert south is not None and south < 0


def test_mil_readings_and_gyro_classes():
    assert MIL_READINGS["NATO mil (2π/6400)"] == pytest.approx(2 * math.pi / 6400, rel=1e-15)
    assert MIL_READINGS["6000-mil circle (2π/6000)"] == pytest.approx(2 * math.pi / 6000)
    assert MIL_READINGS["milliradian"] == 1e-3
    assert gyro_class(0.001) == "navigation-grade"
    assert gyro_class(0.05) == "tactical-grade"
    assert gyro_class(1.0) == "below tactical-grade"


def test_against_published_grades_scale_with_the_published_sigma():
    """The grade a published heading sigma implies is proportional to it (the bound scales
    with the factor): so the three readings of 'mil' give factors in the ratio of the mil
    sizes, and each reading's heading in degrees is its definition."""
    # A requirement other than the paper's: the grade sweep's Monte Carlo answer is not
    # quoted, so the (slow) grade sweep need not run.
    t = T
    sc = _study(requirement=0.4 * MIL, time=t, history_duration=t)
    hist, _ = time_history(sc)
    paper = PublishedRepeatability(heading=0.5 * MIL, time=t, latitude=0.0538 * DEG)
    pub = against_published(sc, {"time_history": hist}, paper)
    assert pub["paper"]["heading_mil"] == pytest.approx(0.5, rel=1e-12)
    assert pub["paper"]["latitude_over_heading"] == pytest.approx(
        0.0538 * DEG / (0.5 * 2 * math.pi / 6400), rel=1e-12
    )
    nato = pub["heading_grade"]["NATO mil (2π/6400)"]
    assert nato["heading_deg"] == pytest.approx(0.5 * 360 / 6400, rel=1e-12)
    for name, mil in MIL_READINGS.items():
        h = pub["heading_grade"][name]
        assert "monte_carlo" not in h
        assert h["heading_deg"] == pytest.approx(0.5 * mil / DEG, rel=1e-12)
        ratio = h["crlb"]["factor"] / nato["crlb"]["factor"]
        assert ratio == pytest.approx(mil / MIL_READINGS["NATO mil (2π/6400)"], rel=1e-5)
    assert pub["model"]["time_s"] == pytest.approx(t, abs=1.0)
    # The latitude grade meets the published latitude sigma on the bound.
    f = pub["latitude_grade"]["crlb"]["factor"]
    b = crlb(POSE, sc.instrument, scaled_gyro(GRADE, f), t, bias_instability=True)
    assert b.lat[-1] == pytest.approx(0.0538 * DEG, rel=1e-9)
    # Where both figures imply one grade, the bound ratio equals the published ratio.
    c = pub["consistent_latitude"]["NATO mil (2π/6400)"]
    p = replace(POSE, lat=c["latitude_deg"] * DEG)
    bc = crlb(p, sc.instrument, GRADE, t, bias_instability=True)
    assert bc.lat[-1] / bc.heading[-1] == pytest.approx(
        pub["paper"]["latitude_over_heading"], rel=1e-9
    )
