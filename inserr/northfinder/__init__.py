"""North finder: one gyro and one accelerometer on a rotating table find north (P3).

* ``instrument`` — the pose, the instrument and its exact sensor simulation.
* ``inputs`` — what a north-finder study reads from a scenario.
* ``bounds`` — Cramér-Rao lower bound on heading and latitude.
* ``filter`` — the Kalman filter and the heading/latitude solution.
* ``study`` — Monte Carlo repeatability beside the bound
  (:func:`~inserr.northfinder.study.monte_carlo`).
* ``figures`` — heading, convergence and latitude figures; the accuracy study's sweeps
  and maps.
* ``report`` — the north-finder report, for the one writer.
* ``api`` — the notebook front door: ``northfind`` from a scenario, file or dict.
* ``accuracy`` — the accuracy study: heading σ vs time, table rate, gyro grade and over
  heading × latitude; the gyro grade that meets a requirement (the study of
  ``analyses/p3_northfinder``).
* ``accuracy_report`` — its write-up, for the one writer.
* ``published`` — published heading and latitude repeatability beside the model, and the
  sensor grade they imply.
"""

from inserr.core.lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "Instrument": "inserr.northfinder.instrument",
        "Pose": "inserr.northfinder.instrument",
        "SensorGrade": "inserr.northfinder.instrument",
        "simulate": "inserr.northfinder.instrument",
        "Bound": "inserr.northfinder.bounds",
        "crlb": "inserr.northfinder.bounds",
        "run_filter": "inserr.northfinder.filter",
        "solve": "inserr.northfinder.filter",
        "MonteCarloResult": "inserr.northfinder.study",
        "monte_carlo": "inserr.northfinder.study",
        "build_report": "inserr.northfinder.report",
        "NorthfinderInputs": "inserr.northfinder.inputs",
        "northfinder_inputs": "inserr.northfinder.inputs",
        "northfind": "inserr.northfinder.api",
        "NorthfinderStudy": "inserr.northfinder.api",
        "AccuracyStudy": "inserr.northfinder.accuracy",
        "accuracy_study": "inserr.northfinder.accuracy",
        "against_published": "inserr.northfinder.published",
    },
)

__all__ = [
    "Instrument",
    "Pose",
    "SensorGrade",
    "simulate",
    "Bound",
    "crlb",
    "run_filter",
    "solve",
    "MonteCarloResult",
    "monte_carlo",
    "build_report",
    "NorthfinderInputs",
    "northfinder_inputs",
    "northfind",
    "NorthfinderStudy",
    "AccuracyStudy",
    "accuracy_study",
    "against_published",
]
