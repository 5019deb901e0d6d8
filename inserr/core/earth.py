"""Earth model: WGS84 ellipsoid, Somigliana normal gravity, Earth rate; the Site.

Frames: n = local-level East-North-Up (ENU) at the site. All angles in radians,
lengths in metres.

The model matches the WGS84 constants and the Somigliana gravity formula with a
linear height correction (Groves, *Principles of GNSS, Inertial and Multisensor
Integrated Navigation Systems*, 2nd ed., eqs. 2.105-2.106, 2.134), so that the
linear error model and the nonlinear reference share the same Earth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from inserr.core.errors import require_finite, require_latitude

#: Earth rotation rate, rad/s (WGS84).
OMEGA_IE = 7.292115e-5
#: Semi-major axis, m (WGS84).
A = 6378137.0
#: First eccentricity squared (WGS84).
E2 = 6.6943799901413e-3
#: Normal gravity at the equator and the pole, m/s^2 (WGS84).
GAMMA_E = 9.7803253359
GAMMA_P = 9.8321849378
_K_SOMIGLIANA = math.sqrt(1.0 - E2) * GAMMA_P / GAMMA_E - 1.0


def radii(lat: float, height: float = 0.0) -> tuple[float, float]:
    """Meridian and prime-vertical radii of curvature, including height.

    Parameters
    ----------
    lat : float
        Geodetic latitude, rad.
    height : float
        Height above the ellipsoid, m.

    Returns
    -------
    r_m, r_n : float
        Meridian (north-south) radius R_M + h and prime-vertical (east-west)
        radius R_N + h, m.
    """
    s2 = math.sin(lat) ** 2
    w = 1.0 - E2 * s2
    r_n = A / math.sqrt(w)
    r_m = r_n * (1.0 - E2) / w
    return r_m + height, r_n + height


def gravity(lat, height=0.0):
    """Magnitude of normal gravity (gravitation + centrifugal) on the WGS84 ellipsoid.

    Somigliana's closed formula with the linear free-air height correction
    ``(1 - 2 h / a)``.

    Parameters
    ----------
    lat : float or array_like
        Geodetic latitude, rad.
    height : float or array_like
        Height above the ellipsoid, m; broadcasts against ``lat``.

    Returns
    -------
    float or ndarray
        Normal gravity, m/s^2 (a float for scalar inputs).
    """
    s2 = np.sin(lat) ** 2
    g = (
        GAMMA_E
        * (1.0 + _K_SOMIGLIANA * s2)
        / np.sqrt(1.0 - E2 * s2)
        * (1.0 - 2.0 * np.asarray(height) / A)
    )
    return float(g) if np.ndim(g) == 0 else g


@dataclass(frozen=True)
class Site:
    """A fixed location on the Earth, where the vehicle sits, swings or turns in place.

    Parameters
    ----------
    lat : float
        Geodetic latitude, rad; strictly inside (-pi/2, pi/2).
    lon : float
        Longitude, rad (only used by the nonlinear reference and reports).
    height : float
        Height above the WGS84 ellipsoid, m.
    spherical : bool
        If True, both horizontal channels use the Gaussian mean radius
        sqrt(R_M R_N) (a locally spherical Earth: the textbook Schuler and
        Foucault formulas hold exactly). Default False: the ellipsoid, whose
        east and north Schuler frequencies differ by about 0.2 %.

    Attributes
    ----------
    r_m, r_n : float
        Meridian and prime-vertical radii of curvature plus height, m (both the
        Gaussian mean radius when ``spherical``); derived, not arguments.
    g : float
        Normal gravity at the site, m/s^2 (:func:`gravity`); derived.
    """

    lat: float
    lon: float = 0.0
    height: float = 0.0
    spherical: bool = False
    r_m: float = field(init=False, repr=False)
    r_n: float = field(init=False, repr=False)
    g: float = field(init=False, repr=False)

    def __post_init__(self) -> None:
        require_latitude(self.lat, "latitude")
        require_finite(self.lon, "longitude")
        require_finite(self.height, "height")
        r_m, r_n = radii(self.lat, self.height)
        if self.spherical:
            r_m = r_n = math.sqrt(r_m * r_n)
        object.__setattr__(self, "r_m", r_m)
        object.__setattr__(self, "r_n", r_n)
        object.__setattr__(self, "g", gravity(self.lat, self.height))

    @classmethod
    def from_degrees(
        cls, lat_deg: float, lon_deg: float = 0.0, height: float = 0.0, spherical: bool = False
    ) -> Site:
        """Build a site from latitude and longitude in degrees.

        Parameters
        ----------
        lat_deg : float
            Geodetic latitude, deg.
        lon_deg : float
            Longitude, deg.
        height : float
            Height above the WGS84 ellipsoid, m.
        spherical : bool
            Locally spherical Earth (see the class parameters).

        Returns
        -------
        Site
        """
        return cls(math.radians(lat_deg), math.radians(lon_deg), height, spherical)

    @property
    def earth_rate_n(self) -> np.ndarray:
        """Earth rate resolved in ENU, [0, Omega cos L, Omega sin L], rad/s."""
        return np.array([0.0, OMEGA_IE * math.cos(self.lat), OMEGA_IE * math.sin(self.lat)])

    @property
    def specific_force_n(self) -> np.ndarray:
        """Specific force sensed at rest, resolved in ENU, [0, 0, g], m/s^2."""
        return np.array([0.0, 0.0, self.g])

    @property
    def mean_radius(self) -> float:
        """Gaussian mean radius of curvature sqrt(R_M R_N), m."""
        return math.sqrt(self.r_m * self.r_n)

    @property
    def schuler_rate(self) -> float:
        """Schuler angular frequency sqrt(g / R) with the Gaussian mean radius, rad/s."""
        return math.sqrt(self.g / self.mean_radius)
