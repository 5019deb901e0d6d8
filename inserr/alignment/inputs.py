"""What the alignment and observability studies read from a scenario.

``inserr align``, ``inserr observability`` and ``analyses/alignment_observability``
build their inputs here from a :class:`~inserr.scenario.schema.Scenario` loaded for
the ``alignment`` study (whose defaults are a 10-minute run, 60 s stops, a free
vertical channel, a P0-grade IMU and a coarse-alignment prior; see
``docs/scenarios.md``). Errors name the scenario key.

Keys read
---------
* the schemes: ``scheme.name`` (when given, or when nothing else is) and then those of
  ``compare.schemes``, as ``inserr run`` does; their table
  ``scheme.rate`` and ``scheme.stop``; the base ``site`` and ``motion``
  (``output.substep`` for continuous motion); the length ``scenario.duration``;
* the IMU ``[imu]``: the gyro and accelerometer biases are both the prior 1 sigma of
  the filter's bias states and the true biases of the simulated run (so >= 0); the
  scale factors and misalignments are errors of the simulated run only (the filter
  does not model them); ``arw``/``vrw`` drive both; no bias instability;
* the prior ``[initial]``: ``attitude`` is the 1 sigma of phi_E, phi_N (tilts) and
  phi_U (heading), ``velocity`` and ``position`` one 1 sigma for all three axes;
* the filter ``[alignment]`` (update rate and 1 sigma, optional position updates),
  ``output.vertical`` and ``scenario.seed``;
* ``[observability]``: headings (one stop of ``scheme.stop`` each) instead of a
  scheme, the model, position measurements.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from inserr.alignment.filter import Prior, Settings
from inserr.alignment.study import Base, alignment_timeline
from inserr.core.errors import InputError
from inserr.core.imu import ImuErrors
from inserr.scenario.schema import Scenario
from inserr.schemes.vehicle_motion import heading_sign

#: Fields of :class:`~inserr.alignment.filter.Prior` -> the scenario key they come from.
_PRIOR_KEYS = {
    "prior.attitude": "initial.attitude",
    "prior.velocity": "initial.velocity",
    "prior.position": "initial.position",
    "prior.gyro_bias": "imu.gyro_bias",
    "prior.accel_bias": "imu.accel_bias",
}


@dataclass(frozen=True)
class AlignmentInputs:
    """Validated inputs of an alignment study (SI).

    Attributes
    ----------
    schemes : tuple of str
        Schemes run during alignment, in order.
    base : Base
        Site, base motion, table rate (rad/s) and stop time (s).
    duration : float
        Length of the alignment, s.
    imu : ImuErrors
        True errors of the simulated run (biases also the prior 1 sigma).
    prior : Prior
        Prior 1 sigma of the filter states.
    settings : Settings
        Measurements, vertical channel and seed.
    """

    schemes: tuple[str, ...]
    base: Base
    duration: float
    imu: ImuErrors
    prior: Prior
    settings: Settings


def _one_value(scen: Scenario, key: str) -> float:
    """A 3-axis key that the alignment prior takes as one 1 sigma for all axes."""
    v = np.asarray(scen.value(key), dtype=float)
    if not np.all(v == v[0]):
        raise InputError(
            key, "the alignment prior takes one 1 sigma for all three axes", "give one value"
        )
    return float(v[0])


def alignment_inputs(scen: Scenario) -> AlignmentInputs:
    """The alignment study's inputs from ``scen`` (load it with ``study="alignment"``).

    Parameters
    ----------
    scen : Scenario

    Returns
    -------
    AlignmentInputs

    Raises
    ------
    InputError
        Naming the scenario key: negative bias 1 sigma, a bias instability, per-axis
        velocity or position priors, bad filter settings.
    """
    imu = scen.imu
    for key in ("gyro_bias_instability", "accel_bias_instability"):
        if getattr(imu, key) > 0:
            raise InputError(
                f"imu.{key}",
                "the alignment filter models constant biases and white noise only",
                "set it to 0",
            )
    for key in ("gyro_bias", "accel_bias"):
        if np.any(getattr(imu, key) < 0):
            raise InputError(
                f"imu.{key}",
                "the biases are also the prior 1 sigma of the bias states, so >= 0",
                "give magnitudes",
            )
    try:
        prior = Prior(
            attitude=np.asarray(scen.init.attitude, dtype=float),
            velocity=_one_value(scen, "initial.velocity"),
            position=_one_value(scen, "initial.position"),
            gyro_bias=imu.gyro_bias,
            accel_bias=imu.accel_bias,
        )
    except InputError as exc:
        raise InputError(_PRIOR_KEYS.get(exc.field, exc.field), exc.problem, exc.fix) from None
    settings = Settings(
        zupt_rate=scen.value("alignment.zupt_rate"),
        zupt_sigma=scen.value("alignment.zupt_sigma"),
        position_sigma=scen.value("alignment.position_sigma"),
        vertical=scen.vertical,
        seed=scen.seed,
    )
    # As `inserr run`: the scheme, then the ones compared with it; the default scheme
    # ("none") only when nothing else is named.
    first = (scen.scheme_name,) if scen.given("scheme.name") or not scen.compare else ()
    schemes = tuple(dict.fromkeys(first + tuple(scen.compare)))
    base = Base(scen.site, scen.motion, scen.scheme_rate, scen.scheme_stop, scen.substep)
    return AlignmentInputs(schemes, base, scen.duration, imu, prior, settings)


def observability_system(scen: Scenario) -> tuple[Any, dict[str, Any]]:
    """The piecewise-constant system ``[observability]`` (or the scheme) of ``scen`` describes.

    With ``observability.headings``: one stop of ``scheme.stop`` per heading of a
    level IMU turned about the vertical, in the classic 10-state model (``model``
    ``auto`` or ``alignment10``) or the core 15-state one (``full``). Otherwise the
    intervals of ``scheme.name`` running for ``scenario.duration`` on the scenario's
    base, always in the full model.

    Parameters
    ----------
    scen : Scenario
        Loaded with ``study="alignment"``.

    Returns
    -------
    system : Pwcs
        For :func:`inserr.alignment.observability.analyze`.
    extra : dict
        What describes the segments in the result (headings in deg and dwell in s,
        or the scheme name).
    """
    from inserr.alignment import observability as ob
    from inserr.model.psi_model import ErrorModel, Layout

    headings = scen.value("observability.headings")
    model = scen.value("observability.model")
    position = scen.value("observability.position_updates")
    if not headings:
        if not scen.given("scheme.name"):
            raise InputError(
                "observability.headings",
                "no segments given",
                "give headings (e.g. 0, 180 deg) or a scheme (scheme.name)",
            )
        if model == "alignment10":
            raise InputError(
                "observability.model", "a scheme timeline needs the full model", "use full"
            )
        base = Base(scen.site, scen.motion, scen.scheme_rate, scen.scheme_stop)
        tl = alignment_timeline(base, scen.scheme_name, scen.duration)
        em = ErrorModel(scen.site, Layout(bias=True), vertical=scen.vertical)
        return ob.full_timeline(em, tl, position=position), {"scheme": scen.scheme_name}
    if scen.given("scheme.name"):
        raise InputError(
            "observability.headings", "give either headings or a scheme (scheme.name), not both"
        )
    # IMU headings in the declared sense (motion.heading_convention), turned into inserr's.
    h = np.asarray(headings, dtype=float) * heading_sign(scen.heading_convention)
    dwell = scen.scheme_stop
    extra = {"headings_deg": [float(v) for v in np.degrees(headings)], "dwell_s": dwell}
    if model in ("auto", "alignment10"):
        if position:
            raise InputError(
                "observability.position_updates",
                "the 10-state model has no position states",
                "use the full model",
            )
        return _as_declared(ob.alignment10(scen.site, h, dwell), h, headings), extra
    system = ob.full_headings(scen.site, h, dwell, position=position, vertical=scen.vertical)
    return _as_declared(system, h, headings), extra


def _as_declared(system: Any, h: np.ndarray, declared) -> Any:
    """``system`` whose description lists the headings as the scenario declared them."""
    if np.array_equal(h, np.asarray(declared, dtype=float)):
        return system

    def deg(values) -> str:
        return ", ".join(f"{math.degrees(v):g}" for v in values)

    text = system.description.replace(
        f"headings {deg(h)} deg", f"headings {deg(declared)} deg counter-clockwise", 1
    )
    return dataclasses.replace(system, description=text)
