"""Nonlinear reference: inverse navigation, error injection and full strapdown navigation (pyins).

P0's validation set-up, made automatic for any scenario inserr can analyse:
the exact IMU attitude history of the scenario -> ideal IMU increments by
inverse navigation (``pyins.sim.generate_imu``) -> errors injected in the IMU
frame (:mod:`inserr.reference.injection`) -> full strapdown navigation
(``pyins.strapdown.Integrator``) -> navigation errors against the known truth.
The strapdown mechanization is python-ins (MIT), an independent library: code
written by the same hands as the linear model would share its conventions and
its mistakes. It is the optional extra ``inserr[reference]``.

Frames and conventions
----------------------
inserr: n = ENU, IMU frame s right-front-up, ``C_s^n`` maps s to n, angles in rad.
pyins: navigation frame NED, body frame forward-right-down, ``mat_nb`` maps body to
NED, attitude as (roll, pitch, heading) in degrees
(``Rotation.from_euler('xyz', rph, degrees=True)``), latitude/longitude in degrees.
ENU -> NED and right-front-up -> forward-right-down are the *same* coordinate
swap :data:`SWAP` (x <-> y, z -> -z; a proper rotation, its own inverse), so::

    mat_nb = SWAP C_s^n SWAP,     v_pyins = SWAP v_inserr   (any body or nav vector).

The pyins body frame is the inserr IMU frame s with relabelled axes; nothing else
differs (both use WGS84 radii, Somigliana gravity and Earth rate 7.292115e-5 rad/s).

Errors are reported the inserr way (:mod:`inserr.model.psi_model`): position and velocity
errors computed minus true in metres / m/s ENU, and the true attitude error
``phi`` with ``C_s^n(computed) = (I - [phi x]) C_s^n``, i.e.
``phi = log(C_s^n C_s^n(computed)^T)``; the psi-angle follows as
``psi = phi - dtheta(dr)`` (:func:`inserr.model.psi_model.position_angle`).

Vertical channel: inserr's default ``"clamped"`` (externally aided) model holds the
vertical velocity and position errors at zero and lets nothing feed back from
them. pyins's ``Integrator(with_altitude=False)`` holds the vertical velocity at
zero and the altitude at its initial value, so its horizontal equations see
exactly the same (zero) vertical terms: the two are equivalent. ``"free"`` maps to
``with_altitude=True``.

Inverse navigation and chunking
-------------------------------
``generate_imu`` fits a C2 rotation spline through the sampled attitudes and
returns the exact integrals of its angular rate and specific force over each
sample interval. The spline reproduces every sampled attitude exactly, so the
integrated attitude is exact at every sample; between samples the path is the
spline's. Long runs are cut into chunks (1 h by default). Each chunk is generated
with :data:`MARGIN` extra samples at both ends and the margins are dropped: the
influence of a cubic spline's end conditions decays by a factor of about 0.27
per knot, so after 32 knots the chunked increments equal the unchunked ones to
rounding. The integrator is restarted at every chunk from the last computed
position, velocity and attitude (its update uses only the current state), and the
previous measured sample is carried so the coning/sculling corrections see the
same data as in one long run.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.core.imu import ImuErrors, InitialErrors
from inserr.core.rotations import log_so3
from inserr.model.psi_model import position_angle
from inserr.model.timeline import Timeline
from inserr.output.progress import Bar
from inserr.reference.injection import Injector, initial_state, position_error

#: ENU <-> NED and right-front-up <-> forward-right-down coordinate swap (a proper rotation).
SWAP = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
#: Extra samples generated at each end of a chunk (see the module notes).
MARGIN = 32
#: Default IMU sample rate, Hz (P0's).
DEFAULT_RATE = 100.0
#: Default chunk length, s.
DEFAULT_CHUNK = 3600.0

AttitudeFn = Callable[[np.ndarray], np.ndarray]


def require_pyins():
    """Import python-ins, or raise an :class:`InputError` saying how to install it.

    Returns
    -------
    module
        The ``pyins`` package with ``sim``, ``strapdown``, ``transform`` and ``util`` loaded.
    """
    try:
        import pyins
        import pyins.sim
        import pyins.strapdown
        import pyins.transform
        import pyins.util  # noqa: F401
    except ImportError as exc:
        raise InputError(
            "nonlinear reference",
            f"needs the optional package python-ins (import pyins), which fails to import: {exc}",
            "install the extra: pip install 'inserr[reference]'",
        ) from None
    return pyins


def to_pyins_dcm(c_sn: np.ndarray) -> np.ndarray:
    """Convert inserr ``C_s^n`` to the pyins attitude matrix ``mat_nb``.

    Parameters
    ----------
    c_sn : (..., 3, 3) array
        IMU frame s (right-front-up) to ENU.

    Returns
    -------
    (..., 3, 3) ndarray
        pyins body (forward-right-down) to NED, ``SWAP C_s^n SWAP``.
    """
    return SWAP @ np.asarray(c_sn, dtype=float) @ SWAP


def from_pyins_dcm(mat_nb: np.ndarray) -> np.ndarray:
    """Convert the pyins attitude matrix ``mat_nb`` to inserr ``C_s^n``.

    Parameters
    ----------
    mat_nb : (..., 3, 3) array
        pyins body (forward-right-down) to NED.

    Returns
    -------
    (..., 3, 3) ndarray
        IMU frame s (right-front-up) to ENU (the swap is its own inverse).
    """
    return SWAP @ np.asarray(mat_nb, dtype=float) @ SWAP


def swap_vectors(v: np.ndarray) -> np.ndarray:
    """Swap vector components between inserr axes and pyins axes (either direction).

    Parameters
    ----------
    v : (..., 3) array
        Components in inserr axes (ENU or right-front-up) or pyins axes (NED or
        forward-right-down); any unit.

    Returns
    -------
    (..., 3) ndarray
        ``SWAP v``: the same vectors in the other library's axes, same unit.
    """
    return np.asarray(v, dtype=float) @ SWAP  # SWAP is symmetric: row form of SWAP @ v


def attitude_history(timeline: Timeline) -> AttitudeFn:
    """The exact IMU attitude ``C_s^n(t)`` behind a timeline.

    When the timeline carries its table schedule and vehicle motion (every
    scenario timeline does), this is their exact composition
    ``C_b^n(t) C_s^b(t)``, continuous in time: the reference then also checks the
    timeline's sub-stepping of continuous motion. Otherwise the timeline's own
    piecewise-constant-rate history (:meth:`Timeline.attitude_at`).

    Parameters
    ----------
    timeline : Timeline
        Scenario timeline, optionally with ``meta["table"]`` and ``meta["motion"]``.

    Returns
    -------
    callable
        ``attitude(t)``: times (n,) in s to ``C_s^n`` (n, 3, 3), IMU frame s to ENU.
    """
    table = timeline.meta.get("table")
    motion = timeline.meta.get("motion")
    if table is not None and motion is not None:

        def exact(t: np.ndarray) -> np.ndarray:
            t = np.atleast_1d(np.asarray(t, dtype=float))
            return motion.attitude(t) @ table.dcm_at(t, motion)

        return exact
    return timeline.attitude_at


def ideal_increments(
    site: Site, attitude: AttitudeFn, times: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Ideal IMU increments of an IMU at rest at ``site`` with attitude history ``attitude``.

    Parameters
    ----------
    site : Site
        Position of the IMU (lat, lon rad, height m), converted to degrees for pyins.
    attitude : callable
        ``C_s^n`` (IMU frame s to ENU), (n, 3, 3), at an array of times (s).
    times : (n,) array
        Sample times, s, equally spaced.

    Returns
    -------
    gyro : (n, 3) ndarray
        Angle increment, rad, over ``[times[i-1], times[i]]`` in the IMU frame s (row 0
        repeats row 1, pyins's convention).
    accel : (n, 3) ndarray
        Integrated specific force, m/s, over the same intervals, IMU frame s.
    """
    pyins = require_pyins()
    times = np.asarray(times, dtype=float)
    mat_nb = to_pyins_dcm(attitude(times))
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Gimbal lock")
        rph = pyins.transform.mat_to_rph(mat_nb)
    lla = np.tile([math.degrees(site.lat), math.degrees(site.lon), site.height], (len(times), 1))
    _, imu = pyins.sim.generate_imu(
        times, lla, rph, np.zeros((len(times), 3)), sensor_type="increment"
    )
    gyro = swap_vectors(imu[pyins.util.GYRO_COLS].to_numpy())
    accel = swap_vectors(imu[pyins.util.ACCEL_COLS].to_numpy())
    return gyro, accel


@dataclass
class ErrorHistory:
    """Navigation errors of one nonlinear run (ENU, SI, computed minus true).

    Attributes
    ----------
    t : (M,) ndarray
        Output times, s.
    phi : (M, 3) ndarray
        True attitude error, rad (E, N tilts; U heading error, + = heading too large).
    dv : (M, 3) ndarray
        Velocity error, m/s, ENU.
    dr : (M, 3) ndarray
        Position error, m, ENU.
    """

    t: np.ndarray
    phi: np.ndarray
    dv: np.ndarray
    dr: np.ndarray

    @property
    def horizontal(self) -> np.ndarray:
        """Horizontal position error magnitude, m."""
        return np.hypot(self.dr[:, 0], self.dr[:, 1])

    def nav(self, site: Site) -> np.ndarray:
        """Navigation errors in the linear model's layout ``[psi, dv, dr]``.

        Parameters
        ----------
        site : Site
            True site (radii and latitude of the position-error angle).

        Returns
        -------
        (M, 9) ndarray
            psi (rad), dv (m/s), dr (m), all ENU; ``psi = phi - dtheta(dr)``.
        """
        psi = self.phi - position_angle(site, self.dr)
        return np.hstack([psi, self.dv, self.dr])


@dataclass(frozen=True)
class RunSpec:
    """One nonlinear run: its errors, randomness and output step.

    Parameters
    ----------
    imu : ImuErrors
        Sensor errors of the run (constants as realised; noise levels), SI, IMU frame s.
    init : InitialErrors
        Initial attitude (rad), velocity (m/s) and position (m) errors, ENU.
    seed : numpy.random.SeedSequence, optional
        Entropy of the noise streams (needed when ``noise`` and the budget is noisy).
    noise : bool
        Draw white noise and bias instability (False: deterministic errors only).
    record_step : float, optional
        Output step of this run, s (default: :func:`simulate`'s).
    """

    imu: ImuErrors
    init: InitialErrors
    seed: np.random.SeedSequence | None = None
    noise: bool = True
    record_step: float | None = None


def _record_indices(n: int, stride: int) -> np.ndarray:
    idx = np.arange(0, n + 1, stride)
    return idx if idx[-1] == n else np.append(idx, n)


class _RunState:
    """Integrator state of one run carried from chunk to chunk."""

    def __init__(
        self, spec: RunSpec, site: Site, c_sn0: np.ndarray, vertical: str, stride: int, n: int
    ):
        pyins = require_pyins()
        self.injector = Injector(spec.imu, spec.seed, spec.noise)
        s0 = initial_state(site, c_sn0, spec.init, vertical)
        v_ned = swap_vectors(s0.velocity)
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message="Gimbal lock")
            rph = pyins.transform.mat_to_rph(to_pyins_dcm(s0.c_sn))
        import pandas as pd

        self.pva = pd.Series(
            np.concatenate([[math.degrees(s0.lat), math.degrees(s0.lon), s0.height], v_ned, rph]),
            index=pyins.util.TRAJECTORY_COLS,
            name=0.0,
        )
        self.prev: np.ndarray | None = None  # last measured raw sample, pyins axes (6,)
        self.rec = _record_indices(n, stride)
        self.rows: list[np.ndarray] = []  # recorded trajectory rows (lla, vel, rph)


def simulate(
    site: Site,
    attitude: AttitudeFn,
    duration: float,
    runs: Sequence[RunSpec],
    *,
    rate: float = DEFAULT_RATE,
    record_step: float = 1.0,
    chunk: float = DEFAULT_CHUNK,
    vertical: str = "clamped",
    desc: str = "nonlinear reference",
) -> list[ErrorHistory]:
    """Run the nonlinear reference for one attitude history and several error realisations.

    The ideal increments of each chunk are generated once and shared by all runs
    (they do not depend on the errors), so extra Monte Carlo runs cost only the
    injection and the integration.

    Parameters
    ----------
    site : Site
        Where the IMU rests (WGS84 ellipsoid; pyins has no spherical Earth).
    attitude : callable
        Exact ``C_s^n(t)`` (IMU frame s to ENU) at times in s, e.g.
        :func:`attitude_history`.
    duration : float
        Length of the run, s.
    runs : sequence of RunSpec
        Error realisations, all integrated over the same ideal increments.
    rate : float
        IMU sample rate, Hz. Samples are at ``k / rate``,
        ``k = 0 .. floor(duration rate)``.
    record_step : float
        Output step, s, rounded to a whole number of samples (the last sample is
        always recorded).
    chunk : float
        Length of the pieces generated and integrated at once, s (bounds memory).
    vertical : {"clamped", "free"}
        Vertical channel: aided (pyins ``with_altitude=False``) or free.
    desc : str
        Label of the progress bar.

    Returns
    -------
    list of ErrorHistory
        One per run, in the order of ``runs`` (ENU, SI, computed minus true).
    """
    pyins = require_pyins()
    import pandas as pd

    if not (math.isfinite(rate) and rate > 0):
        raise InputError("imu.sample_rate", f"must be > 0 Hz, got {rate!r}", "give e.g. 100 Hz")
    if not (math.isfinite(chunk) and chunk > 0):
        raise InputError("validate.chunk", f"must be > 0 s, got {chunk!r}")
    if vertical not in ("clamped", "free"):
        raise InputError("output.vertical", f"unknown mode {vertical!r}", "use clamped or free")
    dt = 1.0 / rate
    n = int(math.floor(duration * rate + 1e-9))
    if n < 2:
        raise InputError(
            "duration", f"{duration:g} s holds fewer than 2 IMU samples at {rate:g} Hz"
        )
    nc = max(1, int(round(chunk * rate)))
    c_sn0 = attitude(np.array([0.0]))[0]
    states = []
    for spec in runs:
        step = spec.record_step if spec.record_step is not None else record_step
        stride = max(1, int(round(step * rate)))
        states.append(_RunState(spec, site, c_sn0, vertical, stride, n))

    cols = pyins.util.GYRO_COLS + pyins.util.ACCEL_COLS
    with_altitude = vertical == "free"
    with Bar(total=n, desc=desc, unit="sample") as bar, warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Gimbal lock")
        # pyins 1.0.1 passes a keyword pandas 3 deprecates; nothing a user can act on.
        warnings.filterwarnings("ignore", message="The copy keyword is deprecated")
        k0 = 1
        while k0 <= n:
            k1 = min(k0 + nc - 1, n)
            idx = np.arange(k0 - 1 - MARGIN, k1 + MARGIN + 1)
            gyro, accel = ideal_increments(site, attitude, idx * dt)
            keep = slice(MARGIN, MARGIN + k1 - k0 + 2)  # samples k0-1 .. k1
            g_id, a_id = gyro[keep], accel[keep]
            index = pd.Index(np.arange(k0 - 1, k1 + 1) * dt, name="time")
            for st in states:
                if st.prev is None:  # first chunk: sample 0 is the coning "before" sample
                    g, a = st.injector.apply(g_id, a_id, dt)
                    raw = swap_vectors(np.hstack([g, a]).reshape(-1, 2, 3)).reshape(-1, 6)
                else:
                    g, a = st.injector.apply(g_id[1:], a_id[1:], dt)
                    new = swap_vectors(np.hstack([g, a]).reshape(-1, 2, 3)).reshape(-1, 6)
                    raw = np.vstack([st.prev[None, :], new])
                inc = pyins.strapdown.compute_increments_from_imu(
                    pd.DataFrame(raw, index=index, columns=cols), "increment"
                )
                integ = pyins.strapdown.Integrator(st.pva, with_altitude=with_altitude)
                traj = integ.integrate(inc)  # rows for samples k0-1 .. k1
                values = traj[pyins.util.TRAJECTORY_COLS].to_numpy()
                sel = st.rec[(st.rec >= k0 - 1) & (st.rec <= k1)]
                if k0 > 1:
                    sel = sel[sel >= k0]  # sample k0-1 was recorded by the previous chunk
                st.rows.append(np.column_stack([sel * dt, values[sel - (k0 - 1)]]))
                st.pva = traj.iloc[-1].copy()
                st.prev = raw[-1]
            bar.update(k1 - k0 + 1)
            k0 = k1 + 1
    return [_errors(site, attitude, np.vstack(st.rows)) for st in states]


def _errors(site: Site, attitude: AttitudeFn, rows: np.ndarray) -> ErrorHistory:
    """Navigation errors from rows ``[t, lat, lon, alt, VN, VE, VD, roll, pitch, heading]``."""
    pyins = require_pyins()
    t = rows[:, 0]
    dr = position_error(site, np.radians(rows[:, 1]), np.radians(rows[:, 2]), rows[:, 3])
    dv = swap_vectors(rows[:, 4:7])
    c_comp = from_pyins_dcm(pyins.transform.mat_from_rph(rows[:, 7:10]))
    c_true = attitude(t)
    phi = log_so3(c_true @ np.swapaxes(c_comp, -1, -2))
    return ErrorHistory(t, phi, dv, dr)


def deterministic_run(
    imu: ImuErrors, init: InitialErrors, record_step: float | None = None
) -> RunSpec:
    """The run with the budget's deterministic errors as given and no noise.

    Parameters
    ----------
    imu : ImuErrors
        Budget (SI, IMU frame s); its noise and bias instability are dropped.
    init : InitialErrors
        Initial errors (rad, m/s, m, ENU), applied as given.
    record_step : float, optional
        Output step, s (default: :func:`simulate`'s).

    Returns
    -------
    RunSpec
    """
    return RunSpec(imu.without_noise(), init, None, noise=False, record_step=record_step)
