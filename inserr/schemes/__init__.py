"""Schemes: how the IMU turns — vehicle motion, the turntable and every indexing scheme.

* ``vehicle_motion`` — static base, yaw swing, steady turn, heading history.
* ``turntable`` — table geometry and the piecewise table-angle history every scheme plans.
* ``open_loop`` — rotation tables repeated for the whole run (two-, four-, sixteen-position, ...).
* ``closed_loop`` — rules that look at the IMU heading (flexible two-position, heading isolation).
* ``nulling`` — the nulling two-position rule, inserr's own closed-loop scheme.
* ``catalogue`` — every scheme by name (:data:`~inserr.schemes.catalogue.SCHEMES`) and
  :func:`~inserr.schemes.catalogue.build_scheme`.
* ``composition`` — table schedule plus vehicle motion into the IMU attitude timeline.
* ``cycle_integrals`` — closed-form cycle integrals of periodic schemes on a static base.
"""

from inserr.core.lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "HeadingHistory": "inserr.schemes.vehicle_motion",
        "Motion": "inserr.schemes.vehicle_motion",
        "Turn": "inserr.schemes.vehicle_motion",
        "YawSwing": "inserr.schemes.vehicle_motion",
        "TableSchedule": "inserr.schemes.turntable",
        "SCHEMES": "inserr.schemes.catalogue",
        "build_scheme": "inserr.schemes.catalogue",
        "build_timeline": "inserr.schemes.composition",
        "CycleIntegrals": "inserr.schemes.cycle_integrals",
        "cycle_integrals": "inserr.schemes.cycle_integrals",
    },
)

__all__ = [
    "HeadingHistory",
    "Motion",
    "Turn",
    "YawSwing",
    "TableSchedule",
    "SCHEMES",
    "build_scheme",
    "build_timeline",
    "CycleIntegrals",
    "cycle_integrals",
]
