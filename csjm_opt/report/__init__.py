"""Reports: the document model and renderer, the ``csjm demo`` job and its steps, the design-study report."""

from .demo import run as run_demo
from .document import Cell, Column, Document, Figure, Link, Links, Paragraph, Section, Table
from .render import render_html, render_markdown, write_document

__all__ = ["Cell", "Column", "Document", "Figure", "Link", "Links", "Paragraph", "Section", "Table",
           "render_html", "render_markdown", "run_demo", "write_document"]
