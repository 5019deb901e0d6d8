"""The ``inserr`` command: argparse and formatting only; nothing outside this package imports it.

Each command is one module exposing ``HELP``, ``add_arguments(parser)`` and
``run(args)``, imported only when its command runs:

* ``main`` — the entry point and the command table.
* ``common`` — shared flags and output formatting (``--json``, tables, provenance).
* ``modes`` — eigen-periods of the error model.
* ``drift`` — drift of an IMU budget under a scheme.
* ``compare`` — several schemes on one scenario.
* ``run`` — a scenario file and its report directory.
* ``cycle`` — closed-form cycle integrals.
* ``validate`` — linear prediction against the nonlinear reference.
* ``observability`` — piecewise-constant observability.
* ``align`` — the alignment study.
* ``calibrate`` — multi-position calibration.
* ``northfind`` — the north finder.
* ``sweep`` — parameter sweeps.
* ``imu_budget`` — noise terms of a static recording (Allan deviation).
"""

from inserr.core.lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "main": "inserr.cli.main",
    },
)

__all__ = ["main"]
