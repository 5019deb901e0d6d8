"""Scenario files (TOML with explicit units) and the one validation path for all inputs.

A scenario is a nested table of sections (``scenario``, ``site``, ``imu``,
``initial``, ``motion``, ``scheme``, ``output``, ``compare``). Physical values are
strings carrying their unit (``gyro_bias = "0.02 deg/h"``, ``"0.01,0.02,0.03 deg/h"``
for the three IMU axes). CLI flags are translated into the same nested table (with
their documented units) and go through :func:`scenario_from_dict` too, so a flag
and a scenario key are validated by the same code. Reference: ``docs/scenarios.md``.
"""

from __future__ import annotations

import copy
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from inserr.core.earth import Site
from inserr.core.errors import InputError
from inserr.core.imu import ImuErrors, InitialErrors
from inserr.core.units import DEG, parse_quantity
from inserr.schemes.vehicle_motion import HeadingHistory, Motion, Turn, YawSwing

#: Largest number of samples (or sub-step segments) one run keeps in memory.
MAX_SAMPLES = 3_000_000

#: Schema: section -> key -> (kind, size, default). kind is a units kind, or
#: "str", "float", "list", "table-list". size: None = scalar, 3 = axes, 6 = misalignments.
SCHEMA: dict[str, dict[str, tuple[str, int | None, Any]]] = {
    "scenario": {
        "name": ("str", None, "scenario"),
        "duration": ("time", None, "72 h"),
        "seed": ("int", None, 0),
    },
    "site": {
        "latitude": ("angle", None, "34 deg"),
        "longitude": ("angle", None, "0 deg"),
        "height": ("length", None, "0 m"),
        "earth": ("str", None, "ellipsoid"),
    },
    "imu": {
        "gyro_bias": ("angular_rate", 3, "0 deg/h"),
        "accel_bias": ("acceleration", 3, "0 ug"),
        "gyro_scale_factor": ("ratio", 3, "0 ppm"),
        "accel_scale_factor": ("ratio", 3, "0 ppm"),
        "gyro_misalignment": ("angle", 6, "0 arcsec"),
        "accel_misalignment": ("angle", 6, "0 arcsec"),
        "arw": ("arw", None, "0 deg/sqrt(h)"),
        "vrw": ("vrw", None, "0 ug/sqrt(Hz)"),
        "gyro_bias_instability": ("angular_rate", None, "0 deg/h"),
        "accel_bias_instability": ("acceleration", None, "0 ug"),
        "gyro_correlation_time": ("time", None, "1 h"),
        "accel_correlation_time": ("time", None, "1 h"),
    },
    "initial": {
        "attitude": ("angle", 3, "0 arcsec"),
        "velocity": ("velocity", 3, "0 m/s"),
        "position": ("length", 3, "0 m"),
    },
    "motion": {
        "type": ("str", None, "static"),
        "heading": ("angle", None, "0 deg"),
        "pitch": ("angle", None, "0 deg"),
        "roll": ("angle", None, "0 deg"),
        "amplitude": ("angular_rate", None, "0 deg/s"),
        "period": ("time", None, "60 s"),
        "rate": ("angular_rate", None, "0 deg/s"),
        "file": ("str", None, ""),
    },
    "scheme": {
        "name": ("str", None, "none"),
        "rate": ("angular_rate", None, "6 deg/s"),
        "stop": ("time", None, "300 s"),
        "reversal": ("time", None, "0 s"),
        "delta": ("float", None, 0.01),
        "variant": ("str", None, "threshold"),
        "decision_rate": ("frequency", None, "100 Hz"),
        "mounting": ("angle", 3, "0 deg"),
        "steps": ("table-list", None, []),
    },
    "output": {
        "step": ("time", None, "1 s"),
        "covariance_step": ("time", None, "60 s"),
        "substep": ("time", None, "1 s"),
        "vertical": ("str", None, "clamped"),
        "engine": ("str", None, "fast"),
    },
    "compare": {
        "schemes": ("list", None, []),
    },
}

MOTION_TYPES = ("static", "yaw-swing", "turn", "heading-history")
STEP_KEYS = {
    "gimbal": "str",
    "angle": "angle",
    "dwell": "time",
    "rotation_time": "time",
    "label": "str",
}


@dataclass(frozen=True)
class Scenario:
    """A validated scenario (SI units inside).

    Use :meth:`timeline` to get the IMU attitude history of its scheme (or of any
    scheme name, for comparisons).
    """

    name: str
    duration: float
    seed: int
    site: Site
    imu: ImuErrors
    init: InitialErrors
    motion: Motion
    scheme_name: str
    scheme_rate: float
    scheme_stop: float
    scheme_options: dict
    dt_out: float
    dt_cov: float
    substep: float
    vertical: str
    compare: tuple[str, ...]
    engine: str
    raw: dict = field(compare=False, repr=False)
    base_dir: Path | None = field(default=None, compare=False, repr=False)

    def scheme(self, name: str | None = None):
        """The scheme object (``name`` overrides the scenario's scheme)."""
        from inserr.schemes.catalogue import build_scheme

        name = name or self.scheme_name
        opts = dict(self.scheme_options)
        if name != self.scheme_name:
            opts = {k: v for k, v in opts.items() if k == "mounting"}
        return build_scheme(name, self.scheme_rate, self.scheme_stop, **_options_for(name, opts))

    def timeline(self, name: str | None = None):
        """The :class:`~inserr.model.timeline.Timeline` of the scenario's (or ``name``'s) scheme."""
        from inserr.schemes.composition import build_timeline

        table = self.scheme(name).plan(self.motion, self.duration)
        return build_timeline(table, self.motion, self.duration, self.substep)

    def history(self, name: str | None = None):
        """The exact IMU attitude history of the scenario's (or ``name``'s) scheme.

        A :class:`~inserr.schemes.composition.ScheduleHistory`: the table schedule of the
        scheme composed with the vehicle motion, without sub-steps.
        """
        from inserr.schemes.composition import ScheduleHistory

        return ScheduleHistory(
            self.scheme(name).plan(self.motion, self.duration), self.motion, self.duration
        )

    def with_changes(self, changes: dict[str, Any]) -> Scenario:
        """A new scenario with dotted keys replaced (e.g. ``{"scheme.stop": "60 s"}``)."""
        raw = copy.deepcopy(self.raw)
        for key, value in changes.items():
            section, _, name = key.partition(".")
            if section not in SCHEMA or name not in SCHEMA[section]:
                raise InputError(
                    key, "unknown scenario key", f"use one of: {', '.join(all_keys())}"
                )
            raw.setdefault(section, {})[name] = value
        return scenario_from_dict(raw, self.base_dir)


def all_keys() -> list[str]:
    """Every dotted scenario key."""
    return [f"{s}.{k}" for s, keys in SCHEMA.items() for k in keys]


def _options_for(name: str, opts: dict) -> dict:
    keep = {"mounting"}
    if name == "continuous":
        keep |= {"reversal"}
    if name in ("flexible-two-position", "nulling-two-position"):
        keep |= {"delta", "variant", "f"}
    if name == "custom":
        keep |= {"steps"}
    return {k: v for k, v in opts.items() if k in keep}


def _value(section: str, key: str, raw: Any) -> Any:
    kind, size, _ = SCHEMA[section][key]
    fld = f"{section}.{key}"
    if kind == "str":
        if not isinstance(raw, str):
            raise InputError(fld, f"expected a string, got {raw!r}")
        return raw
    if kind == "int":
        if isinstance(raw, bool) or not isinstance(raw, int):
            raise InputError(fld, f"expected an integer, got {raw!r}")
        return raw
    if kind == "float":
        if isinstance(raw, bool) or not isinstance(raw, (int, float)) or not math.isfinite(raw):
            raise InputError(fld, f"expected a finite number, got {raw!r}")
        return float(raw)
    if kind == "list":
        if not isinstance(raw, list) or not all(isinstance(v, str) for v in raw):
            raise InputError(fld, f"expected a list of names, got {raw!r}")
        return tuple(raw)
    if kind == "table-list":
        if not isinstance(raw, list) or not all(isinstance(v, dict) for v in raw):
            raise InputError(fld, "expected an array of tables ([[scheme.steps]])")
        return raw
    if isinstance(raw, (int, float)) and not isinstance(raw, bool) and raw == 0:
        raw = f"0 {_first_unit(kind)}"  # a bare 0 needs no unit
    return parse_quantity(raw, kind, fld, size=size)


def _first_unit(kind: str) -> str:
    from inserr.core.units import units_for

    return units_for(kind)[0]


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario TOML file.

    Raises
    ------
    InputError
        Missing file, malformed TOML, unknown section/key, wrong unit, bad value.
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(str(path), "scenario file not found", "check the path")
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except UnicodeDecodeError as exc:
        raise InputError(
            str(path),
            f"not a UTF-8 text file (byte {exc.start}: {exc.reason})",
            "save the scenario as UTF-8 TOML",
        ) from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(
            str(path), f"malformed TOML ({exc})", "fix the syntax at that line"
        ) from None
    return scenario_from_dict(data, base_dir=p.parent)


def scenario_from_dict(data: dict, base_dir: Path | None = None) -> Scenario:
    """Validate a nested dict (parsed TOML or translated CLI flags) into a :class:`Scenario`."""
    raw: dict[str, dict[str, Any]] = {}
    for section, table in data.items():
        if section not in SCHEMA:
            raise InputError(
                section, "unknown scenario section", f"use one of: {', '.join(SCHEMA)}"
            )
        if not isinstance(table, dict):
            raise InputError(section, "must be a table ([section])")
        for key in table:
            if key not in SCHEMA[section]:
                raise InputError(
                    f"{section}.{key}",
                    "unknown scenario key",
                    f"use one of: {', '.join(SCHEMA[section])}",
                )
        raw[section] = dict(table)
    v: dict[str, dict[str, Any]] = {}
    for section, keys in SCHEMA.items():
        v[section] = {}
        for key, (_, _, default) in keys.items():
            given = raw.get(section, {}).get(key, default)
            v[section][key] = _value(section, key, given)

    sc, si, im, ini, mo, sh, out = (
        v[k] for k in ("scenario", "site", "imu", "initial", "motion", "scheme", "output")
    )
    duration = sc["duration"]
    if duration <= 0:
        raise InputError(
            "scenario.duration", f"must be > 0, got {duration / 3600:g} h", "give e.g. 72 h"
        )
    if si["earth"] not in ("ellipsoid", "spherical"):
        raise InputError(
            "site.earth", f"unknown Earth model {si['earth']!r}", "use ellipsoid or spherical"
        )
    try:
        site = Site(
            si["latitude"], si["longitude"], si["height"], spherical=si["earth"] == "spherical"
        )
    except InputError as exc:
        raise InputError(f"site.{exc.field}", exc.problem, exc.fix) from None
    try:
        imu = ImuErrors(
            gyro_bias=im["gyro_bias"],
            accel_bias=im["accel_bias"],
            gyro_scale_factor=im["gyro_scale_factor"],
            accel_scale_factor=im["accel_scale_factor"],
            arw=im["arw"],
            vrw=im["vrw"],
            gyro_bias_instability=im["gyro_bias_instability"],
            accel_bias_instability=im["accel_bias_instability"],
            gyro_correlation_time=im["gyro_correlation_time"],
            accel_correlation_time=im["accel_correlation_time"],
            gyro_misalignment=im["gyro_misalignment"],
            accel_misalignment=im["accel_misalignment"],
        )
    except InputError as exc:
        raise InputError(f"imu.{exc.field}", exc.problem, exc.fix) from None
    init = InitialErrors(ini["attitude"], ini["velocity"], ini["position"])
    motion = _motion(mo, base_dir)
    motion.pieces(duration)  # a heading history shorter than the run fails here, early
    if sh["rate"] <= 0:
        raise InputError("scheme.rate", "table rate must be > 0", "give e.g. 6 deg/s")
    if sh["stop"] < 0:
        raise InputError("scheme.stop", "stop time must be >= 0", "give e.g. 300 s")
    for key in ("step", "covariance_step", "substep"):
        if out[key] <= 0:
            raise InputError(f"output.{key}", "must be > 0", "give e.g. 1 s")
    # The engine keeps every output sample (and, under continuous motion, every
    # sub-step segment) in memory: about 1.3 MB per hour at 1 s, so 30 days at 1 s
    # is ~1 GB. Refuse beyond that before any work, with the fix.
    grids = [("step", out["step"]), ("covariance_step", out["covariance_step"])]
    if not motion.is_static:
        grids.append(("substep", out["substep"]))
    for key, dt in grids:
        flag = "covariance-step" if key == "covariance_step" else key
        n = duration / dt
        if n > MAX_SAMPLES:
            raise InputError(
                f"output.{key}",
                f"{duration / 3600:g} h at {dt:g} s is {n:.3g} samples, more than the "
                f"{MAX_SAMPLES:.3g} kept in memory",
                f"use a coarser output.{key} (flag --{flag}) of at least "
                f"{math.ceil(duration / MAX_SAMPLES * 1000.0) / 1000.0:g} s, or a shorter duration",
            )
    if out["engine"] not in ("fast", "exact"):
        raise InputError("output.engine", f"unknown engine {out['engine']!r}", "use fast or exact")
    if out["vertical"] not in ("clamped", "free"):
        raise InputError(
            "output.vertical", f"unknown mode {out['vertical']!r}", "use clamped or free"
        )
    opts: dict[str, Any] = {
        "reversal": sh["reversal"],
        "delta": sh["delta"],
        "variant": sh["variant"],
        "f": sh["decision_rate"],
    }
    if np.any(sh["mounting"]):
        from inserr.core.rotations import body_to_nav

        m = sh["mounting"]
        opts["mounting"] = body_to_nav(m[0], m[1], m[2])
    if sh["steps"]:
        opts["steps"] = _steps(sh["steps"])
    scen = Scenario(
        name=sc["name"],
        duration=duration,
        seed=sc["seed"],
        site=site,
        imu=imu,
        init=init,
        motion=motion,
        scheme_name=sh["name"],
        scheme_rate=sh["rate"],
        scheme_stop=sh["stop"],
        scheme_options=opts,
        dt_out=out["step"],
        dt_cov=out["covariance_step"],
        substep=out["substep"],
        vertical=out["vertical"],
        compare=v["compare"]["schemes"],
        engine=out["engine"],
        raw=raw,
        base_dir=base_dir,
    )
    scen.scheme(scen.scheme_name)  # unknown scheme names fail here, before any work
    for name in scen.compare:
        try:
            scen.scheme(name)
        except InputError as exc:
            if "unknown scheme" not in exc.problem:
                raise
            raise InputError("compare.schemes", exc.problem, exc.fix) from None
    return scen


def _motion(mo: dict, base_dir: Path | None) -> Motion:
    kind = mo["type"]
    common = {"heading": mo["heading"], "pitch": mo["pitch"], "roll": mo["roll"]}
    if kind == "static":
        return Motion(**common)
    if kind == "yaw-swing":
        if mo["period"] <= 0:
            raise InputError("motion.period", "must be > 0 s")
        return YawSwing(**common, amplitude=mo["amplitude"], period=mo["period"])
    if kind == "turn":
        return Turn(**common, rate=mo["rate"])
    if kind == "heading-history":
        path = Path(mo["file"])
        if base_dir is not None and not path.is_absolute():
            path = base_dir / path
        if not mo["file"] or not path.is_file():
            raise InputError("motion.file", f"heading history file {str(path)!r} not found")
        try:
            arr = np.loadtxt(path, delimiter=",", comments="#", ndmin=2)
        except ValueError as exc:
            raise InputError(
                "motion.file", f"cannot read {path}: {exc}", "two columns: time_s, heading_deg"
            ) from None
        if arr.shape[1] != 2:
            raise InputError("motion.file", "needs two columns: time_s, heading_deg")
        return HeadingHistory(
            pitch=mo["pitch"], roll=mo["roll"], times=arr[:, 0], headings=np.unwrap(arr[:, 1] * DEG)
        )
    raise InputError(
        "motion.type", f"unknown motion {kind!r}", f"use one of: {', '.join(MOTION_TYPES)}"
    )


def _steps(rows: list[dict]):
    from inserr.schemes.open_loop import Step

    steps = []
    for i, row in enumerate(rows):
        fld = f"scheme.steps[{i}]"
        for key in row:
            if key not in STEP_KEYS:
                raise InputError(f"{fld}.{key}", "unknown step key", f"use: {', '.join(STEP_KEYS)}")
        for key in ("gimbal", "angle", "dwell"):
            if key not in row:
                raise InputError(f"{fld}.{key}", "missing")
        gimbal = row["gimbal"]
        if gimbal not in ("outer", "inner"):
            raise InputError(f"{fld}.gimbal", f"unknown gimbal {gimbal!r}", "use outer or inner")
        angle = parse_quantity(row["angle"], "angle", f"{fld}.angle")
        dwell = parse_quantity(row["dwell"], "time", f"{fld}.dwell")
        if dwell < 0:
            raise InputError(f"{fld}.dwell", "must be >= 0")
        rt = row.get("rotation_time")
        rt = parse_quantity(rt, "time", f"{fld}.rotation_time") if rt is not None else None
        if rt is not None and rt <= 0:
            raise InputError(f"{fld}.rotation_time", "must be > 0")
        steps.append(Step(gimbal, angle, dwell, rt, str(row.get("label", f"P{i + 1}"))))
    return steps
