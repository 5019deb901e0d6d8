"""The one report writer: ``report.md``, ``report.html`` (figures embedded), PNGs, ``results.json``.

Every study of inserr — drift and scheme comparison (:mod:`inserr.drift.report`),
validation against the nonlinear reference (:mod:`inserr.reference.report`),
alignment (:mod:`inserr.alignment.report`), calibration
(:mod:`inserr.calibration.report`), the north finder
(:mod:`inserr.northfinder.report`) — and every analysis write-up in ``analyses/``
builds a :class:`Report` (headings, paragraphs, tables, Markdown text, figures and
the ``results`` dict) and hands it to this module; nothing else writes a report.
So every report has the same layout, heading style, figure style
(:mod:`inserr.output.figure_style`) and output-directory safety:

* :meth:`Report.write` renders everything into a temporary directory next to the
  target and renames it into place (with the :data:`MARKER` file), so a failure
  never leaves a partial report directory behind and an existing report is replaced
  only by a complete one; :func:`check_report_dir` refuses, before any work, a
  target holding anything inserr did not write (the marker's manifest lists every
  file with its SHA-256; :mod:`inserr.output.outdir`);
* :meth:`Report.write_into` writes the same files one by one, each atomically,
  into a directory that other scripts also write into (an analysis whose slow
  nonlinear part writes beside it).

Layout of a report directory::

    report.md        (REPORT.md for the analyses' write-ups) title, blocks, figure links
    report.html      the same, self-contained (PNG figures base64-embedded)
    <name>.png       one file per figure, named by the study
    <name>.csv ...   data files a study attaches (e.g. timeseries.csv, budget.csv)
    results.json     the study's numbers (strict JSON, engineering units)
    .inserr-report   marker: the manifest of the files above (name and SHA-256)
"""

from __future__ import annotations

import base64
import html
import json
import math
import os
import re
import shutil
import tempfile
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from inserr.core.errors import InputError
from inserr.output.outdir import (
    TMP_TAG,
    Manifest,
    check_output_dir,
    clean_leftovers,
    foreign_entry,
    old_name,
    read_manifest,
    sha256,
    tag_temp_dir,
    temp_prefix,
    write_bytes_atomic,
)


def to_jsonable(obj: Any) -> Any:
    """Convert numpy scalars/arrays (recursively) to plain Python for ``json.dumps``.

    Non-finite floats become ``None`` so the output is strict JSON.
    """
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (np.bool_,)):
        return bool(obj)
    return obj


def dumps(obj: Any) -> str:
    """Strict JSON text of ``obj`` (numpy-aware), indented."""
    return json.dumps(to_jsonable(obj), indent=2, allow_nan=False, ensure_ascii=False)


_CODE = re.compile(r"`([^`]+)`")
_LINK = re.compile(r"\[([^\]]+)\]\(([^)\s]+)\)")
_BOLD = re.compile(r"\*\*(?=\S)(.+?)(?<=\S)\*\*")
# One star on each side, not part of "**" and hugging the text: "a * b * c" stays as it is.
_ITALIC = re.compile(r"(?<![*\w])\*(?=[^\s*])(.+?)(?<=[^\s*])\*(?![*\w])")
_HEADING = re.compile(r"^(#{1,6})\s+(.*)$")
_RULE_ROW = re.compile(r"^\|?\s*:?-+:?\s*(\|\s*:?-+:?\s*)*\|?\s*$")


def inline_html(text: str) -> str:
    """HTML of one line of report text: escaped, with inline Markdown rendered.

    Handles ```code```, ``[text](url)``, ``**bold**`` and ``*italic*`` (the inline
    syntax the reports use); everything else is escaped literally.

    Parameters
    ----------
    text : str

    Returns
    -------
    str
    """
    parts = _CODE.split(text)  # odd indices are code spans: escaped only
    out = []
    for i, part in enumerate(parts):
        if i % 2:
            out.append(f"<code>{html.escape(part)}</code>")
            continue
        s = html.escape(part, quote=False)
        s = _LINK.sub(lambda m: f'<a href="{html.escape(m[2])}">{m[1]}</a>', s)
        s = _BOLD.sub(r"<strong>\1</strong>", s)
        s = _ITALIC.sub(r"<em>\1</em>", s)
        out.append(s)
    return "".join(out)


def _cells(line: str) -> list[str]:
    line = line.strip()
    if line.startswith("|"):
        line = line[1:]
    if line.endswith("|"):
        line = line[:-1]
    return [c.strip() for c in line.split("|")]


def _table_html(header: list[str], rows: list[list[str]]) -> str:
    out = ["<table><tr>" + "".join(f"<th>{inline_html(h)}</th>" for h in header) + "</tr>"]
    for r in rows:
        out.append("<tr>" + "".join(f"<td>{inline_html(c)}</td>" for c in r) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


def markdown_to_html(text: str) -> str:
    """HTML of the Markdown subset the reports write.

    Blocks: ``#`` headings, pipe tables (header, ``|---|`` rule, rows), ``-`` or
    ``*`` bullet lists, fenced code, and paragraphs (consecutive lines, separated
    by blank lines); inline syntax as in :func:`inline_html`.

    Parameters
    ----------
    text : str
        Markdown.

    Returns
    -------
    str
        HTML fragment.
    """
    lines = text.split("\n")
    out: list[str] = []
    para: list[str] = []
    items: list[str] = []

    def flush() -> None:
        if para:
            out.append("<p>" + "\n".join(inline_html(x) for x in para) + "</p>")
            para.clear()
        if items:
            out.append("<ul>" + "".join(f"<li>{inline_html(x)}</li>" for x in items) + "</ul>")
            items.clear()

    i = 0
    while i < len(lines):
        line = lines[i]
        stripped = line.strip()
        if stripped.startswith("```"):
            flush()
            j = i + 1
            while j < len(lines) and not lines[j].strip().startswith("```"):
                j += 1
            out.append("<pre><code>" + html.escape("\n".join(lines[i + 1 : j])) + "</code></pre>")
            i = j + 1
            continue
        if not stripped:
            flush()
        elif m := _HEADING.match(stripped):
            flush()
            level = len(m[1])
            out.append(f"<h{level}>{inline_html(m[2])}</h{level}>")
        elif stripped.startswith("|"):
            flush()
            j = i
            while j < len(lines) and lines[j].strip().startswith("|"):
                j += 1
            block = lines[i:j]
            if len(block) > 1 and _RULE_ROW.match(block[1].strip()):
                del block[1]
            out.append(_table_html(_cells(block[0]), [_cells(x) for x in block[1:]]))
            i = j
            continue
        elif stripped[:2] in ("- ", "* "):
            if para:
                flush()
            items.append(stripped[2:])
        elif items and line[:1] in (" ", "\t"):
            items[-1] += " " + stripped  # continuation of a list item
        else:
            if items:
                flush()
            para.append(stripped)
        i += 1
    flush()
    return "\n".join(out)


@dataclass
class _Block:
    kind: str
    payload: Any


@dataclass
class Report:
    """A report: an ordered collection of blocks and the numbers behind them.

    A study builds one (its ``build_report``), adding headings, paragraphs, tables,
    Markdown text and figures and setting :attr:`results`; :meth:`write` (or
    :meth:`write_into`) renders it, the same way for every study.

    Parameters
    ----------
    title : str
        Report title (first heading of both the Markdown and the HTML file).
    blocks : list
        The content, in order (filled by the methods below).
    results : dict
        Written as ``results.json`` (numpy values allowed, see :func:`dumps`).
    """

    title: str
    blocks: list[_Block] = field(default_factory=list)
    results: dict[str, Any] = field(default_factory=dict)

    def heading(self, text: str, level: int = 2) -> None:
        """Add a section heading (level 2 = ``##``)."""
        self.blocks.append(_Block("heading", (text, level)))

    def paragraph(self, text: str) -> None:
        """Add a paragraph of plain text (Markdown inline syntax allowed)."""
        self.blocks.append(_Block("paragraph", text))

    def table(self, header: list[str], rows: list[list[Any]], fmt: str = "{:.4g}") -> None:
        """Add a table; floats are formatted with ``fmt``."""

        def cell(v: Any) -> str:
            if isinstance(v, (float, np.floating)):
                return fmt.format(float(v))
            return str(v)

        self.blocks.append(_Block("table", (header, [[cell(v) for v in r] for r in rows])))

    def markdown_text(self, text: str) -> None:
        """Add Markdown written by the caller, copied verbatim into the Markdown file.

        For write-ups generated as Markdown (headings ``#``, pipe tables, ``-``
        lists, paragraphs, inline ``**bold**``, ``*italic*``, ``code``); the HTML
        page renders that subset (:func:`markdown_to_html`).
        """
        self.blocks.append(_Block("markdown", text.strip("\n")))

    def figure(self, fig, name: str, caption: str = "", *, crop: bool = True) -> None:
        """Add a matplotlib figure, saved as ``<name>.png`` and embedded in the HTML.

        The figure is finished in the inserr style (:func:`.figure_style.finish`) and
        rendered at once; the caller's figure is not needed afterwards. ``crop=False``
        renders the figure as laid out, without the tight crop (one drawing instead of
        two: for figures whose layout already fits everything, see
        :func:`.figure_style.png_bytes`).
        """
        from inserr.output.figure_style import finish, png_bytes

        self.blocks.append(_Block("figure", (name, caption, png_bytes(finish(fig), crop=crop))))

    def attach(self, name: str, data: str | bytes, caption: str = "") -> None:
        """Add a data file (e.g. ``timeseries.csv``) written beside the report and linked.

        Parameters
        ----------
        name : str
            File name inside the report directory (no directory part).
        data : str or bytes
            Content; text is written as UTF-8.
        caption : str
            What the file holds (shown with the link).
        """
        if not name or "/" in name or "\\" in name or name.startswith("."):
            raise ValueError(f"attachment name must be a plain file name, got {name!r}")
        payload = data.encode("utf-8") if isinstance(data, str) else bytes(data)
        self.blocks.append(_Block("file", (name, caption, payload)))

    # --- rendering ------------------------------------------------------------
    def markdown(self) -> str:
        """The report as Markdown, figures linked as PNG files."""
        out = [f"# {self.title}", ""]
        for b in self.blocks:
            if b.kind == "heading":
                text, level = b.payload
                out += ["#" * level + " " + text, ""]
            elif b.kind in ("paragraph", "markdown"):
                out += [b.payload, ""]
            elif b.kind == "table":
                header, rows = b.payload
                out.append("| " + " | ".join(header) + " |")
                out.append("|" + "|".join("---" for _ in header) + "|")
                out += ["| " + " | ".join(r) + " |" for r in rows]
                out.append("")
            elif b.kind == "figure":
                name, caption, _ = b.payload
                out += [f"![{caption or name}]({name}.png)", ""]
                if caption:
                    out += [f"*{caption}*", ""]
            elif b.kind == "file":
                name, caption, _ = b.payload
                out += [f"- [{name}]({name})" + (f": {caption}" if caption else ""), ""]
        return "\n".join(out)

    def html(self) -> str:
        """The report as one self-contained HTML page (PNG figures base64-embedded)."""
        esc = html.escape
        out = [
            "<!DOCTYPE html><html><head><meta charset='utf-8'>",
            f"<title>{esc(self.title)}</title>",
            # Wide enough for an 11 in figure at its own 110 dpi (1210 px): figures show
            # at 100 % on a usual screen, so their 7-10 pt text stays legible.
            "<style>body{font-family:sans-serif;max-width:1300px;margin:auto;padding:1em}"
            "figure{margin:1em 0}"
            "table{border-collapse:collapse}td,th{border:1px solid #999;padding:2px 6px;"
            "text-align:right}th{background:#eee}td:first-child{text-align:left}"
            "img{max-width:100%;height:auto}figcaption{font-style:italic;margin:0.3em 0 1em}"
            "</style>",
            "</head><body>",
            f"<h1>{esc(self.title)}</h1>",
        ]
        for b in self.blocks:
            if b.kind == "heading":
                text, level = b.payload
                out.append(f"<h{level}>{esc(text)}</h{level}>")
            elif b.kind in ("paragraph", "markdown"):
                out.append(markdown_to_html(b.payload))
            elif b.kind == "table":
                out.append(_table_html(*b.payload))
            elif b.kind == "figure":
                name, caption, png = b.payload
                data = base64.b64encode(png).decode("ascii")
                out.append(
                    f"<figure><img alt='{esc(name)}' src='data:image/png;base64,{data}'>"
                    f"<figcaption>{esc(caption)}</figcaption></figure>"
                )
            elif b.kind == "file":
                name, caption, _ = b.payload
                text = f": {esc(caption)}" if caption else ""
                out.append(f"<p class='file'><a href='{esc(name)}'>{esc(name)}</a>{text}</p>")
        out.append("</body></html>")
        return "\n".join(out)

    def files(self, markdown_name: str = "report.md") -> dict[str, bytes]:
        """Every file of the report, by name: Markdown, HTML, one PNG per figure, results.

        Parameters
        ----------
        markdown_name : str
            Name of the Markdown file (``report.md``; the analyses use ``REPORT.md``).

        Returns
        -------
        dict of str to bytes
            In writing order; the marker file is not included.
        """
        out = {
            markdown_name: self.markdown().encode("utf-8"),
            "report.html": self.html().encode("utf-8"),
        }
        for b in self.blocks:
            if b.kind == "figure":
                name, _, png = b.payload
                out[f"{name}.png"] = png
            elif b.kind == "file":
                name, _, data = b.payload
                out[name] = data
        out["results.json"] = dumps(self.results).encode("utf-8")
        return out

    def write_into(self, out_dir: str | os.PathLike, markdown_name: str = "report.md") -> Path:
        """Write the report's files into ``out_dir`` one by one, each atomically.

        Unlike :meth:`write`, other files already in the directory are left alone
        (an analysis directory that several scripts write into); the same files as
        :meth:`write` are written, without the marker (the directory is not
        replaced as a whole). Temporaries of these files left by a killed run are
        removed first (:func:`inserr.output.outdir.clean_leftovers`).
        """
        target = Path(out_dir).resolve()
        files = self.files(markdown_name)
        clean_leftovers(target, files)
        # The Markdown last: it is the write-up's index, updated once all it links is there.
        for name in sorted(files, key=lambda n: n == markdown_name):
            write_bytes_atomic(target / name, files[name])
        return target

    def write(self, out_dir: str | os.PathLike, markdown_name: str = "report.md") -> Path:
        """Write the complete report directory atomically and return its path.

        The target is checked first (:func:`check_report_dir`: new, empty, or an
        earlier inserr report whose every file is still as inserr wrote it; writable).
        Everything is rendered into a temporary sibling ``.<name>.tmp-<pid>-*`` (tagged
        as inserr's) with the marker and its manifest (every file and its SHA-256);
        only when that succeeds is it renamed to ``out_dir``, replacing an older
        report. Leftovers of a killed earlier run beside the target are removed first
        (:func:`inserr.output.outdir.clean_leftovers`).
        ``markdown_name`` names the Markdown file (analyses use ``REPORT.md``).
        """
        target = check_report_dir(out_dir)
        target.parent.mkdir(parents=True, exist_ok=True)
        clean_leftovers(target.parent, [target.name], MARKER)
        tmp = Path(tempfile.mkdtemp(prefix=temp_prefix(target.name), dir=target.parent))
        try:
            tag_temp_dir(tmp)  # proves the directory is inserr's if this run is killed
            tmp.chmod(0o755)  # mkdtemp makes it private; a report is meant to be shared
            files = self.files(markdown_name)
            for name, data in files.items():
                (tmp / name).write_bytes(data)
            manifest = Manifest("report", {name: sha256(data) for name, data in files.items()})
            (tmp / MARKER).write_text(manifest.text(), encoding="utf-8")
            (tmp / TMP_TAG).unlink()  # from here on the marker's manifest proves it
            replace_dir(tmp, target)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        return target


#: Written into every report directory: its JSON manifest lists every file of the report
#: with its SHA-256 (:class:`inserr.output.outdir.Manifest`), so that only inserr's own
#: reports, unchanged, are replaced.
MARKER = ".inserr-report"

#: Files a report written before manifests existed may hold (its marker was one line of
#: text); anything else in such a directory is the user's.
_LEGACY_REPORT_FILES = re.compile(
    r"^(report\.md|REPORT\.md|report\.html|results\.json|[^/]+\.png)$"
)


def _legacy_report_file(path: Path) -> bool:
    return path.is_file() and not path.is_symlink() and bool(_LEGACY_REPORT_FILES.match(path.name))


def is_report_dir(path: Path) -> bool:
    """Whether ``path`` is a report directory inserr wrote and nobody changed since.

    It must hold the :data:`MARKER` and nothing its manifest does not list (each
    file with the SHA-256 recorded); a marker from before manifests vouches only for
    the files a report had then (Markdown, HTML, ``results.json``, PNGs).
    """
    return (
        path.is_dir()
        and read_manifest(path, MARKER) is not None
        and foreign_entry(path, MARKER, legacy=_legacy_report_file) is None
    )


def check_report_dir(
    out_dir: str | os.PathLike,
    field: str = "out",
    inputs: Iterable[str | os.PathLike] = (),
) -> Path:
    """Check, before any work, that a report can be written to ``out_dir``.

    :meth:`Report.write` replaces the target directory as a whole, so it must be
    new, empty or an earlier inserr report holding only what inserr wrote, unchanged
    (:func:`is_report_dir`); it must not hold the run's ``inputs``; and a probe file
    must be creatable in it and beside it (:func:`check_output_dir`).

    Parameters
    ----------
    out_dir : str or path
        The report directory the user asked for.
    field : str
        Name of the flag or key reported in the error message.
    inputs : iterable of path
        Files the run reads (the scenario), which must not be inside ``out_dir``.

    Returns
    -------
    Path
        The resolved target.
    """
    return check_output_dir(
        out_dir,
        field,
        lambda p: False,
        "an inserr report",
        "name a new directory, or move that file out first "
        "(a report replaces its directory as a whole)",
        marker=MARKER,
        legacy=_legacy_report_file,
        replaces_whole=True,
        inputs=inputs,
    )


def replace_dir(src: Path, target: Path) -> None:
    """Move a finished report directory ``src`` to ``target``, replacing an earlier report.

    The earlier report is checked once more just before (a file added to it while
    this run worked is never deleted: InputError), renamed aside
    (``.<name>.old-<pid>-*``), and removed once ``src`` is in place.
    """
    if target.exists():
        bad = foreign_entry(target, MARKER, legacy=_legacy_report_file)
        if bad is not None:
            name, why = bad
            raise InputError(
                "out",
                f"{target} now holds {name}, {why}",
                "move that file out and rerun (nothing was replaced)",
            )
        old = target.with_name(old_name(target.name))
        try:
            os.replace(target, old)
        except OSError as exc:  # checked before any work; this is a last line of defence
            raise InputError(
                "out", f"cannot replace {target} ({exc.strerror})", "name a new directory"
            ) from None
        os.replace(src, target)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(src, target)


def write_text_atomic(path: str | os.PathLike, text: str) -> None:
    """Write a UTF-8 text file atomically (see :func:`write_bytes_atomic`)."""
    write_bytes_atomic(path, text.encode("utf-8"))
