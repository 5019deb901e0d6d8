"""``inserr imu-budget``: known noise terms recovered from synthetic static recordings.

The recordings are made here, from the definitions of IEEE Std 952 (Annex C), not
from inserr: white rate noise of density N (samples of 1 sigma ``N sqrt(rate)``),
flicker noise of two-sided PSD ``B^2 / (2 pi f)`` (shaped in the frequency domain)
and a rate random walk of density K (a cumulative sum). The fit must recover N, B
and K within the intervals it states, and the intervals must cover the truth as
often as they say over many recordings.
"""

from __future__ import annotations

import json
import math
import tomllib

import numpy as np
import pytest

from inserr.calibration import allan
from inserr.cli.main import main
from inserr.core.units import DEG_PER_HOUR, DEG_PER_SQRT_HOUR, HOUR, MICRO_G, MICRO_G_PER_SQRT_HZ

RATE = 10.0  # Hz
#: Gyro truth: ARW, bias instability, rate random walk (SI). Chosen so that each term
#: rules the Allan deviation over a decade or more of a 12 h recording: random walk
#: below ~10 s, the flicker floor from ~10 s to ~200 s, the rate random walk above.
ARW = 0.05 * DEG_PER_SQRT_HOUR
BI = 1.5 * DEG_PER_HOUR
RRW = 7.0 * DEG_PER_HOUR / math.sqrt(HOUR)
VRW = 50.0 * MICRO_G_PER_SQRT_HZ
ABI = 30.0 * MICRO_G


def flicker(rng, n: int, b: float, over: int = 8) -> np.ndarray:
    """Flicker rate noise, two-sided PSD ``b^2 / (2 pi f)`` (floor 0.664 b).

    Generated ``over`` times longer than needed and cut, so that its lowest
    frequency lies well below the recording's (the floor then holds to long tau).
    """
    m = over * n
    f = np.fft.rfftfreq(m, 1.0 / RATE)
    shape = np.zeros_like(f)
    shape[1:] = np.sqrt(RATE * b**2 / (2.0 * math.pi * f[1:]))
    return np.fft.irfft(np.fft.rfft(rng.standard_normal(m)) * shape, m)[:n]


def axis_samples(rng, n: int, white: float, b: float = 0.0, k: float = 0.0) -> np.ndarray:
    """White noise of density ``white`` + flicker ``b`` + rate random walk ``k`` (SI)."""
    x = white * math.sqrt(RATE) * rng.standard_normal(n)
    if b:
        x += flicker(rng, n, b)
    if k:
        x += np.cumsum(k / math.sqrt(RATE) * rng.standard_normal(n))
    return x


def recording(seed: int, hours: float = 12.0) -> allan.Recording:
    rng = np.random.default_rng(seed)
    n = int(hours * HOUR * RATE)
    gyro = np.column_stack([axis_samples(rng, n, ARW, BI, RRW) for _ in range(3)])
    accel = np.column_stack([axis_samples(rng, n, VRW, ABI) for _ in range(3)])
    return allan.Recording(RATE, gyro, accel, f"synthetic-{seed}")


@pytest.fixture(scope="module")
def fitted():
    return allan.fit_recording(recording(11))


def test_every_known_term_is_recovered_within_its_stated_interval(fitted):
    truth = {
        ("gyro", "white"): ARW,
        ("gyro", "bias_instability"): BI,
        ("gyro", "rate_random_walk"): RRW,
        ("accel", "white"): VRW,
        ("accel", "bias_instability"): ABI,
    }
    for (sensor, name), value in truth.items():
        for axis in allan.AXES:
            t = fitted.term(sensor, axis, name)
            assert t.resolved, (sensor, axis, name)
            assert t.low <= value <= t.high, (sensor, axis, name, t, value)
    # Absent terms are not claimed: no rate ramp anywhere, no random walk of the
    # accelerometers (their intervals reach 0).
    for axis in allan.AXES:
        assert not fitted.term("gyro", axis, "rate_ramp").resolved
        assert not fitted.term("accel", axis, "rate_random_walk").resolved


def test_the_intervals_cover_the_truth_as_often_as_they_say():
    # 95 % intervals over 24 independent 12 h recordings (one gyro axis each): honest
    # intervals give 22.8 hits on average, and 18 or fewer with probability < 0.1 %
    # (binomial); fewer than 19 means intervals clearly too narrow (coverage < 80 %).
    # (The rate random walk, read from the few clusters at the longest taus, is the
    # loosest: its normal-approximation interval covers about 92 %.)
    hits = {"white": 0, "bias_instability": 0, "rate_random_walk": 0}
    truth = {"white": ARW, "bias_instability": BI, "rate_random_walk": RRW}
    n = int(12 * HOUR * RATE)
    for seed in range(24):
        rng = np.random.default_rng(1000 + seed)
        fit = allan.fit_terms(allan.allan_deviation(axis_samples(rng, n, ARW, BI, RRW), RATE))
        for name, value in truth.items():
            t = fit.terms[name]
            hits[name] += t.low <= value <= t.high
    assert all(h >= 19 for h in hits.values()), hits


def test_a_rate_ramp_is_recovered_when_present():
    # A rate ramp R (rate = R t) has the Allan deviation R tau / sqrt(2) exactly
    # (IEEE Std 952, C.1: the cluster means differ by R tau); over white noise it
    # rules the long taus, and the fit must find it, within its interval.
    ramp = 40.0 * DEG_PER_HOUR / HOUR  # rad/s^2
    n = int(6 * HOUR * RATE)
    rng = np.random.default_rng(21)
    x = axis_samples(rng, n, ARW) + ramp * np.arange(n) / RATE
    fit = allan.fit_terms(allan.allan_deviation(x, RATE))
    t = fit.terms["rate_ramp"]
    assert t.resolved and t.low <= ramp <= t.high, (t, ramp)
    w = fit.terms["white"]
    assert w.low <= ARW <= w.high


def test_the_sampled_flicker_shape_matches_simulated_flicker_noise():
    # The Allan variance of sampled flicker noise at 1 and 4 samples, measured on
    # many generated samples, against flicker_shape (a quadrature of the PSD).
    rng = np.random.default_rng(5)
    n = 2**20
    x = flicker(rng, n, 1.0, over=1)
    floor = 2.0 * math.log(2.0) / math.pi
    for m in (1, 4):
        y = x[: (n // m) * m].reshape(-1, m).mean(axis=1)
        avar = 0.5 * np.mean(np.diff(y) ** 2)
        # Relative 1-sigma of an Allan variance from n/m clusters: sqrt(2 / (n/m)),
        # under 1 % here; 4 % bounds the flicker's slow drift too.
        assert avar / floor == pytest.approx(allan.flicker_shape([m])[0], rel=0.04)
    assert allan.flicker_shape([10**6])[0] == pytest.approx(1.0, abs=1e-9)


def test_gauss_markov_peak_matches_a_simulated_process():
    # A first-order Gauss-Markov rate (exact discretisation), its Allan deviation
    # measured: the peak sits near x_peak * T at ratio * sigma.
    x_peak, ratio = allan.gauss_markov_peak()
    sigma, corr, dt, n = 1.0, 20.0, 0.1, 2_000_000
    rng = np.random.default_rng(3)
    a = math.exp(-dt / corr)
    drive = sigma * math.sqrt(1 - a * a) * rng.standard_normal(n)
    from scipy.signal import lfilter

    x = lfilter([1.0], [1.0, -a], drive)
    taus = np.geomspace(5.0, 200.0, 40)
    measured = []
    for tau in taus:
        m = int(round(tau / dt))
        y = x[: (n // m) * m].reshape(-1, m).mean(axis=1)
        measured.append(math.sqrt(0.5 * np.mean(np.diff(y) ** 2)))
    measured = np.array(measured)
    # The closed form against the simulation along the curve (5 %: cluster scatter).
    assert measured == pytest.approx(allan.gauss_markov_adev(taus, sigma, corr), rel=0.05)
    assert measured.max() == pytest.approx(ratio * sigma, rel=0.05)
    assert taus[np.argmax(measured)] == pytest.approx(x_peak * corr, rel=0.35)


def _write_csv(path, rec: allan.Recording, header: str | None, index: bool = False) -> None:
    t = np.arange(rec.samples) if index else np.arange(rec.samples) / rec.rate
    deg = math.pi / 180.0
    data = np.column_stack([t, rec.gyro / deg, rec.accel / 9.80665])
    with open(path, "w", encoding="utf-8") as f:
        if header is not None:
            f.write(header + "\n")
        np.savetxt(f, data, delimiter=",", fmt="%.10g")


HEADER = "time (s),gyro x (deg/s),gyro y (deg/s),gyro z (deg/s),accel x (g),accel y (g),accel z (g)"


def test_cli_reads_the_recording_and_prints_an_imu_section_that_inserr_run_accepts(
    tmp_path, capsys
):
    rec = recording(21, hours=2.0)
    csv = tmp_path / "static.csv"
    _write_csv(csv, rec, HEADER)
    out = tmp_path / "noise"
    assert main(["imu-budget", str(csv), "--rate", "10", "--json", "--out", str(out)]) == 0
    result = json.loads(capsys.readouterr().out)
    assert (out / "allan_deviation.png").is_file() and (out / "report.html").is_file()
    gyro_arw = result["gyro"]["x"]["terms"]["white"]
    assert gyro_arw["unit"] == "deg/sqrt(h)"
    # 2 h at 10 Hz read the random walk to ~0.3 % (1 sigma): 2 % is > 6 sigma.
    assert gyro_arw["value"] == pytest.approx(0.05, rel=0.02)
    section = result["imu_section"]
    keys = tomllib.loads(section)["imu"]
    assert {"arw", "vrw", "gyro_bias_instability", "accel_bias_instability"} <= set(keys)
    # The section runs as it is, under the same validation as any scenario file.
    scen = tmp_path / "s.toml"
    scen.write_text('[scenario]\nduration = "1 h"\n' + section, encoding="utf-8")
    assert main(["run", str(scen), "--out", str(tmp_path / "rep"), "--json"]) == 0
    run = json.loads(capsys.readouterr().out)
    assert run["runs"][0]["final_horizontal_1sigma_nmi"] > 0


def test_sample_index_and_units_by_flag(tmp_path, capsys):
    rec = recording(22, hours=0.5)
    csv = tmp_path / "plain.csv"
    _write_csv(csv, rec, None, index=True)
    assert main(["imu-budget", str(csv), "--rate", "10", "--json"]) == 2
    err = capsys.readouterr().err
    assert "no unit" in err and "--gyro-unit" in err and len(err.strip().splitlines()) == 1
    argv = ["imu-budget", str(csv), "--rate", "10", "--gyro-unit", "deg/s", "--accel-unit", "g"]
    assert main([*argv, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["recording"]["samples"] == rec.samples


@pytest.mark.parametrize(
    ("content", "expected"),
    [
        ("time (s),gyro x (deg/s)\n0,1\n", "expected 7"),
        (HEADER + "\n0,1,2,3,4,5\n", "6 columns, expected 7"),
        (HEADER + "\n0,1,2,3,4,5,x\n", "not a number"),
        (HEADER + "\n" + "".join(f"{k / 10},0,0,0,0,0,1\n" for k in range(50)), "too short"),
        (
            HEADER.replace("(deg/s)", "(furlongs)", 1)
            + "\n"
            + "".join(f"{k / 10},0,0,0,0,0,1\n" for k in range(2000)),
            "unknown unit",
        ),
        (HEADER + "\n" + "".join(f"{k / 5},0,0,0,0,0,1\n" for k in range(2000)), "time step"),
        ("", "no data"),
    ],
)
def test_a_malformed_or_short_recording_gets_one_clear_error(tmp_path, capsys, content, expected):
    csv = tmp_path / "bad.csv"
    csv.write_text(content, encoding="utf-8")
    out = tmp_path / "never"
    assert main(["imu-budget", str(csv), "--rate", "10", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and expected in err and str(csv) in err
    assert not out.exists()  # no partial output


def test_bad_rate_and_missing_file(tmp_path, capsys):
    assert main(["imu-budget", str(tmp_path / "none.csv"), "--rate", "10"]) == 2
    assert "not found" in capsys.readouterr().err
    csv = tmp_path / "r.csv"
    csv.write_text(HEADER + "\n0,0,0,0,0,0,1\n", encoding="utf-8")
    assert main(["imu-budget", str(csv), "--rate", "-5"]) == 2
    assert capsys.readouterr().err.startswith("inserr imu-budget: error: --rate")


def test_noise_budget_front_door(fitted):
    from inserr.calibration.api import NoiseBudget

    nb = NoiseBudget(fitted)
    tau = 100.0
    b = nb.budget("gyro", tau=tau)
    # Allan variances of independent noises add: the RSS total is the fitted curve.
    for axis in allan.AXES:
        col = [c for c in b.columns if c.startswith(axis)][0]
        model = fitted.axes[("gyro", axis)].model(np.array([tau]))[0] / DEG_PER_HOUR
        assert b[col].iloc[-1] == pytest.approx(model, rel=1e-12)
    frame = nb.to_dataframe()
    assert "gyro x Allan deviation (deg/h)" in frame.columns
    assert "<table>" in nb._repr_html_()
    assert len(nb.plot().axes) == 6
