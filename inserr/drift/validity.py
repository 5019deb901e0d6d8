"""Where a drift result can be trusted: finiteness, the free vertical channel, the
linear psi model's range, and Schuler resonance of an indexing cycle.

The drift engine is linear: it answers for any input, including inputs for which
the answer means nothing. This module states when that happens. Its thresholds are
justified in ``docs/theory.md`` (section "Where the linear model holds") from the
nonlinear reference's measured departure (``python tools/linear_validity.py``).
"""

from __future__ import annotations

import math

import numpy as np

from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.core.units import DEG, HOUR

#: Largest tilt error (east or north) the small-angle psi model is trusted with:
#: measured departure of the nonlinear reference 0.64 % at 0.3 deg, 2.2 % at 1 deg
#: (linear in the tilt: 1 % at about 0.46 deg); docs/theory.md.
TILT_LIMIT = 0.4 * DEG

#: Largest heading error the small-angle psi model is trusted with: measured
#: departure 0.73 % at 1 deg, 1.4 % at 2 deg of initial heading error, 0.44 % when a
#: gyro bias drives it to 0.99 deg, 1.5 % at 3.3 deg; docs/theory.md.
HEADING_LIMIT = 1.0 * DEG

#: Largest fixed-site measure ``max|dr_h| max(1, |tan L|) / R`` (the model keeps the
#: site's latitude, gravity and transport rates fixed): with velocity errors alone
#: (attitude errors far below their limits) the measured departure is 0.26 % at
#: 1.3e-2 (lat 34 deg) and 0.89 % at 2.1e-2 (lat 80 deg); docs/theory.md.
FIXED_SITE_LIMIT = 2.0e-2

#: Latitude beyond which the linear model's polar band is flagged: the transport
#: rate ``v_E tan L / R`` and the east-error to longitude conversion ``1 / cos L``
#: grow without bound. With a 0.1 deg/h, 100 ug budget over 6 h the measured
#: position departure is 0.88 % at 80 deg and 1.8 % at 85 deg (docs/theory.md).
POLE_BAND = 80.0 * DEG

#: Growth factor of the free vertical channel (``exp(t / tau)``) past which its
#: results are refused: by then an error of 1 um at the start is 1 m, and any
#: term of the solution is dominated by the unstable mode.
VERTICAL_GROWTH_LIMIT = 1.0e6


def vertical_time_constant(site: Site) -> float:
    """Time constant of the free vertical channel, s, from the model's eigenvalues.

    The positive real eigenvalue of the navigation block with a free vertical
    channel is ``sqrt(2 g / R)`` (about 1 / 570 s); its inverse is returned.
    """
    from inserr.model.psi_model import ErrorModel, modes

    tau = modes(ErrorModel(site, vertical="free")).vertical_time_constant_s
    if tau is None:  # pragma: no cover - the free channel always has one
        raise RuntimeError("the free vertical model has no unstable eigenvalue")
    return tau


def check_vertical(site: Site, duration: float, vertical: str) -> list[str]:
    """Refuse a free vertical channel run past its meaningful time; else a warning.

    Raises
    ------
    InputError
        ``output.vertical``: the run is longer than ``tau ln(1e6)``.
    """
    if vertical != "free":
        return []
    tau = vertical_time_constant(site)
    t_max = tau * math.log(VERTICAL_GROWTH_LIMIT)
    if duration > t_max:
        raise InputError(
            "output.vertical",
            f"the free vertical channel diverges as exp(t / {tau:.0f} s): after "
            f"{t_max / HOUR:.2g} h (growth {VERTICAL_GROWTH_LIMIT:.0e}) its results are "
            f"meaningless, and this run lasts {duration / HOUR:.3g} h",
            f"use output.vertical = clamped, or a duration of at most {t_max / HOUR:.2g} h",
        )
    return [
        f"free vertical channel: errors grow as exp(t / {tau:.0f} s) "
        f"(x{math.exp(duration / tau):.3g} over this run); results are meaningless after "
        f"{t_max / HOUR:.2g} h"
    ]


def all_finite(*arrays: np.ndarray) -> bool:
    """True if every entry of every array is finite.

    A NaN or an infinity makes the sum non-finite, so a finite sum proves every entry
    finite in one pass without temporaries; a non-finite sum (an entry, or an overflow
    of the sum itself) is settled entry by entry.
    """
    return all(bool(np.isfinite(np.sum(a))) or bool(np.all(np.isfinite(a))) for a in arrays)


def check_finite(res, scheme: str) -> None:
    """InputError if any number of a drift result is not finite (:attr:`DriftResult.finite
    <inserr.drift.analysis.DriftResult.finite>`).

    Inside the documented input ranges this does not happen; it guards the edge
    anyway, so that no NaN or infinity ever reaches a report or the JSON.
    """
    finite = getattr(res, "finite", None)  # a DriftResult knows (computed with its curves)
    if finite is None:
        arrays = (res.nav, res.attitude, res.source_horizontal, *res.noise_cov.values())
        finite = all_finite(*arrays, getattr(res, "source_heading", np.zeros(0)))
    if finite:
        return
    raise InputError(
        "scenario",
        f"scheme {scheme!r} gave non-finite errors (overflow): the inputs are outside "
        "the range where the error model means anything",
        "use smaller error magnitudes or a shorter duration (ranges: docs/scenarios.md)",
    )


def attitude_extent(attitude: np.ndarray) -> tuple[float, float]:
    """Largest ``|tilt|`` (E and N) and ``|heading error|`` of attitude errors (M, 3), rad
    (0 for none)."""
    if not attitude.size:
        return 0.0, 0.0
    # Rows of one component each: whole-array reductions, not strided column ones.
    rows = np.ascontiguousarray(attitude.T)
    tilt, head = rows[:2], rows[2]
    return max(float(tilt.max()), -float(tilt.min())), max(float(head.max()), -float(head.min()))


def linear_validity_warnings(res, site: Site) -> list[str]:
    """Warnings when a drift result leaves the range where the linear psi model holds.

    Parameters
    ----------
    res : DriftResult
    site : Site

    Returns
    -------
    list of str
        One warning per limit passed (tilt, heading, fixed site, pole band); empty when
        the run stays inside all three.
    """
    out = []
    extent = getattr(res, "attitude_extent", None)  # a DriftResult has it with its curves
    tilt, heading = extent if extent is not None else attitude_extent(res.attitude)
    for what, value, limit in (
        ("tilt", tilt, TILT_LIMIT),
        ("heading", heading, HEADING_LIMIT),
    ):
        if value > limit:
            out.append(
                f"linear model out of range: {what} error reaches {value / DEG:.3g} deg, past "
                f"the {limit / DEG:g} deg small-angle limit (the nonlinear reference departs "
                "by more than 1 %); reduce the errors or the duration"
            )
    h = float(res.horizontal.max()) if res.horizontal.size else 0.0
    measure = h * max(1.0, abs(math.tan(site.lat))) / site.mean_radius
    if measure > FIXED_SITE_LIMIT:
        out.append(
            f"linear model out of range: horizontal error {h / 1000.0:.3g} km is too large for "
            f"the fixed-site linearization (max|dr| max(1, |tan L|) / R = {measure:.2g} > "
            f"{FIXED_SITE_LIMIT:g}); reduce the errors or the duration"
        )
    if abs(site.lat) > POLE_BAND:
        out.append(
            f"linear model near its polar limit: |latitude| {abs(site.lat) / DEG:.4g} deg > "
            f"{POLE_BAND / DEG:g} deg, where the transport rate and the east-error to "
            "longitude conversion (1 / cos L) blow up; treat the results with care"
        )
    return out


def near_schuler_resonance(cycle: float, schuler: float, duration: float) -> int | None:
    """The harmonic of an indexing cycle that is near Schuler resonance, or None.

    A forcing at angular frequency ``w`` drives the undamped Schuler oscillator
    (``w_s``) as ``sin((w - w_s) t / 2) / ((w - w_s) / 2)``; over a run of length
    ``T`` this is at least ``2 / pi`` (64 %) of the exactly resonant growth ``t``
    while ``|w - w_s| T / 2 <= pi / 2``, i.e. ``|f - f_s| <= 1 / (2 T)``. That
    half-width is the resonance band over the run: the harmonic ``k / cycle``
    nearest ``1 / schuler`` is flagged only inside it. (The former ``0.15 k``
    tolerance on ``cycle / schuler`` flagged every cycle of 4+ Schuler periods.)

    Parameters
    ----------
    cycle, schuler, duration : float, s

    Returns
    -------
    int or None
        The harmonic number k, or None.
    """
    if cycle <= 0 or duration <= 0:
        return None
    k = max(1, round(cycle / schuler))
    if abs(k / cycle - 1.0 / schuler) <= 1.0 / (2.0 * duration):
        return k
    return None
