"""Discrete multi-position calibration: measurement model, least squares, identifiability, CRLB.

Measurement model (the sensor model of :mod:`inserr.core.imu`, IMU frame s). At a static
stop p with nominal attitude ``C_p = C_s^n`` the sensor triad sees the reference
vector ``r`` (Earth rate ``[0, W cos L, W sin L]`` for the gyros, specific force
``[0, 0, g]`` for the accelerometers, both ENU) as the input ``u_p = C_p^T r``. The
dwell average of the output is::

    m_p = (I + K) u_p + b + n_p,     K = S + M,     n_p ~ N(0, (q^2 / T_p) I_3)

with ``q`` the white-noise density (ARW for gyros, VRW for accelerometers) and
``T_p`` the dwell: the average of white noise over ``T_p`` is *exactly* Gaussian
with that variance, whatever the sample rate, so the simulation uses it directly
(the per-sample alternative is kept for checking, :class:`MonteCarloConfig`).

The observation ``y_p = m_p - u_p`` is linear in the 12 parameters
``theta = [sf_x, sf_y, sf_z, mis_xy, mis_xz, mis_yx, mis_yz, mis_zx, mis_zy,
bias_x, bias_y, bias_z]``: the row of sensor axis i has ``u_p[i]`` under ``sf_i``,
``u_p[j]`` under ``mis_ij`` and 1 under ``bias_i``. Every sensor axis therefore sees the
same regressors ``[u_p, 1]``; the 12-parameter design has rank ``3 * rank([u_p, 1])``,
i.e. all 12 parameters are identifiable exactly when the input vectors of the stops do
not all lie on one plane. That is what :func:`identifiability` reports in words.

Estimation is dwell-weighted least squares (``numpy.linalg.lstsq`` on the whitened,
column-scaled design), which for this linear Gaussian model is efficient: its
covariance *is* the Cramer-Rao bound ``(H^T R^-1 H)^-1``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from inserr.calibration.two_axis_table import PositionSet
from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.core.imu import AXES, MISALIGNMENT_INDEX, MISALIGNMENTS, ImuErrors, error_matrix
from inserr.core.rotations import skew
from inserr.core.units import (
    ARCSEC,
    DEG_PER_HOUR,
    DEG_PER_SQRT_HOUR,
    G0,
    MICRO_G,
    MICRO_G_PER_SQRT_HZ,
    PPM,
)
from inserr.output.progress import progress

#: Parameter names, in the order of the parameter vector (same for gyro and accel).
PARAMETER_NAMES: tuple[str, ...] = (
    tuple(f"sf_{a}" for a in AXES)
    + tuple(f"mis_{m}" for m in MISALIGNMENTS)
    + tuple(f"bias_{a}" for a in AXES)
)
N_PARAMETERS = len(PARAMETER_NAMES)
SENSORS = ("gyro", "accel")

#: Singular values below this fraction of the largest (column-scaled design) count as
#: zero. Physical designs are either well conditioned (condition number < 1e3 for any
#: sensible set) or exactly singular up to the ~1e-16 rounding of the DCMs; 1e-10
#: separates the two with margins of many orders on both sides.
RANK_RTOL = 1e-10

# --- P1's simulation set-up and the defaults chosen where P1 is silent ----------
#: P1 true gyro scale-factor errors (dimensionless) and misalignments (rad).
P1_GYRO_SCALE_FACTOR = 1e-4
P1_GYRO_MISALIGNMENT = 2.145e-5
#: P1 true gyro biases, rad/s.
P1_GYRO_BIAS = np.array([2.04173693, 3.01844241, 2.09545751]) * DEG_PER_HOUR
#: Accelerometer truth (P1 gives none; chosen to mirror the gyro: 100 ppm, 2.145e-5 rad,
#: biases of a navigation-grade accelerometer), SI.
DEFAULT_ACCEL_SCALE_FACTOR = 1e-4
DEFAULT_ACCEL_MISALIGNMENT = 2.145e-5
DEFAULT_ACCEL_BIAS = np.array([50.0, 80.0, 100.0]) * MICRO_G
#: Default noise (P1 gives none): a navigation-grade ring-laser gyro, 0.0005 deg/sqrt(h),
#: and 5 ug/sqrt(Hz) accelerometers -- the IMU of P0 in this project.
DEFAULT_ARW = 0.0005 * DEG_PER_SQRT_HOUR
DEFAULT_VRW = 5.0 * MICRO_G_PER_SQRT_HZ
#: P1's positioning error: uniform within +-3 arcsec at every stop.
P1_POSITIONING_ERROR = 3.0 * ARCSEC
#: P1's sample rate, Hz (only used by the per-sample simulation).
P1_SAMPLE_RATE = 100.0


def p1_truth(arw: float = DEFAULT_ARW, vrw: float = DEFAULT_VRW) -> ImuErrors:
    """Error budget of P1's simulation: P1's gyro truth, the default accelerometer truth.

    Parameters
    ----------
    arw : float
        Gyro angle random walk, rad/sqrt(s).
    vrw : float
        Accelerometer velocity random walk, m/s/sqrt(s).

    Returns
    -------
    ImuErrors
        Biases (rad/s, m/s^2), scale factors (dimensionless) and misalignments (rad) in
        the IMU frame s, with the given noise; no bias instability.
    """
    return ImuErrors(
        gyro_bias=P1_GYRO_BIAS,
        gyro_scale_factor=np.full(3, P1_GYRO_SCALE_FACTOR),
        gyro_misalignment=np.full(6, P1_GYRO_MISALIGNMENT),
        accel_bias=DEFAULT_ACCEL_BIAS,
        accel_scale_factor=np.full(3, DEFAULT_ACCEL_SCALE_FACTOR),
        accel_misalignment=np.full(6, DEFAULT_ACCEL_MISALIGNMENT),
        arw=arw,
        vrw=vrw,
    )


# --- units for reports ---------------------------------------------------------


def parameter_unit(name: str, sensor: str) -> tuple[str, float]:
    """Engineering unit of a calibration parameter for reports.

    Scale factors in ppm, misalignments in arcsec, gyro biases in deg/h and
    accelerometer biases in micro-g.

    Parameters
    ----------
    name : str
        Parameter name from :data:`PARAMETER_NAMES` (``sf_*``, ``mis_*``, ``bias_*``).
    sensor : str
        "gyro" or "accel" (only matters for biases).

    Returns
    -------
    label : str
        Unit label ("ppm", "arcsec", "deg/h" or "ug").
    value : float
        SI value of one such unit (divide an SI value by it to convert).
    """
    if name.startswith("sf_"):
        return "ppm", PPM
    if name.startswith("mis_"):
        return "arcsec", ARCSEC
    return ("deg/h", DEG_PER_HOUR) if sensor == "gyro" else ("ug", MICRO_G)


def _input_text(value: float, sensor: str) -> str:
    if sensor == "gyro":
        return f"{value / DEG_PER_HOUR:.4g} deg/h"
    return f"{value / G0:.4g} g"


# --- the linear model ------------------------------------------------------------


def parameter_vector(scale_factor, misalignment, bias) -> np.ndarray:
    """Stack scale factors, misalignments and biases into the 12-parameter vector theta.

    Parameters
    ----------
    scale_factor : float or (3,) array
        Scale-factor errors of axes x, y, z, dimensionless (a scalar is broadcast).
    misalignment : float or (6,) array
        Misalignments in the order xy, xz, yx, yz, zx, zy, rad.
    bias : float or (3,) array
        Biases of axes x, y, z, IMU frame s: rad/s (gyro) or m/s^2 (accel).

    Returns
    -------
    (12,) ndarray
        ``theta`` in the order of :data:`PARAMETER_NAMES` (SI).
    """
    return np.concatenate(
        [
            np.broadcast_to(scale_factor, 3),
            np.broadcast_to(misalignment, 6),
            np.broadcast_to(bias, 3),
        ]
    ).astype(float)


def truth_vector(imu: ImuErrors, sensor: str) -> np.ndarray:
    """The 12 true calibration parameters of one sensor triad from an error budget.

    Parameters
    ----------
    imu : ImuErrors
        Error budget (SI, IMU frame s).
    sensor : str
        "gyro" or "accel".

    Returns
    -------
    (12,) ndarray
        ``theta`` in the order of :data:`PARAMETER_NAMES`: scale factors
        (dimensionless), misalignments (rad), biases (rad/s or m/s^2).
    """
    _check_sensor(sensor)
    return parameter_vector(
        getattr(imu, f"{sensor}_scale_factor"),
        getattr(imu, f"{sensor}_misalignment"),
        getattr(imu, f"{sensor}_bias"),
    )


def error_matrix_of(theta: np.ndarray) -> np.ndarray:
    """Error matrix ``K = S + M`` of a triad from its 12-parameter vector.

    Parameters
    ----------
    theta : (12,) array
        Parameters in the order of :data:`PARAMETER_NAMES` (the biases are ignored).

    Returns
    -------
    (3, 3) ndarray
        ``K`` (dimensionless, IMU frame s): scale factors on the diagonal,
        ``K[i, j] = mis_ij``.
    """
    return error_matrix(theta[0:3], theta[3:9])


def reference_vector(site: Site, sensor: str) -> np.ndarray:
    """Reference input sensed at rest: Earth rate or specific force, ENU.

    Parameters
    ----------
    site : Site
        Latitude and gravity.
    sensor : str
        "gyro" or "accel".

    Returns
    -------
    (3,) ndarray
        ``[0, W cos L, W sin L]`` rad/s for "gyro", ``[0, 0, g]`` m/s^2 for "accel",
        navigation frame n (ENU).
    """
    _check_sensor(sensor)
    return site.earth_rate_n if sensor == "gyro" else site.specific_force_n


def sensor_inputs(attitudes: np.ndarray, reference_n: np.ndarray) -> np.ndarray:
    """Nominal sensor inputs ``u_p = C_p^T r`` of every stop, IMU frame s.

    Parameters
    ----------
    attitudes : (N, 3, 3) array
        ``C_s^n`` of the stops (IMU frame s to ENU).
    reference_n : (3,) array
        Reference vector ``r`` in ENU: rad/s (Earth rate) or m/s^2 (specific force).

    Returns
    -------
    (N, 3) ndarray
        Inputs in the IMU frame s, same unit as ``reference_n``.
    """
    return np.einsum("pji,j->pi", np.asarray(attitudes, float), np.asarray(reference_n, float))


def design_matrix(inputs: np.ndarray) -> np.ndarray:
    """Jacobian ``H = dy / dtheta`` of the stacked observations with respect to theta.

    Parameters
    ----------
    inputs : (N, 3) array
        Nominal inputs ``u_p``, IMU frame s: rad/s (gyro) or m/s^2 (accel).

    Returns
    -------
    (3N, 12) ndarray
        Row ``3 p + i`` is sensor axis i at stop p; columns follow
        :data:`PARAMETER_NAMES`. Units: the input's for scale-factor and
        misalignment columns, 1 for bias columns.
    """
    u = np.asarray(inputs, dtype=float)
    n = u.shape[0]
    h = np.zeros((n, 3, N_PARAMETERS))
    for i in range(3):
        h[:, i, i] = u[:, i]
        h[:, i, 9 + i] = 1.0
    for k, name in enumerate(MISALIGNMENTS):
        i, j = MISALIGNMENT_INDEX[name]
        h[:, i, 3 + k] = u[:, j]
    return h.reshape(3 * n, N_PARAMETERS)


def _check_sensor(sensor: str) -> None:
    if sensor not in SENSORS:
        raise InputError("sensor", f"unknown sensor {sensor!r}", "use 'gyro' or 'accel'")


def _param_name(sensor_axis: int, input_axis: int) -> str:
    if sensor_axis == input_axis:
        return f"sf_{AXES[sensor_axis]}"
    return f"mis_{AXES[sensor_axis]}{AXES[input_axis]}"


@dataclass(frozen=True)
class InputRelation:
    """A linear relation ``a . u_p + c = 0`` that the inputs obey at every stop.

    Attributes
    ----------
    coefficients : (3,) array
        ``a`` (1 / input unit).
    constant : float
        ``c`` (dimensionless).
    reason : str
        The relation in words.
    groups : tuple of tuple of str
        For each sensor axis, the parameters made inseparable by the relation.
    """

    coefficients: np.ndarray
    constant: float
    reason: str
    groups: tuple[tuple[str, ...], ...]


@dataclass(frozen=True)
class Identifiability:
    """What a position set can and cannot determine.

    Attributes
    ----------
    sensor : str
        "gyro" or "accel".
    rank : int
        Rank of the 12-column design.
    condition_number : float
        2-norm condition number of the dwell-weighted design with every column scaled
        to unit 2-norm (so parameter units do not matter; van der Sluis: within a
        factor sqrt(12) of the best diagonal scaling); ``inf`` if rank < 12.
    identifiable : tuple of bool
        Per parameter: True if it is uniquely determined by noise-free data.
    relations : tuple of InputRelation
        A basis of the input relations that cause the rank loss.
    messages : tuple of str
        One sentence per inseparable group, e.g. "gyro sf_z and bias_z are
        inseparable: every position has the same z input (8.41 deg/h)".
    """

    sensor: str
    rank: int
    condition_number: float
    identifiable: tuple[bool, ...]
    relations: tuple[InputRelation, ...]
    messages: tuple[str, ...]

    @property
    def full_rank(self) -> bool:
        """True when all 12 parameters are identifiable."""
        return self.rank == N_PARAMETERS

    @property
    def unidentifiable(self) -> list[str]:
        """Names of the parameters that cannot be determined individually."""
        return [n for n, ok in zip(PARAMETER_NAMES, self.identifiable, strict=True) if not ok]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary of the identifiability.

        Returns
        -------
        dict
            ``rank``, ``condition_number``, ``unidentifiable`` (names) and ``messages``.
        """
        return {
            "rank": self.rank,
            "condition_number": self.condition_number,
            "unidentifiable": self.unidentifiable,
            "messages": list(self.messages),
        }


def _rref(m: np.ndarray, tol: float) -> np.ndarray:
    """Reduced row echelon form with partial pivoting; entries below ``tol`` set to 0."""
    a = np.array(m, dtype=float)
    rows, cols = a.shape
    r = 0
    for c in range(cols):
        if r == rows:
            break
        piv = r + int(np.argmax(np.abs(a[r:, c])))
        if abs(a[piv, c]) <= tol:
            continue
        a[[r, piv]] = a[[piv, r]]
        a[r] /= a[r, c]
        for k in range(rows):
            if k != r:
                a[k] -= a[k, c] * a[r]
        r += 1
    a[np.abs(a) <= tol] = 0.0
    return a[:r]


def input_relations(inputs: np.ndarray, sensor: str) -> tuple[InputRelation, ...]:
    """Basis of the affine relations ``a . u_p + c = 0`` obeyed by every stop's input.

    The regressors of every sensor axis are ``[u_p, 1]``; a null vector of that
    (N x 4) matrix is exactly a relation among the inputs, and the parameters under its
    non-zero entries cannot be separated. The basis is put in reduced row echelon form
    so that simple relations ("z input constant", "x input zero") come out as such.

    Parameters
    ----------
    inputs : (N, 3) array
        Nominal inputs (rad/s for gyros, m/s^2 for accelerometers), IMU frame s.
    sensor : str
        "gyro" or "accel" (for the words).

    Returns
    -------
    tuple of InputRelation
        One per independent relation (empty when the inputs span 3-D affinely,
        i.e. all 12 parameters are identifiable).
    """
    u = np.asarray(inputs, dtype=float)
    scale = float(np.max(np.abs(u))) or 1.0
    a = np.column_stack([u / scale, np.ones(len(u))])
    # full_matrices: with fewer than 4 stops the trailing right singular vectors are
    # null vectors too.
    _, s, vt = np.linalg.svd(a, full_matrices=True)
    null = vt[int(np.sum(s > RANK_RTOL * s[0])) :]
    if len(null) == 0:
        return ()
    # 1e-9 after the SVD's ~1e-15 rounding: a coefficient this small is rounding, not physics.
    basis = _rref(null, 1e-9)
    relations = []
    for row in basis:
        coef_scaled, c = row[:3], float(row[3])
        nz = [j for j in range(3) if coef_scaled[j] != 0.0]
        names = [AXES[j] for j in nz]
        if len(nz) == 1 and c != 0.0:
            value = -c / coef_scaled[nz[0]] * scale
            reason = f"every position has the same {names[0]} input ({_input_text(value, sensor)})"
        elif len(nz) == 1:
            reason = f"the {names[0]} input is zero at every position"
        elif (
            len(nz) == 2
            and c == 0.0
            and abs(abs(coef_scaled[nz[0]]) - abs(coef_scaled[nz[1]])) < 1e-9
        ):
            same = coef_scaled[nz[0]] * coef_scaled[nz[1]] < 0
            word = "equal" if same else "opposite"
            reason = f"the {names[0]} and {names[1]} inputs are {word} at every position"
        else:
            terms = " ".join(f"{v:+.4g}*{AXES[j]}" for j, v in enumerate(coef_scaled) if v != 0.0)
            const = f" {c:+.4g}" if c != 0.0 else ""
            reason = (
                f"the inputs obey {terms}{const} = 0 at every position (in units of "
                f"{_input_text(scale, sensor)}): they lie on one plane"
            )
        groups = []
        for i in range(3):
            g = [_param_name(i, j) for j in nz]
            if c != 0.0:
                g.append(f"bias_{AXES[i]}")
            groups.append(tuple(g))
        relations.append(InputRelation(coef_scaled / scale, c, reason, tuple(groups)))
    return tuple(relations)


def _relation_messages(relations: tuple[InputRelation, ...], sensor: str) -> tuple[str, ...]:
    out = []
    for rel in relations:
        if all(len(g) == 1 for g in rel.groups):
            # The relation starves single parameters (an input never excited): one sentence.
            names = [g[0] for g in rel.groups]
            out.append(
                f"{sensor} {', '.join(names[:-1])} and {names[-1]} cannot be determined: "
                f"{rel.reason}"
            )
            continue
        for g in rel.groups:
            out.append(f"{sensor} {' and '.join(g)} are inseparable: {rel.reason}")
    return tuple(out)


@dataclass(frozen=True)
class CalibrationDesign:
    """The linear calibration problem of one sensor triad over a position set.

    Parameters
    ----------
    sensor : str
        "gyro" or "accel".
    attitudes : (N, 3, 3) array
        Nominal ``C_s^n`` of the stops (IMU frame s to ENU).
    dwell : (N,) array
        Dwell times, s.
    reference_n : (3,) array
        Reference input in ENU (rad/s or m/s^2).
    noise_density : float
        White-noise density of the sensor: ARW (rad/sqrt(s)) or VRW (m/s/sqrt(s)).

    Attributes
    ----------
    inputs : (N, 3) ndarray
        Nominal inputs ``u_p`` (:func:`sensor_inputs`), IMU frame s, unit of ``reference_n``.
    design : (3N, 12) ndarray
        Unweighted design matrix (:func:`design_matrix`).
    """

    sensor: str
    attitudes: np.ndarray
    dwell: np.ndarray
    reference_n: np.ndarray
    noise_density: float
    inputs: np.ndarray = field(init=False, repr=False)
    design: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        _check_sensor(self.sensor)
        att = np.asarray(self.attitudes, dtype=float)
        dwell = np.asarray(self.dwell, dtype=float)
        if att.ndim != 3 or att.shape[1:] != (3, 3) or dwell.shape != (att.shape[0],):
            raise InputError("positions", "attitudes (N,3,3) and dwell (N,) do not match")
        if np.any(dwell <= 0) or not np.all(np.isfinite(dwell)):
            raise InputError("dwell", "every dwell must be a finite time > 0 s")
        if not math.isfinite(self.noise_density) or self.noise_density < 0:
            raise InputError(
                "noise", f"noise density must be finite and >= 0, got {self.noise_density!r}"
            )
        object.__setattr__(self, "attitudes", att)
        object.__setattr__(self, "dwell", dwell)
        object.__setattr__(self, "reference_n", np.asarray(self.reference_n, dtype=float))
        u = sensor_inputs(att, self.reference_n)
        object.__setattr__(self, "inputs", u)
        object.__setattr__(self, "design", design_matrix(u))

    @classmethod
    def from_position_set(
        cls, pset: PositionSet, site: Site, sensor: str, noise_density: float
    ) -> CalibrationDesign:
        """Build the calibration problem of one sensor triad for a position set at a site.

        Parameters
        ----------
        pset : PositionSet
            Nominal stops (attitudes ``C_s^n`` and dwells, s).
        site : Site
            Latitude (Earth rate) and gravity.
        sensor : str
            "gyro" or "accel".
        noise_density : float
            ARW (rad/sqrt(s)) for "gyro", VRW (m/s/sqrt(s)) for "accel".

        Returns
        -------
        CalibrationDesign
        """
        return cls(
            sensor, pset.attitudes, pset.dwells, reference_vector(site, sensor), noise_density
        )

    # --- weighting and scaling ---------------------------------------------------
    @property
    def row_weights(self) -> np.ndarray:
        """Whitening weight ``sqrt(T_p)`` (sqrt(s)) per observation row, (3N,), up to 1/q."""
        return np.repeat(np.sqrt(self.dwell), 3)

    @property
    def sigma(self) -> np.ndarray:
        """1-sigma noise of each stop's dwell average, ``q / sqrt(T_p)``, (N,), input unit."""
        return self.noise_density / np.sqrt(self.dwell)

    def _scaled(self) -> tuple[np.ndarray, np.ndarray]:
        """Whitened design with *physical* column scaling, and the scale factors.

        Input columns are divided by ``|r|`` (bias columns by 1), so every column is at
        most ``sqrt(sum T_p)`` long. Scaling by the columns' own norms would blow up a
        column that is zero only up to rounding (an input that is never excited) and
        hide the rank loss; scaling by the physical magnitude keeps it ~1e-16.
        """
        hw = self.design * self.row_weights[:, None]
        norms = np.ones(N_PARAMETERS)
        norms[:9] = float(np.linalg.norm(self.reference_n)) or 1.0
        return hw / norms, norms

    def _svd(self):
        hs, norms = self._scaled()
        u, s, vt = np.linalg.svd(hs, full_matrices=False)
        rank = int(np.sum(s > RANK_RTOL * s[0])) if s.size and s[0] > 0 else 0
        return hs, norms, u, s, vt, rank

    def condition_number(self) -> float:
        """Condition number of the dwell-weighted design, every column scaled to unit 2-norm.

        Unit-norm columns make it independent of parameter units and, by van der
        Sluis' theorem, within a factor sqrt(12) of the smallest condition number any
        diagonal column scaling can give.

        Returns
        -------
        float
            2-norm condition number (dimensionless); ``inf`` if the design is rank
            deficient.
        """
        if self._svd()[-1] < N_PARAMETERS:
            return math.inf
        hw = self.design * self.row_weights[:, None]
        s = np.linalg.svd(hw / np.linalg.norm(hw, axis=0), compute_uv=False)
        return float(s[0] / s[-1])

    # --- identifiability -------------------------------------------------------
    def identifiability(self) -> Identifiability:
        """Rank, condition number and the inseparable parameter groups in words.

        Returns
        -------
        Identifiability
        """
        _, _, _, _, vt, rank = self._svd()
        cond = self.condition_number()
        null = vt[rank:]
        # A parameter is identifiable iff its unit vector is orthogonal to the null space.
        # The null vectors are unit length in the physically scaled coordinates, so an
        # identifiable parameter leaks only rounding (~1e-30); 1e-12 (a component of 1e-6)
        # still flags a parameter that enters a null vector at any physical level.
        leak = np.sum(null**2, axis=0) if len(null) else np.zeros(N_PARAMETERS)
        identifiable = tuple(bool(v < 1e-12) for v in leak)
        rel = input_relations(self.inputs, self.sensor) if rank < N_PARAMETERS else ()
        return Identifiability(
            self.sensor, rank, cond, identifiable, rel, _relation_messages(rel, self.sensor)
        )

    # --- estimation --------------------------------------------------------------
    def estimator(self) -> np.ndarray:
        """Weighted least-squares estimator matrix ``E`` with ``theta_hat = E @ y``.

        Returns
        -------
        (12, 3N) ndarray
            Maps observations ``y`` (input unit) to SI parameters; rows of
            unidentifiable parameters are NaN.
        """
        hs, norms, u, s, vt, rank = self._svd()
        pinv = (vt[:rank].T / s[:rank]) @ u[:, :rank].T
        e = (pinv / norms[:, None]) * self.row_weights[None, :]
        ident = self.identifiability().identifiable
        e[~np.array(ident)] = np.nan
        return e

    def estimate(self, y: np.ndarray) -> np.ndarray:
        """Least-squares parameters from observations ``y = m - u_nominal``.

        Parameters
        ----------
        y : (3N,) or (R, N, 3) or (R, 3N) array
            Dwell-averaged output minus the nominal input, IMU frame s, same unit as
            the input (rad/s or m/s^2); R independent calibrations.

        Returns
        -------
        (12,) or (R, 12) array
            Parameters (SI); NaN for those the set cannot determine.
        """
        y = np.asarray(y, dtype=float)
        single = y.ndim == 1
        y2 = y.reshape(1 if single else y.shape[0], -1)
        hs, norms, *_, rank = self._svd()
        w = self.row_weights
        # lstsq on the whitened, column-scaled system; its minimum-norm answer is unique
        # in every identifiable parameter, the others are blanked below.
        x, *_ = np.linalg.lstsq(hs, (y2 * w).T, rcond=RANK_RTOL)
        theta = (x / norms[:, None]).T
        theta[:, ~np.array(self.identifiability().identifiable)] = np.nan
        return theta[0] if single else theta

    # --- precision ---------------------------------------------------------------
    def covariance(self) -> np.ndarray:
        """Cramer-Rao covariance of the parameters from the white sensor noise.

        ``(H^T R^-1 H)^+`` with ``R = diag(q^2 / T_p)``.

        Returns
        -------
        (12, 12) ndarray
            Covariance in SI units of :data:`PARAMETER_NAMES`; rows/columns of
            unidentifiable parameters are ``inf``.
        """
        hs, norms, _, s, vt, rank = self._svd()
        cov_s = (vt[:rank].T / s[:rank] ** 2) @ vt[:rank]
        cov = self.noise_density**2 * cov_s / np.outer(norms, norms)
        bad = ~np.array(self.identifiability().identifiable)
        cov[bad, :] = np.inf
        cov[:, bad] = np.inf
        return cov

    def crlb_sigma(self) -> np.ndarray:
        """Cramer-Rao 1-sigma of every parameter.

        Returns
        -------
        (12,) ndarray
            SI (dimensionless, rad, rad/s or m/s^2); ``inf`` if unidentifiable.
        """
        return np.sqrt(np.diag(self.covariance()))

    def positioning_sensitivity(self, k_true: np.ndarray | None = None) -> np.ndarray:
        """First-order parameter error per rad of positioning error, shape (12, N, 3).

        ``J[j, p, k]`` is the change of the estimate of parameter j when the IMU at stop
        p is turned by a small angle about ENU axis k (east, north, up) away from its
        nominal attitude (``C_true = (I + [delta x]) C_nom``), while the estimate still
        uses the nominal attitude. The input error is ``C_nom^T [r x] delta``, and the
        sensor sees it through ``(I + K)``.

        Parameters
        ----------
        k_true : (3, 3) array, optional
            True error matrix ``K`` (dimensionless, IMU frame s; default zero, its
            effect is second order).

        Returns
        -------
        (12, N, 3) ndarray
            ``J[j, p, k]``: SI parameter unit per rad of rotation about ENU axis k.
        """
        k = np.zeros((3, 3)) if k_true is None else np.asarray(k_true, float)
        e = self.estimator()
        n = len(self.dwell)
        dudd = np.einsum("pji,jk->pik", self.attitudes, skew(self.reference_n))
        dydd = np.einsum("ij,pjk->pik", np.eye(3) + k, dudd)  # (N, 3 sensor axes, 3 ENU axes)
        return np.einsum("jpi,pik->jpk", e.reshape(N_PARAMETERS, n, 3), dydd)


def gimbal_sensitivity(j_enu: np.ndarray, pset: PositionSet) -> np.ndarray:
    """Parameter sensitivity to the outer and inner gimbal-angle errors of every stop.

    A gimbal-angle error is a rotation about that gimbal's axis (in ENU at the stop),
    so it projects the ENU sensitivity of
    :meth:`CalibrationDesign.positioning_sensitivity` on the axis.

    Parameters
    ----------
    j_enu : (12, N, 3) array
        Sensitivity to small rotations about the ENU axes, SI per rad.
    pset : PositionSet
        The stops (gimbal angles, rad) and the table whose axes are used.

    Returns
    -------
    (12, N, 2) ndarray
        SI per rad; ``[:, p, 0]`` outer gimbal, ``[:, p, 1]`` inner gimbal.
    """
    axes = np.stack(
        [
            np.stack([pset.table.outer_axis, pset.table.inner_axis_nav(p.outer, p.inner)])
            for p in pset.positions
        ]
    )  # (N, 2, 3)
    return np.einsum("jpk,pgk->jpg", j_enu, axes)


POSITIONING_MODELS = ("three-axis", "gimbal")


def positioning_sigma(
    design: CalibrationDesign, pset: PositionSet, half_width: float, model: str = "three-axis"
) -> np.ndarray:
    """First-order 1-sigma parameter error from uniform positioning errors of the table.

    ``"three-axis"``: at every stop an independent small rotation about each ENU axis;
    ``"gimbal"``: independent errors of the outer and inner gimbal angles. The variance
    of a uniform error is ``half_width^2 / 3``.

    Parameters
    ----------
    design : CalibrationDesign
        The calibration problem of one triad.
    pset : PositionSet
        The same stops (needed for the gimbal axes).
    half_width : float
        Half-width of each uniform error, rad.
    model : str
        "three-axis" or "gimbal".

    Returns
    -------
    (12,) ndarray
        1-sigma in SI units of :data:`PARAMETER_NAMES` (NaN where unidentifiable).
    """
    j = design.positioning_sensitivity()
    if model == "gimbal":
        j = gimbal_sensitivity(j, pset)
    elif model != "three-axis":
        raise InputError(
            "positioning_model", f"unknown model {model!r}", f"use one of {POSITIONING_MODELS}"
        )
    return np.sqrt(half_width**2 / 3.0 * np.sum(j**2, axis=(1, 2)))


# --- Monte Carlo ------------------------------------------------------------------


@dataclass(frozen=True)
class MonteCarloConfig:
    """Settings of a calibration Monte Carlo.

    Parameters
    ----------
    runs : int
        Number of simulated calibrations (>= 2, so a sample std exists).
    seed : int
        Seed of ``numpy.random.default_rng``.
    positioning_error : float
        Half-width, rad, of the uniform positioning error at every stop.
    positioning_model : str
        "three-axis" (small rotation about each ENU axis, each uniform) or "gimbal"
        (outer and inner gimbal-angle errors, each uniform).
    per_sample : bool
        If True, simulate every sample at ``sample_rate`` and average over the dwell
        instead of drawing the dwell average directly (identical statistics, slower;
        the dwell is rounded to whole samples).
    sample_rate : float
        Output rate, Hz; used only when ``per_sample``.
    """

    runs: int = 100
    seed: int = 1
    positioning_error: float = P1_POSITIONING_ERROR
    positioning_model: str = "three-axis"
    per_sample: bool = False
    sample_rate: float = P1_SAMPLE_RATE

    def __post_init__(self) -> None:
        if int(self.runs) != self.runs or self.runs < 2:
            raise InputError(
                "scenario.runs", f"need at least 2 runs, got {self.runs!r}", "give 2 or more"
            )
        if int(self.seed) != self.seed or self.seed < 0:
            raise InputError("scenario.seed", f"seed must be an integer >= 0, got {self.seed!r}")
        if not math.isfinite(self.positioning_error) or self.positioning_error < 0:
            raise InputError(
                "calibration.positioning_error",
                f"must be finite and >= 0, got {self.positioning_error!r}",
            )
        if self.positioning_model not in POSITIONING_MODELS:
            raise InputError(
                "calibration.positioning_model",
                f"unknown model {self.positioning_model!r}",
                f"use one of {', '.join(POSITIONING_MODELS)}",
            )
        if not math.isfinite(self.sample_rate) or self.sample_rate <= 0:
            raise InputError("imu.sample_rate", f"must be > 0 Hz, got {self.sample_rate!r}")


@dataclass(frozen=True)
class SensorResult:
    """Monte Carlo and prediction for one sensor triad (all SI, order of :data:`PARAMETER_NAMES`).

    Attributes
    ----------
    sensor : str
        "gyro" or "accel".
    identifiability : Identifiability
        What the position set determines.
    truth : (12,) ndarray
        True parameters.
    estimates : (R, 12) ndarray
        Estimates of every run (NaN where unidentifiable).
    crlb_sigma : (12,) ndarray
        Cramer-Rao 1-sigma from the sensor noise.
    positioning_sigma : (12,) ndarray
        First-order 1-sigma from the positioning error.
    """

    sensor: str
    identifiability: Identifiability
    truth: np.ndarray
    estimates: np.ndarray
    crlb_sigma: np.ndarray
    positioning_sigma: np.ndarray

    @property
    def deviations(self) -> np.ndarray:
        """Estimate minus truth per run, (R, 12), SI."""
        return self.estimates - self.truth

    @property
    def mean_deviation(self) -> np.ndarray:
        """Mean over runs of estimate minus truth, (12,), SI."""
        return np.mean(self.deviations, axis=0)

    @property
    def std(self) -> np.ndarray:
        """Sample standard deviation (ddof = 1) of the estimates, (12,), SI."""
        return np.std(self.estimates, axis=0, ddof=1)

    @property
    def predicted_std(self) -> np.ndarray:
        """Predicted 1-sigma ``sqrt(crlb^2 + positioning^2)``, (12,), SI (independent sources)."""
        return np.hypot(self.crlb_sigma, self.positioning_sigma)

    def table(self) -> dict[str, dict[str, Any]]:
        """Monte Carlo statistics and predictions per parameter, in engineering units.

        Returns
        -------
        dict
            ``{name: row}`` over :data:`PARAMETER_NAMES`; each row holds ``unit``
            (:func:`parameter_unit`), ``true``, ``mean_deviation``, ``std``,
            ``variance`` (unit squared), ``crlb_sigma``, ``positioning_sigma``,
            ``predicted_std`` and ``identifiable``; ``None`` for values that do not
            exist (unidentifiable parameter).
        """
        out = {}
        for j, name in enumerate(PARAMETER_NAMES):
            unit, f = parameter_unit(name, self.sensor)

            def conv(v: float, f: float = f) -> float | None:
                return float(v) / f if math.isfinite(v) else None

            std = conv(self.std[j])
            out[name] = {
                "unit": unit,
                "true": conv(self.truth[j]),
                "mean_deviation": conv(self.mean_deviation[j]),
                "std": std,
                "variance": None if std is None else std**2,
                "crlb_sigma": conv(self.crlb_sigma[j]),
                "positioning_sigma": conv(self.positioning_sigma[j]),
                "predicted_std": conv(self.predicted_std[j]),
                "identifiable": self.identifiability.identifiable[j],
            }
        return out


def _rotation_matrices(phi: np.ndarray) -> np.ndarray:
    """``expm([phi x])`` for rotation vectors of shape (..., 3) (Rodrigues)."""
    theta = np.linalg.norm(phi, axis=-1)[..., None, None]
    k = skew(phi)
    small = theta < 1e-8
    safe = np.where(small, 1.0, theta)
    a = np.where(small, 1.0 - theta**2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, 0.5 - theta**2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
    return np.eye(3) + a * k + b * (k @ k)


def true_attitudes(
    pset: PositionSet, config: MonteCarloConfig, rng: np.random.Generator
) -> np.ndarray:
    """True attitudes ``C_s^n`` reached in every run, with random positioning errors.

    Parameters
    ----------
    pset : PositionSet
        Nominal stops.
    config : MonteCarloConfig
        Runs R, positioning error half-width (rad) and model.
    rng : numpy.random.Generator
        Source of the uniform errors.

    Returns
    -------
    (R, N, 3, 3) ndarray
        ``C_s^n`` (IMU frame s to ENU) of every run and stop.
    """
    nominal = pset.attitudes
    r, n, a = config.runs, len(pset), config.positioning_error
    if config.positioning_model == "three-axis":
        delta = rng.uniform(-a, a, size=(r, n, 3))
        return _rotation_matrices(delta) @ nominal
    eps = rng.uniform(-a, a, size=(r, n, 2))
    out = np.empty((r, n, 3, 3))
    for p, pos in enumerate(pset.positions):
        for k in range(r):
            out[k, p] = pset.table.attitude(pos.outer + eps[k, p, 0], pos.inner + eps[k, p, 1])
    return out


def _dwell_noise(
    rng: np.random.Generator, density: float, dwell: np.ndarray, config: MonteCarloConfig
) -> np.ndarray:
    """Noise of the dwell averages, (R, N, 3)."""
    r, n = config.runs, len(dwell)
    if not config.per_sample:
        return rng.standard_normal((r, n, 3)) * (density / np.sqrt(dwell))[None, :, None]
    out = np.empty((r, n, 3))
    sample_sigma = density * math.sqrt(config.sample_rate)  # white noise of PSD q^2 sampled at f
    for k in progress(range(r), total=r, desc="per-sample runs"):
        for p in range(n):
            m = max(1, round(dwell[p] * config.sample_rate))
            out[k, p] = rng.standard_normal((3, m)).mean(axis=1) * sample_sigma
    return out


def monte_carlo(
    pset: PositionSet, site: Site, imu: ImuErrors, config: MonteCarloConfig
) -> dict[str, SensorResult]:
    """Simulate ``config.runs`` calibrations of both triads and estimate by least squares.

    In every run the table's positioning errors (shared by gyros and accelerometers,
    which sit on the same IMU) are drawn, then the gyro noise, then the accelerometer
    noise, all from ``numpy.random.default_rng(config.seed)``: same inputs and seed give
    identical numbers.

    Parameters
    ----------
    pset : PositionSet
        Nominal stops (the estimator assumes these attitudes).
    site : Site
        Latitude (Earth rate) and gravity.
    imu : ImuErrors
        True scale factors, misalignments, biases, ARW and VRW (SI).
    config : MonteCarloConfig
        Runs, seed, positioning error.

    Returns
    -------
    dict
        ``{"gyro": SensorResult, "accel": SensorResult}``.
    """
    rng = np.random.default_rng(config.seed)
    c_true = true_attitudes(pset, config, rng)
    out = {}
    for sensor, density in (("gyro", imu.arw), ("accel", imu.vrw)):
        design = CalibrationDesign.from_position_set(pset, site, sensor, density)
        theta = truth_vector(imu, sensor)
        k = error_matrix_of(theta)
        u_true = np.einsum("rpji,j->rpi", c_true, design.reference_n)
        noise = _dwell_noise(rng, density, design.dwell, config)
        y = u_true @ (np.eye(3) + k).T + theta[9:] + noise - design.inputs
        est = design.estimate(y.reshape(config.runs, -1))
        out[sensor] = SensorResult(
            sensor,
            design.identifiability(),
            theta,
            est,
            design.crlb_sigma(),
            positioning_sigma(design, pset, config.positioning_error, config.positioning_model),
        )
    return out
