"""Core: the ground every chapter stands on; imports nothing else of inserr.

* ``units`` — named unit constants (``DEG``, ``HOUR``, ``MICRO_G``, ``NMI``, ...) and
  :func:`~inserr.core.units.parse_quantity` for strings with units.
* ``errors`` — :class:`~inserr.core.errors.InputError`, the one exception for bad input.
* ``rotations`` — direction cosine matrices, Euler angles in the ENU convention, exp/log.
* ``earth`` — WGS84 ellipsoid, normal gravity, Earth rate; the :class:`~inserr.core.earth.Site`.
* ``imu`` — the IMU error budget (:class:`~inserr.core.imu.ImuErrors`) and initial errors.
* ``lazy`` — lazy re-exports for the package ``__init__`` files (this one included).
"""

from inserr.core.lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "parse_quantity": "inserr.core.units",
        "InputError": "inserr.core.errors",
        "require_finite": "inserr.core.errors",
        "require_latitude": "inserr.core.errors",
        "body_to_nav": "inserr.core.rotations",
        "euler_from_dcm": "inserr.core.rotations",
        "rot_x": "inserr.core.rotations",
        "rot_y": "inserr.core.rotations",
        "rot_z": "inserr.core.rotations",
        "skew": "inserr.core.rotations",
        "Site": "inserr.core.earth",
        "gravity": "inserr.core.earth",
        "radii": "inserr.core.earth",
        "ImuErrors": "inserr.core.imu",
        "InitialErrors": "inserr.core.imu",
    },
)

__all__ = [
    "parse_quantity",
    "InputError",
    "require_finite",
    "require_latitude",
    "body_to_nav",
    "euler_from_dcm",
    "rot_x",
    "rot_y",
    "rot_z",
    "skew",
    "Site",
    "gravity",
    "radii",
    "ImuErrors",
    "InitialErrors",
]
