"""inserr: error analysis of rotation-modulated ("indexed") strapdown inertial navigation.

The map — the subpackages in reading order, each a chapter with one job; a module
only imports chapters above it in this list (``docs/architecture.md``):

* :mod:`inserr.core` — units, the input error, rotations, the Earth, the IMU error budget.
* :mod:`inserr.output` — the one report writer, the one figure style, progress bars.
* :mod:`inserr.model` — the psi-angle error model, error sources, timeline, exact propagation.
* :mod:`inserr.schemes` — vehicle motion, turntable, the indexing schemes and cycle integrals.
* :mod:`inserr.scenario` — the one validated input: scenario files, units, flag vocabulary.
* :mod:`inserr.drift` — free-inertial drift of a scenario under its schemes, and its report.
* :mod:`inserr.reference` — the nonlinear strapdown reference that checks the linear model.
* :mod:`inserr.alignment` — fine alignment: Kalman filter and observability per scheme.
* :mod:`inserr.calibration` — multi-position calibration on a two-axis table.
* :mod:`inserr.northfinder` — the rotation-modulation north finder (one gyro, one accelerometer).
* :mod:`inserr.sweep` — design sweeps over a grid of scenario changes, on Dask.
* :mod:`inserr.cli` — the ``inserr`` command: argparse and formatting only.

Conventions (stated once, with equations, in ``docs/theory.md``):

* Frames: n is the East-North-Up (ENU) navigation frame at the site; b is the
  vehicle body, right-front-up (x right, y forward, z up); s is the IMU frame, the
  IMU's own axes (equal to b when the table is at its zero and the IMU mounting
  is the identity). ``C_a^b`` maps components in a to components in b.
* Heading is measured clockwise from north; pitch about body x (nose up
  positive), roll about body y (right wing down positive); table angles are
  right-handed about the table axes.
* Every error is computed minus true: velocity and position errors resolved in
  ENU (m/s, m); sensor errors ``measured = (I + K) true + bias + noise``.
* Attitude: the model propagates the psi-angle (Benson 1975), the small rotation
  from the computed local-level frame c to the platform frame p,
  ``C_c^p = I - [psi x]``, and reports the true attitude error
  ``phi = psi + dtheta`` (``dtheta`` the position-error angle); ``phi_U > 0``
  means the indicated heading is too large (clockwise).
* Units: SI inside (rad, s, m, m/s, m/s^2, rad/s); named constants of
  :mod:`inserr.core.units` and strings with units only at the edges (scenario
  files, flags, reports).

The notebook front door (every result has ``metrics()``, ``to_dataframe()``,
``budget()``, ``plot()`` and a Jupyter summary; ``docs/tutorials/notebook.md``):
``inserr.load_scenario(path)``, ``inserr.drift(scenario, scheme)``,
``inserr.compare(scenario, schemes)``, ``inserr.align(scenario)``,
``inserr.calibrate(scenario)``, ``inserr.northfind(scenario)``,
``inserr.sweep(scenario, params)``, ``inserr.imu_budget(recording, rate)``
(``inserr.drift`` and ``inserr.sweep`` are the subpackages, callable).

Public entry points, importable from ``inserr`` directly (each imported on first
use, so ``import inserr`` itself imports no other module: not numpy, matplotlib,
scipy, control or dask): :func:`load_scenario`, :func:`scenario_from_dict`,
:class:`Scenario`, :func:`run_scheme`, :func:`analyze_drift`, :func:`build_scheme`,
:data:`SCHEMES`, :func:`validate`, :func:`run_alignment`, :class:`Site`,
:class:`ImuErrors`, :class:`InitialErrors`, :class:`Report`, :class:`InputError`,
``__version__``; and every subpackage as an attribute (``inserr.drift``).
"""

from __future__ import annotations

import importlib

__version__ = "0.2.0"

#: Subpackages in reading (and layer) order.
SUBPACKAGES = (
    "core",
    "output",
    "model",
    "schemes",
    "scenario",
    "drift",
    "reference",
    "alignment",
    "calibration",
    "northfinder",
    "sweep",
    "cli",
)

#: Public name -> module defining it (imported on first use).
_EXPORTS = {
    "InputError": "inserr.core.errors",
    "Site": "inserr.core.earth",
    "ImuErrors": "inserr.core.imu",
    "InitialErrors": "inserr.core.imu",
    "Report": "inserr.output.report",
    "SCHEMES": "inserr.schemes.catalogue",
    "build_scheme": "inserr.schemes.catalogue",
    "Scenario": "inserr.scenario.schema",
    "load_scenario": "inserr.scenario.schema",
    "scenario_from_dict": "inserr.scenario.schema",
    "analyze_drift": "inserr.drift.analysis",
    "run_scheme": "inserr.drift.study",
    "validate": "inserr.reference.validation",
    "run_alignment": "inserr.alignment.filter",
    # The notebook front door (``inserr.drift`` and ``inserr.sweep`` are the callable
    # subpackages themselves; see inserr.core.lazy.callable_package).
    "compare": "inserr.drift.api",
    "align": "inserr.alignment.api",
    "calibrate": "inserr.calibration.api",
    "northfind": "inserr.northfinder.api",
    "imu_budget": "inserr.calibration.api",
}

__all__ = ["__version__", *_EXPORTS]


def __getattr__(name: str):
    # Module-level __getattr__ (PEP 562): the entry points and subpackages load on
    # first use, so that "import inserr" stays free of heavy imports.
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name]), name)
    elif name in SUBPACKAGES:
        value = importlib.import_module(f"{__name__}.{name}")
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS) | set(SUBPACKAGES))
