"""Read a rendered report page back with the stdlib HTML parser (shared by the report tests)."""

from __future__ import annotations

import json
import math
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlparse


class Page(HTMLParser):
    """Links, images, sections (title, verdict, number of tables) and checkable number cells of a page."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.links: list[str] = []
        self.images: list[str] = []
        self.frames: list[str] = []        # iframes (the 3-D views beside the report)
        self.sections: list[dict] = []
        self.cells: list[dict] = []
        self.data_json = ""
        self._stack: list[dict] = []       # open <section>s
        self._capture: dict | None = None  # element whose text is being collected
        self._heading = False

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "body":
            self.data_json = a.get("data-json", "")
        elif tag == "a" and "href" in a:
            self.links.append(a["href"])
        elif tag == "img":
            self.images.append(a["src"])
        elif tag == "iframe" and "src" in a:
            self.frames.append(a["src"])
        elif tag == "section":
            sec = {"id": a.get("id"), "title": "", "verdict": None, "tables": 0, "figures": 0}
            self.sections.append(sec)
            self._stack.append(sec)
        elif tag in ("h2", "h3", "h4") and self._stack:
            self._heading = True
        elif tag == "p" and "verdict" in (a.get("class") or "").split() and self._stack:
            self._stack[-1]["verdict"] = ""
            self._capture = {"kind": "verdict", "section": self._stack[-1]}
        elif tag == "table" and self._stack:
            self._stack[-1]["tables"] += 1
        elif tag == "figure" and self._stack:
            self._stack[-1]["figures"] += 1
        elif tag == "td" and "data-src" in a:
            cell = {"src": json.loads(a["data-src"]), "scale": float(a["data-scale"]), "fmt": a["data-fmt"],
                    "text": ""}
            self.cells.append(cell)
            self._capture = {"kind": "cell", "cell": cell}

    def handle_endtag(self, tag):
        if tag == "section" and self._stack:
            self._stack.pop()
        elif tag in ("h2", "h3", "h4"):
            self._heading = False
        elif tag in ("p", "td"):
            self._capture = None

    def handle_data(self, data):
        if self._heading and self._stack:
            self._stack[-1]["title"] += data
        if self._capture is not None:
            if self._capture["kind"] == "verdict":
                self._capture["section"]["verdict"] += data
            else:
                self._capture["cell"]["text"] += data


def parse(path: Path) -> Page:
    page = Page()
    page.feed(Path(path).read_text(encoding="utf-8"))
    page.close()
    return page


def unresolved(page: Page, folder: Path) -> list[str]:
    """Relative links and images of ``page`` that do not name an existing file under ``folder``."""
    bad = []
    for ref in page.links + page.images + page.frames:
        u = urlparse(ref)
        if u.scheme or ref.startswith("#"):
            continue
        if ref.startswith("/") or not (folder / unquote(u.path)).exists():
            bad.append(ref)
    return bad


def tolerance(text: str, fmt: str) -> float:
    """Half a unit in the last place of a number shown with ``fmt`` (the stated rounding)."""
    shown = float(text)
    if fmt == "int":
        return 0.5
    if fmt.startswith("fix"):
        return 0.5 * 10.0 ** -int(fmt[3:])
    n = int(fmt[3:])
    if shown == 0:
        return 1e-300
    return 0.5 * 10.0 ** (math.floor(math.log10(abs(shown))) - n + 1)


def lookup(data, path):
    for key in path:
        data = data[key]
    return data


def mismatches(page: Page, data: dict) -> list[str]:
    """Number cells whose text differs from the JSON value at their source by more than the rounding."""
    bad = []
    for c in page.cells:
        value = lookup(data, c["src"])
        if c["text"] == "n/a":
            if value is not None and math.isfinite(value):
                bad.append(f"{c['src']}: n/a for {value}")
            continue
        expected = value * c["scale"]
        if abs(float(c["text"]) - expected) > tolerance(c["text"], c["fmt"]) * (1 + 1e-9) + 1e-12 * abs(expected):
            bad.append(f"{c['src']}: shown {c['text']}, JSON {value} x {c['scale']}")
    return bad
