"""The report layer: number display, document model, HTML and Markdown rendering."""

from __future__ import annotations

import math

import pytest

from csjm_opt.report.document import (
    Cell,
    Column,
    Document,
    Figure,
    Hyperlink,
    Links,
    Paragraph,
    Section,
    Table,
    format_number,
)
from csjm_opt.report.render import render_html, render_markdown, write_document
from tests.report_html import mismatches, parse, unresolved


@pytest.mark.parametrize("value, fmt, scale, text", [
    (4870.3, "sig3", 1.0, "4870"), (4870.3, "sig4", 1.0, "4870"), (17.4412, "sig3", 1.0, "17.4"),
    (9.96, "sig2", 1.0, "10"), (9.96, "sig3", 1.0, "9.96"), (0.00123456, "sig3", 1.0, "0.00123"),
    (4.6251e-15, "sig2", 1.0, "4.6e-15"), (1234567.0, "sig3", 1.0, "1.23e+06"), (-0.25, "sig2", 1.0, "-0.25"),
    (0.1234, "sig2", 1e3, "120"), (0.98133, "fix1", 100.0, "98.1"), (-0.0004, "fix3", 1.0, "0.000"),
    (12.6, "int", 1.0, "13"), (0.0, "sig3", 1.0, "0"), (None, "sig3", 1.0, "n/a"), (math.nan, "fix2", 1.0, "n/a"),
    (True, "sig3", 1.0, "yes"), ("t3=t_min", "sig3", 1.0, "t3=t_min"),
])
def test_format_number(value, fmt, scale, text):
    assert format_number(value, fmt, scale) == text


def test_unknown_format_is_refused():
    with pytest.raises(ValueError):
        format_number(1.0, "pct2")


def _doc() -> Document:
    table = Table([Column("name"), Column("value", "mrad", scale=1e3), Column("note")],
                  [["a|b", Cell(0.0123456, src=("x", 0)), None], ["c", Cell(None, src=("y",)), "`code`"]],
                  "caption <i>")
    sec = Section("Step <one>", "residual 5e-15 N m: at round-off <b>", "ok",
                  [table, Figure("fig.png", "a figure"), Links([Hyperlink("sub/index.html", "sub report", "more")]),
                   Paragraph("see `summary.json`")])
    sec.subsections.append(Section("Detail", "second verdict.", "warn"))
    return Document("Title & more", "lead", [sec, Section("Two")], data_file="data.json",
                    links=[Hyperlink("data.json", "data")])


def test_html_escapes_text_and_carries_sources(tmp_path):
    html = render_html(_doc())
    assert "&lt;b&gt;" in html and "<b>" not in html and "Title &amp; more" in html
    assert "<code>summary.json</code>" in html
    page = parse_text(tmp_path, html)
    assert [s["title"] for s in page.sections] == ["Step <one>", "Detail", "Two"]
    assert page.sections[0]["verdict"] == "residual 5e-15 N m: at round-off <b>"
    assert page.sections[0]["tables"] == 1 and page.sections[0]["figures"] == 1
    assert [c["src"] for c in page.cells] == [["x", 0], ["y"]]
    assert page.cells[0]["text"] == "12.3"
    assert mismatches(page, {"x": [0.0123456], "y": None}) == []
    assert mismatches(page, {"x": [0.0124], "y": None}) != []          # 12.4 mrad is not 12.3


def test_markdown_twin(tmp_path):
    md = render_markdown(_doc())
    assert md.startswith("# Title & more")
    assert "| a\\|b | 12.3 |  |" in md and "| name | value (mrad) | note |" in md
    assert "> residual 5e-15 N m: at round-off <b>" in md
    assert "![fig.png](fig.png)" in md and "- [sub report](sub/index.html): more" in md
    assert "### Detail" in md


def test_rebase_and_prefix_for_a_step_in_a_subfolder(tmp_path):
    doc = _doc()
    doc.sections[0].rebase("sub").prefix_sources(("step",))
    (tmp_path / "sub" / "sub").mkdir(parents=True)
    (tmp_path / "sub" / "fig.png").write_bytes(b"png")
    (tmp_path / "sub" / "sub" / "index.html").write_text("x")
    (tmp_path / "data.json").write_text("{}")
    page = parse(write_document(doc, tmp_path))
    assert unresolved(page, tmp_path) == []
    assert page.cells[0]["src"] == ["step", "x", 0]
    assert (tmp_path / "index.md").exists()


def test_status_is_checked():
    with pytest.raises(ValueError):
        Section("x", "y", "great")


def parse_text(tmp_path, html):
    path = tmp_path / "page.html"
    path.write_text(html)
    return parse(path)


def test_the_figure_check_finds_what_a_figure_lacks():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from tests.report_figures import describe, problems

    fig, ax = plt.subplots()
    ax.plot([1, 2], [3, 4], label="a")
    ax.legend(loc="upper left")
    ax.set_xlabel("time")
    found = problems("f", describe(fig))
    assert any("no title" in p for p in found) and any("no unit" in p for p in found)
    assert any("no ylabel" in p for p in found) and any("legend" in p for p in found)
    ax.set(title="T", xlabel="time (s)", ylabel="angle (rad)")
    ax.legend(loc="best")
    assert problems("f", describe(fig)) == []
    plt.close(fig)
