"""A small document model for reports: sections with a verdict, tables with units, figures, links.

A :class:`Document` is rendered by :mod:`csjm_opt.report.render` through two
Jinja2 templates (HTML and Markdown) into one folder; nothing here knows about
either format. Numbers stay numbers until rendering: a :class:`Cell` holds the
value, the display format and, optionally, the path of the same value in the
report's JSON file (``Document.data_file``), so the rendered HTML carries
``data-src`` / ``data-scale`` / ``data-fmt`` attributes that a reader (or a
test) can check against the JSON.

Display formats: ``"sigN"`` (N significant digits, plain notation between
1e-4 and 1e6, else scientific), ``"fixN"`` (N decimals), ``"int"``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Sequence, Union

#: Statuses of a verdict: ``ok`` (as expected), ``warn`` (off the expectation, explained), ``fail``, ``info``.
STATUSES = ("ok", "warn", "fail", "info")


def format_number(value: Any, fmt: str = "sig3", scale: float = 1.0) -> str:
    """Display text of a number (``None``/NaN: "n/a"; bools: "yes"/"no"; text unchanged).

    Parameters
    ----------
    value : number, bool, str or None
        The value in the units of its JSON key.
    fmt : str
        ``"sigN"``, ``"fixN"`` or ``"int"`` (module docstring).
    scale : float
        Display factor (e.g. ``1e3`` for rad shown in mrad).

    Returns
    -------
    str
    """
    if value is None:
        return "n/a"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, str):
        return value
    x = float(value) * scale
    if not math.isfinite(x):
        return "n/a"
    if fmt == "int":
        return str(int(round(x)))
    if fmt.startswith("fix"):
        text = f"{x:.{int(fmt[3:])}f}"
        return text.lstrip("-") if float(text) == 0 else text
    if fmt.startswith("sig"):
        n = int(fmt[3:])
        if x == 0:
            return "0"
        e = math.floor(math.log10(abs(x)))
        if -4 <= e < 6:
            decimals = n - 1 - e
            rounded = round(x, decimals)
            if rounded != 0 and math.floor(math.log10(abs(rounded))) > e:   # 9.96 -> 10.0
                decimals -= 1
            return f"{rounded:.{max(decimals, 0)}f}"
        return f"{x:.{n - 1}e}"
    raise ValueError(f"unknown number format {fmt!r}")


def sig(value: Any, n: int = 3, scale: float = 1.0) -> str:
    """Shorthand for ``format_number(value, f"sig{n}", scale)`` (used in verdict sentences)."""
    return format_number(value, f"sig{n}", scale)


@dataclasses.dataclass(frozen=True)
class Cell:
    """A table cell: a value, its display format and where the same value is in the JSON file."""

    value: Any
    fmt: str | None = None           # None: the column's format
    scale: float | None = None       # None: the column's scale
    src: tuple | None = None         # path of keys/indices into Document.data_file


@dataclasses.dataclass(frozen=True)
class Column:
    """A table column: label, unit and the default display of its numbers."""

    label: str
    unit: str = ""
    fmt: str = "sig3"
    scale: float = 1.0

    @property
    def header(self) -> str:
        """The column heading: ``label (unit)``, or ``label`` alone without a unit."""
        return f"{self.label} ({self.unit})" if self.unit else self.label


@dataclasses.dataclass
class Table:
    """Rows of cells (:class:`Cell`, numbers, text, bools or None) under :class:`Column` headers."""

    columns: list[Column]
    rows: list[list[Any]]
    caption: str = ""
    kind: str = "table"

    def cells(self) -> list[list[dict[str, Any]]]:
        """Rendered rows: for each cell its text and, for numbers with a source, the check attributes."""
        out = []
        for row in self.rows:
            rendered = []
            for col, cell in zip(self.columns, row):
                if cell is None:                   # nothing to show (not applicable); Cell(None) shows "n/a"
                    rendered.append({"text": "", "numeric": False, "src": None, "fmt": "", "scale": 1.0})
                    continue
                c = cell if isinstance(cell, Cell) else Cell(cell)
                fmt = c.fmt or col.fmt
                scale = col.scale if c.scale is None else c.scale
                numeric = (isinstance(c.value, (int, float)) and not isinstance(c.value, bool)) or \
                    (c.value is None and c.src is not None)         # a missing number: "n/a", still checkable
                rendered.append({"text": format_number(c.value, fmt, scale), "numeric": numeric,
                                 "src": list(c.src) if c.src is not None else None, "fmt": fmt, "scale": scale})
            out.append(rendered)
        return out


@dataclasses.dataclass
class Figure:
    """An image file (path relative to the document's folder) with a caption."""

    path: str
    caption: str
    kind: str = "figure"


@dataclasses.dataclass
class Hyperlink:
    """A link (relative path or URL) with its text and an optional note after it."""

    href: str
    text: str
    note: str = ""


@dataclasses.dataclass
class Links:
    """A list of links (sub-reports, data files)."""

    links: list[Hyperlink]
    kind: str = "links"


@dataclasses.dataclass
class View:
    """An interactive page beside the document (``csjm_opt.view``), shown in an iframe; a link in Markdown."""

    path: str
    caption: str
    height_px: int = 980
    kind: str = "view"


@dataclasses.dataclass
class Paragraph:
    """Plain text; ``code`` in backticks is shown as code."""

    text: str
    kind: str = "paragraph"


Block = Union[Table, Figure, Links, Paragraph, View]


@dataclasses.dataclass
class Section:
    """A titled section: one verdict sentence first, then its blocks and subsections."""

    title: str
    verdict: str = ""
    status: str = "info"
    blocks: list[Block] = dataclasses.field(default_factory=list)
    subsections: list["Section"] = dataclasses.field(default_factory=list)
    anchor: str = ""

    def __post_init__(self) -> None:
        if self.status not in STATUSES:
            raise ValueError(f"status must be one of {STATUSES}, got {self.status!r}")
        if not self.anchor:
            self.anchor = "".join(ch if ch.isalnum() else "-" for ch in self.title.lower()).strip("-")

    def add(self, *blocks: Block) -> "Section":
        """Append blocks; returns self."""
        self.blocks.extend(blocks)
        return self

    def prefix_sources(self, prefix: Sequence[Any]) -> "Section":
        """Prepend ``prefix`` to every cell source (a step's summary nested under its name)."""
        for block in self.blocks:
            if isinstance(block, Table):
                block.rows = [[dataclasses.replace(c, src=tuple(prefix) + tuple(c.src))
                               if isinstance(c, Cell) and c.src is not None else c for c in row]
                              for row in block.rows]
        for sub in self.subsections:
            sub.prefix_sources(prefix)
        return self

    def rebase(self, folder: str) -> "Section":
        """Make figure and link paths relative to the parent folder (a section of a sub-folder's step)."""
        folder = folder.rstrip("/") + "/"
        for block in self.blocks:
            if isinstance(block, (Figure, View)) and "://" not in block.path:
                block.path = folder + block.path
            elif isinstance(block, Links):
                for link in block.links:
                    if "://" not in link.href:
                        link.href = folder + link.href
        for sub in self.subsections:
            sub.rebase(folder)
        return self


@dataclasses.dataclass
class Document:
    """A report: title, a lead paragraph, sections; ``data_file`` is the JSON its cells point into."""

    title: str
    lead: str = ""
    sections: list[Section] = dataclasses.field(default_factory=list)
    data_file: str = ""
    links: list[Hyperlink] = dataclasses.field(default_factory=list)
    footer: str = ""


def quantity_table(rows: Sequence[tuple[str, Any, str, str]], caption: str = "",
                   expectation: bool = False) -> Table:
    """A two- or three-column table of named quantities: (name, value or Cell, unit, expected).

    Parameters
    ----------
    rows : sequence of (name, value, unit, expected)
        ``value`` is a number, text or :class:`Cell`; ``expected`` a short text (shown when
        ``expectation`` is true).
    caption : str
    expectation : bool
        Show the "expected" column.

    Returns
    -------
    Table
    """
    cols = [Column("quantity"), Column("value"), Column("unit")]
    if expectation:
        cols.append(Column("expected"))
    body = [[name, value, unit] + ([expected] if expectation else []) for name, value, unit, expected in rows]
    return Table(cols, body, caption)
