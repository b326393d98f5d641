"""Reports: the document model and its renderer, and the pages built with them (design study, diagnosis)."""

from .document import Cell, Column, Document, Figure, Hyperlink, Links, Paragraph, Section, Table, View
from .render import render_html, render_markdown, write_document

__all__ = ["Cell", "Column", "Document", "Figure", "Hyperlink", "Links", "Paragraph", "Section", "Table", "View",
           "render_html", "render_markdown", "write_document"]
