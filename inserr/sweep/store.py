"""The output directory of a sweep: one atomic record per point, and the tidy table built from them.

Layout of ``OUT/``::

    sweep.json          the grid of the last run (base scenario, parameters, point ids)
    points/<id>.json    one record per point: status, headline metrics, error message
    results.csv         one row per grid point, assembled from the records
    sweep*.png          summary plots of results.csv (:mod:`inserr.sweep.figures`)
    .inserr-sweep       marker: the manifest of what a sweep writes here (:data:`MANIFEST`)

A sweep writes into a directory only if it is new, empty or an earlier sweep's
holding nothing else (:func:`check_sweep_dir`): a file of the user's is never
overwritten or removed. Every file is written atomically (temporary file, then
rename), so an interrupted sweep leaves complete records or none. A point is
*finished* when its record has status ``ok``; a rerun with the same ``OUT`` skips
finished points and retries the others (a worker lost last time may well succeed
now). Records are keyed by the point's content hash, so growing the grid reuses
every point already done. Run one sweep at a time in a directory: two runs sharing
one would both compute the points neither had finished (harmlessly, but twice).

The figures always describe the current ``results.csv``: each figure inserr
writes carries a PNG text chunk :data:`FIGURE_MARK`, and a run removes the marked
figures it did not write this time (all of them with ``--no-plots`` or after an
interrupted run). PNG files without the mark (not written by inserr) are never
touched.
"""

from __future__ import annotations

import csv
import io
import json
import re
import struct
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from inserr.output.outdir import Manifest, clean_leftovers, write_manifest
from inserr.output.report import dumps, write_text_atomic
from inserr.sweep.grid import Grid, Point, describe_grid

OK = "ok"
FAILED = "failed"
INVALID = "invalid"
PENDING = "pending"

#: The one metric the plots and the terminal table lead with.
HEADLINE = "max_horizontal_error_nmi"

#: PNG text chunk (keyword, text) that marks a figure as written by ``inserr sweep``.
FIGURE_MARK = ("inserr", "sweep figure")

_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"

#: Temporary record names of inserr versions before :mod:`inserr.output.outdir`
#: (``tempfile.mkstemp(prefix=".<id>.json.")``), inside ``points/`` only.
_TEMP_OF_OLD_VERSIONS = re.compile(r"^\.[0-9a-f]{16}\.json\.[A-Za-z0-9_]{8}$")


#: Marker of a sweep directory; its manifest (:class:`inserr.output.outdir.Manifest`)
#: names the files a sweep rewrites and the pattern of the records in ``points/``.
MARKER = ".inserr-sweep"

#: Name of a point's record: the point's id (16 hex digits) and ``.json``.
RECORD_NAME = r"[0-9a-f]{16}\.json"

#: What every sweep directory may hold, besides its figures (PNG files carrying
#: :data:`FIGURE_MARK`).
MANIFEST = Manifest("sweep", {"sweep.json": None, "results.csv": None}, {"points": RECORD_NAME})


def _legacy_sweep_dir(path: Path) -> bool:
    """A sweep directory written before markers existed, proven by its content.

    It holds a ``sweep.json`` that describes a grid, and nothing but what a sweep
    writes: ``results.csv``, figures carrying :data:`FIGURE_MARK`, and ``points/``
    holding only records named by a point id whose ``"id"`` is that name.
    """
    try:
        desc = json.loads((path / "sweep.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    if not isinstance(desc, dict) or not {"base_scenario", "params", "points"} <= set(desc):
        return False
    pattern = re.compile(RECORD_NAME)
    for e in path.iterdir():
        if e.name in ("sweep.json", "results.csv") and e.is_file() and not e.is_symlink():
            continue
        if e.suffix == ".png" and is_sweep_figure(e):
            continue
        if e.name == "points" and e.is_dir() and not e.is_symlink():
            for rec in e.iterdir():
                if _TEMP_OF_OLD_VERSIONS.match(rec.name):
                    continue  # half-written by a killed run: prepare() removes it
                if not (rec.is_file() and pattern.fullmatch(rec.name)):
                    return False
                try:
                    if json.loads(rec.read_text(encoding="utf-8")).get("id") != rec.stem:
                        return False
                except (OSError, ValueError, AttributeError):
                    return False
            continue
        return False
    return True


def check_sweep_dir(
    out_dir: str | Path, field: str = "out", inputs: Iterable[str | Path] = ()
) -> Path:
    """Check, before any work, that ``out_dir`` can hold this sweep.

    A sweep writes ``sweep.json``, ``results.csv``, ``points/`` and its figures into
    the directory and resumes from what is there, so the directory must be new,
    empty, or an earlier sweep's holding nothing else: its :data:`MARKER` manifest
    (or, for a sweep written before markers, :func:`_legacy_sweep_dir`) must cover
    every entry. It must be writable and hold none of the run's ``inputs``; see
    :func:`inserr.output.outdir.check_output_dir` for the rest.

    Parameters
    ----------
    out_dir : str or Path
        The sweep directory asked for.
    field : str
        Name of the argument in the error message.
    inputs : iterable of path
        Files the sweep reads (its scenario file).

    Returns
    -------
    Path
        The resolved directory.
    """
    from inserr.output.outdir import check_output_dir

    return check_output_dir(
        out_dir,
        field,
        _legacy_sweep_dir,
        "an inserr sweep",
        "name a new directory, or move that file out "
        "(a sweep's directory holds only what the sweep writes)",
        marker=MARKER,
        also_ours=lambda p: p.suffix == ".png" and is_sweep_figure(p),
        inputs=inputs,
    )


class SweepStore:
    """Reads and writes the records of one sweep output directory.

    Parameters
    ----------
    out_dir : str or Path
        The output directory (created by :meth:`prepare`, not before).
    """

    def __init__(self, out_dir: str | Path):
        self.root = Path(out_dir)
        self.points_dir = self.root / "points"

    def prepare(self, grid: Grid) -> None:
        """Create the directory and its marker, drop what a killed run left, record the grid.

        The marker (:data:`MARKER`, with :data:`MANIFEST`) is written before anything
        else, so the directory is provably the sweep's from its first file on.

        Parameters
        ----------
        grid : Grid
            The grid of this run, written to ``sweep.json``.
        """
        self.root.mkdir(parents=True, exist_ok=True)
        write_manifest(self.root, MARKER, MANIFEST)
        self.points_dir.mkdir(exist_ok=True)
        # Half-written files of a run that was killed mid-write (their writer is gone).
        clean_leftovers(self.root)
        clean_leftovers(self.points_dir)
        for stale in self.points_dir.glob(".*.json.*"):
            if not _TEMP_OF_OLD_VERSIONS.match(stale.name):
                continue
            stale.unlink(missing_ok=True)
        write_text_atomic(self.root / "sweep.json", dumps(describe_grid(grid)) + "\n")

    def path(self, pid: str) -> Path:
        """Path of the record of point ``pid``.

        Parameters
        ----------
        pid : str
            A point id (:attr:`inserr.sweep.grid.Point.id`).

        Returns
        -------
        Path
            ``OUT/points/<pid>.json`` (which may not exist yet).
        """
        return self.points_dir / f"{pid}.json"

    def load(self, pid: str) -> dict[str, Any] | None:
        """The record of point ``pid``, or None if there is none (or it cannot be read).

        Parameters
        ----------
        pid : str
            A point id.

        Returns
        -------
        dict or None
            The record as :func:`point_record` made it (JSON types).
        """
        try:
            rec = json.loads(self.path(pid).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        return rec if isinstance(rec, dict) and rec.get("id") == pid else None

    def save(self, record: dict[str, Any]) -> None:
        """Write one point's record atomically.

        Parameters
        ----------
        record : dict
            A record from :func:`point_record` (its ``"id"`` names the file).
        """
        write_text_atomic(self.path(record["id"]), dumps(record) + "\n")

    def finished(self, grid: Grid) -> set[str]:
        """Ids of the grid points already computed successfully.

        Parameters
        ----------
        grid : Grid

        Returns
        -------
        set of str
            Ids of the points whose record has status ``ok``.
        """
        done = set()
        for pt in grid.points:
            rec = self.load(pt.id)
            if rec is not None and rec.get("status") == OK:
                done.add(pt.id)
        return done

    def records(self, grid: Grid) -> list[dict[str, Any] | None]:
        """The record of every grid point in grid order (None where none exists yet).

        Parameters
        ----------
        grid : Grid

        Returns
        -------
        list of dict or None
            One entry per point of ``grid.points``.
        """
        return [self.load(pt.id) for pt in grid.points]


def point_record(grid: Grid, point: Point, result: dict[str, Any]) -> dict[str, Any]:
    """A point's full record: what the worker returned plus the point's place in the grid.

    Parameters
    ----------
    grid : Grid
    point : Point
        A point of ``grid``.
    result : dict
        What :func:`inserr.sweep.runner.run_point` returned: ``status``, ``error``,
        ``metrics`` (headline numbers, errors in nmi) and ``elapsed_s`` (s).

    Returns
    -------
    dict
        Id, values by parameter name, scenario changes, seed, status, error,
        metrics and, when known, the elapsed time ``elapsed_s`` (s).
    """
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
    """Record of a point whose combination of values is not a valid scenario.

    Parameters
    ----------
    grid : Grid
    point : Point
        A point with a non-empty :attr:`~inserr.sweep.grid.Point.error`.

    Returns
    -------
    dict
        A :func:`point_record` with status ``invalid`` and the point's error.
    """
    return point_record(grid, point, {"status": INVALID, "error": point.error})


def table(grid: Grid, records: list[dict[str, Any] | None]) -> tuple[list[str], list[list[Any]]]:
    """Tidy table: one row per point (parameters, seed, status, metrics, error).

    Metric columns are those of the successful points, in the order they first
    appear in grid order, so the table depends only on the grid and the numbers,
    never on which worker finished first. Timings are left out for the same reason.

    Parameters
    ----------
    grid : Grid
    records : list of dict or None
        One record per point, in grid order (None: status ``pending``).

    Returns
    -------
    header : list of str
        ``point``, the parameter names, ``seed``, ``status``, the metric names
        (units in their names, e.g. ``max_horizontal_error_nmi``), ``error``.
    rows : list of list
        One row per point, in grid order; ``""`` where a metric is missing.
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
    """CSV text; floats in their shortest exact form so equal numbers give equal files.

    Parameters
    ----------
    header : list of str
    rows : list of list

    Returns
    -------
    str
        The CSV text, ``\\n`` line endings.
    """
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for r in rows:
        w.writerow([repr(v) if isinstance(v, float) else v for v in r])
    return buf.getvalue()


def write_results(store: SweepStore, grid: Grid) -> tuple[Path, list[str], list[list[Any]]]:
    """Assemble ``results.csv`` from the point records.

    Parameters
    ----------
    store : SweepStore
    grid : Grid

    Returns
    -------
    path : Path
        ``OUT/results.csv``.
    header, rows
        The table written (see :func:`table`).
    """
    header, rows = table(grid, store.records(grid))
    path = store.root / "results.csv"
    write_text_atomic(path, csv_text(header, rows))
    return path, header, rows


def is_sweep_figure(path: str | Path) -> bool:
    """Whether ``path`` is a PNG file that ``inserr sweep`` wrote (it carries :data:`FIGURE_MARK`).

    Reads the chunk headers only (and the text chunks), not the image data.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    bool
        False for anything else: other PNG files, other files, unreadable files.
    """
    mark = FIGURE_MARK[0].encode("latin-1") + b"\0" + FIGURE_MARK[1].encode("latin-1")
    try:
        with open(path, "rb") as f:
            if f.read(8) != _PNG_SIGNATURE:
                return False
            while True:
                head = f.read(8)
                if len(head) < 8:
                    return False
                length, kind = struct.unpack(">I4s", head)
                if kind == b"tEXt" and length == len(mark):
                    if f.read(length) == mark:
                        return True
                    f.seek(4, io.SEEK_CUR)
                elif kind == b"IEND":
                    return False
                else:
                    f.seek(length + 4, io.SEEK_CUR)  # data and CRC
    except OSError:
        return False


def sweep_figures(out_dir: str | Path) -> list[Path]:
    """The figures ``inserr sweep`` wrote in ``out_dir`` (top level only), sorted.

    Parameters
    ----------
    out_dir : str or Path

    Returns
    -------
    list of Path
        The ``*.png`` files that carry :data:`FIGURE_MARK`.
    """
    root = Path(out_dir)
    if not root.is_dir():
        return []
    return sorted(p for p in root.glob("*.png") if p.is_file() and is_sweep_figure(p))


def remove_stale_figures(out_dir: str | Path, keep: Iterable[str | Path] = ()) -> list[Path]:
    """Remove the figures inserr wrote in ``out_dir`` for earlier results.

    Parameters
    ----------
    out_dir : str or Path
    keep : iterable of str or Path
        Figures of the current results (their names), left in place.

    Returns
    -------
    list of Path
        The files removed. Files without :data:`FIGURE_MARK` are never removed.
    """
    kept = {Path(k).name for k in keep}
    removed = []
    for path in sweep_figures(out_dir):
        if path.name not in kept:
            path.unlink(missing_ok=True)
            removed.append(path)
    return removed
