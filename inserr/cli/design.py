"""``inserr design``: search a family of schedules for the one robust to the vehicle's motion.

The scenario (file and/or the flags of ``inserr drift``) gives the site, the IMU
budget, the vehicle and the table; its ``[design]`` section the family, the motion
set, the objective, the constraints and the optimizer (``docs/design.md``). Runs on
Dask: local processes by default, ``--scheduler tcp://HOST:PORT`` for a cluster.
Rerunning with the same ``--out`` resumes (every evaluation is kept there).
"""

from __future__ import annotations

import argparse

from inserr.cli.common import add_dask_flags, add_json_flag, emit, format_table
from inserr.scenario.flags import DESIGN, DRIFT, add_flags, scenario_from_args


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Add the arguments of ``inserr design`` to its parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The ``design`` sub-command's parser.
    """
    add_flags(p, "drift", (*DRIFT, *DESIGN))
    add_dask_flags(p)
    p.add_argument(
        "--out",
        default=None,
        metavar="DIR",
        help="design directory; rerunning with the same DIR resumes from its evaluations "
        "(default design-<scenario file name>)",
    )
    add_json_flag(p)


def run(args: argparse.Namespace) -> int:
    """Run ``inserr design`` and print the comparison.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments (:func:`add_arguments`).

    Returns
    -------
    int
        0, or 1 when nothing met the constraints or an evaluation failed.
    """
    import sys

    from inserr.design.study import DesignFailed, check_design_dir, default_out_dir, run_design

    scen = scenario_from_args(args)
    out = args.out or default_out_dir(scen, getattr(args, "scenario", None))
    check_design_dir(out, "--out")
    try:
        res = run_design(scen, out_dir=out, scheduler=args.scheduler, workers=args.workers)
    except DesignFailed as exc:
        print(f"inserr design: failed: {exc}", file=sys.stderr)
        return 1
    emit(args, _json(res), _human(res))
    return 0


def _json(res) -> dict:
    r = dict(res.results)
    r["out"] = str(res.out_dir) if res.out_dir else None
    r["files"] = [str(p) for p in res.files]
    return r


def _human(res) -> str:
    r = res.results
    rows = []
    entries = ([r["chosen"]] if r["chosen"] else []) + r["catalogue"]
    for e in sorted(entries, key=lambda e: e["worst_nmi"]):
        name = ("designed: " if e is r["chosen"] else "") + e["label"]
        rows.append(
            [
                name[:48],
                e["worst_nmi"],
                e["mean_nmi"],
                e.get("held_out_worst_nmi", ""),
                e["starts_per_hour"],
                "yes" if e["meets_constraints"] else "no",
            ]
        )
    st = res.settings
    lines = [
        f"design of {st.family.name} schedules: {len(st.motions)} motions, "
        f"{len(st.held_out)} held out, {res.search.message.lower()}",
        format_table(
            ["scheme", "worst RMS (nmi)", "mean RMS (nmi)", "held-out worst", "starts/h", "ok"],
            rows,
        ),
        "",
        f"chosen: {r['chosen']['label'] if r['chosen'] else 'none'}",
        f"{res.seconds:.0f} s, {res.computed} motion evaluations computed, {res.cached} in the "
        f"cache at the start ({res.engine})",
    ]
    lines += [f"wrote {p}" for p in res.files]
    return "\n".join(lines)
