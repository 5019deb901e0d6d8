"""Discretization of the error model, cached by what it depends on.

A segment's transition matrix depends only on the model constants, the segment's
angular velocity ``w`` (IMU relative to n, resolved in n) and its duration, so
:class:`Discretizer` caches ``Phi`` and ``Qd`` under the key ``(w, dt)``; a whole
72 h indexing run typically needs three or four distinct discretizations.

* ``Phi`` of whole stops and long turns, and of every segment of a model without
  rotating states, comes from python-control: ``control.sample_system(sys, dt,
  "zoh")`` of the segment's :class:`control.StateSpace` (the augmented model is
  homogeneous, so the ZOH state matrix is exactly ``expm(A dt)``).
* ``Qd`` comes from Van Loan's method (:func:`filterpy.common.van_loan_discretization`),
  because python-control has no process-noise discretization.
* Short sub-steps bypass python-control by design: turning sub-steps and pieces
  of stops shorter than ``MAX_STRUCTURED_STOP`` (a stop cut by output times), as
  long as ``(|w| + lambda_max) dt <= MAX_TURN_PER_STEP`` with ``lambda_max`` the
  fastest rate of the model at rest (Schuler, Earth, or ``1/tau`` of a short
  Gauss-Markov bias). Continuous vehicle motion cut into sub-steps, and stops whose
  ends fall between output times, yield many *distinct* ``(w, dt)`` keys (tens of
  thousands), each a cache miss, and one ``sample_system`` call (a StateSpace build
  plus a full n x n ``expm``) per sub-step would dominate the run. These sub-steps
  are instead discretized together, vectorised, from the block structure of A
  (closed-form rotation of the exo states, cached navigation block, Gauss-Legendre
  quadrature of the one coupling integral), which is exact to roundoff for the
  sub-step sizes allowed and some tens of times faster per sub-step.
  ``tests/test_model.py`` compares this structured path with ``scipy.linalg.expm``
  of the full augmented-state matrix :meth:`~inserr.model.psi_model.ErrorModel.matrix`, not
  with python-control; the python-control path is compared in the same test with
  ``scipy.linalg.expm`` of A bordered by a zero input row and column.
"""

from __future__ import annotations

import threading
from functools import lru_cache

import numpy as np

from inserr.model.psi_model import ErrorModel

#: Quantum of the cache key: angular velocity in rad/s and duration in s. Segments
#: whose w and dt agree to these quanta share a discretization; the quantized values
#: are also the ones used in the computation, so results are deterministic.
OMEGA_QUANTUM = 1e-13
DT_QUANTUM = 1e-9
#: Most transition matrices kept in the cache.
MAX_CACHE = 8192
#: Largest rotation per step (rad) for the structured (quadrature) path.
MAX_TURN_PER_STEP = 0.5
#: Stop pieces shorter than this (s) also take the structured path (if the model's
#: fastest rate allows, see ``Discretizer._use_structured``).
MAX_STRUCTURED_STOP = 60.0


class Discretizer:
    """Cache of ``Phi(w, dt)`` and ``Qd(w, dt)`` for one error model.

    The model is an :class:`~inserr.model.psi_model.ErrorModel`.

    Parameters
    ----------
    model : ErrorModel
        The error model; its constants and layout fix every discretization.
    q : ndarray (12, 12), optional
        Diagonal noise power spectral density (``model.noise_intensity(...)``;
        ``G sqrt(q)`` is taken elementwise, so it must be diagonal); needed only
        for :meth:`noise`.
    """

    def __init__(self, model: ErrorModel, q: np.ndarray | None = None):
        self.model = model
        self.q = q
        self._phi: dict[tuple, np.ndarray] = {}
        self._qd: dict[tuple, np.ndarray] = {}
        self._nav_nodes: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        # Shared across threads (discretizer_for): one lock guards the caches.
        self._lock = threading.RLock()
        # Fastest rate of the model at rest (Schuler, Earth, 1/tau of a Gauss-Markov
        # bias), 1/s: it bounds the quadrature error of the structured path.
        self._fastest = float(np.max(np.abs(np.linalg.eigvals(model.matrix(np.zeros(3))))))

    def key(self, omega_n: np.ndarray, dt: float) -> tuple:
        """Cache key of a segment: quantized ``w`` and ``dt`` as integers.

        Parameters
        ----------
        omega_n : (3,) array, rad/s
            Angular velocity of the IMU frame relative to n, resolved in ENU;
            ignored (key 0) when the model has no rotating states.
        dt : float
            Segment duration, s.

        Returns
        -------
        tuple of int
            ``(w_E, w_N, w_U, dt)`` in units of :data:`OMEGA_QUANTUM` and
            :data:`DT_QUANTUM`.
        """
        k_dt = int(np.round(dt / DT_QUANTUM))
        if not self.model.layout.rotating:
            return (0, 0, 0, k_dt)
        k = np.round(np.asarray(omega_n, dtype=float) / OMEGA_QUANTUM).astype(np.int64)
        return (int(k[0]), int(k[1]), int(k[2]), k_dt)

    @staticmethod
    def _unkey(key: tuple) -> tuple[np.ndarray, float]:
        return np.array(key[:3], dtype=float) * OMEGA_QUANTUM, key[3] * DT_QUANTUM

    def transition(self, omega_n: np.ndarray, dt: float) -> np.ndarray:
        """Transition matrix ``Phi = expm(A(w) dt)`` of one segment, cached.

        Whole stops, long turns and non-rotating models go through python-control
        ``sample_system`` (ZOH); short sub-steps (turning, or a piece of a stop cut
        by an output time) through the structured evaluation (module docstring).

        Parameters
        ----------
        omega_n : (3,) array, rad/s
            Angular velocity of the IMU frame relative to n, resolved in ENU,
            constant over the segment.
        dt : float
            Segment duration, s.

        Returns
        -------
        ndarray, shape (n, n)
            ``Phi`` for the quantized ``(w, dt)``; the cached array itself (do not modify).
        """
        with self._lock:
            return self._transition(omega_n, dt)

    def _transition(self, omega_n: np.ndarray, dt: float) -> np.ndarray:
        key = self.key(omega_n, dt)
        phi = self._phi.get(key)
        if phi is not None:
            self._phi[key] = self._phi.pop(key)  # most recently used last, as in transitions()
        if phi is None and self._use_structured(key):
            w, h = self._unkey(key)
            phi = self._structured(w[None, :], h)[0]
            self._store(key, phi)
        if phi is None:
            import control

            w, h = self._unkey(key)
            if h == 0.0:
                phi = np.eye(self.model.layout.n)
            else:
                phi = np.asarray(control.sample_system(self.model.state_space(w), h, "zoh").A)
            self._store(key, phi)
        return phi

    def noise(self, omega_n: np.ndarray, dt: float) -> np.ndarray:
        """Discrete process-noise covariance ``Qd(w, dt)`` by Van Loan, cached.

        Parameters
        ----------
        omega_n : (3,) array, rad/s
            Angular velocity of the IMU frame relative to n, resolved in ENU.
        dt : float
            Segment duration, s.

        Returns
        -------
        ndarray, shape (n, n)
            ``int_0^dt expm(A s) G Q G^T expm(A s)^T ds``, symmetrised, in the
            state units squared (the cached array itself).

        Raises
        ------
        ValueError
            If the discretizer was built without ``q``.
        """
        with self._lock:
            return self._noise(omega_n, dt)

    def _noise(self, omega_n: np.ndarray, dt: float) -> np.ndarray:
        if self.q is None:
            raise ValueError("Discretizer was built without a noise intensity")
        key = self.key(omega_n, dt)
        qd = self._qd.get(key)
        if qd is None:
            from filterpy.common import van_loan_discretization

            w, h = self._unkey(key)
            if h == 0.0:
                qd = np.zeros((self.model.layout.n,) * 2)
            else:
                g = self.model.noise_input() @ np.sqrt(self.q)
                _, qd = van_loan_discretization(self.model.matrix(w), g, h)
                qd = 0.5 * (qd + qd.T)
            _bounded_put(self._qd, key, qd)
        return qd

    def transitions(self, omegas: np.ndarray, dts: np.ndarray) -> list[np.ndarray]:
        """Transition matrices ``Phi`` of many segments at once.

        Cache hits are served from the cache. Whole stops and long turns (the
        segments of an indexing scheme) go through python-control
        (:meth:`transition`); short sub-steps (continuous motion, pieces of stops cut
        by output times) through :meth:`_structured`, which evaluates the same matrix
        exponential from its block structure, vectorised.

        Parameters
        ----------
        omegas : (K, 3) array, rad/s
            Angular velocities of the IMU frame relative to n, resolved in ENU.
        dts : (K,) array, s
            Segment durations.

        Returns
        -------
        list of ndarray, each (n, n)
            ``Phi`` per segment, in input order (cached arrays; do not modify).
        """
        with self._lock:
            return self._transitions(omegas, dts)

    def _transitions(self, omegas: np.ndarray, dts: np.ndarray) -> list[np.ndarray]:
        omegas = np.asarray(omegas, dtype=float).reshape(-1, 3)
        dts = np.asarray(dts, dtype=float).reshape(-1)
        keys = [self.key(w, h) for w, h in zip(omegas, dts, strict=True)]
        for k in keys:
            # Least-recently-used order: a hit moves to the end, away from eviction.
            if k in self._phi:
                self._phi[k] = self._phi.pop(k)
        missing = sorted({k for k in keys if k not in self._phi})
        # The path is a function of the key alone, never of the batch or of what the
        # cache happens to hold, so every run gives bit-identical numbers.
        by_dt: dict[int, list[tuple]] = {}
        for k in missing:
            if self._use_structured(k):
                by_dt.setdefault(k[3], []).append(k)
            else:
                self._transition(*self._unkey(k))
        for group in by_dt.values():
            h = self._unkey(group[0])[1]
            for i in range(0, len(group), 1024):
                chunk = group[i : i + 1024]
                w = np.array([self._unkey(k)[0] for k in chunk])
                for k, phi in zip(chunk, self._structured(w, h), strict=True):
                    self._store(k, phi)
        return [self._phi[k] if k in self._phi else self._transition(*self._unkey(k)) for k in keys]

    def _use_structured(self, key: tuple) -> bool:
        """Short sub-steps take the structured path; whole stops and long turns python-control.

        Short means ``(|w| + lambda_max) dt <= MAX_TURN_PER_STEP`` (``lambda_max`` the
        fastest rate of the model at rest), and for a stop (``w = 0``) also shorter
        than :data:`MAX_STRUCTURED_STOP` s: where a stop ends between two output times,
        its remainder has a length that differs from cycle to cycle (e.g. the
        Ts + 2/w stops of the modified four-position scheme), and one python-control
        call per remainder used to dominate the run time.
        """
        w, h = self._unkey(key)
        if not self.model.layout.rotating or h <= 0.0:
            return False
        rate = float(np.linalg.norm(w))
        if (rate + self._fastest) * h > MAX_TURN_PER_STEP:
            return False
        return rate > 0.0 or h < MAX_STRUCTURED_STOP

    def _structured(self, omegas: np.ndarray, h: float) -> np.ndarray:
        """``expm(A(w) h)`` for many ``w`` from the block structure of A (vectorised).

        ``A(w) = [[F, B(w)], [0, E(w)]]``: the navigation block F does not depend on
        ``w`` (its exponential is cached per step length) and ``expm(E(w) s)`` is a
        closed-form rotation (:meth:`ErrorModel.exo_transition`). The only integral
        left, ``Gamma = int_0^h expm(F (h - s)) B(w) expm(E(w) s) ds``, has an entire
        integrand whose fastest oscillation is ``2 |w|``; an 8-point Gauss-Legendre
        rule integrates it to roundoff for ``|w| h <= 0.5`` (error ~ (2|w|h)^16 / 16!,
        < 1e-13 relative; ``tests/test_model.py`` checks it against
        ``scipy.linalg.expm(A(w) h)``; python-control is bypassed here by design, see
        the module docstring).
        """
        from scipy.linalg import expm

        nav = 9
        n = self.model.layout.n
        x, wts = np.polynomial.legendre.leggauss(8)
        s = 0.5 * h * (x + 1.0)
        wts = 0.5 * h * wts
        key = round(h / DT_QUANTUM)
        cached = self._nav_nodes.get(key)
        if cached is None:
            f = self.model.nav_matrix
            cached = (expm(f * h), np.array([expm(f * (h - sj)) for sj in s]))
            _bounded_put(self._nav_nodes, key, cached)
        phi_f, phi_nodes = cached
        bx = self.model.coupled_exo(omegas, s)  # (K, J, 9, m): B(w) expm(E(w) s_j)
        # sum_j w_j Phi_F(h - s_j) BX_j as one (9, 9J) @ (9J, m) product per w.
        phicat = np.concatenate(list(wts[:, None, None] * phi_nodes), axis=1)
        gamma = phicat @ bx.reshape(len(omegas), -1, bx.shape[-1])
        out = np.zeros((len(omegas), n, n))
        out[:, :nav, :nav] = phi_f
        out[:, :nav, nav:] = gamma
        out[:, nav:, nav:] = self.model.exo_transition(omegas, np.array([h]))[:, 0]
        return out

    def _store(self, key: tuple, phi: np.ndarray) -> None:
        _bounded_put(self._phi, key, phi)


def _bounded_put(cache: dict, key, value) -> None:
    # Bounded caches: continuous motion can produce tens of thousands of distinct
    # sub-steps; evict the oldest quarter rather than grow without limit.
    if len(cache) >= MAX_CACHE:
        for old in list(cache)[: MAX_CACHE // 4]:
            del cache[old]
    cache[key] = value


@lru_cache(maxsize=16)
def _shared(model: ErrorModel, q_bytes: bytes | None) -> Discretizer:
    q = None if q_bytes is None else np.frombuffer(q_bytes).reshape(12, 12).copy()
    return Discretizer(model, q)


def discretizer_for(model: ErrorModel, q: np.ndarray | None = None) -> Discretizer:
    """A process-wide shared :class:`Discretizer` for ``model`` (and noise intensity ``q``).

    Discretizations depend only on constants, so runs of the same model in one
    process (scheme comparisons, sweeps, repeated analyses) reuse them.

    Parameters
    ----------
    model : ErrorModel
        Hashable (frozen) model; equal models share one discretizer.
    q : (12, 12) array, optional
        Diagonal noise PSD (:meth:`ErrorModel.noise_intensity`); None for
        deterministic runs.

    Returns
    -------
    Discretizer
        Shared (at most 16 kept) and thread-safe.
    """
    return _shared(model, None if q is None else np.ascontiguousarray(q, dtype=float).tobytes())
