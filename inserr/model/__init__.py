"""Model: the psi-angle error model and its exact propagation over an attitude timeline.

* ``psi_model`` — the error model of a strapdown INS at a fixed site as a state-space
  model (:class:`~inserr.model.psi_model.ErrorModel`) and its eigen-periods
  (:func:`~inserr.model.psi_model.modes`).
* ``error_sources`` — the error sources and the initial augmented state they define.
* ``timeline`` — the IMU attitude history as constant-angular-velocity intervals.
* ``discretization`` — transition matrices and noise of each interval, cached.
* ``exact_propagation`` — the step engine: states and covariances propagated interval by
  interval (the reference).
* ``attitude_history`` — the attitude history as the fast engine reads it: smooth pieces.
* ``modal`` — modal form of the navigation-error dynamics at a fixed site.
* ``quadrature`` — Chebyshev quadrature and spectral integration on one interval.
* ``fast_propagation`` — the fast engine: constant errors and white noise through the
  modal form, window by window.
"""

from inserr.core.lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "ErrorModel": "inserr.model.psi_model",
        "Layout": "inserr.model.psi_model",
        "Modes": "inserr.model.psi_model",
        "attitude_error": "inserr.model.psi_model",
        "modes": "inserr.model.psi_model",
        "Source": "inserr.model.error_sources",
        "constant_sources": "inserr.model.error_sources",
        "Timeline": "inserr.model.timeline",
        "Discretizer": "inserr.model.discretization",
        "discretizer_for": "inserr.model.discretization",
        "propagate_covariance": "inserr.model.exact_propagation",
        "propagate_outputs": "inserr.model.exact_propagation",
        "propagate_states": "inserr.model.exact_propagation",
        "AttitudeHistory": "inserr.model.attitude_history",
        "NavModes": "inserr.model.modal",
        "constant_error_response": "inserr.model.fast_propagation",
        "white_noise_covariance": "inserr.model.fast_propagation",
    },
)

__all__ = [
    "ErrorModel",
    "Layout",
    "Modes",
    "attitude_error",
    "modes",
    "Source",
    "constant_sources",
    "Timeline",
    "Discretizer",
    "discretizer_for",
    "propagate_covariance",
    "propagate_outputs",
    "propagate_states",
    "AttitudeHistory",
    "NavModes",
    "constant_error_response",
    "white_noise_covariance",
]
