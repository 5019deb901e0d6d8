"""Scenario: the one validated input of every study — TOML or dict, units at the edges.

* ``schema`` — the scenario schema, :func:`~inserr.scenario.schema.load_scenario`,
  :func:`~inserr.scenario.schema.scenario_from_dict` and :class:`~inserr.scenario.schema.Scenario`.
* ``flags`` — the flag vocabulary: every command-line flag as an override of a scenario key.
"""

from inserr.core.lazy import lazy_exports

__getattr__, __dir__ = lazy_exports(
    __name__,
    {
        "Scenario": "inserr.scenario.schema",
        "load_scenario": "inserr.scenario.schema",
        "scenario_from_dict": "inserr.scenario.schema",
    },
)

__all__ = ["Scenario", "load_scenario", "scenario_from_dict"]
