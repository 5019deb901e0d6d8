"""The flag table of the ``inserr`` command: every value flag overrides one scenario key.

One table (:data:`FLAGS`) for all sub-commands: each flag has one name, one scenario
key, one unit for bare numbers (written one way: ``ug``, ``deg/h``, ``deg/sqrt(h)``,
``ug/sqrt(Hz)``, ``arcsec``, ``ppm``, ``deg``, ``s``, ``min``, ``h``, ``Hz``), one
help text and one default, the scenario's (:func:`inserr.scenario.schema.study_default`:
a study's own default where it has one). A sub-command picks the flags it offers
from the table (:func:`add_flags`); the flags it was given become a nested scenario
table (:func:`flags_to_dict`) laid over its optional scenario file, and the result
is validated by :func:`inserr.scenario.schema.scenario_from_dict` like any file.
Values may carry an explicit unit (``--gyro-bias "0.02 deg/h"``).

Library code names scenario keys in its errors; :func:`name_the_flag` adds the flag
when the value came from one (``--arw (imu.arw): ...``).
"""

from __future__ import annotations

import argparse
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from inserr.core.errors import InputError
from inserr.core.units import UNITS
from inserr.scenario.schema import (
    CHOICES,
    SCHEMA,
    Key,
    Scenario,
    read_scenario_file,
    scenario_from_dict,
    study_default,
)


@dataclass(frozen=True)
class Flag:
    """One value flag.

    Attributes
    ----------
    key : str or tuple of str
        The scenario key it overrides (``--yaw-swing AMP,PERIOD`` sets two).
    unit : str or None
        Unit of bare numbers; None for words, counts and plain numbers, and for a
        quantity whose natural unit differs between studies (``--duration``), which
        must then be written with its unit.
    help : str
        What it is, without unit or default (both are added from the table: the unit
        after the first words, before a ``": "`` that introduces the value's form).
    metavar : str
        Placeholder of the value in ``--help``.
    """

    key: str | tuple[str, ...]
    unit: str | None
    help: str
    metavar: str = "X"

    @property
    def keys(self) -> tuple[str, ...]:
        """Every scenario key the flag sets."""
        return (self.key,) if isinstance(self.key, str) else tuple(self.key)

    @property
    def spec(self) -> Key:
        """The schema entry of its (first) key."""
        section, _, name = self.keys[0].partition(".")
        return SCHEMA[section][name]


_F = Flag

#: flag name (without --) -> :class:`Flag`. Grouped as the scenario sections are.
FLAGS: dict[str, Flag] = {
    # [scenario]
    "duration": _F("scenario.duration", None, "duration of the run (of each run in a study)"),
    "seed": _F("scenario.seed", None, "seed of the random draws", "N"),
    "runs": _F("scenario.runs", None, "Monte Carlo runs", "N"),
    # [site]
    "lat": _F("site.latitude", "deg", "latitude"),
    "lon": _F("site.longitude", "deg", "longitude"),
    "height": _F("site.height", "m", "height above the ellipsoid"),
    "earth": _F("site.earth", None, "Earth shape"),
    # [imu]
    "gyro-bias": _F("imu.gyro_bias", "deg/h", "gyro bias: one value or x,y,z"),
    "accel-bias": _F("imu.accel_bias", "ug", "accelerometer bias: one value or x,y,z"),
    "gyro-sf": _F("imu.gyro_scale_factor", "ppm", "gyro scale-factor error: one value or x,y,z"),
    "accel-sf": _F(
        "imu.accel_scale_factor", "ppm", "accelerometer scale-factor error: one value or x,y,z"
    ),
    "gyro-misalignment": _F(
        "imu.gyro_misalignment", "arcsec", "gyro misalignment: one value or xy,xz,yx,yz,zx,zy"
    ),
    "accel-misalignment": _F(
        "imu.accel_misalignment",
        "arcsec",
        "accelerometer misalignment: one value or xy,xz,yx,yz,zx,zy",
    ),
    "arw": _F("imu.arw", "deg/sqrt(h)", "gyro angle random walk"),
    "vrw": _F("imu.vrw", "ug/sqrt(Hz)", "accelerometer velocity random walk"),
    "gyro-bias-instability": _F(
        "imu.gyro_bias_instability", "deg/h", "Gauss-Markov gyro bias, 1 sigma"
    ),
    "accel-bias-instability": _F(
        "imu.accel_bias_instability", "ug", "Gauss-Markov accelerometer bias, 1 sigma"
    ),
    "gyro-correlation-time": _F(
        "imu.gyro_correlation_time", "s", "correlation time of the Gauss-Markov gyro bias"
    ),
    "accel-correlation-time": _F(
        "imu.accel_correlation_time",
        "s",
        "correlation time of the Gauss-Markov accelerometer bias",
    ),
    "sample-rate": _F("imu.sample_rate", "Hz", "IMU sample rate of simulated data"),
    # [initial]
    "initial-attitude": _F(
        "initial.attitude",
        "arcsec",
        "initial attitude error: E,N,U (tilts, heading); align: also the prior 1 sigma",
    ),
    "initial-velocity": _F("initial.velocity", "m/s", "initial velocity error: one value or E,N,U"),
    "initial-position": _F("initial.position", "m", "initial position error: one value or E,N,U"),
    # [motion]
    "heading-convention": _F(
        "motion.heading_convention",
        None,
        "sense of --heading, --turn-rate, --yaw-swing, heading histories and the mounting heading",
    ),
    "heading": _F("motion.heading", "deg", "vehicle heading from north (see --heading-convention)"),
    "pitch": _F("motion.pitch", "deg", "vehicle pitch"),
    "roll": _F("motion.roll", "deg", "vehicle roll"),
    "turn-rate": _F("motion.rate", "deg/s", "turn on the spot at this constant heading rate"),
    "yaw-swing": _F(
        ("motion.amplitude", "motion.period"),
        "deg/s,s",
        "swinging base: heading rate AMP cos(2 pi t / PERIOD), AMP in deg/s, PERIOD in s",
        "AMP,PERIOD",
    ),
    # [scheme], [compare]
    "scheme": _F("scheme.name", None, "indexing scheme", "NAME"),
    "schemes": _F("compare.schemes", None, "schemes to run side by side, comma-separated", "A,B"),
    "rate": _F("scheme.rate", "deg/s", "table rate"),
    "stop": _F("scheme.stop", "s", "stop (dwell) time at each position"),
    "start": _F("scheme.start", None, "opening phase: a stop at the first position, or a turn"),
    "reversal": _F("scheme.reversal", "s", "reversal period of the continuous scheme (0 = never)"),
    "delta": _F("scheme.delta", None, "stop threshold of the flexible scheme"),
    "variant": _F("scheme.variant", None, "variant of the flexible scheme"),
    "phase": _F("scheme.phase", None, "phase rule of the nulling scheme"),
    # [output]
    "step": _F("output.step", "s", "output step of the deterministic run"),
    "covariance-step": _F("output.covariance_step", "s", "output step of covariance results"),
    "export-step": _F(
        "output.export_step", "s", "row step of the exported time series (timeseries.csv)"
    ),
    "substep": _F("output.substep", "s", "sub-step of continuous motion"),
    "vertical": _F("output.vertical", None, "vertical channel"),
    "engine": _F("output.engine", None, "drift engine: fast, or exact (step by step, reference)"),
    # [alignment]
    "zupt-rate": _F("alignment.zupt_rate", "Hz", "zero-velocity update rate"),
    "zupt-sigma": _F("alignment.zupt_sigma", "m/s", "zero-velocity measurement 1 sigma"),
    "position-sigma": _F(
        "alignment.position_sigma", "m", "position updates at the update rate with this 1 sigma"
    ),
    # [observability]
    "headings": _F(
        "observability.headings",
        "deg",
        "IMU headings: comma-separated, one stop each instead of a scheme",
        "H1,H2",
    ),
    "model": _F(
        "observability.model",
        None,
        "observability model (auto = alignment10 with headings, full with a scheme)",
    ),
    "position-updates": _F(
        "observability.position_updates", None, "position measurements too (full model)"
    ),
    # [calibration]
    "method": _F(
        "calibration.method",
        None,
        "position set: offaxis-four-position, six-position or a .toml position-set file",
        "SET",
    ),
    "settle": _F("calibration.settle", "s", "settling time after every move"),
    "positioning-error": _F(
        "calibration.positioning_error",
        "arcsec",
        "half-width of the uniform positioning error at every stop",
    ),
    "positioning-model": _F(
        "calibration.positioning_model",
        None,
        "positioning error: about east, north and up (three-axis) or of the two gimbal angles",
    ),
    "per-sample": _F(
        "calibration.per_sample",
        None,
        "simulate every sample and average (default: draw the exact dwell average)",
    ),
    "design": _F(
        "calibration.design", None, "rank candidate position sets instead of a Monte Carlo"
    ),
    "design-sizes": _F(
        "calibration.design_sizes", None, "numbers of positions to try, comma-separated", "N,M"
    ),
    "design-sensors": _F("calibration.design_sensors", None, "what must be identifiable"),
    "design-step": _F("calibration.design_step", "deg", "gimbal step of the candidate sets"),
    "top": _F("calibration.top", None, "candidate sets shown", "N"),
    # [northfinder]
    "filter-period": _F("northfinder.filter_period", "s", "Kalman filter period"),
    "gyro-tilt": _F("northfinder.gyro_tilt", "deg", "gyro tilt toward the rotation axis"),
    "accel-azimuth": _F(
        "northfinder.accel_azimuth", "deg", "accelerometer azimuth from the gyro axis"
    ),
    "accel-tilt": _F(
        "northfinder.accel_tilt", "deg", "accelerometer tilt toward the rotation axis"
    ),
    "latitude-known": _F(
        "northfinder.latitude_known",
        None,
        "give the estimator the true latitude (the hemisphere is then not used)",
    ),
    "hemisphere": _F(
        "northfinder.hemisphere",
        None,
        "hemisphere declared to the estimator (never taken from the true latitude)",
    ),
    # [validate]
    "chunk": _F("validate.chunk", "h", "chunk length of the nonlinear reference (bounds memory)"),
    "confidence": _F(
        "validate.confidence", None, "confidence of the two-sided chi-square consistency test"
    ),
    "random-constants": _F(
        "validate.random_constants",
        None,
        "the Monte Carlo also draws the constant errors (zero mean, 1 sigma = magnitude)",
    ),
    # [sweep]
    "param": _F(
        "sweep.parameters",
        None,
        "a swept parameter (repeat for a grid): a flag name (bare numbers take its unit: "
        "stop=60,300) or a dotted scenario key (values with units: 'scheme.stop=60 s,5 min'); "
        "x,y,z or AMP,PERIOD values in brackets: gyro-bias=[0.01,0.02,0.03],0.02",
        "NAME=V1,V2,...",
    ),
    # [design]
    "family": _F("design.family", None, "schedules searched"),
    "motions": _F("design.motions", None, "motion set designed for"),
    "budget": _F("design.budget", None, "feasible candidates the optimizer evaluates", "N"),
    "max-starts": _F(
        "design.max_starts", None, "motor starts per hour at most: none = the two-position cycle's"
    ),
    "held-out": _F("design.held_out", None, "random motions drawn for the robustness check", "N"),
}

#: Flags that say how or where to run, not what: they override no scenario key.
CONTROLS: dict[str, str] = {
    "out": "output directory",
    "json": "print JSON on stdout",
    "scheduler": "Dask scheduler of a sweep or a design",
    "workers": "local worker processes of a sweep or a design",
    "no-plots": "no summary plots for a sweep",
}

#: The flags of ``inserr imu-budget``, the one command that reads a recording, not a
#: scenario: they describe the file and the fit and set no scenario key. ``--rate`` is
#: there the recording's sample rate (Hz), as issue 16 spells the command.
RECORDING_FLAGS: dict[str, str] = {
    "rate": "sample rate of the recording, Hz",
    "gyro-unit": "unit of the recording's gyro columns",
    "accel-unit": "unit of the recording's accelerometer columns",
    "confidence": "level of the fitted terms' confidence intervals",
}

#: Flags that repeat (each occurrence adds one list item).
REPEATED = frozenset({"param"})

# --- the flag groups the sub-commands offer ----------------------------------------------
SITE = ("lat", "lon", "height", "earth")
IMU_FLAGS = (
    "gyro-bias",
    "accel-bias",
    "gyro-sf",
    "accel-sf",
    "gyro-misalignment",
    "accel-misalignment",
    "arw",
    "vrw",
    "gyro-bias-instability",
    "accel-bias-instability",
    "gyro-correlation-time",
    "accel-correlation-time",
)
INITIAL = ("initial-attitude", "initial-velocity", "initial-position")
MOTION = ("heading-convention", "heading", "pitch", "roll", "turn-rate", "yaw-swing")
SCHEME = ("scheme", "rate", "stop", "start", "reversal", "delta", "variant", "phase")
OUTPUT = ("step", "covariance-step", "export-step", "substep", "vertical", "engine")
#: The scenario flags of ``drift`` (and ``compare``, ``validate``, ``sweep``).
DRIFT = ("duration", *SITE, *IMU_FLAGS, *INITIAL, *MOTION, *SCHEME, *OUTPUT)
#: The flags of ``design`` beyond :data:`DRIFT`.
DESIGN = ("seed", "family", "motions", "budget", "max-starts", "held-out")


def dest(name: str) -> str:
    """argparse destination of a flag (``gyro-bias`` -> ``gyro_bias``)."""
    return name.replace("-", "_")


def default_text(name: str, study: str = "drift") -> str | None:
    """The default of a flag as its help shows it (None: a switch that is off).

    Bare numbers when the default is written in the flag's unit (``0.003`` for
    ``--gyro-bias`` under ``align``), else the scenario value as written (``10 min``).
    """
    flag = FLAGS[name]
    if name == "yaw-swing":
        return None  # no swing unless asked (motion.type static)
    value = study_default(flag.keys[0], study)
    if isinstance(value, bool):
        return None if not value else "on"
    if value == []:
        return None  # an empty list: nothing is added
    if value is None:
        return "none"
    if isinstance(value, list):
        return ",".join(str(v) for v in value)
    if isinstance(value, str) and flag.unit and value.endswith(f" {flag.unit}"):
        return value[: -len(flag.unit) - 1].replace(" ", "")
    return str(value)


def help_text(name: str, study: str = "drift") -> str:
    """The ``--help`` line of a flag: what, unit, choices and the study's default."""
    flag = FLAGS[name]
    spec = flag.spec
    what, colon, form = flag.help.partition(": ")
    if flag.unit and name != "yaw-swing":
        what += f", {flag.unit}"
    elif spec.kind in UNITS and name != "yaw-swing":
        what += ", with its unit (e.g. 72h, 10min, 180s)"
    text = what + colon + form
    choices = CHOICES.get(flag.keys[0])
    if choices:
        text += f": {' | '.join(choices)}"
    default = default_text(name, study)
    if default is not None:
        text += f" (default {default})"
    return text


def add_flags(
    parser: argparse.ArgumentParser,
    study: str,
    names: Iterable[str],
    *,
    scenario_file: bool = True,
) -> None:
    """Add the flags ``names`` of :data:`FLAGS` (all optional) and a positional scenario file.

    Every flag's argparse default is None (a switch's too), so that what the user gave
    is known and an absent flag leaves the scenario's value (file or default) alone.

    Parameters
    ----------
    parser : argparse.ArgumentParser
    study : str
        Whose defaults the help shows (a key of
        :data:`inserr.scenario.schema.STUDY_DEFAULTS`).
    names : iterable of str
        Flag names without dashes.
    scenario_file : bool
        Add the optional positional ``scenario`` (a TOML file the flags override).
    """
    if scenario_file:
        parser.add_argument("scenario", nargs="?", help="scenario TOML file (flags override it)")
    for name in names:
        flag = FLAGS[name]
        kw: dict[str, Any] = {"dest": dest(name), "default": None, "help": help_text(name, study)}
        if flag.spec.kind == "bool":
            kw["action"] = "store_true"
        else:
            choices = CHOICES.get(flag.keys[0])
            kw["metavar"] = "{" + ",".join(choices) + "}" if choices else flag.metavar
            if name in REPEATED:
                kw["action"] = "append"
        parser.add_argument(f"--{name}", **kw)


def _with_unit(text: str, unit: str | None) -> str:
    """Append the flag's unit to bare numbers (``"0.02"``, ``"1,2,3"``, ``"nan"``)."""
    text = text.strip()
    if unit is None:
        return text
    try:
        [float(v) for v in text.split(",")]
    except ValueError:
        return text  # the user wrote a unit (or garbage, which the parser will name)
    return f"{text} {unit}"


def _split(text: str) -> list[str]:
    return [s.strip() for s in str(text).split(",") if s.strip()]


def _flag_value(name: str, value: Any) -> Any:
    """A flag's text as the scenario file would hold the value of its key."""
    flag = FLAGS[name]
    key, kind = flag.keys[0], flag.spec.kind
    where = f"--{name} ({key})"
    if kind == "bool":
        return bool(value)
    if kind == "int":
        try:
            return int(str(value).strip())
        except ValueError:
            raise InputError(where, f"{value!r} is not an integer", "give a whole number") from None
    if kind == "float":
        try:
            return float(str(value).strip())
        except ValueError:
            raise InputError(where, f"{value!r} is not a number") from None
    if kind in ("list", "int-list") and name not in REPEATED:
        # "a,,b" or a trailing comma: refuse rather than silently drop (or run the
        # base scheme for) the empty item.
        if any(not s.strip() for s in str(value).split(",")):
            raise InputError(where, f"empty item in {value!r}", "remove the extra comma")
    if kind == "list":
        return list(value) if name in REPEATED else _split(value)
    if kind == "int-list":
        try:
            return [int(v) for v in _split(value)]
        except ValueError:
            raise InputError(
                where, f"cannot read {value!r}", "give whole numbers, e.g. 4,5,6"
            ) from None
    if kind == "str":
        return str(value).strip()
    return _with_unit(str(value), flag.unit)


def flags_to_dict(args: argparse.Namespace, names: Iterable[str] | None = None) -> dict:
    """Nested scenario table of the flags that were given (of ``names``, default all)."""
    d: dict[str, dict] = {}
    for name in FLAGS if names is None else names:
        value = getattr(args, dest(name), None)
        if value is None or value is False:
            continue
        if name == "yaw-swing":
            parts = str(value).split(",")
            if len(parts) != 2:
                raise InputError(
                    "--yaw-swing", f"expected AMP,PERIOD, got {value!r}", "e.g. --yaw-swing 6,120"
                )
            m = d.setdefault("motion", {})
            if m.get("type") == "turn":
                raise InputError("--yaw-swing", "cannot be combined with --turn-rate")
            m["type"] = "yaw-swing"
            m["amplitude"] = _with_unit(parts[0], "deg/s")
            m["period"] = _with_unit(parts[1], "s")
            continue
        section, _, key = FLAGS[name].keys[0].partition(".")
        d.setdefault(section, {})[key] = _flag_value(name, value)
        if name == "turn-rate":
            if d["motion"].get("type") == "yaw-swing":
                raise InputError("--yaw-swing", "cannot be combined with --turn-rate")
            d["motion"]["type"] = "turn"
    return d


def merge(base: dict, over: dict) -> dict:
    """Section-wise merge of two nested scenario tables (``over`` wins)."""
    for k, v in base.items():
        if not isinstance(v, dict):  # ``site = "x"``: validated here, before the merge
            raise InputError(k, "must be a table ([section])", f"write [{k}] and its keys")
    out = {k: dict(v) for k, v in base.items()}
    _drop_replaced_options(out, over)
    for section, table in over.items():
        out.setdefault(section, {}).update(table)
    return out


def _drop_replaced_options(base: dict, over: dict) -> None:
    """A flag that replaces the file's scheme or motion type replaces its options too.

    The file's ``[[scheme.steps]]`` belong to its custom scheme; under ``--scheme
    four-position`` they are dropped rather than refused as keys the scheme ignores
    (which they are in a file that names a scheme that does not read them).
    """
    from inserr.scenario.schema import _MOTION_KEY_TYPES, _SCHEME_OPTION_KEYS, _options_for

    name = over.get("scheme", {}).get("name")
    sch = base.get("scheme", {})
    if name is not None and name != sch.get("name"):
        for key, opt in _SCHEME_OPTION_KEYS.items():
            if key not in over.get("scheme", {}) and opt not in _options_for(name, {opt: 1}):
                sch.pop(key, None)
    kind = over.get("motion", {}).get("type")
    mo = base.get("motion", {})
    if kind is not None and kind != mo.get("type"):
        for key, needs in _MOTION_KEY_TYPES.items():
            if key not in over.get("motion", {}) and needs != kind:
                mo.pop(key, None)


def scenario_from_args(args: argparse.Namespace, study: str = "drift") -> Scenario:
    """Scenario of the optional file argument overlaid with the flags, for ``study``.

    The file is read, the flags laid over it, and the result validated once, so a
    flag may repair a value the file gets wrong. Errors name scenario keys;
    :func:`name_the_flag` adds the flag where the value came from one.
    """
    over = flags_to_dict(args)
    path = getattr(args, "scenario", None)
    if not path:
        return scenario_from_dict(over, study=study)
    data, base_dir = read_scenario_file(path)
    return scenario_from_dict(merge(data, over), base_dir, study=study)


def given_flags(args: argparse.Namespace) -> dict[str, str]:
    """Scenario key -> the flag (``--lat``) that set it, for the flags given in ``args``."""
    out: dict[str, str] = {}
    for name, flag in FLAGS.items():
        value = getattr(args, dest(name), None)
        if value is None or value is False:
            continue
        keys = flag.keys
        if name in ("yaw-swing", "turn-rate"):
            keys += ("motion.type",)
        for key in keys:
            out[key] = f"--{name}"
    return out


def name_the_flag(exc: InputError, args: argparse.Namespace) -> InputError:
    """``exc`` with the flag added to its field when the value came from a flag.

    ``imu.arw: ...`` becomes ``--arw (imu.arw): ...`` if ``--arw`` was given, and
    ``sweep.parameters[stop]: ...`` becomes ``--param (sweep.parameters[stop]): ...``;
    an error about a value from the scenario file (or a default) is left as it is.
    """
    field = exc.field
    for key, flag in given_flags(args).items():
        if field == key or field.startswith(key + "["):
            return InputError(f"{flag} ({field})", exc.problem, exc.fix)
    # Run controls (sweep's scheduler and workers) have no scenario key: the library
    # names its argument, which is the flag's name.
    name = field.replace("_", "-")
    if name in CONTROLS and getattr(args, dest(name), None) is not None:
        return InputError(f"--{name}", exc.problem, exc.fix)
    return exc
