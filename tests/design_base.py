"""The design problem in small, shared by the designer's tests: P0's IMU budget and tilted
swinging vehicle over 2 h (each test file adds its own ``scenario`` and ``design``)."""

from __future__ import annotations

import json

P0_TINY = {
    "site": {"latitude": "34.246 deg"},
    "imu": {
        "gyro_bias": "0.003 deg/h",
        "accel_bias": "30 ug",
        "gyro_scale_factor": "10 ppm",
        "gyro_misalignment": "10 arcsec",
        "accel_misalignment": "10 arcsec",
    },
    "initial": {"attitude": "10,10,60 arcsec"},
    "motion": {
        "type": "yaw-swing",
        "heading": "15 deg",
        "pitch": "1 deg",
        "roll": "-2 deg",
        "amplitude": "6 deg/s",
        "period": "120 s",
    },
    "scheme": {"name": "two-position", "rate": "6 deg/s", "stop": "300 s"},
    "output": {"covariance_step": "60 s"},
}


#: The search in small: two swing periods, four stops, a few candidates.
TINY_DESIGN = {
    "periods": "45, 330 s",
    "amplitudes": "6 deg/s",
    "stops": 4,
    "budget": 18,
    "population": 6,
    "held_out": 2,
}


def make_scenario(base: dict, duration: str | None = None, **design):
    """The scenario ``base`` with ``design`` keys changed (and the duration)."""
    from inserr.scenario.schema import scenario_from_dict

    data = json.loads(json.dumps(base))
    data["design"].update(design)
    if duration:
        data["scenario"]["duration"] = duration
    return scenario_from_dict(data)


def comparable(results: dict) -> dict:
    """A design's results without what depends on the run (times, cache counts, engine)."""
    r = json.loads(json.dumps(results))
    for k in ("seconds", "motion_evaluations_computed", "evaluations_in_cache_at_start", "engine"):
        r.pop(k)
    for g in r["search"]["generations"]:
        g.pop("seconds")
        g.pop("motion_evaluations")
    return r


def p0_tiny(scenario: dict, design: dict) -> dict:
    """A fresh copy of :data:`P0_TINY` with these ``scenario`` and ``design`` sections."""
    data = json.loads(json.dumps(P0_TINY))
    return {"scenario": scenario, **data, "design": design}


def run_interrupted(monkeypatch, scen, out, after: int) -> None:
    """Run the design of ``scen`` into ``out`` and stop it, as Ctrl-C would, once
    ``after`` evaluations are stored in its cache."""
    import pytest

    from inserr.design import study
    from inserr.design.cache import EvaluationCache

    put = EvaluationCache.put
    count = {"n": 0}

    def interrupting(self, key, record):
        put(self, key, record)
        count["n"] += 1
        if count["n"] == after:
            raise KeyboardInterrupt

    monkeypatch.setattr(EvaluationCache, "put", interrupting)
    try:
        with pytest.raises(KeyboardInterrupt):
            study.run_design(scen, out_dir=out, scheduler="sync")
    finally:
        monkeypatch.setattr(EvaluationCache, "put", put)
