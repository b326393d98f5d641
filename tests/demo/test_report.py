"""``csjm demo --quick``: the report folder reads as a document and agrees with summary.json.

One quick demo run per session (``demo_dir``) is shared by every test here.
"""

from __future__ import annotations

import fcntl
import json
import shutil

import pytest

from csjm_opt.cli import main
from csjm_opt.demo.pipeline import STEPS
from tests.report_figures import problems, record_figures
from tests.report_html import mismatches, parse, unresolved

STEP_TITLES = {"plan tensions and stiffness": "Tensions and stiffness",
               "stiffness shaping and closed loop": "Stiffness shaping and closed loop",
               "simulate experiment, identify, verify": "Identification and verification",
               "diagnose model-rig gap": "Sim-to-real diagnosis"}


@pytest.fixture(scope="session")
def demo_run(tmp_path_factory):
    """One quick demo for the whole session, also across xdist workers (they share the parent temp dir)."""
    shared = tmp_path_factory.getbasetemp().parent
    out, figs = shared / "csjm_demo_quick", shared / "csjm_demo_quick_figures.json"
    with open(shared / "csjm_demo_quick.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)          # the first worker runs the demo, the others wait and reuse it
        if not figs.exists():
            with record_figures() as figures:
                assert main(["demo", "--quick", "--out", str(out)]) == 0
            figs.write_text(json.dumps(figures))
    return out, json.loads(figs.read_text())


@pytest.fixture(scope="session")
def demo_dir(demo_run):
    return demo_run[0]


@pytest.fixture(scope="session")
def summary(demo_dir):
    return json.loads((demo_dir / "summary.json").read_text())


def test_every_step_has_a_section_with_verdict_and_table(demo_dir, summary):
    page = parse(demo_dir / "index.html")
    assert list(summary) == [name for name, _ in STEPS]        # JSON keys: the step names, in order
    by_title = {s["title"].strip(): s for s in page.sections}
    for title in STEP_TITLES.values():
        sec = by_title[title]
        assert sec["verdict"] and sec["verdict"].strip().endswith("."), title
        assert sec["tables"] >= 1, title
    # verdicts state the result and the expectation, with the numbers of summary.json
    core = summary["plan tensions and stiffness"]
    residual = f"{core['max_equilibrium_residual_Nm']:.1e} N m: at round-off"
    assert residual in by_title["Tensions and stiffness"]["verdict"]
    shaping = by_title["Stiffness shaping and closed loop"]["verdict"]
    assert "is not reachable here" in shaping and "t_min" in shaping
    diag = summary["diagnose model-rig gap"]
    assert f"selected {diag['selected']}:" in by_title["Sim-to-real diagnosis"]["verdict"]
    assert diag["correct"] and "correct, as expected" in by_title["Sim-to-real diagnosis"]["verdict"]


def test_figures_sit_in_their_sections(demo_dir):
    page = parse(demo_dir / "index.html")
    by_title = {s["title"].strip(): s for s in page.sections}
    for title in ("Tensions and stiffness", "Stiffness shaping and closed loop", "Closed loop",
                  "Identification and verification", "Sim-to-real diagnosis"):
        assert by_title[title]["figures"] >= 1, title
    assert len(page.images) >= 7


def test_links_and_images_resolve_also_in_a_moved_copy(demo_dir, tmp_path):
    pages = ["index.html", "diagnosis/index.html", "experiment/index.html"]
    for name in pages:
        page = parse(demo_dir / name)
        assert page.links and unresolved(page, (demo_dir / name).parent) == [], name
    moved = tmp_path / "elsewhere" / "copy"
    shutil.copytree(demo_dir, moved)
    for name in pages:
        page = parse(moved / name)
        assert unresolved(page, (moved / name).parent) == [], name
    links = parse(demo_dir / "index.html").links
    assert "diagnosis/index.html" in links and "experiment/index.html" in links and "summary.json" in links


def test_the_rig_is_shown_in_3d(demo_dir, summary):
    """The demo shows the rig (rig.html in the first section); the diagnosis draws friction/offsets on it."""
    assert parse(demo_dir / "index.html").frames == ["rig.html"]
    assert (demo_dir / "rig.html").stat().st_size <= 3_000_000
    diag = json.loads((demo_dir / "diagnosis" / "diagnosis.json").read_text())
    drawn = diag["selected"] in ("friction", "hole_offsets")
    assert parse(demo_dir / "diagnosis" / "index.html").frames == (["rig.html"] if drawn else [])


@pytest.mark.parametrize("name", ["index.html", "diagnosis/index.html", "experiment/index.html"])
def test_table_numbers_equal_the_json(demo_dir, name):
    page = parse(demo_dir / name)
    data = json.loads(((demo_dir / name).parent / page.data_json).read_text())
    assert len(page.cells) >= 20
    assert mismatches(page, data) == []


def test_cells_point_at_the_right_keys(demo_dir, summary):
    """A few cells read independently: the row label names the quantity the cell's source holds."""
    page = parse(demo_dir / "index.html")
    srcs = {tuple(c["src"]): c["text"] for c in page.cells}
    core = summary["plan tensions and stiffness"]
    assert float(srcs[("plan tensions and stiffness", "min_eigenvalue_Nm_per_rad")]) == pytest.approx(
        min(min(p["eigenvalues_Nm_per_rad"]) for p in core["poses"]), rel=5e-3)
    upright = core["poses"][0]
    assert float(srcs[("plan tensions and stiffness", "poses", 0, "max_tension_N")]) == pytest.approx(
        max(upright["tensions_N"]), rel=5e-3)
    diag = summary["diagnose model-rig gap"]
    shown = float(srcs[("diagnose model-rig gap", "gap", "after_rad")])
    assert shown == pytest.approx(1e3 * diag["gap"]["after_rad"], rel=5e-3)   # shown in mrad


def test_markdown_twin_has_the_same_sections(demo_dir):
    md = (demo_dir / "README.md").read_text()
    for title in STEP_TITLES.values():
        assert f"## {title}" in md
    assert "](/" not in md and "poses: 13 entries" not in md
    assert "(diagnosis/index.html)" in md


def test_diagnosis_page_leads_with_the_verdict(demo_dir):
    page = parse(demo_dir / "diagnosis" / "index.html")
    first = page.sections[0]
    j = json.loads((demo_dir / "diagnosis" / "diagnosis.json").read_text())
    assert first["title"].strip() == "Verdict" and first["figures"] == 4
    assert f"{j['selected']} explains" in first["verdict"]
    assert f"{1e3 * j['gap']['before_rad']:.3g}" in first["verdict"]
    text = (demo_dir / "diagnosis" / "index.html").read_text()
    assert "{'" not in text and "tension_band_percent" in text     # derived values as a table, no raw dict


#: Figures drawn by the report layer itself (the others come from the plotting of their own modules).
REPORT_FIGURES = ("tensions_and_stiffness", "residual_map", "hysteresis", "candidates", "before_after")


def test_report_figures_have_titles_units_and_free_legends(demo_run):
    _, figures = demo_run
    assert set(REPORT_FIGURES) <= set(figures)
    assert [p for name in REPORT_FIGURES for p in problems(name, figures[name])] == []


def test_every_written_file_is_readable_by_others(demo_dir):
    """Figures included: mode ``0o666 & ~umask`` (0644 under the usual umask), never mkstemp's 0600."""
    import os
    import stat

    mask = os.umask(0)
    os.umask(mask)
    files = [p for p in demo_dir.rglob("*") if p.is_file()]
    assert any(p.suffix == ".png" for p in files)
    wrong = {str(p.relative_to(demo_dir)): oct(stat.S_IMODE(p.stat().st_mode)) for p in files
             if stat.S_IMODE(p.stat().st_mode) != 0o666 & ~mask}
    assert wrong == {}
