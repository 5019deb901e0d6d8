"""IMU noise terms from a static recording: Allan deviation and the IEEE slopes.

Engineers get the noise budget of an IMU (angle and velocity random walk, bias
instability, rate random walk) from a static recording through the Allan deviation
(IEEE Std 952-1997 Annex C, IEEE Std 1293 for accelerometers). This module:

1. reads the recording (:func:`read_recording`): a CSV file whose first column is
   the time or the sample index and whose next six are the three gyro rates and the
   three specific forces, with units declared in the header (``gyro x (deg/s)``) or
   given by the caller;
2. computes the overlapping Allan deviation of every axis at octave-spaced
   averaging times with ``allantools`` (:func:`allan_deviation`), with the relative
   error of each point from its number of independent clusters ``n = N / m``,
   ``1 / sqrt(2 (n - 1))`` (IEEE Std 952, C.2);
3. fits the standard terms by their slopes on the log-log plot (:func:`fit_terms`):
   the Allan variance of independent noises adds, and each term has its own power of
   the averaging time tau,

   ========================  ======  ===========================  ==================
   term                      slope   Allan variance               read as
   ========================  ======  ===========================  ==================
   angle / velocity RW (N)   -1/2    N^2 / tau                    sigma at tau = 1 s
   bias instability (B)      0       (2 ln 2 / pi) B^2            floor / 0.664
   rate random walk (K)      +1/2    K^2 tau / 3                  sigma at tau = 3 s
   rate ramp (R)             +1      R^2 tau^2 / 2                sigma at tau = sqrt 2
   ========================  ======  ===========================  ==================

   so ``sigma^2(tau) = c_-1 / tau + c_0 g(tau) + c_1 tau + c_2 tau^2`` with
   non-negative coefficients (``g`` -> 1 at long tau is the shape of sampled flicker
   noise, :func:`flicker_shape`, 1.19 at one sample), fitted by weighted non-negative
   least squares (weights from the cluster counts, refined twice with the fitted
   curve); each term's confidence interval follows from the covariance of that fit
   (doubled for the correlation between the points, :data:`CORRELATION_ALLOWANCE`). A
   term whose interval reaches 0 is reported as not resolved (the rate ramp is
   usually absent);
4. turns the terms into a ready ``[imu]`` scenario section (:func:`imu_section`):
   inserr models noise as ARW, VRW and first-order Gauss-Markov bias instability, so
   the bias instability becomes the Gauss-Markov process whose Allan-deviation peak
   matches the measured floor (:func:`gauss_markov_peak`).

All values are SI inside (rad/s, m/s^2, s); units only at the edges.
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from inserr.core.errors import InputError
from inserr.core.units import (
    DEG_PER_HOUR,
    DEG_PER_SQRT_HOUR,
    HOUR,
    MICRO_G,
    MICRO_G_PER_SQRT_HZ,
    UNITS,
)

#: Sensors and their axes, in column order.
SENSORS = ("gyro", "accel")
AXES = ("x", "y", "z")

#: Fewest samples accepted: the octave grid then spans at least ten averaging times,
#: enough for the slopes to be told apart.
MIN_SAMPLES = 2**10

#: Factor on the fit's covariance for the correlation between the Allan-deviation
#: points (see :func:`fit_terms`).
CORRELATION_ALLOWANCE = 2.0

#: Exponents of tau in the Allan variance of the fitted terms, by term.
TERM_POWERS = {"white": -1, "bias_instability": 0, "rate_random_walk": 1, "rate_ramp": 2}

#: Flicker floor factor: sigma_floor = sqrt(2 ln 2 / pi) B = 0.664 B (IEEE Std 952, C.2).
FLICKER_FACTOR = math.sqrt(2.0 * math.log(2.0) / math.pi)

#: Per sensor and term: (readable label, unit text, SI per unit, how the coefficient
#: of the Allan variance gives the term in SI).
TERMS: dict[str, dict[str, tuple[str, str, float]]] = {
    "gyro": {
        "white": ("angle random walk (ARW)", "deg/sqrt(h)", DEG_PER_SQRT_HOUR),
        "bias_instability": ("bias instability", "deg/h", DEG_PER_HOUR),
        "rate_random_walk": ("rate random walk", "deg/h/sqrt(h)", DEG_PER_HOUR / math.sqrt(HOUR)),
        "rate_ramp": ("rate ramp", "deg/h^2", DEG_PER_HOUR / HOUR),
    },
    "accel": {
        "white": ("velocity random walk (VRW)", "ug/sqrt(Hz)", MICRO_G_PER_SQRT_HZ),
        "bias_instability": ("bias instability", "ug", MICRO_G),
        "rate_random_walk": ("acceleration random walk", "ug/sqrt(h)", MICRO_G / math.sqrt(HOUR)),
        "rate_ramp": ("acceleration ramp", "ug/h", MICRO_G / HOUR),
    },
}

#: Unit of the Allan deviation in tables and figures: (text, SI per unit).
ADEV_UNITS = {"gyro": ("deg/h", DEG_PER_HOUR), "accel": ("ug", MICRO_G)}


def _coefficient_to_term(term: str, c: float) -> float:
    """A term's value (SI) from its Allan-variance coefficient (see the module table)."""
    c = max(float(c), 0.0)
    if term == "white":
        return math.sqrt(c)
    if term == "bias_instability":
        return math.sqrt(c) / FLICKER_FACTOR
    if term == "rate_random_walk":
        return math.sqrt(3.0 * c)
    return math.sqrt(2.0 * c)


# --- the recording ----------------------------------------------------------------------
@dataclass(frozen=True)
class Recording:
    """A static IMU recording, SI.

    Attributes
    ----------
    rate : float, Hz
        Sample rate.
    gyro : (N, 3) rad/s
        Angular rates, IMU axes x, y, z.
    accel : (N, 3) m/s^2
        Specific forces, IMU axes x, y, z.
    source : str
        Where it came from (file name), for reports.
    """

    rate: float
    gyro: np.ndarray
    accel: np.ndarray
    source: str = "array"

    @property
    def samples(self) -> int:
        """Number of samples."""
        return len(self.gyro)

    @property
    def duration(self) -> float:
        """Length of the recording, s."""
        return self.samples / self.rate

    def sensor(self, name: str) -> np.ndarray:
        """The (N, 3) samples of ``"gyro"`` or ``"accel"``."""
        return self.gyro if name == "gyro" else self.accel


_UNIT = re.compile(r"[\(\[]\s*([^\)\]]*?)\s*[\)\]]\s*$")


def _split_header(cell: str) -> tuple[str, str | None]:
    """``"gyro x (deg/s)"`` -> ``("gyro x", "deg/s")``; no unit -> ``(name, None)``."""
    m = _UNIT.search(cell)
    if m is None:
        return cell.strip(), None
    return cell[: m.start()].strip(), (m.group(1) or None)


def _factor(unit: str, kind: str, where: str, argument: str) -> float:
    table = UNITS[kind]
    if unit not in table:
        raise InputError(
            where,
            f"unknown unit {unit!r}",
            f"use one of {', '.join(u for u in table if u)} (in the header or with {argument})",
        )
    return table[unit]


def check_rate(rate: Any, field: str = "rate") -> float:
    """The sample rate as a positive finite float, Hz, or InputError naming ``field``."""
    try:
        r = float(rate)
    except (TypeError, ValueError):
        raise InputError(field, f"expected a sample rate in Hz, got {rate!r}") from None
    if not math.isfinite(r) or r <= 0:
        raise InputError(field, f"the sample rate must be > 0 Hz, got {rate!r}", "e.g. 100")
    return r


def read_recording(
    path: str | Path,
    rate: float,
    *,
    gyro_unit: str | None = None,
    accel_unit: str | None = None,
) -> Recording:
    """Read a static recording from a CSV file.

    The file (``#`` comment lines allowed) has seven columns: time or sample index,
    gyro x, y, z, accelerometer x, y, z. An optional header line names them, with
    units in brackets: ``time (s), gyro x (deg/s), ..., accel z (m/s^2)``. A first
    column named ``sample``, ``index``, ``n``, ``i`` or ``k`` (or, without a header,
    holding consecutive integers) is a sample index; otherwise it is the time, which
    must advance by ``1 / rate`` (within 1 %).

    Parameters
    ----------
    path : str or Path
        The CSV file.
    rate : float, Hz
        Sample rate.
    gyro_unit, accel_unit : str, optional
        Units of the gyro (``deg/s``, ``rad/s``, ``deg/h``) and accelerometer
        (``m/s^2``, ``g``, ``mg``, ``ug``) columns; they override the header's. One of
        the two is needed for each sensor.

    Returns
    -------
    Recording

    Raises
    ------
    InputError
        Missing or unreadable file, wrong number of columns, non-numeric or
        non-finite values, units missing or unknown, irregular sampling, fewer than
        :data:`MIN_SAMPLES` samples. The message names the file (and line or column).
    """
    rate = check_rate(rate)
    p = Path(path)
    name = str(path)
    if not p.is_file():
        raise InputError(name, "recording file not found", "check the path")
    try:
        text = p.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise InputError(
            name, "not a UTF-8 text (CSV) file", "export the recording as CSV"
        ) from None
    lines = [(i + 1, ln) for i, ln in enumerate(text.splitlines())]
    lines = [(i, ln) for i, ln in lines if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise InputError(name, "the file holds no data", "one line per sample: t, 3 gyro, 3 accel")
    first_no, first = lines[0]
    cells = next(csv.reader([first]))
    header: list[tuple[str, str | None]] | None = None
    try:
        [float(c) for c in cells]
    except ValueError:
        header = [_split_header(c) for c in cells]
        lines = lines[1:]
        if len(header) != 7:
            raise InputError(
                f"{name}:{first_no}",
                f"the header names {len(header)} columns, expected 7",
                "time or sample index, gyro x, y, z, accel x, y, z",
            ) from None
    rows = []
    for no, ln in lines:
        parts = ln.split(",")
        if len(parts) != 7:
            raise InputError(
                f"{name}:{no}",
                f"{len(parts)} columns, expected 7",
                "time or sample index, gyro x, y, z, accel x, y, z (comma-separated)",
            )
        try:
            rows.append([float(v) for v in parts])
        except ValueError:
            raise InputError(f"{name}:{no}", f"not a number in {ln.strip()!r}") from None
    data = np.array(rows, dtype=float).reshape(-1, 7)
    if not np.all(np.isfinite(data)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(data), axis=1))[0])
        raise InputError(f"{name}:{lines[bad][0]}", "a value is NaN or infinite", "remove it")
    if len(data) < MIN_SAMPLES:
        raise InputError(
            name,
            f"only {len(data)} samples ({len(data) / rate:g} s at {rate:g} Hz): too short "
            "for an Allan deviation",
            f"record at least {MIN_SAMPLES} samples; the longest averaging time read is "
            "about a tenth of the recording",
        )
    # The first column: a sample index or the time.
    label = (header[0][0] if header else "").lower()
    first_col = data[:, 0]
    steps = np.diff(first_col)
    # Without a header, a column of consecutive integers is a sample index (at 1 Hz
    # the two readings agree anyway).
    unnamed_index = header is None and bool(np.all(steps == 1.0)) and first_col[0] % 1 == 0
    if label in ("sample", "index", "n", "i", "k", "sample index") or unnamed_index:
        if not np.all(steps == 1.0):
            k = int(np.flatnonzero(steps != 1.0)[0])
            raise InputError(
                f"{name}:{lines[k + 1][0]}",
                "the sample index does not advance by 1 (missing or repeated samples)",
                "give a gap-free recording",
            )
    else:
        t_unit = header[0][1] if header and header[0][1] else "s"
        t = first_col * _factor(t_unit, "time", f"{name}: column 1", "a time unit")
        dt = np.diff(t)
        off = np.abs(dt * rate - 1.0) > 0.01
        if np.any(off):
            k = int(np.flatnonzero(off)[0])
            raise InputError(
                f"{name}:{lines[k + 1][0]}",
                f"time step {dt[k]:g} s, not 1/rate = {1.0 / rate:g} s (rate {rate:g} Hz)",
                "give the recording's sample rate (rate), or a gap-free recording",
            )
    out = {}
    for s, (sensor, given_unit, kind, argument) in enumerate(
        (
            ("gyro", gyro_unit, "angular_rate", "gyro_unit"),
            ("accel", accel_unit, "acceleration", "accel_unit"),
        )
    ):
        cols = []
        for a in range(3):
            c = 1 + 3 * s + a
            unit = given_unit or (header[c][1] if header else None)
            where = f"{name}: column {c + 1}" + (f" ({header[c][0]})" if header else "")
            if unit is None:
                raise InputError(
                    where,
                    f"no unit for the {sensor} {AXES[a]} column",
                    f"declare it in the header, e.g. '{sensor} {AXES[a]} "
                    f"({'deg/s' if sensor == 'gyro' else 'm/s^2'})', or give {argument}",
                )
            cols.append(data[:, c] * _factor(unit, kind, where, argument))
        out[sensor] = np.column_stack(cols)
    return Recording(rate, out["gyro"], out["accel"], name)


# --- Allan deviation ------------------------------------------------------------------
@dataclass(frozen=True)
class AllanCurve:
    """The overlapping Allan deviation of one axis at octave-spaced averaging times.

    Attributes
    ----------
    tau : (K,) s
        Averaging times ``m / rate``, m = 1, 2, 4, ...
    adev : (K,)
        Allan deviation, the unit of the samples (SI).
    clusters : (K,)
        Independent clusters ``N / m`` behind each point.
    rate : float, Hz, optional
        Sample rate (the bias-instability term's shape at short tau, see
        :func:`flicker_shape`); None: the flat long-tau form.
    """

    tau: np.ndarray
    adev: np.ndarray
    clusters: np.ndarray
    rate: float | None = None

    @property
    def rel_error(self) -> np.ndarray:
        """Relative 1-sigma error of each point, ``1 / sqrt(2 (N/m - 1))`` (IEEE 952, C.2)."""
        return 1.0 / np.sqrt(2.0 * np.maximum(self.clusters - 1.0, 1.0))


def allan_deviation(samples: np.ndarray, rate: float) -> AllanCurve:
    """Overlapping Allan deviation of rate samples at octave-spaced averaging times.

    Parameters
    ----------
    samples : (N,)
        Rate (or specific-force) samples, any unit.
    rate : float, Hz
        Sample rate.

    Returns
    -------
    AllanCurve
        Points with at least 3 independent clusters (fewer say nothing about a slope).
    """
    import allantools

    y = np.asarray(samples, dtype=float)
    taus, adev, _, _ = allantools.oadev(y, rate=rate, data_type="freq", taus="octave")
    taus = np.asarray(taus, dtype=float)
    adev = np.asarray(adev, dtype=float)
    clusters = len(y) / (taus * rate)
    keep = (clusters >= 3.0) & np.isfinite(adev) & (adev > 0)
    return AllanCurve(taus[keep], adev[keep], clusters[keep], float(rate))


# --- fit ------------------------------------------------------------------------------
@dataclass(frozen=True)
class Term:
    """One fitted noise term of one axis (SI).

    Attributes
    ----------
    name : str
        Key of :data:`TERM_POWERS`.
    value : float
        The term (SI: rad/sqrt(s), rad/s, rad/s/sqrt(s), rad/s^2 for a gyro; m/s/sqrt(s),
        m/s^2, m/s^2/sqrt(s), m/s^3 for an accelerometer).
    low, high : float
        Confidence interval (same unit).
    confidence : float
        Its level (e.g. 0.95).
    resolved : bool
        Whether the interval excludes 0 (the term is seen in the data).
    """

    name: str
    value: float
    low: float
    high: float
    confidence: float

    @property
    def resolved(self) -> bool:
        return self.low > 0.0


@dataclass(frozen=True)
class AxisFit:
    """The Allan deviation of one axis and its fitted terms.

    Attributes
    ----------
    curve : AllanCurve
    coefficients : (4,)
        Allan-variance coefficients ``c_-1, c_0, c_1, c_2`` (SI).
    covariance : (4, 4)
        Their covariance.
    terms : dict
        Term name -> :class:`Term`.
    z : float
        Normal quantile of the intervals.
    """

    curve: AllanCurve
    coefficients: np.ndarray
    covariance: np.ndarray
    terms: dict[str, Term]
    z: float

    def model(self, tau: np.ndarray) -> np.ndarray:
        """Fitted Allan deviation at ``tau``."""
        return np.sqrt(_design(np.asarray(tau, dtype=float), self.curve.rate) @ self.coefficients)

    def model_band(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Confidence band of the fitted Allan deviation (delta method on the variance)."""
        a = _design(np.asarray(tau, dtype=float), self.curve.rate)
        var = a @ self.coefficients
        sd = np.sqrt(np.einsum("ij,jk,ik->i", a, self.covariance, a))
        return np.sqrt(np.maximum(var - self.z * sd, 0.0)), np.sqrt(var + self.z * sd)

    def term_line(self, name: str, tau: np.ndarray) -> np.ndarray:
        """The Allan deviation of one term alone (its slope line)."""
        k = list(TERM_POWERS).index(name)
        return np.sqrt(
            self.coefficients[k] * _design(np.asarray(tau, dtype=float), self.curve.rate)[:, k]
        )

    @property
    def floor_tau(self) -> float:
        """Averaging time of the fitted curve's minimum within the measured range, s."""
        tau = np.geomspace(self.curve.tau[0], self.curve.tau[-1], 400)
        return float(tau[np.argmin(self.model(tau))])


def flicker_shape(m: np.ndarray) -> np.ndarray:
    """Allan variance of sampled flicker noise over its long-tau floor, at ``m`` samples.

    Flicker (bias-instability) rate noise of two-sided PSD ``B^2 / (2 pi |f|)`` has the
    Allan variance ``(2 ln 2 / pi) B^2`` only for averaging times long against the
    sample period: sampled at ``rate`` (no power above the Nyquist frequency) and
    averaged over ``m`` samples, its Allan variance is

    ``(2 / pi) B^2 int_0^(pi/2) sin^4(m u) / (m^2 u sin^2 u) du``,

    1.19 times the floor at m = 1, 1.03 at m = 4, within 0.3 % from m = 16 on (the
    m-sample average's response is ``sin(m u) / (m sin u)``, ``u = pi f / rate``).
    Fitting the floor as flat down to m = 1 would bias the random walk read at
    short tau.

    Parameters
    ----------
    m : array
        Averaging lengths, samples (>= 1).

    Returns
    -------
    ndarray
        The ratio to ``2 ln 2 / pi`` (-> 1 as m grows).
    """
    return np.array([_flicker_shape(int(mi)) for mi in np.asarray(m, dtype=float)])


@lru_cache(maxsize=4096)
def _flicker_shape(m: int) -> float:
    if m > 512:
        # Continuous limit less the tail of int sin^4 x / x^3 beyond X = pi m / 2
        # (sin^4 averages 3/8): the sampling correction is O(1/m^2) below this.
        x_end = math.pi * m / 2.0
        return 1.0 - 3.0 / (16.0 * math.log(2.0) * x_end**2)
    n = max(20000, 60 * m)  # >= 30 points per half-period of sin(m u)
    u = np.linspace(0.0, math.pi / 2.0, n + 1)[1:]
    y = np.sin(m * u) ** 4 / (u * m * m * np.sin(u) ** 2)
    # Near u = 0 the integrand is m^2 u: its integral over [0, u_1] is m^2 u_1^2 / 2.
    integral = np.trapezoid(y, u) + m * m * u[0] ** 2 / 2.0
    return float(integral / math.log(2.0))


def _design(tau: np.ndarray, rate: float | None = None) -> np.ndarray:
    cols = [tau**p for p in TERM_POWERS.values()]
    if rate is not None:
        cols[1] = flicker_shape(np.maximum(np.rint(tau * rate), 1.0))
    return np.column_stack(cols)


def _z(confidence: float) -> float:
    from scipy.stats import norm

    return float(norm.ppf(0.5 + confidence / 2.0))


def fit_terms(curve: AllanCurve, confidence: float = 0.95) -> AxisFit:
    """Fit the standard noise terms to one axis' Allan deviation (see the module).

    Parameters
    ----------
    curve : AllanCurve
    confidence : float
        Level of the intervals (two-sided, normal approximation).

    Returns
    -------
    AxisFit
    """
    from scipy.optimize import nnls

    tau, v = curve.tau, curve.adev**2
    a = _design(tau, curve.rate)
    # The variance of a point's Allan variance is (2 e v)^2 (e: relative error of the
    # deviation). First weights from the data, then twice from the fitted curve (the
    # data's own scatter would favour the points that happen to fall low).
    sd = 2.0 * curve.rel_error * v
    # Columns scaled to unit norm so that NNLS treats terms of very different sizes alike.
    for _ in range(3):
        aw = a / sd[:, None]
        scale = np.linalg.norm(aw, axis=0)
        c_scaled, _ = nnls(aw / scale, v / sd)
        c = c_scaled / scale
        model = a @ c
        sd = 2.0 * curve.rel_error * np.maximum(model, 1e-3 * v)
    aw = a / sd[:, None]
    info = aw.T @ aw
    # The least-squares covariance treats the points as independent; they are not (the
    # overlapping estimate at 2 tau reuses the clusters of tau). Doubling it (intervals
    # x sqrt 2) is the allowance that gives the stated coverage on synthetic recordings
    # of known noise (tests/test_imu_budget.py checks the coverage over many seeds).
    cov = CORRELATION_ALLOWANCE * np.linalg.pinv(info)
    z = _z(confidence)
    terms = {}
    for k, name in enumerate(TERM_POWERS):
        sigma = math.sqrt(max(cov[k, k], 0.0))
        lo, hi = max(c[k] - z * sigma, 0.0), c[k] + z * sigma
        terms[name] = Term(
            name,
            _coefficient_to_term(name, c[k]),
            _coefficient_to_term(name, lo),
            _coefficient_to_term(name, hi),
            confidence,
        )
    return AxisFit(curve, c, cov, terms, z)


# --- Gauss-Markov equivalent ----------------------------------------------------------
def gauss_markov_adev(tau: np.ndarray, sigma: float, corr_time: float) -> np.ndarray:
    """Allan deviation of a first-order Gauss-Markov rate of 1-sigma ``sigma``.

    ``sigma_A^2 = (2 sigma^2 T / tau) [1 - (T / 2 tau)(3 - 4 e^(-tau/T) + e^(-2 tau/T))]``
    (the Allan variance of exponentially correlated noise, IEEE Std 952 C.1).

    Parameters
    ----------
    tau : array, s
    sigma : float
        Stationary 1 sigma of the process.
    corr_time : float, s
        Correlation time T.
    """
    x = np.asarray(tau, dtype=float) / corr_time
    inner = 1.0 - (3.0 - 4.0 * np.exp(-x) + np.exp(-2.0 * x)) / (2.0 * x)
    return sigma * np.sqrt(np.maximum(2.0 / x * inner, 0.0))


@lru_cache(maxsize=1)
def gauss_markov_peak() -> tuple[float, float]:
    """Where a Gauss-Markov process' Allan deviation peaks, and how high.

    Returns
    -------
    x_peak : float
        ``tau / T`` at the peak (about 1.89).
    ratio : float
        Peak Allan deviation over the process' 1 sigma (about 0.62).
    """
    from scipy.optimize import minimize_scalar

    res = minimize_scalar(
        lambda x: -gauss_markov_adev(np.array([x]), 1.0, 1.0)[0],
        bounds=(0.1, 20.0),
        method="bounded",
        options={"xatol": 1e-10},
    )
    return float(res.x), float(-res.fun)


# --- the budget of a recording ---------------------------------------------------------
@dataclass(frozen=True)
class NoiseFit:
    """Every axis of a recording, fitted.

    Attributes
    ----------
    recording : Recording
    axes : dict
        ``(sensor, axis)`` -> :class:`AxisFit`, e.g. ``("gyro", "x")``.
    confidence : float
    """

    recording: Recording
    axes: dict[tuple[str, str], AxisFit] = field(repr=False)
    confidence: float = 0.95

    def term(self, sensor: str, axis: str, name: str) -> Term:
        """One term of one axis."""
        return self.axes[(sensor, axis)].terms[name]


def fit_recording(recording: Recording, confidence: float = 0.95) -> NoiseFit:
    """Allan deviation and fitted terms of all six axes of a recording."""
    axes = {}
    for sensor in SENSORS:
        data = recording.sensor(sensor)
        for a, axis in enumerate(AXES):
            curve = allan_deviation(data[:, a], recording.rate)
            axes[(sensor, axis)] = fit_terms(curve, confidence)
    return NoiseFit(recording, axes, confidence)


def in_units(sensor: str, name: str, value: float) -> float:
    """A term's SI value in its reporting unit (:data:`TERMS`)."""
    return value / TERMS[sensor][name][2]


def summary(fit: NoiseFit) -> dict[str, Any]:
    """JSON-ready summary: the recording, every term of every axis with its interval.

    Returns
    -------
    dict
        ``recording`` (file, rate_hz, samples, duration_s), ``confidence``, and per
        sensor (``gyro``, ``accel``) per axis per term: ``value``, ``low``, ``high``,
        ``unit``, ``resolved``; plus ``floor_tau_s`` per axis and the ``[imu]``
        section as text (``imu_section``).
    """
    rec = fit.recording
    out: dict[str, Any] = {
        "recording": {
            "file": rec.source,
            "rate_hz": rec.rate,
            "samples": rec.samples,
            "duration_s": rec.duration,
        },
        "confidence": fit.confidence,
    }
    for sensor in SENSORS:
        block: dict[str, Any] = {}
        for axis in AXES:
            f = fit.axes[(sensor, axis)]
            terms = {}
            for name, t in f.terms.items():
                terms[name] = {
                    "value": in_units(sensor, name, t.value),
                    "low": in_units(sensor, name, t.low),
                    "high": in_units(sensor, name, t.high),
                    "unit": TERMS[sensor][name][1],
                    "resolved": t.resolved,
                }
            block[axis] = {"terms": terms, "floor_tau_s": f.floor_tau}
        out[sensor] = block
    out["imu_section"] = imu_section(fit)
    return out


def _largest(fit: NoiseFit, sensor: str, name: str) -> tuple[float, str]:
    """The largest value of a term over the three axes, and its axis."""
    vals = [(fit.term(sensor, a, name).value, a) for a in AXES]
    return max(vals)


def scenario_imu(fit: NoiseFit) -> dict[str, str]:
    """The ``[imu]`` keys inserr models, as a scenario file would hold them.

    inserr's noise is isotropic, so each key takes the largest axis (conservative).
    ``arw`` and ``vrw`` are the white terms. The bias instability B becomes the
    first-order Gauss-Markov process whose Allan-deviation peak equals the measured
    floor ``0.664 B`` at the floor's averaging time: 1 sigma ``0.664 B / ratio`` and
    correlation time ``tau_floor / x_peak`` (:func:`gauss_markov_peak`). Terms not
    resolved in the data are left out (0 by default). Rate random walk and ramp have
    no inserr key (listed as comments by :func:`imu_section`).
    """
    x_peak, ratio = gauss_markov_peak()
    out: dict[str, str] = {}
    for sensor, key in (("gyro", "arw"), ("accel", "vrw")):
        value, axis = _largest(fit, sensor, "white")
        if fit.term(sensor, axis, "white").resolved:
            label, unit, si = TERMS[sensor]["white"]
            out[key] = f"{value / si:.4g} {unit}"
    for sensor in SENSORS:
        value, axis = _largest(fit, sensor, "bias_instability")
        if not fit.term(sensor, axis, "bias_instability").resolved:
            continue
        _, unit, si = TERMS[sensor]["bias_instability"]
        sigma = FLICKER_FACTOR * value / ratio
        corr = fit.axes[(sensor, axis)].floor_tau / x_peak
        out[f"{sensor}_bias_instability"] = f"{sigma / si:.4g} {unit}"
        out[f"{sensor}_correlation_time"] = f"{corr:.4g} s"
    return out


def imu_section(fit: NoiseFit) -> str:
    """A ready ``[imu]`` scenario section (TOML text) with the fitted noise.

    The keys of :func:`scenario_imu`, then comments with the per-axis terms and
    intervals, so that ``inserr run`` reads the section as it is.
    """
    keys = scenario_imu(fit)
    pct = f"{fit.confidence:.0%}"
    lines = [
        f"# Noise fitted to {Path(fit.recording.source).name}: "
        f"{fit.recording.duration / HOUR:.3g} h at {fit.recording.rate:g} Hz",
        f"# (Allan deviation, IEEE Std 952 slopes, {pct} intervals). Each key is the "
        "largest axis; the bias",
        "# instability is the Gauss-Markov process whose Allan-deviation peak is the "
        "measured floor.",
        "[imu]",
    ]
    lines += [f'{k} = "{v}"' for k, v in keys.items()]
    if not keys:
        lines.append("# no noise term was resolved in this recording")
    for sensor in SENSORS:
        for name in TERM_POWERS:
            label, unit, _ = TERMS[sensor][name]
            parts = []
            for axis in AXES:
                t = fit.term(sensor, axis, name)
                if t.resolved:
                    parts.append(
                        f"{axis} {in_units(sensor, name, t.value):.3g} "
                        f"[{in_units(sensor, name, t.low):.3g}, "
                        f"{in_units(sensor, name, t.high):.3g}]"
                    )
                else:
                    parts.append(f"{axis} < {in_units(sensor, name, t.high):.3g}")
            lines.append(f"# {sensor} {label} ({unit}): " + ", ".join(parts))
    return "\n".join(lines) + "\n"
