"""Modal form of the navigation-error dynamics at a fixed site: ``x = Re(V (c * z))``.

At a fixed site with zero velocity the navigation-error block ``F`` of
:class:`~inserr.model.psi_model.ErrorModel` (psi, dv, dr; Schuler, Earth-rate and
Foucault dynamics) does not depend on the IMU attitude: the vehicle and the
turntable enter only through the *input* (the IMU errors resolved in n). ``F`` has
distinct eigenvalues (clamped vertical channel: ``0``, ``+-i Omega`` of the psi block
and the two Foucault-split Schuler pairs; free vertical channel: also the real pair
``+-sqrt(2 g / R)`` coupled by Coriolis), so ``F = V diag(lambda) V^-1`` and every
mode evolves on its own::

    z_m' = lambda_m z_m + (V^-1 B u)_m,     x = V z.

For a real input the modes of a complex-conjugate pair carry conjugate values, so
only one *representative* of each pair is kept (``Im lambda > 0``) and
``x = Re(V_keep (c * z_keep))`` with ``c = 2`` for a representative and ``c = 1`` for a
real mode. The vertical states of a clamped channel are identically zero and are left
out of the decomposition.

Conditioning. In SI units the eigenvector matrix of ``F`` has a condition number of
about 1e7 (attitude errors of 1e-5 rad sit beside position errors of 1e2 m). The
decomposition is done on the physically scaled state ``D x`` with psi scaled by the
Earth radius and dv by the Schuler period, which brings it to O(10), so the modal
round trip loses no more than a few digits of machine precision
(``tests/test_fast_propagation.py`` checks ``V diag(lambda) V^-1 = F`` and the
transition ``V diag(exp(lambda t)) V^-1`` against ``scipy.linalg.expm``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from inserr.model.psi_model import DV, N_NAV, PSI, ErrorModel


@dataclass(frozen=True)
class NavModes:
    """Eigen-decomposition of the navigation block of an :class:`ErrorModel`.

    Parameters
    ----------
    model : ErrorModel
        Only its site, vertical mode and navigation block are used.

    Attributes
    ----------
    lam : (R,) complex, 1/s
        Kept eigenvalues (real modes and one of each complex pair).
    weight : (R,) float
        ``c``: 2 for a pair representative, 1 for a real mode.
    out : (9, R) complex
        ``V`` restricted to the kept modes, rows = the nine navigation states (zero
        rows for the clamped vertical states): ``x = Re(out @ (weight * z))``.
    inv : (R, 9) complex
        Rows of ``V^-1`` of the kept modes (zero columns for clamped vertical states):
        ``z = inv @ x`` for a real ``x``.
    lam_all, out_all, inv_all : complex arrays (A,), (9, A), (A, 9)
        The same for every mode, conjugates included (used for covariances:
        ``P = out_all @ Pz @ out_all^H`` with ``Pz = inv_all @ P @ inv_all^H``).
    """

    model: ErrorModel
    lam: np.ndarray = field(init=False, repr=False, compare=False)
    weight: np.ndarray = field(init=False, repr=False, compare=False)
    out: np.ndarray = field(init=False, repr=False, compare=False)
    inv: np.ndarray = field(init=False, repr=False, compare=False)
    lam_all: np.ndarray = field(init=False, repr=False, compare=False)
    out_all: np.ndarray = field(init=False, repr=False, compare=False)
    inv_all: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        site = self.model.site
        f = self.model.nav_matrix
        active = [0, 1, 2, 3, 4, 6, 7] if self.model.vertical == "clamped" else list(range(N_NAV))
        fa = f[np.ix_(active, active)]
        # Physical scaling: psi * R and dv / w_s have the unit and size of dr.
        ws = math.sqrt(site.g / site.mean_radius)
        scale_all = np.concatenate([np.full(3, site.mean_radius), np.full(3, 1.0 / ws), np.ones(3)])
        d = scale_all[active]
        fs = (d[:, None] * fa) / d[None, :]
        lam, w = np.linalg.eig(fs)
        w_inv = np.linalg.inv(w)
        # Representatives: real modes and the member with Im > 0 of each complex pair.
        tol = 1e-9 * float(np.max(np.abs(lam)))
        real = np.abs(lam.imag) <= tol
        upper = lam.imag > tol
        if int(np.count_nonzero(lam.imag < -tol)) != int(np.count_nonzero(upper)):
            raise RuntimeError(f"eigenvalues of the navigation block are not in pairs: {lam}")
        keep = real | upper
        lam = np.where(real, lam.real + 0j, lam)
        out = np.zeros((N_NAV, len(lam)), dtype=complex)
        out[active, :] = w / d[:, None]
        inv = np.zeros((len(lam), N_NAV), dtype=complex)
        inv[:, active] = w_inv * d[None, :]
        object.__setattr__(self, "lam", lam[keep])
        object.__setattr__(self, "weight", np.where(real[keep], 1.0, 2.0))
        object.__setattr__(self, "out", out[:, keep])
        object.__setattr__(self, "inv", inv[keep, :])
        object.__setattr__(self, "lam_all", lam)
        object.__setattr__(self, "out_all", out)
        object.__setattr__(self, "inv_all", inv)

    @property
    def n_modes(self) -> int:
        """Number of kept (representative) modes R."""
        return len(self.lam)

    @property
    def gyro_input(self) -> np.ndarray:
        """(R, 3) complex: modal input of a gyro error vector resolved in n (``psi' = -eps``)."""
        return -self.inv[:, PSI]

    @property
    def accel_input(self) -> np.ndarray:
        """(R, 3) complex: modal input of an accelerometer error resolved in n (``dv' = nabla``).

        The vertical column is zero when the vertical channel is clamped (the model drops
        vertical accelerometer errors with the vertical channel).
        """
        return self.inv[:, DV]

    def to_nav(self, z: np.ndarray, axis: int = -1) -> np.ndarray:
        """Navigation states from modal values (``Re(V (c z))``) along ``axis`` of ``z``.

        Parameters
        ----------
        z : complex array with R entries along ``axis``
            Modal values.
        axis : int
            The modal axis; it is replaced by the nine navigation states.

        Returns
        -------
        ndarray (real)
            psi (rad), dv (m/s), dr (m), ENU, along ``axis``.
        """
        zz = np.ascontiguousarray(np.moveaxis(np.asarray(z, dtype=complex), axis, -1))
        vw = self.out * self.weight[None, :]  # (9, R)
        # Re(z w V^T) as one real product: the complex values seen as interleaved
        # (re, im) pairs times the matching rows (Re V, -Im V); no copies of z.
        rows = np.empty((2 * vw.shape[1], vw.shape[0]))
        rows[0::2], rows[1::2] = vw.real.T, -vw.imag.T
        x = zz.view(float) @ rows
        return np.moveaxis(x, -1, axis)

    def to_modes(self, x: np.ndarray, axis: int = -1) -> np.ndarray:
        """Modal values ``V^-1 x`` (kept modes) of real navigation states along ``axis``."""
        xx = np.moveaxis(np.asarray(x, dtype=float), axis, -1)
        z = xx @ self.inv.T
        return np.moveaxis(z, -1, axis)
