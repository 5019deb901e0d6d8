"""Calibration: discrete multi-position calibration of a gyro and an accelerometer triad.

* ``two_axis_table`` — two-axis tables and the IMU position sets they reach.
* ``inputs`` — what a calibration study reads from a scenario.
* ``estimation`` — measurement model, least squares, identifiability, Cramér-Rao bound,
  Monte Carlo.
* ``position_sets`` — the position-set designer: precision per unit of table time.
* ``summary`` — JSON-ready summaries and tables in engineering units.
* ``figures`` — P1-style deviation and repeatability figures.
* ``report`` — the calibration report, for the one writer.
* ``allan`` — IMU noise terms from a static recording: Allan deviation, IEEE slopes.
* ``api`` — the notebook front door: ``calibrate`` and ``imu_budget``.
* ``comparison`` — two position sets side by side: baseline, noise-free, equal time,
  sweeps, designed sets (the study of ``analyses/p1_calibration``).
* ``comparison_report`` — its write-up, for the one writer.
* ``published`` — a published Monte Carlo table of two methods beside the model, claim
  by claim (P1's Table 1).
* ``published_report`` — the write-up's "Against the paper" section.
"""

from inserr.core.lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "PositionSet": "inserr.calibration.two_axis_table",
        "TwoAxisTable": "inserr.calibration.two_axis_table",
        "builtin_set": "inserr.calibration.two_axis_table",
        "load_position_set": "inserr.calibration.two_axis_table",
        "CalibrationDesign": "inserr.calibration.estimation",
        "MonteCarloConfig": "inserr.calibration.estimation",
        "SensorResult": "inserr.calibration.estimation",
        "monte_carlo": "inserr.calibration.estimation",
        "design_sets": "inserr.calibration.position_sets",
        "calibration_summary": "inserr.calibration.summary",
        "build_report": "inserr.calibration.report",
        "CalibrationInputs": "inserr.calibration.inputs",
        "calibration_inputs": "inserr.calibration.inputs",
        "calibrate": "inserr.calibration.api",
        "CalibrationStudy": "inserr.calibration.api",
        "imu_budget": "inserr.calibration.api",
        "NoiseBudget": "inserr.calibration.api",
        "read_recording": "inserr.calibration.allan",
        "fit_recording": "inserr.calibration.allan",
        "compare_sets": "inserr.calibration.comparison",
        "against_published": "inserr.calibration.published",
    },
)

__all__ = [
    "PositionSet",
    "TwoAxisTable",
    "builtin_set",
    "load_position_set",
    "CalibrationDesign",
    "MonteCarloConfig",
    "SensorResult",
    "monte_carlo",
    "design_sets",
    "calibration_summary",
    "build_report",
    "CalibrationInputs",
    "calibration_inputs",
    "calibrate",
    "CalibrationStudy",
    "imu_budget",
    "NoiseBudget",
    "read_recording",
    "fit_recording",
    "compare_sets",
    "against_published",
]
