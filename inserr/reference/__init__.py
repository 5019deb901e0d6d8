"""Reference: the nonlinear strapdown reference (pyins) that checks the linear model.

* ``strapdown`` — inverse navigation, ideal increments and full strapdown navigation.
* ``injection`` — IMU errors injected on the ideal increments, initial errors.
* ``validation`` — linear against nonlinear, Monte Carlo against covariance
  (:func:`~inserr.reference.validation.validate`).
* ``linearity`` — long runs through both, and where the linearisation stops holding.
* ``figures`` — the overlay and Monte Carlo figures.
* ``report`` — the validation report, for the one writer.
"""

from inserr.core.lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "ErrorHistory": "inserr.reference.strapdown",
        "RunSpec": "inserr.reference.strapdown",
        "require_pyins": "inserr.reference.strapdown",
        "simulate": "inserr.reference.strapdown",
        "Validation": "inserr.reference.validation",
        "validate": "inserr.reference.validation",
        "build_report": "inserr.reference.report",
    },
)

__all__ = [
    "ErrorHistory",
    "RunSpec",
    "require_pyins",
    "simulate",
    "Validation",
    "validate",
    "build_report",
]
