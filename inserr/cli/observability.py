"""``inserr observability``: piecewise-constant observability of zero-velocity alignment.

Two ways to give the segments (an ``alignment`` scenario: file and/or flags, see
:func:`inserr.alignment.inputs.observability_system`):

* ``--headings H1,H2,...``: one stop of ``--stop`` seconds per heading of a level IMU
  turned about the vertical (instantaneous turns). ``--model alignment10`` (the
  default, ``auto``, with headings) is the classic 10-state model; ``--model full``
  the core 15-state model.
* ``--scheme NAME``: the intervals of an indexing scheme running for ``--duration`` on
  the given base (stops and table turns, or a swinging base); always the full model.
"""

from __future__ import annotations

import argparse

from inserr.cli.common import add_json_flag, emit, format_table
from inserr.scenario.flags import MOTION, add_flags, scenario_from_args

#: The flags of ``inserr observability``.
FLAG_NAMES = (
    "lat",
    "height",
    "headings",
    "model",
    "position-updates",
    "scheme",
    "duration",
    "rate",
    "stop",
    "vertical",
    *MOTION,
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    add_flags(p, "alignment", FLAG_NAMES)
    add_json_flag(p)


def run(args: argparse.Namespace) -> int:
    from inserr.alignment.inputs import observability_system
    from inserr.alignment.observability import TYPICAL, analyze

    system, extra = observability_system(scenario_from_args(args, "alignment"))
    res = analyze(system, extra={**extra, "typical_magnitudes_si": dict(TYPICAL)})
    out = res.to_dict()
    s = res.singular_values
    rows = [[i + 1, float(v), float(v / s[0]) if s[0] > 0 else 0.0] for i, v in enumerate(s)]
    human = (
        f"{res.description}\n"
        f"rank {res.rank} of {res.n_states} (tolerance {res.tolerance:.3g}; gap {res.gap:.3g})\n"
        + format_table(["order", "singular value", "relative"], rows)
        + "\n\nunobservable:\n"
        + ("\n".join(f"  {u}" for u in res.unobservable) if res.unobservable else "  none")
    )
    emit(args, out, human)
    return 0
