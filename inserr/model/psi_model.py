"""The psi-angle error model of a strapdown INS at a fixed site, as a state-space model.

Frames and conventions (full statement with equations in ``docs/theory.md``):

* n = ENU navigation frame at the site, s = IMU frame, b = body (right-front-up).
* ``psi`` is the psi-angle: the small rotation from the computed frame c (the
  local-level frame at the *computed* position) to the platform frame p (the
  frame the INS believes is level and north-pointing): ``C_c^p = I - [psi x]``.
  The true attitude error is ``phi = psi + dtheta`` with the position-error angle
  ``dtheta = [-dr_N / R_M, dr_E / R_N, dr_E tan(L) / R_N]``. ``phi_U`` is the
  heading error: positive = indicated heading too large (clockwise).
* Velocity and position errors are computed minus true, in metres (per second),
  resolved in ENU.
* Sensor errors are computed minus true: ``gyro error = C_s^n [b_g + K_g w_is^s]``.

Static-site psi-angle equations (Benson 1975), ``Omega`` the Earth rate, ``f`` the
specific force ``[0, 0, g]``::

    psi'  = -Omega x psi - eps^n
    dv'   =  f x psi + nabla^n - 2 Omega x dv + dg,  dg = [-g/R_N dr_E, -g/R_M dr_N, +2g/R dr_U]
    dr'   =  dv

How the error sources enter. The IMU frame turns (indexing, vehicle motion), so
``C_s^n(t)`` varies. Instead of carrying IMU-frame biases with a time-varying input
matrix, the engine carries every constant IMU error *resolved in n*:
``eps^n = C_s^n b_g``, ``nabla^n = C_s^n b_a``, ``K_g^n = C_s^n K_g C_n^s``,
``K_a^n = C_s^n K_a C_n^s``. When the IMU turns at a constant angular velocity
``w`` (of s relative to n, resolved in n) these obey linear constant-coefficient
equations, ``eps^n' = w x eps^n`` and ``K^n' = [w x] K^n - K^n [w x]``, and the
scale-factor/misalignment terms become ``K_g^n (Omega + w)`` and ``K_a^n f``. So every
constant-rate segment (stop, table rotation, steady turn) is an exactly solvable
LTI system whose matrix depends only on ``w``: all stops share one discretization,
all +6 deg/s table turns another. The IMU-frame 15-state model of the textbooks is
the same model seen through ``T = blockdiag(I, C_n^s, C_n^s)``
(:meth:`ErrorModel.state_space_imu`).

Optional first-order Gauss-Markov bias instability adds ``bg^n, ba^n`` (resolved in
n, same rotation law, plus ``-b/tau`` and white driving noise).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.core.rotations import skew

#: Navigation-error state names (always the first nine states).
NAV_STATES = ("psi_e", "psi_n", "psi_u", "dv_e", "dv_n", "dv_u", "dr_e", "dr_n", "dr_u")
PSI = slice(0, 3)
DV = slice(3, 6)
DR = slice(6, 9)
N_NAV = 9
#: Index of each navigation state.
IDX = {name: i for i, name in enumerate(NAV_STATES)}

_ENU = ("e", "n", "u")
_PAIRS = tuple(a + b for a in _ENU for b in _ENU)

VERTICAL_MODES = ("clamped", "free")


@dataclass(frozen=True)
class Layout:
    """Which augmented (exo) states a model carries, and where.

    Parameters
    ----------
    bias : bool
        Constant gyro and accelerometer biases, resolved in n (6 states).
    scale_misalignment : bool
        Gyro and accelerometer ``K = S + M`` matrices resolved in n (18 states).
    bias_instability : bool
        Gauss-Markov gyro and accelerometer biases resolved in n (6 states).

    Attributes
    ----------
    names : tuple of str
        State names in order: the nine :data:`NAV_STATES` (psi rad, dv m/s, dr m,
        ENU), then ``eps_*`` (rad/s) and ``nabla_*`` (m/s^2), ``kg_**`` and ``ka_**``
        (dimensionless, row-major ``vec(K^n)``, ENU row then ENU column), ``bg_*``
        (rad/s) and ``ba_*`` (m/s^2), as carried.
    slices : dict of str to slice
        Where each block lives: ``psi``, ``dv``, ``dr``, ``nav`` and the carried
        ones of ``eps``, ``nabla``, ``kg``, ``ka``, ``bg``, ``ba``; also ``layout[key]``.
    """

    bias: bool = True
    scale_misalignment: bool = False
    bias_instability: bool = False
    names: tuple[str, ...] = field(init=False, repr=False)
    slices: dict[str, slice] = field(init=False, repr=False, compare=False, hash=False)

    def __post_init__(self) -> None:
        names = list(NAV_STATES)
        slices = {"psi": PSI, "dv": DV, "dr": DR, "nav": slice(0, N_NAV)}

        def add(key: str, labels: list[str]) -> None:
            slices[key] = slice(len(names), len(names) + len(labels))
            names.extend(labels)

        if self.bias:
            add("eps", [f"eps_{a}" for a in _ENU])
            add("nabla", [f"nabla_{a}" for a in _ENU])
        if self.scale_misalignment:
            add("kg", [f"kg_{p}" for p in _PAIRS])
            add("ka", [f"ka_{p}" for p in _PAIRS])
        if self.bias_instability:
            add("bg", [f"bg_{a}" for a in _ENU])
            add("ba", [f"ba_{a}" for a in _ENU])
        object.__setattr__(self, "names", tuple(names))
        object.__setattr__(self, "slices", slices)

    @property
    def n(self) -> int:
        """Number of states."""
        return len(self.names)

    @property
    def rotating(self) -> bool:
        """True if some state is resolved in n and so depends on the IMU rotation."""
        return self.n > N_NAV

    def __getitem__(self, key: str) -> slice:
        return self.slices[key]


def _commutator_matrix(w: np.ndarray) -> np.ndarray:
    """Matrix of ``X -> [w x] X - X [w x]`` acting on row-major ``vec(X)`` (9x9)."""
    k = skew(w)
    eye = np.eye(3)
    # vec_r(A X B) = (A kron B^T) vec_r(X); [w x]^T = -[w x].
    return np.kron(k, eye) + np.kron(eye, k)


@dataclass(frozen=True)
class ErrorModel:
    """Psi-angle error model of a strapdown INS resting (or turning in place) at a site.

    Parameters
    ----------
    site : Site
        Latitude, height and Earth-shape option.
    layout : Layout
        Which error-source states are carried.
    vertical : {"clamped", "free"}
        ``"clamped"`` (default): the vertical channel is externally aided (baro or
        known height), vertical velocity and position errors are held at zero, and
        the horizontal channels are unaffected by it. ``"free"``: pure inertial
        vertical channel, unstable with time constant ``1/sqrt(2 g / R)``.
    gyro_correlation_time, accel_correlation_time : float
        Gauss-Markov correlation times, s (used when ``layout.bias_instability``).
    """

    site: Site
    layout: Layout = field(default_factory=Layout)
    vertical: str = "clamped"
    gyro_correlation_time: float = 3600.0
    accel_correlation_time: float = 3600.0

    def __post_init__(self) -> None:
        if self.vertical not in VERTICAL_MODES:
            raise InputError(
                "vertical",
                f"unknown vertical-channel mode {self.vertical!r}",
                "use clamped or free",
            )

    # --- continuous-time matrices ---------------------------------------------
    @cached_property
    def nav_matrix(self) -> np.ndarray:
        """The 9x9 navigation-error block F of ``x' = F x`` (psi, dv, dr; ENU, SI).

        Independent of the IMU attitude; with ``vertical="clamped"`` the dv_U and dr_U
        rows and columns are zero.
        """
        s = self.site
        om = s.earth_rate_n
        g = s.g
        f = np.zeros((N_NAV, N_NAV))
        f[PSI, PSI] = -skew(om)
        f[DV, PSI] = skew(s.specific_force_n)
        f[DV, DV] = -2.0 * skew(om)
        f[DV, DR] = np.diag([-g / s.r_n, -g / s.r_m, 2.0 * g / s.mean_radius])
        f[DR, DV] = np.eye(3)
        if self.vertical == "clamped":
            # Aided vertical channel: dv_u and dr_u stay zero and feed nothing.
            f[[5, 8], :] = 0.0
            f[:, [5, 8]] = 0.0
        return f

    def matrix(self, omega_n: np.ndarray | None = None) -> np.ndarray:
        """Continuous-time system matrix A(w) of the augmented model.

        Parameters
        ----------
        omega_n : (3,) array, rad/s
            Angular velocity of the IMU frame relative to the navigation frame,
            resolved in ENU, constant over the segment (zero for a stop).

        Returns
        -------
        ndarray, shape (n, n)
            ``A(w)`` of ``x' = A(w) x`` for the state order of :attr:`Layout.names`.
        """
        lay = self.layout
        w = np.zeros(3) if omega_n is None else np.asarray(omega_n, dtype=float)
        a = np.zeros((lay.n, lay.n))
        a[:N_NAV, :N_NAV] = self.nav_matrix
        rot = skew(w)
        if lay.bias:
            a[PSI, lay["eps"]] = -np.eye(3)
            a[DV, lay["nabla"]] = np.eye(3)
            a[lay["eps"], lay["eps"]] = rot
            a[lay["nabla"], lay["nabla"]] = rot
        if lay.scale_misalignment:
            # Gyro: K_g^n applied to the true IMU rate w_is^n = Omega + w.
            w_is = self.site.earth_rate_n + w
            a[PSI, lay["kg"]] = -np.kron(np.eye(3), w_is)
            # Accelerometer: K_a^n applied to the specific force f^n.
            a[DV, lay["ka"]] = np.kron(np.eye(3), self.site.specific_force_n)
            comm = _commutator_matrix(w)
            a[lay["kg"], lay["kg"]] = comm
            a[lay["ka"], lay["ka"]] = comm
        if lay.bias_instability:
            a[PSI, lay["bg"]] = -np.eye(3)
            a[DV, lay["ba"]] = np.eye(3)
            a[lay["bg"], lay["bg"]] = rot - np.eye(3) / self.gyro_correlation_time
            a[lay["ba"], lay["ba"]] = rot - np.eye(3) / self.accel_correlation_time
        if self.vertical == "clamped":
            a[[5, 8], :] = 0.0
        return a

    def exo_transition(self, omega_n: np.ndarray, s: np.ndarray) -> np.ndarray:
        """Closed-form ``expm(E(w) s)`` of the exo block (states after the nine nav states).

        Every exo block is a rotation of n-resolved quantities: vectors turn with
        ``R = expm(s [w x])`` (Rodrigues), matrices ``K^n`` with ``R K R^T`` (``R kron R``
        on the row-major vector), Gauss-Markov states also decay by ``exp(-s / tau)``.

        Parameters
        ----------
        omega_n : (K, 3) or (3,) rad/s
            Angular velocities of the IMU frame relative to n, resolved in ENU.
        s : (J,) or float, s
            Elapsed times.

        Returns
        -------
        ndarray, shape (K, J, m, m) with m = n - 9
            Transition of the exo states over each ``s`` for each ``w``.
        """
        lay = self.layout
        w = np.asarray(omega_n, dtype=float).reshape(-1, 3)
        s = np.asarray(s, dtype=float).reshape(-1)
        r = self._rodrigues(w, s)  # (K, J, 3, 3)
        m = lay.n - N_NAV
        out = np.zeros((len(w), len(s), m, m))
        rr = None
        for key in ("eps", "nabla", "kg", "ka", "bg", "ba"):
            if key not in lay.slices:
                continue
            sl = slice(lay[key].start - N_NAV, lay[key].stop - N_NAV)
            if key in ("kg", "ka"):
                if rr is None:
                    rr = np.einsum("...ij,...kl->...ikjl", r, r).reshape(len(w), len(s), 9, 9)
                out[..., sl, sl] = rr
            elif key == "bg":
                out[..., sl, sl] = r * np.exp(-s / self.gyro_correlation_time)[None, :, None, None]
            elif key == "ba":
                out[..., sl, sl] = r * np.exp(-s / self.accel_correlation_time)[None, :, None, None]
            else:
                out[..., sl, sl] = r
        return out

    def coupled_exo(self, omega_n: np.ndarray, s: np.ndarray) -> np.ndarray:
        """Closed-form ``B(w) expm(E(w) s)``: how exo states at time 0 drive psi and dv at time s.

        ``B(w)`` is the nav-by-exo block of :meth:`matrix`. With ``R = expm(s [w x])``
        the bias columns are ``-R`` (psi) and ``R`` (dv); a matrix state ``K^n`` acts
        through ``R K R^T v`` (v = ``Omega + w`` for the gyros, f for the accelerometers),
        i.e. the 3x9 block ``R kron (R^T v)^T``.

        Parameters
        ----------
        omega_n : (K, 3) or (3,) rad/s
            Angular velocities of the IMU frame relative to n, resolved in ENU.
        s : (J,) or float, s
            Elapsed times.

        Returns
        -------
        ndarray, shape (K, J, 9, m) with m = n - 9
            Rows psi, dv, dr (dr rows zero; dv_U rows zero when clamped); columns
            the exo states.
        """
        lay = self.layout
        w = np.asarray(omega_n, dtype=float).reshape(-1, 3)
        s = np.asarray(s, dtype=float).reshape(-1)
        r = self._rodrigues(w, s)  # (K, J, 3, 3)
        out = np.zeros((len(w), len(s), N_NAV, lay.n - N_NAV))
        dv_mask = np.array([1.0, 1.0, 0.0 if self.vertical == "clamped" else 1.0])[:, None]

        def cols(key: str) -> slice:
            return slice(lay[key].start - N_NAV, lay[key].stop - N_NAV)

        def kron_rows(v: np.ndarray) -> np.ndarray:
            rtv = np.einsum("kjab,ka->kjb", r, v)  # R^T v, (K, J, 3)
            return np.einsum("kjab,kjc->kjabc", r, rtv).reshape(len(w), len(s), 3, 9)

        if lay.bias:
            out[:, :, PSI, cols("eps")] = -r
            out[:, :, DV, cols("nabla")] = dv_mask * r
        if lay.scale_misalignment:
            out[:, :, PSI, cols("kg")] = -kron_rows(self.site.earth_rate_n + w)
            f = np.broadcast_to(self.site.specific_force_n, w.shape)
            out[:, :, DV, cols("ka")] = dv_mask * kron_rows(f)
        if lay.bias_instability:
            out[:, :, PSI, cols("bg")] = (
                -r * np.exp(-s / self.gyro_correlation_time)[None, :, None, None]
            )
            out[:, :, DV, cols("ba")] = (
                dv_mask * r * np.exp(-s / self.accel_correlation_time)[None, :, None, None]
            )
        return out

    @staticmethod
    def _rodrigues(w: np.ndarray, s: np.ndarray) -> np.ndarray:
        """``expm(s [w x])`` for every w (K, 3) and s (J,): (K, J, 3, 3)."""
        rate = np.linalg.norm(w, axis=1)
        axis = w / np.where(rate > 0, rate, 1.0)[:, None]
        kx = skew(axis)[:, None]
        ang = (rate[:, None] * s[None, :])[..., None, None]
        return np.eye(3) + np.sin(ang) * kx + (1.0 - np.cos(ang)) * (kx @ kx)

    def noise_input(self) -> np.ndarray:
        """Unit-intensity white-noise input matrix G of ``x' = A x + G w``.

        Columns: gyro white rate noise (3), accelerometer white noise (3),
        Gauss-Markov gyro driving noise (3), Gauss-Markov accel driving noise (3),
        all resolved in n (they are isotropic, so the IMU attitude does not matter).

        Returns
        -------
        ndarray, shape (n, 12)
            ``-I`` from gyro noise to psi, ``+I`` from accelerometer noise to dv, ``I``
            into the Gauss-Markov states if carried; dv_U and dr_U rows zero when clamped.
        """
        lay = self.layout
        g = np.zeros((lay.n, 12))
        g[PSI, 0:3] = -np.eye(3)
        g[DV, 3:6] = np.eye(3)
        if lay.bias_instability:
            g[lay["bg"], 6:9] = np.eye(3)
            g[lay["ba"], 9:12] = np.eye(3)
        if self.vertical == "clamped":
            g[[5, 8], :] = 0.0
        return g

    def noise_intensity(
        self, arw: float, vrw: float, gyro_bi: float = 0.0, accel_bi: float = 0.0
    ) -> np.ndarray:
        """Diagonal power spectral density matrix (12 x 12) of the noise inputs.

        Parameters
        ----------
        arw : float, rad/sqrt(s)
            Gyro angle random walk; PSD ``arw^2``.
        vrw : float, m/s/sqrt(s)
            Accelerometer velocity random walk; PSD ``vrw^2``.
        gyro_bi, accel_bi : float
            Steady-state 1 sigma of the Gauss-Markov biases (rad/s, m/s^2); their
            driving PSD is ``2 sigma^2 / tau``.

        Returns
        -------
        ndarray, shape (12, 12)
            ``Q = diag(arw^2 (x3), vrw^2 (x3), 2 gyro_bi^2 / tau_g (x3),
            2 accel_bi^2 / tau_a (x3))``: rad^2/s, m^2/s^3, rad^2/s^3, m^2/s^5.
        """
        q = np.zeros(12)
        q[0:3] = arw**2
        q[3:6] = vrw**2
        q[6:9] = 2.0 * gyro_bi**2 / self.gyro_correlation_time
        q[9:12] = 2.0 * accel_bi**2 / self.accel_correlation_time
        return np.diag(q)

    # --- python-control views -------------------------------------------------
    def state_space(self, omega_n: np.ndarray | None = None):
        """The segment model as a ``control.StateSpace`` (inputs: the 12 noise channels).

        Outputs are all states. State names follow :attr:`Layout.names`.

        Parameters
        ----------
        omega_n : (3,) array, rad/s, optional
            Angular velocity of the IMU frame relative to n, resolved in ENU (None = 0).

        Returns
        -------
        control.StateSpace
            ``(A(w), G, I, 0)`` with :meth:`matrix` and :meth:`noise_input`.
        """
        import control

        lay = self.layout
        return control.ss(
            self.matrix(omega_n),
            self.noise_input(),
            np.eye(lay.n),
            np.zeros((lay.n, 12)),
            states=list(lay.names),
            outputs=list(lay.names),
            inputs=[f"w_{k}{a}" for k in ("g", "a", "bg", "ba") for a in "xyz"],
        )

    def imu_transform(self, c_sn: np.ndarray) -> np.ndarray:
        """Similarity transform T with ``x_imu = T x`` (IMU-frame bias states).

        Bias-type states resolved in n are mapped to the IMU frame with ``C_n^s``;
        ``K^n`` blocks with ``C_n^s K^n C_s^n``. Navigation states are unchanged.

        Parameters
        ----------
        c_sn : (3, 3) array
            IMU-to-ENU DCM ``C_s^n``.

        Returns
        -------
        ndarray, shape (n, n)
        """
        lay = self.layout
        t = np.eye(lay.n)
        c_ns = np.asarray(c_sn).T
        for key in ("eps", "nabla", "bg", "ba"):
            if key in lay.slices:
                t[lay[key], lay[key]] = c_ns
        for key in ("kg", "ka"):
            if key in lay.slices:
                t[lay[key], lay[key]] = np.kron(c_ns, c_ns)
        return t

    def state_space_imu(self, c_sn: np.ndarray):
        """Textbook model for a stop with fixed ``C_s^n``: bias states in the IMU frame.

        With ``w = 0`` the n-resolved bias states are constant, and the transform
        :meth:`imu_transform` gives the familiar input matrix ``-C_s^n`` from the
        gyro bias to psi and ``+C_s^n`` from the accelerometer bias to dv.

        Parameters
        ----------
        c_sn : (3, 3) array
            IMU-to-ENU DCM ``C_s^n`` of the stop.

        Returns
        -------
        control.StateSpace
            The stop model (``w = 0``) in the coordinates ``T x`` of :meth:`imu_transform`.
        """
        import control

        t = self.imu_transform(c_sn)
        ti = np.linalg.inv(t)
        sys = self.state_space(None)
        return control.ss(t @ sys.A @ ti, t @ sys.B, sys.C @ ti, sys.D, states=sys.state_labels)


def position_angle(site: Site, dr: np.ndarray) -> np.ndarray:
    """Position-error angle ``dtheta = [-dr_N / R_M, dr_E / R_N, dr_E tan(L) / R_N]``.

    Parameters
    ----------
    site : Site
        Supplies latitude L and the radii ``R_M``, ``R_N`` (m).
    dr : (..., 3) array, m
        Position errors (E, N, U), computed minus true.

    Returns
    -------
    ndarray, shape (..., 3)
        ``dtheta``, rad, ENU.
    """
    dr = np.asarray(dr, dtype=float)
    out = np.empty(dr.shape[:-1] + (3,))
    out[..., 0] = -dr[..., 1] / site.r_m
    out[..., 1] = dr[..., 0] / site.r_n
    out[..., 2] = dr[..., 0] * math.tan(site.lat) / site.r_n
    return out


def attitude_error(site: Site, nav: np.ndarray) -> np.ndarray:
    """True attitude error ``phi = psi + dtheta`` from navigation states.

    Parameters
    ----------
    site : Site
    nav : (..., 9) array
        Navigation states (psi rad, dv m/s, dr m; ENU), or any array whose last
        axis starts with them.

    Returns
    -------
    ndarray, shape (..., 3)
        ``phi``, rad, ENU: E and N tilts, U heading error (positive = indicated
        heading too large).
    """
    nav = np.asarray(nav, dtype=float)
    # phi = psi + dtheta(dr), dtheta linear in dr: one product with the (9, 3) map
    # (a quarter of a million outputs per run: one pass instead of a dozen strided ones).
    a = np.zeros((9, 3))
    a[PSI] = np.eye(3)
    a[DR] = position_angle(site, np.eye(3))  # row k: dtheta of a unit dr_k
    return nav[..., :9] @ a


@dataclass(frozen=True)
class Modes:
    """Characteristic periods read off the eigenvalues of the navigation-error model.

    Attributes
    ----------
    schuler_period_s : float
        2 pi / (geometric mean of the two Schuler-band eigen-frequencies). For a
        spherical Earth the pair is ``sqrt(ws^2 + ou^2) +- ou`` (``ou = Omega sin L``),
        whose product is exactly ``ws^2 = g / R``.
    foucault_period_s : float
        2 pi / (half their difference, exactly ``ou`` on a spherical Earth); inf if
        they coincide.
    earth_period_s : float
        2 pi / (the Earth-band eigen-frequency of the psi block).
    eigenvalues : ndarray
        All eigenvalues of the 9x9 navigation block, 1/s.
    vertical_time_constant_s : float or None
        1 / (the positive real eigenvalue) with a free vertical channel.
    """

    schuler_period_s: float
    foucault_period_s: float
    earth_period_s: float
    eigenvalues: np.ndarray
    vertical_time_constant_s: float | None = None


def modes(model: ErrorModel) -> Modes:
    """Eigen-analysis of the navigation-error block: Schuler, Foucault and Earth periods.

    The Schuler-band eigenvalues are the two pairs with ``|Im| > 1e-4 rad/s``
    (the Schuler rate is 1.24e-3 rad/s, the Earth rate 7.3e-5 rad/s); the Earth band
    is the pair with ``1e-6 < |Im| <= 1e-4``.

    Parameters
    ----------
    model : ErrorModel
        Only :attr:`ErrorModel.nav_matrix` is used (site and vertical mode).

    Returns
    -------
    Modes
        Periods in s.

    Raises
    ------
    RuntimeError
        If the eigenvalues do not show the expected Schuler and Earth bands.
    """
    ev = np.linalg.eigvals(model.nav_matrix)
    freqs = np.sort(np.unique(np.round(np.abs(ev.imag[ev.imag > 0]), 15)))
    schuler = freqs[freqs > 1e-4]
    earth = freqs[(freqs > 1e-6) & (freqs <= 1e-4)]
    if len(schuler) == 1:
        schuler = np.array([schuler[0], schuler[0]])
    if len(schuler) != 2 or len(earth) != 1:
        raise RuntimeError(f"unexpected eigenvalue structure: {ev}")
    w_hi, w_lo = schuler[1], schuler[0]
    split = 0.5 * (w_hi - w_lo)
    vert = ev.real[ev.real > 1e-8]
    return Modes(
        schuler_period_s=2.0 * math.pi / math.sqrt(w_hi * w_lo),
        foucault_period_s=2.0 * math.pi / split if split > 0 else math.inf,
        earth_period_s=2.0 * math.pi / earth[0],
        eigenvalues=ev,
        vertical_time_constant_s=float(1.0 / vert.max()) if len(vert) else None,
    )
