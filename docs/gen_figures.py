"""Figures of the scheme catalogue: table angle and horizontal projection of C_s^n against time.

The documentation build runs this module: the mkdocs hook ``docs/hooks.py`` calls
:func:`scheme_figures` and adds the PNG files to the site in memory, so no binary
figure is committed and every figure is redrawn from the code of its scheme. To
look at them outside the site::

    python docs/gen_figures.py OUT_DIR
"""

from __future__ import annotations

import sys
from pathlib import Path

from inserr.drift import figures as plots
from inserr.output.figure_style import png_bytes
from inserr.scenario.schema import Scenario, scenario_from_dict
from inserr.schemes.catalogue import SCHEMES

#: Table rate and stop of every catalogue figure (short stops keep two cycles readable).
RATE = "6 deg/s"
STOP = "60 s"
#: Closed-loop schemes only differ from their open-loop parents on a yawing vehicle.
CLOSED_LOOP = ("flexible-two-position", "heading-isolation", "nulling-two-position")
SWING = {"type": "yaw-swing", "amplitude": "6 deg/s", "period": "120 s"}
#: The custom example: a three-position azimuth table (120 deg steps and back).
CUSTOM_STEPS = [
    {"gimbal": "outer", "angle": "120 deg", "dwell": STOP, "label": "B"},
    {"gimbal": "outer", "angle": "120 deg", "dwell": STOP, "label": "C"},
    {"gimbal": "outer", "angle": "-240 deg", "dwell": STOP, "label": "A"},
]
#: Shown duration: two cycles, within these bounds (s).
MIN_SPAN, MAX_SPAN = 600.0, 3000.0


def figure_scenario(name: str) -> Scenario:
    """The scenario drawn for scheme ``name`` (static base, or a yaw swing for closed loops)."""
    scheme = {"name": name, "rate": RATE, "stop": STOP}
    if name == "custom":
        scheme["steps"] = CUSTOM_STEPS
    data = {"scheme": scheme, "scenario": {"duration": "1 h"}}
    if name in CLOSED_LOOP:
        data["motion"] = SWING
    base = scenario_from_dict(data)
    cycle = getattr(base.scheme(), "cycle_time", None)
    span = MIN_SPAN if cycle is None else min(max(2.0 * cycle, MIN_SPAN), MAX_SPAN)
    return base.with_changes({"scenario.duration": f"{span:g} s"})


def scheme_figure(name: str) -> bytes:
    """PNG of the table angle and the horizontal projection for scheme ``name``."""
    scen = figure_scenario(name)
    where = (
        f"yaw swing {SWING['amplitude']} peak, period {SWING['period']}"
        if name in CLOSED_LOOP
        else "static base"
    )
    return png_bytes(
        plots.table_angle(scen.timeline(), title=f"{name}: {RATE}, stops {STOP}, {where}")
    )


def scheme_figures() -> dict[str, bytes]:
    """``figures/schemes/<name>.png`` -> PNG, one per :data:`inserr.schemes.catalogue.SCHEMES`."""
    return {f"figures/schemes/{name}.png": scheme_figure(name) for name in SCHEMES}


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print("usage: python docs/gen_figures.py OUT_DIR", file=sys.stderr)
        return 2
    out = Path(argv[0])
    for rel, png in scheme_figures().items():
        path = out / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(png)
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
