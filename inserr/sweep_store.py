"""The output directory of a sweep: one atomic record per point, and the tidy table built from them.

Layout of ``OUT/``::

    sweep.json          the grid of the last run (base scenario, parameters, point ids)
    points/<id>.json    one record per point: status, headline metrics, error message
    results.csv         one row per grid point, assembled from the records
    sweep*.png          summary plots (:mod:`inserr.sweep_plots`)

Every file is written atomically (temporary file, then rename), so an interrupted
sweep leaves complete records or none. A point is *finished* when its record has
status ``ok``; a rerun with the same ``OUT`` skips finished points and retries
the others (a worker lost last time may well succeed now). Records are keyed by
the point's content hash, so growing the grid reuses every point already done.
Run one sweep at a time in a directory: two runs sharing one would both compute
the points neither had finished (harmlessly, but twice).
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path
from typing import Any

from inserr.report import dumps, write_text_atomic
from inserr.sweep import Grid, Point, describe_grid

OK = "ok"
FAILED = "failed"
INVALID = "invalid"
PENDING = "pending"

#: The one metric the plots and the terminal table lead with.
HEADLINE = "max_horizontal_error_nmi"


class SweepStore:
    """Reads and writes the records of one sweep output directory."""

    def __init__(self, out_dir: str | Path):
        self.root = Path(out_dir)
        self.points_dir = self.root / "points"

    def prepare(self, grid: Grid) -> None:
        """Create the directory, drop temporary files a killed run left, record the grid."""
        self.points_dir.mkdir(parents=True, exist_ok=True)
        for stale in self.points_dir.glob(".*.json.*"):
            stale.unlink(missing_ok=True)  # half-written by a run that was killed mid-write
        write_text_atomic(self.root / "sweep.json", dumps(describe_grid(grid)) + "\n")

    def path(self, pid: str) -> Path:
        return self.points_dir / f"{pid}.json"

    def load(self, pid: str) -> dict[str, Any] | None:
        """The record of point ``pid``, or None if there is none (or it cannot be read)."""
        try:
            rec = json.loads(self.path(pid).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        return rec if isinstance(rec, dict) and rec.get("id") == pid else None

    def save(self, record: dict[str, Any]) -> None:
        """Write one point's record atomically."""
        write_text_atomic(self.path(record["id"]), dumps(record) + "\n")

    def finished(self, grid: Grid) -> set[str]:
        """Ids of the grid points already computed successfully."""
        done = set()
        for pt in grid.points:
            rec = self.load(pt.id)
            if rec is not None and rec.get("status") == OK:
                done.add(pt.id)
        return done

    def records(self, grid: Grid) -> list[dict[str, Any] | None]:
        """The record of every grid point in grid order (None where none exists yet)."""
        return [self.load(pt.id) for pt in grid.points]


def point_record(grid: Grid, point: Point, result: dict[str, Any]) -> dict[str, Any]:
    """A point's full record: what the worker returned plus the point's place in the grid."""
    rec = {
        "id": point.id,
        "values": {p.name: v for p, v in zip(grid.params, point.values, strict=True)},
        "changes": point.changes,
        "seed": point.seed,
        "status": result.get("status", FAILED),
        "error": result.get("error", ""),
        "metrics": result.get("metrics", {}),
    }
    if "elapsed_s" in result:
        rec["elapsed_s"] = result["elapsed_s"]
    return rec


def invalid_record(grid: Grid, point: Point) -> dict[str, Any]:
    """Record of a point whose combination of values is not a valid scenario."""
    return point_record(grid, point, {"status": INVALID, "error": point.error})


def table(grid: Grid, records: list[dict[str, Any] | None]) -> tuple[list[str], list[list[Any]]]:
    """Tidy table: one row per point (parameters, seed, status, metrics, error).

    Metric columns are those of the successful points, in the order they first
    appear in grid order, so the table depends only on the grid and the numbers,
    never on which worker finished first. Timings are left out for the same reason.
    """
    metric_keys: list[str] = []
    for rec in records:
        for k in (rec or {}).get("metrics", {}):
            if k not in metric_keys:
                metric_keys.append(k)
    header = ["point", *(p.name for p in grid.params), "seed", "status", *metric_keys, "error"]
    rows = []
    for pt, rec in zip(grid.points, records, strict=True):
        rec = rec or {"status": PENDING, "error": "", "metrics": {}}
        m = rec.get("metrics", {})
        rows.append(
            [
                pt.index,
                *pt.values,
                pt.seed,
                rec["status"],
                *(m.get(k, "") for k in metric_keys),
                rec.get("error", ""),
            ]
        )
    return header, rows


def csv_text(header: list[str], rows: list[list[Any]]) -> str:
    """CSV text; floats in their shortest exact form so equal numbers give equal files."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for r in rows:
        w.writerow([repr(v) if isinstance(v, float) else v for v in r])
    return buf.getvalue()


def write_results(store: SweepStore, grid: Grid) -> tuple[Path, list[str], list[list[Any]]]:
    """Assemble ``results.csv`` from the point records; returns its path, header and rows."""
    header, rows = table(grid, store.records(grid))
    path = store.root / "results.csv"
    write_text_atomic(path, csv_text(header, rows))
    return path, header, rows
