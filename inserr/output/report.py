"""Report directories: ``report.md``, ``report.html`` (figures embedded), PNGs, ``results.json``.

A :class:`Report` collects headings, paragraphs, tables and matplotlib figures, then
:meth:`Report.write` renders everything into a temporary directory next to the
target and renames it into place, so a failure never leaves a partial report
directory behind and an existing report is replaced only by a complete one.
"""

from __future__ import annotations

import base64
import html
import io
import json
import math
import os
import shutil
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np


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


@dataclass
class _Block:
    kind: str
    payload: Any


@dataclass
class Report:
    """An ordered collection of report blocks.

    Parameters
    ----------
    title : str
        Report title (first heading of both the Markdown and the HTML file).
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

    def figure(self, fig, name: str, caption: str = "") -> None:
        """Add a matplotlib figure, saved as ``<name>.png`` and embedded in the HTML."""
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=110, bbox_inches="tight")
        import matplotlib.pyplot as plt

        plt.close(fig)
        self.blocks.append(_Block("figure", (name, caption, buf.getvalue())))

    # --- rendering ------------------------------------------------------------
    def markdown(self) -> str:
        """The report as Markdown, figures linked as PNG files."""
        out = [f"# {self.title}", ""]
        for b in self.blocks:
            if b.kind == "heading":
                text, level = b.payload
                out += ["#" * level + " " + text, ""]
            elif b.kind == "paragraph":
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
        return "\n".join(out)

    def html(self) -> str:
        """The report as one self-contained HTML page (PNG figures base64-embedded)."""
        esc = html.escape
        out = [
            "<!DOCTYPE html><html><head><meta charset='utf-8'>",
            f"<title>{esc(self.title)}</title>",
            "<style>body{font-family:sans-serif;max-width:60em;margin:auto;padding:1em}"
            "table{border-collapse:collapse}td,th{border:1px solid #999;padding:2px 6px;"
            "text-align:right}th{background:#eee}img{max-width:100%}</style>",
            "</head><body>",
            f"<h1>{esc(self.title)}</h1>",
        ]
        for b in self.blocks:
            if b.kind == "heading":
                text, level = b.payload
                out.append(f"<h{level}>{esc(text)}</h{level}>")
            elif b.kind == "paragraph":
                out.append(f"<p>{esc(b.payload)}</p>")
            elif b.kind == "table":
                header, rows = b.payload
                out.append("<table><tr>" + "".join(f"<th>{esc(h)}</th>" for h in header) + "</tr>")
                for r in rows:
                    out.append("<tr>" + "".join(f"<td>{esc(c)}</td>" for c in r) + "</tr>")
                out.append("</table>")
            elif b.kind == "figure":
                name, caption, png = b.payload
                data = base64.b64encode(png).decode("ascii")
                out.append(
                    f"<figure><img alt='{esc(name)}' src='data:image/png;base64,{data}'>"
                    f"<figcaption>{esc(caption)}</figcaption></figure>"
                )
        out.append("</body></html>")
        return "\n".join(out)

    def write_into(self, out_dir: str | os.PathLike, markdown_name: str = "report.md") -> Path:
        """Write the report's files into ``out_dir`` one by one, each atomically.

        Unlike :meth:`write`, other files already in the directory are left alone
        (an analysis directory that several scripts write into).
        """
        target = Path(out_dir).resolve()
        for b in self.blocks:
            if b.kind == "figure":
                name, _, png = b.payload
                write_bytes_atomic(target / f"{name}.png", png)
        write_text_atomic(target / "results.json", dumps(self.results))
        write_text_atomic(target / markdown_name, self.markdown())
        return target

    def write(self, out_dir: str | os.PathLike, markdown_name: str = "report.md") -> Path:
        """Write the complete report directory atomically and return its path.

        Everything is rendered into a temporary sibling directory first; only when
        that succeeds is it renamed to ``out_dir`` (replacing an older inserr report;
        any other existing, non-empty directory is refused, see
        :func:`check_report_dir`).
        ``markdown_name`` names the Markdown file (analyses use ``REPORT.md``).
        """
        target = check_report_dir(out_dir)
        target.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.tmp-", dir=target.parent))
        try:
            tmp.chmod(0o755)  # mkdtemp makes it private; a report is meant to be shared
            (tmp / markdown_name).write_text(self.markdown(), encoding="utf-8")
            (tmp / "report.html").write_text(self.html(), encoding="utf-8")
            for b in self.blocks:
                if b.kind == "figure":
                    name, _, png = b.payload
                    (tmp / f"{name}.png").write_bytes(png)
            (tmp / "results.json").write_text(dumps(self.results), encoding="utf-8")
            (tmp / MARKER).write_text("written by inserr; replaced as a whole on rewrite\n")
            replace_dir(tmp, target)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        return target


#: Written into every report directory, so that only inserr's own reports are replaced.
MARKER = ".inserr-report"


def is_report_dir(path: Path) -> bool:
    """Whether ``path`` is a directory that inserr wrote (safe to replace as a whole).

    A directory counts when it holds the marker file, or (reports written before the
    marker existed) a ``results.json`` beside a ``report.md`` or ``REPORT.md``.
    """
    return path.is_dir() and (
        (path / MARKER).is_file()
        or (
            (path / "results.json").is_file()
            and ((path / "report.md").is_file() or (path / "REPORT.md").is_file())
        )
    )


def check_output_dir(
    out_dir: str | os.PathLike,
    field: str,
    is_ours: Callable[[Path], bool],
    what: str,
    fix: str,
) -> Path:
    """Check, before any work, that inserr may write into ``out_dir``.

    The target must be new, empty, or one inserr wrote before (``is_ours``): never
    the working directory or one of its parents, a file, a directory holding
    anything else, or a path through a file or an unwritable parent.

    Parameters
    ----------
    out_dir : str or path
        The output directory the user asked for.
    field : str
        Name of the flag or key reported in the error message.
    is_ours : callable
        ``is_ours(path)`` is True for a non-empty directory inserr may reuse.
    what : str
        What the directory is meant to be, for the message (e.g. "an inserr report").
    fix : str
        How to fix a refused directory.

    Returns
    -------
    Path
        The resolved target.

    Raises
    ------
    InputError
        If writing there would destroy files inserr did not write, or cannot succeed.
    """
    from inserr.core.errors import InputError

    target = Path(out_dir).expanduser().resolve()
    cwd = Path.cwd().resolve()
    if target == cwd or target in cwd.parents:
        raise InputError(
            field,
            f"{out_dir!s} is the working directory or one of its parents",
            "name a new directory, e.g. my_report",
        )
    if target.exists() and not target.is_dir():
        raise InputError(field, f"{out_dir!s} exists and is not a directory", "name a directory")
    if target.is_dir() and any(target.iterdir()) and not is_ours(target):
        raise InputError(field, f"{out_dir!s} exists and is not {what} directory", fix)
    for parent in target.parents:
        if parent.exists():
            if not parent.is_dir():
                raise InputError(
                    field, f"{parent} is a file, so {out_dir!s} cannot be created", "fix the path"
                )
            if not os.access(parent, os.W_OK | os.X_OK):
                raise InputError(
                    field, f"no permission to write in {parent}", "choose another path"
                )
            break
    return target


def check_report_dir(out_dir: str | os.PathLike, field: str = "out") -> Path:
    """Check, before any work, that a report can be written to ``out_dir``.

    :meth:`Report.write` replaces the target directory as a whole, so it must be
    new, empty or an earlier inserr report (:func:`check_output_dir`).

    Parameters
    ----------
    out_dir : str or path
        The report directory the user asked for.
    field : str
        Name of the flag or key reported in the error message.

    Returns
    -------
    Path
        The resolved target.
    """
    return check_output_dir(
        out_dir,
        field,
        is_report_dir,
        "an inserr report",
        "name a new directory, or remove that one first (a report replaces it as a whole)",
    )


def replace_dir(src: Path, target: Path) -> None:
    """Move a finished directory ``src`` to ``target``, replacing it if it exists."""
    if target.exists():
        old = target.with_name(f".{target.name}.old-{os.getpid()}")
        os.replace(target, old)
        os.replace(src, target)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(src, target)


def write_bytes_atomic(path: str | os.PathLike, data: bytes) -> None:
    """Write a file atomically (temporary file in the same directory, then rename).

    The file ends up world-readable (0644), like any other output.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        os.chmod(tmp, 0o644)  # mkstemp makes it private; results are meant to be read
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_text_atomic(path: str | os.PathLike, text: str) -> None:
    """Write a UTF-8 text file atomically (see :func:`write_bytes_atomic`)."""
    write_bytes_atomic(path, text.encode("utf-8"))
