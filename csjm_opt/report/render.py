"""Render a :class:`~csjm_opt.report.document.Document` to HTML and Markdown (Jinja2 templates).

Both formats come from the same document and the same cell texts, through
``templates/document.html.j2`` and ``templates/document.md.j2`` (package
data). Figures and links stay files beside the page with relative paths, so
a report folder still works when it is moved or zipped.
"""

from __future__ import annotations

import html
import json
import re
from pathlib import Path

from .._fileio import atomic_write_text
from .document import Document

_CODE = re.compile(r"`([^`]+)`")


def _environment(autoescape: bool):
    import jinja2

    env = jinja2.Environment(loader=jinja2.PackageLoader("csjm_opt.report", "templates"),
                             autoescape=autoescape, trim_blocks=True, lstrip_blocks=True,
                             keep_trailing_newline=True, undefined=jinja2.StrictUndefined)
    env.filters["inline"] = _inline_html
    env.filters["md_cell"] = lambda text: str(text).replace("|", "\\|").replace("\n", " ")
    env.filters["tojson_attr"] = lambda value: json.dumps(value, separators=(",", ":"))
    return env


def _inline_html(text: str):
    """Escape text, then show `code` spans as <code> (the only inline markup)."""
    from markupsafe import Markup

    return Markup(_CODE.sub(r"<code>\1</code>", html.escape(str(text), quote=False)))


def render_html(doc: Document) -> str:
    """The document as one HTML page (inline CSS; figures and links relative).

    Parameters
    ----------
    doc : Document

    Returns
    -------
    str
    """
    return _environment(True).get_template("document.html.j2").render(doc=doc)


def render_markdown(doc: Document) -> str:
    """The document as Markdown (pipe tables, images and links relative).

    Parameters
    ----------
    doc : Document

    Returns
    -------
    str
    """
    return _environment(False).get_template("document.md.j2").render(doc=doc)


def write_document(doc: Document, out_dir: str | Path, html_name: str = "index.html",
                   md_name: str = "index.md") -> Path:
    """Write the HTML page and its Markdown twin into ``out_dir`` (atomically); returns the HTML path.

    Parameters
    ----------
    doc : Document
    out_dir : str or Path
        The report folder (figures already in it, at the paths the document names).
    html_name, md_name : str
        File names of the two renderings.

    Returns
    -------
    Path
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    atomic_write_text(out_dir / md_name, render_markdown(doc))
    return atomic_write_text(out_dir / html_name, render_html(doc))
