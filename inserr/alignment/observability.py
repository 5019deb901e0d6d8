"""Observability of piecewise-constant systems: stacked matrix, scaling, SVD, rank, words.

An indexing scheme (or a list of headings) cuts an alignment into segments in which
the error model is linear time-invariant: ``x' = A_j x``, ``z = C_j x`` for a duration
``T_j``, possibly with a jump ``x -> J_j x`` at the start of a segment. Goshen-Meskin
& Bar-Itzhack (IEEE Trans. AES 28(4), 1992) show that such a piecewise-constant system
(PWCS) is observable over the whole run iff its *total observability matrix*

    Q = [ O_1 Psi_1 ; O_2 Psi_2 ; ... ],   O_j = [C_j; C_j A_j; ...; C_j A_j^(n-1)],
    Psi_j = J_j exp(A_(j-1) T_(j-1)) J_(j-1) ... J_1

has full column rank; the null space of Q is the set of initial states that no
measurement of the run can see. Their *stripped* matrix (SOM, the O_j stacked without
the transitions) has the same rank when ``null(O_j)`` lies in ``null(A_j)`` for every
segment, which holds for stops; :func:`analyze` computes the TOM and reports whether
the SOM shortcut would have been valid.

Numerics (``control.gram`` is not used: it needs the GPL slycot library and rejects
marginally stable systems; the per-segment matrix is a row-scaled python-control
``obsv``, built directly so that its powers stay bounded):

* **State scaling.** Every state is divided by a typical magnitude
  (:data:`TYPICAL`): tilt 1 arcsec, heading 1 arcmin, velocity 1 mm/s, position 1 m,
  gyro bias 0.01 deg/h, accelerometer bias 5 micro-g (about g x 1 arcsec, so the classic
  balance ``nabla = g phi`` has a coefficient near 1 in scaled units, and
  0.01 deg/h / (Omega cos L) is a few arcmin of heading). Outputs are divided by 1 mm/s
  (velocity) and 1 m (position). Scaling changes no rank; it makes the singular
  values comparable and the rank decision meaningful.
* **Time scaling.** The k-th block row of ``O_j`` is multiplied by ``T_j^k / k!`` (it
  becomes the k-th Taylor coefficient of the output over the segment), and a segment
  with ``||A~ T||`` above :data:`MAX_SEGMENT_NORM` is cut into equal pieces (the same
  system), so the Krylov powers stay bounded from 1 s dwells to 72 h stops.
* **Rank tolerance.** A singular value counts when it exceeds :data:`RANK_RTOL`
  = 1e-9 times the largest. Exactly unobservable directions come out at the
  round-off level of the scaled matrix (below 1e-13 of the largest, from 1 s to 72 h
  segments), while the weakest genuinely observable direction of the alignment
  cases (heading through Earth rate) is above 1e-7 of the largest for dwells of
  10 s or more (5e-9 for a single 1 s dwell: so short a look barely sees heading).
  1e-9 sits in that gap; :class:`ObservabilityResult` reports the gap
  ``sigma_r / sigma_(r+1)`` so that a borderline decision is visible.

The null space is then written *in words*: it is expressed as "dependent states =
coefficients x free states", with the free states picked in a physical order
(attitude first) and the coefficients recognised as named constants (``g``,
``Omega cos L``, ...) or named matrices (``Omega x``), e.g. ``"∇E = g·φN"``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.core.rotations import body_to_nav, skew
from inserr.core.units import ARCMIN, ARCSEC, DEG_PER_HOUR, MICRO_G
from inserr.model.psi_model import IDX, ErrorModel, Layout

#: Typical magnitude (SI) per kind of state, used to scale the observability matrix.
TYPICAL = {
    "tilt": ARCSEC,
    "heading": ARCMIN,
    "velocity": 1e-3,
    "position": 1.0,
    "gyro": 0.01 * DEG_PER_HOUR,
    "accel": 5.0 * MICRO_G,
}
#: Relative tolerance of the numerical rank (see the module docstring).
RANK_RTOL = 1e-9
#: Largest ``||A~ T||_2`` (scaled units) of one piece of a segment; longer segments
#: are cut. ``||A~||`` is about 0.07 /s at rest and 0.11 /s in a 6 deg/s turn, so
#: stops up to about 45 min and every table turn stay in one piece.
MAX_SEGMENT_NORM = 200.0
#: Relative size below which a coefficient of a null-space relation is dropped.
COEFF_RTOL = 1e-6
#: Relative agreement needed to print a coefficient as a named constant.
SYMBOL_RTOL = 1e-6

MINUS = "\u2212"


@dataclass(frozen=True)
class Segment:
    """One constant-coefficient piece of a PWCS.

    Parameters
    ----------
    a : (n, n) array
        Continuous-time system matrix ``A`` (SI; entries in state unit per state
        unit per s).
    c : (m, n) array
        Measurement matrix ``C`` (SI).
    duration : float
        Length ``T`` of the segment, s.
    jump : (n, n) array, optional
        Applied to the state at the start of the segment (``x+ = J x-``), e.g. the
        n-resolved biases of an instantaneous table turn.
    """

    a: np.ndarray
    c: np.ndarray
    duration: float
    jump: np.ndarray | None = None


@dataclass(frozen=True)
class Vocabulary:
    """How to print null-space directions of a system in words.

    Parameters
    ----------
    display : (n, n) array
        ``x_display = display @ x`` (e.g. IMU-frame biases resolved in n).
    symbols : tuple of str
        Symbol of every display coordinate (``"φN"``, ``"∇E"``...).
    units : tuple of str
        SI unit of every display coordinate (for unrecognised coefficients).
    groups : dict symbol -> indices
        Vector groups of display coordinates (``"ε": (7, 8, 9)``), for relations
        such as ``ε = −Ω×φ``.
    free_order : tuple of tuples of int
        Classes of display coordinates in the order they are preferred as free
        parameters (attitude first, ...); within a class the coordinate with the
        largest remaining component is taken first (column pivoting), which keeps
        the relations sparse.
    constants : dict name -> float
        Named scalars (SI) that coefficients are matched against (``"g"``).
    matrices : dict name -> (3, 3) array
        Named 3x3 matrices that vector relations are matched against (``"Ω×"``, rad/s).
    """

    display: np.ndarray
    symbols: tuple[str, ...]
    units: tuple[str, ...]
    groups: dict[str, tuple[int, ...]]
    free_order: tuple[tuple[int, ...], ...]
    constants: dict[str, float]
    matrices: dict[str, np.ndarray]


@dataclass(frozen=True)
class Pwcs:
    """A piecewise-constant system with what is needed to scale and describe it.

    Parameters
    ----------
    segments : tuple of Segment
        The pieces, in time order.
    names : tuple of str
        Machine names of the states.
    scale : (n,) array
        Typical magnitude of every state, SI (rad, m/s, m, rad/s, m/s^2).
    output_scale : (m,) array
        Typical magnitude of every measurement, SI (m/s or m).
    vocabulary : Vocabulary
        How the null space is put into words.
    description : str
        One line for reports.
    """

    segments: tuple[Segment, ...]
    names: tuple[str, ...]
    scale: np.ndarray
    output_scale: np.ndarray
    vocabulary: Vocabulary
    description: str = ""

    @property
    def n(self) -> int:
        """Number of states."""
        return len(self.names)


@dataclass(frozen=True)
class ObservabilityResult:
    """SVD of the scaled total observability matrix of a :class:`Pwcs`.

    Attributes
    ----------
    names : tuple of str
        State names.
    rank : int
        Numerical rank (singular values above ``tolerance``).
    singular_values : (n,) ndarray
        Of the scaled TOM (dimensionless: output magnitudes in typical units per
        typical unit of state), descending.
    tolerance : float
        Absolute rank threshold, ``RANK_RTOL * singular_values[0]``.
    gap : float
        ``sigma[rank-1] / sigma[rank]`` (inf at full rank): how clear the rank decision is.
    null_space : (n, n - rank) ndarray
        Basis of the unobservable initial states in SI state units (orthonormal in
        scaled units).
    unobservable : tuple of str
        The null space in words.
    som_rank : int
        Rank of the stripped observability matrix (SOM).
    som_valid : bool
        True if ``null(O_j)`` lies in ``null(A_j)`` for every segment and no segment
        starts with a (non-identity) jump, so the SOM rank equals the TOM rank
        (Goshen-Meskin & Bar-Itzhack's condition).
    description : str
        One line for reports (the system's).
    extra : dict
        Extra fields copied into :meth:`to_dict`.
    """

    names: tuple[str, ...]
    rank: int
    singular_values: np.ndarray
    tolerance: float
    gap: float
    null_space: np.ndarray
    unobservable: tuple[str, ...]
    som_rank: int
    som_valid: bool
    description: str = ""
    extra: dict = field(default_factory=dict, compare=False)

    @property
    def n_states(self) -> int:
        """Number of states."""
        return len(self.names)

    def to_dict(self) -> dict:
        """Plain dict for JSON output.

        Returns
        -------
        dict
            Rank, singular values, tolerances, the null space in words, SOM rank and
            validity, and the entries of :attr:`extra`.
        """
        return {
            "model": self.description,
            "n_states": self.n_states,
            "rank": self.rank,
            "singular_values": self.singular_values.tolist(),
            "tolerance": self.tolerance,
            "relative_tolerance": RANK_RTOL,
            "rank_gap": self.gap,
            "unobservable": list(self.unobservable),
            "states": list(self.names),
            "som_rank": self.som_rank,
            "som_valid": self.som_valid,
            **self.extra,
        }


# ---------------------------------------------------------------------------------------
# The stacked matrix and its SVD
# ---------------------------------------------------------------------------------------
def segment_observability(a: np.ndarray, c: np.ndarray, duration: float) -> np.ndarray:
    """Time-scaled observability matrix of one segment (already state/output scaled).

    Block row k is ``C (A T)^k / k!``: the k-th Taylor coefficient of the output over
    the segment, a row scaling of ``[C; C A; ...; C A^(n-1)]`` (python-control's
    ``obsv``) that keeps the powers bounded. Built by the recursion
    ``B_k = B_(k-1) (A T) / k``.

    Parameters
    ----------
    a : (n, n) array
        System matrix, 1/s (in scaled state units).
    c : (m, n) array
        Measurement matrix (scaled units).
    duration : float
        Segment length ``T``, s.

    Returns
    -------
    (n m, n) ndarray
        Dimensionless blocks ``C (A T)^k / k!``, k = 0 .. n-1.
    """
    n = a.shape[0]
    at = a * duration
    blocks = [np.asarray(c, dtype=float)]
    for k in range(1, n):
        blocks.append(blocks[-1] @ at / k)
    return np.vstack(blocks)


@dataclass(frozen=True)
class _Stack:
    tom: np.ndarray
    som: np.ndarray
    som_valid: bool


def _stack(system: Pwcs) -> _Stack:
    """One pass over the segments: TOM, SOM and the SOM validity condition.

    Segments with equal ``(A, C, T)`` (every stop of a scheme, every identical turn)
    share their observability matrix, transition and condition check.
    """
    d = np.asarray(system.scale, dtype=float)
    ys = np.asarray(system.output_scale, dtype=float)
    cache: dict[tuple, tuple[np.ndarray, np.ndarray, bool]] = {}
    tom, som = [], []
    valid = True
    psi = np.eye(system.n)
    for seg in system.segments:
        if seg.jump is not None:
            psi = (seg.jump * d[None, :] / d[:, None]) @ psi
            # The SOM ignores what happens between segments, jumps included.
            valid = valid and bool(np.allclose(seg.jump, np.eye(system.n)))
        a = seg.a * d[None, :] / d[:, None]
        # A long segment is cut into equal pieces with ||A~ T|| <= MAX_SEGMENT_NORM: the
        # same system (so the same rank), but the Taylor blocks stay well scaled.
        pieces = max(1, math.ceil(np.linalg.norm(a, 2) * seg.duration / MAX_SEGMENT_NORM))
        for _ in range(pieces):
            o, phi, ok = _segment(cache, a, seg.c * d[None, :] / ys[:, None], seg.duration / pieces)
            valid = valid and ok
            tom.append(o @ psi)
            som.append(o)
            psi = phi @ psi
    return _Stack(np.vstack(tom), np.vstack(som), valid)


def _segment(cache: dict, a: np.ndarray, c: np.ndarray, duration: float):
    """(O, Phi, SOM-condition) of one scaled segment, cached on its contents."""
    from scipy.linalg import expm

    key = (a.tobytes(), c.tobytes(), float(duration))
    hit = cache.get(key)
    if hit is None:
        o = segment_observability(a, c, duration)
        # Goshen-Meskin's SOM condition null(O_j) in null(A_j), checked in scaled units.
        _, sv, vt = np.linalg.svd(o, full_matrices=True)
        r = int(np.sum(sv > RANK_RTOL * sv[0])) if len(sv) and sv[0] > 0 else 0
        null = vt[r:].T
        at = a * duration
        ok = not null.size or np.linalg.norm(at @ null) <= 1e-8 * max(1.0, np.linalg.norm(at))
        hit = (o, expm(at), bool(ok))
        cache[key] = hit
    return hit


def stacked_observability(system: Pwcs, stripped: bool = False) -> np.ndarray:
    """The scaled total (or, with ``stripped``, the stripped) observability matrix.

    Parameters
    ----------
    system : Pwcs
        The piecewise-constant system.
    stripped : bool
        If True, omit the transition products (Goshen-Meskin's SOM).

    Returns
    -------
    ndarray, shape (sum_j n m_j, n)
        In scaled units: state ``x = diag(scale) x~``, outputs divided by
        ``output_scale``.
    """
    st = _stack(system)
    return st.som if stripped else st.tom


def _svd(q: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Singular values (n,) and right singular vectors (n, n) of a tall or short matrix."""
    if q.shape[0] < n:  # fewer rows than states: pad so vt spans the whole space
        q = np.vstack([q, np.zeros((n - q.shape[0], n))])
    # Thin SVD: the stack of a swinging-base run has tens of thousands of rows.
    _, s, vt = np.linalg.svd(q, full_matrices=False)
    return s, vt


def _rank(s: np.ndarray) -> tuple[int, float]:
    tol = RANK_RTOL * s[0] if len(s) and s[0] > 0 else 0.0
    return int(np.sum(s > tol)), tol


def analyze(system: Pwcs, extra: dict | None = None) -> ObservabilityResult:
    """SVD, numerical rank and null space (with words) of a PWCS.

    Parameters
    ----------
    system : Pwcs
        The piecewise-constant system.
    extra : dict, optional
        Extra fields copied into :meth:`ObservabilityResult.to_dict`.

    Returns
    -------
    ObservabilityResult
    """
    st = _stack(system)
    s, vt = _svd(st.tom, system.n)
    rank, tol = _rank(s)
    gap = math.inf if rank == system.n else (s[rank - 1] / s[rank] if s[rank] > 0 else math.inf)
    null = vt[rank:].T * np.asarray(system.scale)[:, None]
    som_rank, _ = _rank(_svd(st.som, system.n)[0])
    return ObservabilityResult(
        names=system.names,
        rank=rank,
        singular_values=s,
        tolerance=tol,
        gap=float(gap),
        null_space=null,
        unobservable=tuple(describe_null_space(null, system)),
        som_rank=som_rank,
        som_valid=st.som_valid,
        description=system.description,
        extra=dict(extra or {}),
    )


# ---------------------------------------------------------------------------------------
# The null space in words
# ---------------------------------------------------------------------------------------
def _format_number(c: float, vocab: Vocabulary, j: int, f: int) -> tuple[float, str]:
    """(sign, text) of a coefficient: a named constant if one matches, else a number."""
    for name, value in vocab.constants.items():
        if value != 0 and abs(abs(c) - abs(value)) <= SYMBOL_RTOL * abs(value):
            sign = math.copysign(1.0, c) * math.copysign(1.0, value)
            return sign, name
    if abs(abs(c) - 1.0) <= SYMBOL_RTOL:
        return math.copysign(1.0, c), ""
    unit = f"{vocab.units[j]}/{vocab.units[f]}" if vocab.units[j] != vocab.units[f] else ""
    return math.copysign(1.0, c), f"({abs(c):.4g}{' ' + unit if unit else ''})"


def _linear_combination(terms: list[tuple[float, str]]) -> str:
    out = ""
    for i, (sign, text) in enumerate(terms):
        if i == 0:
            out += (MINUS if sign < 0 else "") + text
        else:
            out += f" {MINUS if sign < 0 else '+'} " + text
    return out


def describe_null_space(null: np.ndarray, system: Pwcs) -> list[str]:
    """Write the unobservable subspace as relations between display coordinates.

    Parameters
    ----------
    null : (n, k) array
        Basis of the null space in state coordinates, SI state units.
    system : Pwcs
        Supplies the state scales and the :class:`Vocabulary`.

    Returns
    -------
    list of str
        One relation per dependent vector group or coordinate (``"∇E = g·φN"``,
        ``"ε = −Ω×φ"``), then ``"<symbol> alone"`` for free coordinates that no
        relation mentions (a state no measurement sees at all).
    """
    k = null.shape[1]
    if k == 0:
        return []
    vocab = system.vocabulary
    nd = vocab.display @ null
    # Scale of each display coordinate: the display transform only rotates vectors of
    # like states, so the state scales carry over.
    scale = (
        np.abs(vocab.display)
        @ np.asarray(system.scale)
        / np.maximum(np.abs(vocab.display).sum(1), 1e-300)
    )
    nds = nd / scale[:, None]
    free = _choose_free(nds, vocab.free_order, k)
    if len(free) < k:  # pragma: no cover - free_order covers every coordinate
        raise RuntimeError("could not choose free coordinates for the null space")
    kmat = nd @ np.linalg.inv(nd[free])  # x_display = kmat @ x_free
    ksig = kmat * scale[free][None, :] / scale[:, None]  # in scaled units
    dependent = [j for j in range(len(scale)) if j not in free]
    live = {j for j in dependent if np.max(np.abs(ksig[j])) > COEFF_RTOL}
    mentioned: set[int] = set()
    out: list[str] = []
    done: set[int] = set()
    group_of = {i: (g, idx) for g, idx in vocab.groups.items() for i in idx}
    for j in sorted(live):
        if j in done:
            continue
        g = group_of.get(j)
        if g is not None and all(i in live for i in g[1]):
            rel = _vector_relation(g[0], g[1], kmat, ksig, free, vocab)
            if rel is not None:
                out.append(rel[0])
                done.update(g[1])
                mentioned.update(rel[1])
                continue
        terms = []
        for col, f in enumerate(free):
            if abs(ksig[j, col]) > COEFF_RTOL:
                sign, name = _format_number(kmat[j, col], vocab, j, f)
                terms.append((sign, f"{name}·{vocab.symbols[f]}" if name else vocab.symbols[f]))
                mentioned.add(f)
        out.append(f"{vocab.symbols[j]} = {_linear_combination(terms)}")
        done.add(j)
    out += [f"{vocab.symbols[f]} alone" for f in free if f not in mentioned]
    return out


def _choose_free(nds: np.ndarray, classes, k: int) -> list[int]:
    """Pick k display coordinates to parametrise the null space (rows of ``nds``).

    Class by class, take the coordinate whose row has the largest component outside
    the span of the rows already taken (column-pivoted Gram-Schmidt on the rows).
    ``nds`` has orthonormal columns in scaled units, so the thresholds are absolute:
    a coordinate carrying less than 1e-3 of a direction is first passed over (it would
    give huge coefficients), and only taken in a second round if nothing else is left.
    """
    free: list[int] = []
    basis = np.zeros((0, nds.shape[1]))
    for threshold in (1e-3, 1e-9):
        for cls in classes:
            cand = [i for i in cls if i not in free]
            while cand and len(free) < k:
                res = nds[cand] - (nds[cand] @ basis.T) @ basis if len(basis) else nds[cand]
                norms = np.linalg.norm(res, axis=1)
                best = int(np.argmax(norms))
                if norms[best] <= threshold:
                    break
                free.append(cand.pop(best))
                basis = np.vstack([basis, res[best] / norms[best]])
    return free


def _vector_relation(name, idx, kmat, ksig, free, vocab) -> tuple[str, tuple[int, ...]] | None:
    """``("ε = −Ω×φ", free indices)`` if a dependent 3-vector is a named matrix times a free one."""
    if len(idx) != 3:
        return None
    for gname, gidx in vocab.groups.items():
        if len(gidx) != 3 or not all(i in free for i in gidx):
            continue
        cols = [free.index(i) for i in gidx]
        others = [c for c in range(len(free)) if c not in cols]
        if others and np.max(np.abs(ksig[np.ix_(idx, others)])) > COEFF_RTOL:
            continue
        block = kmat[np.ix_(idx, cols)]
        for mname, m in vocab.matrices.items():
            for sign in (1.0, -1.0):
                if np.max(np.abs(block - sign * m)) <= SYMBOL_RTOL * np.max(np.abs(m)):
                    return f"{name} = {MINUS if sign < 0 else ''}{mname}{gname}", tuple(gidx)
    return None


# ---------------------------------------------------------------------------------------
# Systems built from the core error model
# ---------------------------------------------------------------------------------------
#: States of the classic 10-state alignment model (biases in the IMU frame).
ALIGNMENT10 = (
    "dv_e",
    "dv_n",
    "phi_e",
    "phi_n",
    "phi_u",
    "nabla_x",
    "nabla_y",
    "eps_x",
    "eps_y",
    "eps_z",
)
_ALIGN10_SOURCE = (
    "dv_e",
    "dv_n",
    "psi_e",
    "psi_n",
    "psi_u",
    "nabla_e",
    "nabla_n",
    "eps_e",
    "eps_n",
    "eps_u",
)


def _constants(site: Site) -> tuple[dict[str, float], dict[str, np.ndarray]]:
    om = site.earth_rate_n
    consts = {
        "g": site.g,
        "Ω·cosL": float(om[1]),
        "Ω·sinL": float(om[2]),
        "g/R_M": site.g / site.r_m,
        "g/R_N": site.g / site.r_n,
        "2g/R": 2.0 * site.g / site.mean_radius,
        # A pure east position (longitude) error has psi = -dtheta = -dr_E/R_N [0, 1, tan L].
        "1/R_N": 1.0 / site.r_n,
        "tanL/R_N": math.tan(site.lat) / site.r_n,
    }
    return consts, {"Ω×": skew(om)}


def _scale_of(name: str) -> float:
    if name in ("psi_e", "psi_n", "phi_e", "phi_n"):
        return TYPICAL["tilt"]
    if name in ("psi_u", "phi_u"):
        return TYPICAL["heading"]
    if name.startswith("dv"):
        return TYPICAL["velocity"]
    if name.startswith("dr"):
        return TYPICAL["position"]
    if name.startswith("eps"):
        return TYPICAL["gyro"]
    if name.startswith("nabla"):
        return TYPICAL["accel"]
    raise KeyError(name)


def level_imu(heading: float) -> np.ndarray:
    """Attitude ``C_s^n`` (IMU s to ENU) of a level IMU whose y axis points at ``heading``.

    Parameters
    ----------
    heading : float
        Heading of the IMU y axis, rad, clockwise from north.

    Returns
    -------
    (3, 3) ndarray
    """
    return body_to_nav(heading, 0.0, 0.0)


def _check_headings(headings) -> np.ndarray:
    h = np.atleast_1d(np.asarray(headings, dtype=float))
    if h.ndim != 1 or len(h) == 0 or not np.all(np.isfinite(h)):
        raise InputError(
            "observability.headings", "needs one or more finite headings", "e.g. 0, 180 deg"
        )
    return h


def alignment10(site: Site, headings, dwell: float = 60.0) -> Pwcs:
    """The classic 10-state zero-velocity alignment model as a PWCS over headings.

    States ``[dv_E, dv_N, phi_E, phi_N, phi_U, nabla_x, nabla_y, eps_x, eps_y, eps_z]``
    (m/s, rad, m/s^2 in the IMU frame, rad/s in the IMU frame); measurements
    ``dv_E, dv_N`` (zero-velocity updates). Each heading is one segment of ``dwell``
    seconds with a level IMU turned about the vertical; turns are instantaneous
    (IMU-frame biases and the attitude error carry over unchanged).

    Built from the core model: :class:`~inserr.model.psi_model.ErrorModel` (biases, clamped
    vertical channel) seen through :meth:`~inserr.model.psi_model.ErrorModel.imu_transform` at
    each heading, restricted to the ten states. The dropped states are the position
    errors (known position: ``dr = 0``, so ``phi = psi``), the clamped vertical
    channel and the z accelerometer bias, which for a level IMU enters only the
    clamped vertical channel.

    Parameters
    ----------
    site : Site
        Latitude, gravity and Earth rate.
    headings : float or sequence of float
        Headings of the IMU y axis, rad, clockwise from north, one segment each.
    dwell : float
        Length of every segment, s.

    Returns
    -------
    Pwcs
        Ten states, two velocity measurements; the vocabulary displays the biases
        in ENU at the first heading.
    """
    h = _check_headings(headings)
    if not (math.isfinite(dwell) and dwell > 0):
        raise InputError("scheme.stop", f"must be > 0 s, got {dwell!r}")
    core = ErrorModel(site, Layout(bias=True), vertical="clamped")
    names = core.layout.names
    keep = [names.index(s) for s in _ALIGN10_SOURCE]
    drop = [i for i in range(len(names)) if i not in keep]
    dr = [IDX["dr_e"], IDX["dr_n"], IDX["dr_u"]]
    a_n = core.matrix()
    segments = []
    for heading in h:
        t = core.imu_transform(level_imu(heading))
        a_imu = t @ a_n @ np.linalg.inv(t)
        # Everything dropped except the (assumed zero) position errors must be
        # disconnected from the kept states, or the restriction would be wrong.
        leak = a_imu[np.ix_(keep, [i for i in drop if i not in dr])]
        if np.max(np.abs(leak)) >= 1e-12:  # a model change broke the 10-state restriction
            raise RuntimeError("alignment10 restriction is not closed")
        a = a_imu[np.ix_(keep, keep)]
        c = np.zeros((2, 10))
        c[0, 0] = c[1, 1] = 1.0
        segments.append(Segment(a, c, dwell))
    c0 = level_imu(h[0])
    display = np.eye(10)
    display[5:7, 5:7] = c0[:2, :2]
    display[7:10, 7:10] = c0
    consts, mats = _constants(site)
    vocab = Vocabulary(
        display=display,
        symbols=("δvE", "δvN", "φE", "φN", "φU", "∇E", "∇N", "εE", "εN", "εU"),
        units=("m/s", "m/s", "rad", "rad", "rad", "m/s²", "m/s²", "rad/s", "rad/s", "rad/s"),
        groups={"φ": (2, 3, 4), "∇": (5, 6), "ε": (7, 8, 9), "δv": (0, 1)},
        free_order=((2, 3, 4), (5, 6), (7, 8, 9), (0, 1)),
        constants=consts,
        matrices=mats,
    )
    return Pwcs(
        segments=tuple(segments),
        names=ALIGNMENT10,
        scale=np.array([_scale_of(s) for s in ALIGNMENT10]),
        output_scale=np.full(2, TYPICAL["velocity"]),
        vocabulary=vocab,
        description=f"alignment10: headings {', '.join(f'{math.degrees(v):g}' for v in h)} deg, "
        f"{dwell:g} s each, zero-velocity updates (E, N)",
    )


_SYMBOL = {"psi": "ψ", "dv": "δv", "dr": "δr", "eps": "ε", "nabla": "∇"}
_UNIT = {"psi": "rad", "dv": "m/s", "dr": "m", "eps": "rad/s", "nabla": "m/s²"}


def measurement_matrix(model: ErrorModel, position: bool = False) -> np.ndarray:
    """Zero-velocity (and optionally position) measurement rows of the core model.

    Velocity errors E, N (and U when the vertical channel is free), position errors
    likewise when ``position``. A clamped vertical channel is held at zero by the
    model, so it is not measured.

    Parameters
    ----------
    model : ErrorModel
        The core model (its layout and vertical-channel mode).
    position : bool
        Also measure the position errors.

    Returns
    -------
    (m, n) ndarray
        One 1 per row, selecting ``dv_*`` (m/s, ENU) and ``dr_*`` (m, ENU) out of the
        ``n`` states of ``model.layout``.
    """
    axes = ("e", "n") if model.vertical == "clamped" else ("e", "n", "u")
    names = list(model.layout.names)
    rows = [f"dv_{a}" for a in axes] + ([f"dr_{a}" for a in axes] if position else [])
    c = np.zeros((len(rows), len(names)))
    for i, r in enumerate(rows):
        c[i, names.index(r)] = 1.0
    return c


def _core_states(model: ErrorModel) -> list[int]:
    """Indices of the core states that can move (a clamped vertical channel cannot)."""
    skip = {"dv_u", "dr_u"} if model.vertical == "clamped" else set()
    return [i for i, s in enumerate(model.layout.names) if s not in skip]


def _core_pwcs(model: ErrorModel, mats, position: bool, description: str) -> Pwcs:
    """Assemble a PWCS of the core model from ``(A, duration, jump)`` triples."""
    keep = _core_states(model)
    names = tuple(model.layout.names[i] for i in keep)
    c_full = measurement_matrix(model, position)
    segments = []
    for a, duration, jump in mats:
        j = None if jump is None else jump[np.ix_(keep, keep)]
        segments.append(Segment(a[np.ix_(keep, keep)], c_full[:, keep], duration, j))
    kinds = [s.split("_")[0] for s in names]
    consts, mats_ = _constants(model.site)
    groups: dict[str, tuple[int, ...]] = {}
    for i, k in enumerate(kinds):
        groups.setdefault(_SYMBOL[k], ())
        groups[_SYMBOL[k]] += (i,)
    pref = ("dr", "psi", "dv", "nabla", "eps")
    vocab = Vocabulary(
        display=np.eye(len(names)),
        symbols=tuple(
            _SYMBOL[k] + s.split("_")[1].upper() for k, s in zip(kinds, names, strict=True)
        ),
        units=tuple(_UNIT[k] for k in kinds),
        groups=groups,
        free_order=tuple(tuple(i for i, k in enumerate(kinds) if k == p) for p in pref),
        constants=consts,
        matrices=mats_,
    )
    out_scale = np.array(
        [
            TYPICAL["position"]
            if np.any(c_full[r, [IDX["dr_e"], IDX["dr_n"], IDX["dr_u"]]])
            else TYPICAL["velocity"]
            for r in range(c_full.shape[0])
        ]
    )
    return Pwcs(
        segments=tuple(segments),
        names=names,
        scale=np.array([_scale_of(s) for s in names]),
        output_scale=out_scale,
        vocabulary=vocab,
        description=description,
    )


def full_headings(
    site: Site, headings, dwell: float = 60.0, position: bool = False, vertical: str = "free"
) -> Pwcs:
    """The core model (psi, dv, dr, n-resolved biases) over headings with instant turns.

    Each heading is a stop of ``dwell`` s of a level IMU; at each instantaneous turn the
    n-resolved biases rotate with the IMU (jump ``T_new^-1 T_old`` of the
    :meth:`~inserr.model.psi_model.ErrorModel.imu_transform`). Biases are named by their
    n-frame components at the first heading.

    Parameters
    ----------
    site : Site
        Latitude, gravity and Earth rate.
    headings : float or sequence of float
        Headings of the IMU y axis, rad, clockwise from north, one stop each.
    dwell : float
        Length of every stop, s.
    position : bool
        Also measure the position errors (m, ENU).
    vertical : {"free", "clamped"}
        Vertical-channel mode of the :class:`~inserr.model.psi_model.ErrorModel`.

    Returns
    -------
    Pwcs
        The movable core states (psi rad, dv m/s, dr m, eps rad/s, nabla m/s^2,
        all ENU) with zero-velocity (and position) measurements.
    """
    h = _check_headings(headings)
    model = ErrorModel(site, Layout(bias=True), vertical=vertical)
    a = model.matrix()
    mats = []
    prev = None
    for heading in h:
        t = model.imu_transform(level_imu(heading))
        jump = None if prev is None else np.linalg.solve(t, prev)
        mats.append((a, dwell, jump))
        prev = t
    desc = (
        f"full {len(_core_states(model))}-state model ({vertical} vertical): headings "
        f"{', '.join(f'{math.degrees(v):g}' for v in h)} deg, {dwell:g} s each, zero-velocity"
        + (" and position" if position else "")
        + " updates"
    )
    return _core_pwcs(model, mats, position, desc)


def full_timeline(model: ErrorModel, timeline, position: bool = False) -> Pwcs:
    """The core model over the constant-rate intervals of a timeline.

    The timeline is a :class:`~inserr.model.timeline.Timeline`.

    Every interval (stop, table turn, swing sub-step) is one segment with
    ``A = model.matrix(w)``; the n-resolved biases follow the IMU through ``w``.

    Parameters
    ----------
    model : ErrorModel
        The core model with ``Layout(bias=True)`` (the vocabulary and scales know
        psi, dv, dr, eps and nabla only).
    timeline : Timeline
        Node times (s) and the IMU angular velocity relative to n, resolved in ENU
        (rad/s), per interval.
    position : bool
        Also measure the position errors (m, ENU).

    Returns
    -------
    Pwcs
        The movable core states, ENU, with zero-velocity (and position) measurements.
    """
    dts = np.diff(timeline.times)
    mats = [(model.matrix(w), float(dt), None) for w, dt in zip(timeline.omega_n, dts, strict=True)]
    desc = (
        f"full {len(_core_states(model))}-state model ({model.vertical} vertical) over "
        f"{len(dts)} intervals, "
        f"{timeline.duration:g} s, zero-velocity"
        + (" and position" if position else "")
        + " updates"
    )
    return _core_pwcs(model, mats, position, desc)
