"""Discretization of the error model, cached by what it depends on.

A segment's transition matrix depends only on the model constants, the segment's
angular velocity ``w`` (IMU relative to n, resolved in n) and its duration, so
:class:`Discretizer` caches ``Phi`` and ``Qd`` under the key ``(w, dt)``; a whole
72 h indexing run typically needs three or four distinct discretizations.

* ``Phi`` comes from python-control: ``control.sample_system(sys, dt, "zoh")`` of the
  segment's :class:`control.StateSpace` (the augmented model is homogeneous, so the
  ZOH state matrix is exactly ``expm(A dt)``).
* ``Qd`` comes from Van Loan's method (:func:`filterpy.common.van_loan_discretization`),
  because python-control has no process-noise discretization.
* Many *distinct* short segments (continuous vehicle motion cut into sub-steps)
  are discretized in one batched ``scipy.linalg.expm`` call — the same computation
  python-control performs, vectorised; ``tests/test_discretize.py`` checks that the
  two agree.
"""

from __future__ import annotations

import numpy as np

from inserr.model import ErrorModel

#: Quantum of the cache key: angular velocity in rad/s and duration in s. Segments
#: whose w and dt agree to these quanta share a discretization; the quantized values
#: are also the ones used in the computation, so results are deterministic.
OMEGA_QUANTUM = 1e-13
DT_QUANTUM = 1e-9
#: Most transition matrices kept in the cache.
MAX_CACHE = 8192


def quantize_omega(omega_n: np.ndarray) -> np.ndarray:
    """Angular velocities rounded to :data:`OMEGA_QUANTUM` (rad/s), any shape (..., 3)."""
    return np.round(np.asarray(omega_n, dtype=float) / OMEGA_QUANTUM) * OMEGA_QUANTUM


def quantize_dt(dt) -> np.ndarray:
    """Durations rounded to :data:`DT_QUANTUM` (s)."""
    return np.round(np.asarray(dt, dtype=float) / DT_QUANTUM) * DT_QUANTUM


class Discretizer:
    """Cache of ``Phi(w, dt)`` and ``Qd(w, dt)`` for one :class:`~inserr.model.ErrorModel`.

    Parameters
    ----------
    model : ErrorModel
    q : ndarray (12, 12), optional
        Noise power spectral density (``model.noise_intensity(...)``); needed only
        for :meth:`noise`.
    """

    def __init__(self, model: ErrorModel, q: np.ndarray | None = None):
        self.model = model
        self.q = q
        self._phi: dict[tuple, np.ndarray] = {}
        self._qd: dict[tuple, np.ndarray] = {}
        self.n_control_calls = 0

    def key(self, omega_n: np.ndarray, dt: float) -> tuple:
        """Cache key; ``w`` is ignored when the model has no rotating states."""
        k_dt = int(np.round(dt / DT_QUANTUM))
        if not self.model.layout.rotating:
            return (0, 0, 0, k_dt)
        k = np.round(np.asarray(omega_n, dtype=float) / OMEGA_QUANTUM).astype(np.int64)
        return (int(k[0]), int(k[1]), int(k[2]), k_dt)

    @staticmethod
    def _unkey(key: tuple) -> tuple[np.ndarray, float]:
        return np.array(key[:3], dtype=float) * OMEGA_QUANTUM, key[3] * DT_QUANTUM

    def transition(self, omega_n: np.ndarray, dt: float) -> np.ndarray:
        """``Phi = expm(A(w) dt)`` via ``control.sample_system`` (ZOH), cached."""
        key = self.key(omega_n, dt)
        phi = self._phi.get(key)
        if phi is None:
            import control

            w, h = self._unkey(key)
            if h == 0.0:
                phi = np.eye(self.model.layout.n)
            else:
                phi = np.asarray(control.sample_system(self.model.state_space(w), h, "zoh").A)
                self.n_control_calls += 1
            self._store(key, phi)
        return phi

    def noise(self, omega_n: np.ndarray, dt: float) -> np.ndarray:
        """Discrete process-noise covariance ``Qd(w, dt)`` by Van Loan, cached."""
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
            self._qd[key] = qd
        return qd

    def transitions(self, omegas: np.ndarray, dts: np.ndarray) -> list[np.ndarray]:
        """``Phi`` for many segments at once, as a list of (n, n) arrays.

        Cache hits are served from the cache; the misses are computed in one batched
        ``scipy.linalg.expm`` (equal to what :meth:`transition` gets from
        python-control) and then cached.
        """
        from scipy.linalg import expm

        omegas = np.asarray(omegas, dtype=float).reshape(-1, 3)
        dts = np.asarray(dts, dtype=float).reshape(-1)
        keys = [self.key(w, h) for w, h in zip(omegas, dts, strict=True)]
        missing = sorted({k for k in keys if k not in self._phi})
        for i in range(0, len(missing), 2048):
            chunk = missing[i : i + 2048]
            mats = np.array([self.model.matrix(self._unkey(k)[0]) * self._unkey(k)[1] for k in chunk])
            for k, phi in zip(chunk, expm(mats), strict=True):
                self._store(k, phi)
        return [self._phi[k] if k in self._phi else self.transition(*self._unkey(k)) for k in keys]

    def _store(self, key: tuple, phi: np.ndarray) -> None:
        # Bounded cache: continuous motion can produce tens of thousands of distinct
        # sub-steps; evict the oldest entries rather than grow without limit.
        if len(self._phi) >= MAX_CACHE:
            for old in list(self._phi)[: MAX_CACHE // 4]:
                del self._phi[old]
        self._phi[key] = phi

    def cache_size(self) -> int:
        """Number of distinct transition matrices computed so far."""
        return len(self._phi)
