"""``inserr sweep``: a Cartesian grid of scenario values, one drift analysis per point, on Dask.

The base scenario is a scenario file and/or the flags of ``inserr drift``;
``--param NAME=V1,V2,...`` (repeatable; or ``sweep.parameters`` in the file) names a
flag (``stop``, ``gyro-bias``) or a dotted scenario key (``scheme.stop``). The value
syntax is in :mod:`inserr.sweep.grid`.
"""

from __future__ import annotations

import argparse

from inserr.cli.common import add_dask_flags, add_json_flag, emit, format_table
from inserr.scenario.flags import DRIFT, add_flags, scenario_from_args

#: Columns of the terminal table after the parameters (all are in results.csv).
SHOWN = (
    ("max_horizontal_error_nmi", "max horiz (nmi)"),
    ("rms_horizontal_error_nmi", "RMS unknown signs (nmi)"),
    ("worst_case_horizontal_error_nmi", "worst signs (nmi)"),
    ("motor_starts_per_hour", "motor starts/h"),
)
#: Above this many points the terminal shows the best points only.
MAX_ROWS = 40


def add_arguments(p: argparse.ArgumentParser) -> None:
    """Add the arguments of ``inserr sweep`` to its parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The ``sweep`` sub-command's parser.
    """
    add_flags(p, "drift", (*DRIFT, "param"))
    add_dask_flags(p)
    p.add_argument(
        "--out",
        default=None,
        metavar="DIR",
        help="output directory; rerunning with the same DIR skips finished points "
        "(default sweep-<scenario file name>, lowercase letters, digits, - and _ only)",
    )
    p.add_argument("--no-plots", action="store_true", help="do not draw the summary plots")
    add_json_flag(p)


def run(args: argparse.Namespace) -> int:
    """Run ``inserr sweep``: validate the grid, connect, run the points, print a summary.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments (:func:`add_arguments`).

    Returns
    -------
    int
        Exit status: 0, or 1 when some point failed (a rerun may succeed).

    Raises
    ------
    InputError
        Bad scenario or grid, unreachable cluster: before any output is written.
    """
    from inserr.sweep.grid import build_grid, default_out_dir
    from inserr.sweep.runner import open_engine, run_sweep
    from inserr.sweep.store import check_sweep_dir

    base = scenario_from_args(args)
    grid = build_grid(base)
    out = args.out or default_out_dir(base, getattr(args, "scenario", None))
    check_sweep_dir(out, "--out", inputs=[args.scenario] if args.scenario else [])
    # Connect (or fail) before the output directory exists.
    engine = open_engine(args.scheduler, args.workers)
    res = run_sweep(grid, out, scheduler=engine, plots=not args.no_plots)
    rows = [dict(zip(res.header, r, strict=True)) for r in res.rows]
    result = {
        "out": str(res.out_dir),
        "results_csv": str(res.results_csv),
        "engine": res.engine,
        "points": len(res.rows),
        "computed": res.computed,
        "resumed": res.resumed,
        "counts": res.counts,
        "plots": [str(p) for p in res.plots],
        "rows": rows,
    }
    emit(args, result, _human(grid, res, rows))
    # Failed points (unlike invalid combinations) may succeed on a rerun: tell scripts.
    return 1 if res.counts.get("failed", 0) else 0


def _human(grid, res, rows: list[dict]) -> str:
    names = [p.name for p in grid.params]
    shown = [(k, h) for k, h in SHOWN if k in res.header]
    ranked, note = rows, ""
    if len(rows) > MAX_ROWS and shown:
        key, label = shown[0]
        ok = [r for r in rows if r["status"] == "ok"]
        ranked = sorted(ok, key=lambda r: r[key])[:MAX_ROWS]
        note = f" (best {len(ranked)} of {len(rows)} by {label}; all in results.csv)"
    table = format_table(
        names + ["status"] + [h for _, h in shown],
        [[r[n] for n in names] + [r["status"]] + [r.get(k, "") for k, _ in shown] for r in ranked],
    )
    dims = " x ".join(f"{p.name} ({len(p.values)})" for p in grid.params)
    counts = ", ".join(f"{n} {s}" for s, n in sorted(res.counts.items()))
    lines = [
        f"sweep of {dims} = {len(rows)} points{note}",
        table,
        "",
        f"{counts}; {res.computed} computed now, {res.resumed} already done ({res.engine})",
        f"results: {res.results_csv}",
    ]
    failed = [r for r in rows if r["status"] not in ("ok", "pending")]
    for r in failed[:5]:
        lines.append(
            f"  point {r['point']} ({', '.join(f'{n}={r[n]}' for n in names)}): {r['error']}"
        )
    if len(failed) > 5:
        lines.append(f"  ... {len(failed) - 5} more failed points in results.csv")
    return "\n".join(lines)
