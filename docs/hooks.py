"""mkdocs hooks of the inserr documentation: generated content, and a check of the nav.

* ``on_files`` adds the scheme-catalogue figures (``docs/gen_figures.py``) to the
  site in memory, so no binary is committed and the figures follow the code; and
  warns (failing the strict build) for every ``nav`` page that does not exist, so a
  deleted or renamed page cannot go unnoticed.
* ``on_page_markdown`` replaces the markers of ``docs/cli.md`` and ``docs/api.md``
  with the reference generated from the argparse parsers (``docs/gen_cli.py``) and
  the ``:::`` blocks of every inserr module (rendered by mkdocstrings), and warns
  (failing the strict build) when a scheme of :data:`inserr.schemes.catalogue.SCHEMES` has no
  figure in ``docs/schemes.md``.
"""

from __future__ import annotations

import importlib.util
import logging
import pkgutil
from pathlib import Path

from mkdocs.structure.files import File, Files

log = logging.getLogger("mkdocs.hooks.inserr")
DOCS = Path(__file__).resolve().parent

CLI_MARKER = "<!-- inserr:cli-reference -->"
API_MARKER = "<!-- inserr:api-reference -->"


def _sibling(name: str):
    """Import ``docs/<name>.py`` (hooks are loaded by path, not as a package)."""
    spec = importlib.util.spec_from_file_location(f"inserr_docs_{name}", DOCS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def nav_pages(nav) -> list[tuple[str, str]]:
    """(title, path) of every Markdown page named in a mkdocs ``nav``."""
    out: list[tuple[str, str]] = []
    for item in nav or []:
        if isinstance(item, str):
            out.append((Path(item).stem, item))
            continue
        for title, value in item.items():
            if isinstance(value, str):
                if value.endswith(".md"):
                    out.append((title, value))
            else:
                out.extend(nav_pages(value))
    return out


def on_files(files: Files, *, config) -> Files:
    for rel, png in _sibling("gen_figures").scheme_figures().items():
        files.append(File.generated(config, rel, content=png))
    for title, src in nav_pages(config["nav"]):
        if files.get_file_from_path(src) is None:
            log.warning("inserr docs: nav page %r (%s) does not exist", title, src)
    return files


def api_blocks() -> str:
    """One mkdocstrings block per inserr module (the CLI has its own page)."""
    import inserr

    names = sorted(
        m.name
        for m in pkgutil.walk_packages(inserr.__path__, "inserr.")
        if not m.ispkg and not m.name.startswith("inserr.cli")
    )
    return "\n".join(f"::: {name}\n" for name in names)


def on_page_markdown(markdown: str, *, page, config, files) -> str:
    src = page.file.src_uri
    if src == "cli.md":
        markdown = markdown.replace(CLI_MARKER, _sibling("gen_cli").reference())
    elif src == "api.md":
        markdown = markdown.replace(API_MARKER, api_blocks())
    elif src == "schemes.md":
        from inserr.schemes.catalogue import SCHEMES

        for name in SCHEMES:
            if f"figures/schemes/{name}.png" not in markdown:
                log.warning("inserr docs: scheme %r has no figure in schemes.md", name)
    return markdown
