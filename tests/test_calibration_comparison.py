"""Two-set comparison and the published-table check of the calibration study.

Closed forms and limiting cases: class RMS of known vectors, the CRLB's 1/sqrt(dwell)
law behind the noise/positioning crossover, the equal-time dwell, the probability that
one normal deviation is smaller than another (against a seeded simulation), the
Poisson-binomial count (binomial limit), the ARW thresholds solved back, which IMU axis
each built-in stop points where, and the designer's every-axis-up-and-down filter.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from inserr.calibration.comparison import (
    class_rms,
    compare_sigmas,
    crossover_dwell,
    equal_time_dwell,
    predicted_sigma,
)
from inserr.calibration.estimation import (
    PARAMETER_NAMES,
    CalibrationDesign,
    MonteCarloConfig,
    p1_truth,
    positioning_sigma,
)
from inserr.calibration.position_sets import design_sets, set_criterion
from inserr.calibration.published import (
    EVERY_AXIS_UP_AND_DOWN,
    better_probability,
    count_distribution,
    expected_abs_mean,
    implied_arw,
    max_arw_for_level,
    positions_pointing,
    published_table,
)
from inserr.calibration.two_axis_table import (
    offaxis_four_position,
    pointing,
    six_position,
    up_axis_label,
)
from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.core.units import ARCSEC, DEG_PER_HOUR, PPM

SITE = Site(math.radians(34.0))
CONFIG = MonteCarloConfig(runs=10, seed=1, positioning_error=3 * ARCSEC)


def test_class_rms_in_engineering_units():
    v = np.concatenate(
        [
            [2 * PPM, -2 * PPM, 2 * PPM],
            [3 * ARCSEC, -3 * ARCSEC] * 3,
            [1 * DEG_PER_HOUR, 2 * DEG_PER_HOUR, 2 * DEG_PER_HOUR],
        ]
    )
    rms = class_rms(v)
    assert rms["sf"] == pytest.approx(2.0, rel=1e-12)
    assert rms["mis"] == pytest.approx(3.0, rel=1e-12)
    assert rms["bias"] == pytest.approx(math.sqrt(3.0), rel=1e-12)


def test_compare_sigmas_sorts_by_tolerance():
    first = np.array([1.2, 0.8, 1.05] + [1.0] * 9)
    c = compare_sigmas(first, np.ones(12), 0.10)
    assert c["worse"] == ["sf_x"] and c["better"] == ["sf_y"]
    assert (c["argmax"], c["argmin"]) == ("sf_x", "sf_y")
    assert c["ratio"]["sf_z"] == pytest.approx(1.05)


def test_predicted_sigma_limits():
    """No positioning error: the CRLB; no noise: the positioning sigma alone."""
    pset = offaxis_four_position(300.0)
    imu = p1_truth()
    d = CalibrationDesign.from_position_set(pset, SITE, "gyro", imu.arw)
    exact = MonteCarloConfig(runs=2, positioning_error=0.0)
    np.testing.assert_allclose(predicted_sigma(pset, SITE, imu, exact), d.crlb_sigma(), rtol=1e-14)
    quiet = predicted_sigma(pset, SITE, imu.replace(arw=0.0), CONFIG)
    pos = positioning_sigma(d, pset, CONFIG.positioning_error, CONFIG.positioning_model)
    np.testing.assert_allclose(quiet, pos, rtol=1e-14)


def test_equal_time_dwell_fills_the_time():
    four, six = offaxis_four_position(300.0), six_position(300.0)
    d = equal_time_dwell(four, six.total_time)
    assert offaxis_four_position(d).total_time == pytest.approx(six.total_time, rel=1e-12)
    assert d > 300.0  # fewer positions dwell longer


def test_crossover_dwell_equates_noise_and_positioning():
    """At the returned dwell the CRLB class RMS equals the positioning class RMS."""
    imu = p1_truth()
    cross = crossover_dwell(offaxis_four_position(300.0), 300.0, SITE, imu, CONFIG)
    for cls, sl in (("sf", slice(0, 3)), ("mis", slice(3, 9)), ("bias", slice(9, 12))):
        pset = offaxis_four_position(cross[cls])
        d = CalibrationDesign.from_position_set(pset, SITE, "gyro", imu.arw)
        pos = positioning_sigma(d, pset, CONFIG.positioning_error, CONFIG.positioning_model)
        crlb_rms = np.sqrt(np.mean(d.crlb_sigma()[sl] ** 2))
        # the CRLB of white noise is exactly 1/sqrt(dwell): only round-off remains
        assert crlb_rms == pytest.approx(np.sqrt(np.mean(pos[sl] ** 2)), rel=1e-9)


def test_better_probability_closed_form_and_simulation():
    assert better_probability(1.0, 1.0) == pytest.approx(0.5, abs=1e-15)
    assert better_probability(1e-9, 1.0) == pytest.approx(1.0, abs=1e-8)
    rng = np.random.default_rng(3)
    n = 200_000
    a, b = 1.0, 2.5
    x, y = rng.normal(0, a, n), rng.normal(0, b, n)
    p = better_probability(a, b)
    # binomial standard error sqrt(p(1-p)/n) ~ 0.0008: 5 of them
    assert np.mean(np.abs(x) < np.abs(y)) == pytest.approx(p, abs=5 * math.sqrt(p * (1 - p) / n))


def test_count_distribution_is_binomial_for_equal_odds():
    pmf = count_distribution(np.full(12, 0.5))
    np.testing.assert_allclose(pmf, [math.comb(12, k) / 4096 for k in range(13)], rtol=1e-13)
    p = np.linspace(0.1, 0.9, 12)
    pmf = count_distribution(p)
    assert pmf.sum() == pytest.approx(1.0, abs=1e-14)
    assert np.arange(13) @ pmf == pytest.approx(p.sum(), rel=1e-13)  # mean of a sum


def test_expected_abs_mean_half_normal():
    # E|N(0, s^2/N)| = s sqrt(2 / (pi N))
    assert expected_abs_mean(2.0, 100) == pytest.approx(0.2 * math.sqrt(2 / math.pi), rel=1e-15)


def test_max_arw_for_level_solves_back():
    c = np.array([1e3, 2e3, 3e3])
    p = np.array([1e-7, 2e-7, 1e-7])
    level, runs = 1e-6, 100
    w = max_arw_for_level(c, p, level, runs)
    sigma = np.sqrt((w * c) ** 2 + p**2)
    assert np.sqrt(np.mean(expected_abs_mean(sigma, runs) ** 2)) == pytest.approx(level, rel=1e-12)
    assert max_arw_for_level(c, p * 1e3, level, runs) is None  # positioning alone too large


def test_implied_arw_solves_back():
    c = np.array([1e3, 4e3, 2e3, 1e3])
    p = np.array([1e-7, 2e-7, 1e-7, 3e-7])
    w = 5e-11
    k = np.mean((c / p) ** 2)
    z = np.full(4, math.sqrt(1 + w**2 * k))  # RMS exactly sqrt(1 + w^2 k)
    assert implied_arw(z, c, p) == pytest.approx(w, rel=1e-12, abs=0)  # w = 5e-11: abs=0
    assert implied_arw(np.full(4, 0.9), c, p) is None


def test_pointing_of_the_builtin_sets():
    assert pointing(np.eye(3)) == {"east": "+x", "north": "+y", "up": "+z"}
    rows = positions_pointing(six_position(), SITE)
    # every axis up once and down once
    assert sorted(r["up"] for r in rows) == sorted(EVERY_AXIS_UP_AND_DOWN)
    # the pointing labels agree with the ideal Earth-rate inputs: an axis along north
    # sees +-Omega cos L, along up +-Omega sin L, along east nothing
    w_n, w_u = SITE.earth_rate_n[1] / DEG_PER_HOUR, SITE.earth_rate_n[2] / DEG_PER_HOUR
    for r in rows:
        expect = np.zeros(3)
        for nav, w in (("north", w_n), ("up", w_u)):
            sign, axis = r[nav][0], "xyz".index(r[nav][1])
            expect[axis] += w if sign == "+" else -w
        np.testing.assert_allclose(r["gyro_input_deg_h"], expect, atol=1e-9)


def test_every_axis_up_and_down_designer():
    six = six_position(300.0)
    found = design_sets(SITE, 300.0, (6,), "gyro", top=3, up_axes=EVERY_AXIS_UP_AND_DOWN)
    assert found
    for c in found:
        ups = [up_axis_label(a) for a in c.position_set().attitudes]
        assert sorted(ups) == sorted(EVERY_AXIS_UP_AND_DOWN)
    # the built-in set is one of the candidates (trunnion, 90 deg grid): the best is no worse
    assert found[0].criterion >= set_criterion(six, SITE) * (1 - 1e-12)
    # and no four-position set points six axes up
    assert design_sets(SITE, 300.0, (4,), "gyro", up_axes=EVERY_AXIS_UP_AND_DOWN) == []


def test_published_table_units_misprint_and_errors():
    rows = list(PARAMETER_NAMES)
    units = {"scale_factor": 1e-4, "misalignment": 1e-5, "bias": DEG_PER_HOUR}
    means = ([1.0] * 12, [2.0] * 12)
    t = published_table(
        ("a", "b"),
        rows,
        means,
        units,
        runs=100,
        misprint=("sf_y", 3.0),
        better_count=9,
        time_saving=0.33,
        deviation_level=1e-7,
    )
    v = t.read("a")
    assert v[0] == pytest.approx(1e-4) and v[1] == pytest.approx(3e-4)  # the reading
    assert t.read("a", corrected=False)[1] == pytest.approx(1e-4)  # as printed
    assert t.read("b")[1] == pytest.approx(2e-4)  # only the first set's entry is read anew
    assert t.read("b")[3] == pytest.approx(2e-5) and t.read("b")[9] == pytest.approx(
        2 * DEG_PER_HOUR
    )
    assert t.unit(0)[0] == "1e-4" and t.unit(3)[0] == "1e-5 rad" and t.unit(9)[0] == "deg/h"
    with pytest.raises(InputError) as exc:
        published_table(
            ("a", "b"),
            rows[:-1] + ["sf_x"],
            means,
            units,
            runs=100,
            misprint=None,
            better_count=9,
            time_saving=0.33,
            deviation_level=1e-7,
            field="analysis.paper",
        )
    assert exc.value.field == "analysis.paper.rows"
    with pytest.raises(InputError) as exc:
        published_table(
            ("a", "b"),
            rows,
            ([1.0] * 11, [2.0] * 12),
            units,
            runs=100,
            misprint=None,
            better_count=9,
            time_saving=0.33,
            deviation_level=1e-7,
            field="analysis.paper",
        )
    assert exc.value.field == "analysis.paper.candidate_means"


def test_against_a_paper_that_prints_the_truth():
    """A table equal to the truth: zero deviations, no implied noise, no wins by chance."""
    from inserr.calibration.comparison import Comparison
    from inserr.calibration.estimation import monte_carlo, truth_vector
    from inserr.calibration.published import PublishedTable, against_published

    imu = p1_truth()
    sets = {"four": offaxis_four_position(300.0), "six": six_position(300.0)}
    base = {n: monte_carlo(ps, SITE, imu, CONFIG) for n, ps in sets.items()}
    quiet = {n: monte_carlo(ps, SITE, imu.replace(arw=0.0), CONFIG) for n, ps in sets.items()}
    comparison = Comparison(("four", "six"), {}, base, quiet)
    truth = dict(zip(PARAMETER_NAMES, truth_vector(imu, "gyro"), strict=True))
    units = {"sf": ("1e-4", 1e-4), "mis": ("1e-5 rad", 1e-5), "bias": ("deg/h", DEG_PER_HOUR)}
    paper = PublishedTable({"four": truth, "six": truth}, 100, units, None, 9, 0.33, 1e-7)
    out = against_published(comparison, paper, sets, SITE, imu, CONFIG, (30.0, 300.0))
    for n in sets:
        assert all(
            abs(r["deviation"]) < 1e-12 and abs(r["z_noise_free"]) < 1e-6 for r in out["rows"][n]
        )
    assert out["better"]["in_table"] == 0  # ties are not wins
    assert out["implied"]["arw_deg_per_sqrt_h"] is None
    assert out["time"]["dwell_limit"] == pytest.approx(1 / 3, rel=1e-15)
    for row in out["time"]["by_dwell"]:
        t4 = offaxis_four_position(row["dwell_s"]).total_time
        t6 = six_position(row["dwell_s"]).total_time
        assert row["saving"] == pytest.approx(1 - t4 / t6, rel=1e-12)
    # expected count under the noise-free model: the sum of the win probabilities
    p4 = predicted_sigma(sets["four"], SITE, imu.replace(arw=0.0), CONFIG)
    p6 = predicted_sigma(sets["six"], SITE, imu.replace(arw=0.0), CONFIG)
    expected = better_probability(p4, p6).sum()
    assert out["better"]["noise_free"]["expected"] == pytest.approx(expected, rel=1e-12)
    assert out["better"]["noise_free"]["sigma_better"] == int(np.sum(p4 < p6))
