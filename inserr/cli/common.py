"""Helpers shared by the CLI commands: the integer run-control flag, JSON and table output."""

from __future__ import annotations

import argparse
import sys
from typing import Any


def positive_int(text: str) -> int:
    """argparse ``type=``: an integer >= 1."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"{text!r} must be >= 1")
    return v


def add_json_flag(parser: argparse.ArgumentParser) -> None:
    """Add ``--json`` (machine-readable output on stdout, no progress bars)."""
    parser.add_argument("--json", action="store_true", help="print JSON on stdout")


def emit(args: argparse.Namespace, result: dict[str, Any], human: str) -> None:
    """Print ``result`` as JSON under ``--json``, else the human-readable text."""
    if getattr(args, "json", False):
        from inserr.output.report import dumps

        sys.stdout.write(dumps(result) + "\n")
    else:
        sys.stdout.write(human.rstrip() + "\n")


def format_table(header: list[str], rows: list[list[Any]], fmt: str = "{:.4g}") -> str:
    """Plain-text table with right-aligned columns."""

    def cell(v: Any) -> str:
        if isinstance(v, float):
            return fmt.format(v)
        return str(v)

    body = [[cell(v) for v in r] for r in rows]
    widths = [
        max(len(h), *(len(r[i]) for r in body)) if body else len(h) for i, h in enumerate(header)
    ]
    lines = ["  ".join(h.rjust(w) for h, w in zip(header, widths, strict=True))]
    lines.append("  ".join("-" * w for w in widths))
    lines += ["  ".join(c.rjust(w) for c, w in zip(r, widths, strict=True)) for r in body]
    return "\n".join(lines)


def warn_empty_budget(args: argparse.Namespace, runs: list) -> None:
    """Say on stderr (also under ``--json``) when the runs have no error source at all.

    Every number is then zero; exit status stays 0 (it is a valid, if empty, question).
    """
    from inserr.drift.study import EMPTY_BUDGET

    if runs and all(EMPTY_BUDGET in r.metrics()["warnings"] for r in runs):
        fix = "e.g. --gyro-bias 0.01" if getattr(args, "scenario", None) is None else ""
        text = EMPTY_BUDGET + (f" ({fix})" if fix else "")
        sys.stderr.write(f"inserr {args.command}: warning: {text}\n")


def by_column(header: list[str], rows: list[list[Any]]) -> tuple[list[str], list[list[Any]]]:
    """The table turned: one row per column of ``rows``, one column per row.

    For comparisons on a terminal: the schemes become the columns and the long,
    unit-bearing metric names the rows, so the table stays narrow.
    """
    out_header = [header[0], *(str(r[0]) for r in rows)]
    out_rows = [[name, *(r[i] for r in rows)] for i, name in enumerate(header) if i > 0]
    return out_header, out_rows


def stamp(rep: Any, scen: Any, args: argparse.Namespace) -> Any:
    """Add the provenance to a study's report (as the drift report has it); return it.

    ``results.json`` gains the inserr version, the SHA-256 of the resolved scenario,
    the scenario file and its SHA-256 (when one was read) and the resolved scenario
    itself (every key, units as text); the page ends with the same line the drift
    report opens with, and the scenario's declared heading convention (the drift
    report has it in its set-up table).

    Parameters
    ----------
    rep : inserr.output.report.Report
    scen : inserr.scenario.schema.Scenario
        The scenario the study ran (flags applied).
    args : argparse.Namespace
        The command's arguments (``args.scenario``: the file, if any).
    """
    from inserr.drift.report import provenance
    from inserr.scenario.schema import resolved_scenario

    prov = provenance(scen, getattr(args, "scenario", None))
    results = dict(rep.results or {})
    rep.results = {**prov, "scenario": resolved_scenario(scen), **results}
    where = f"scenario file `{prov['scenario_file']}`, " if "scenario_file" in prov else ""
    rep.paragraph(
        f"Written by inserr {prov['inserr_version']} from {where}resolved scenario "
        f"SHA-256 `{prov['scenario_sha256'][:16]}…` (full digest in results.json). "
        f"Heading convention: {scen.heading_convention} (table angles right-handed about "
        "their axes; docs/theory.md section 1)."
    )
    return rep


def add_dask_flags(p: argparse.ArgumentParser) -> None:
    """``--scheduler`` and ``--workers``: where a sweep or a design runs its batches.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The sub-command's parser (``sweep``, ``design``).
    """
    p.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDRESS",
        help="dask.distributed scheduler to submit to (tcp://HOST:PORT), or a local Dask "
        "scheduler: processes (default), threads, sync",
    )
    p.add_argument(
        "--workers",
        type=positive_int,
        default=None,
        metavar="N",
        help="local worker processes (default: the CPUs available)",
    )
