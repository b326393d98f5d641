"""``csjm report RESULTS``: Pareto front, best designs, geometry; numbers equal design_report.json."""

from __future__ import annotations

import json

import numpy as np
import pytest

from csjm_opt.cli import main
from csjm_opt.model import hexagon
from csjm_opt.report.design.report import pareto_layers, pareto_mask
from tests.report_figures import problems, record_figures
from tests.report_html import mismatches, parse, unresolved


def brute_force_front(x, y):
    n = len(x)
    return np.array([not any(x[j] >= x[i] and y[j] >= y[i] and (x[j] > x[i] or y[j] > y[i]) for j in range(n))
                     for i in range(n)])


def test_pareto_mask_and_layers_against_brute_force():
    rng = np.random.default_rng(3)
    x = np.round(rng.random(60), 1)             # ties on purpose
    y = np.round(rng.random(60), 1)
    assert np.array_equal(pareto_mask(x, y), brute_force_front(x, y))
    layers = pareto_layers(x, y)
    for k in range(1, layers.max() + 1):
        rest = layers >= k
        assert np.array_equal(layers[rest] == k, brute_force_front(x[rest], y[rest]))


def _record(i, params, ws, kmin):
    return {"id": f"d{i}", "settings": "s", "index": i, "params": params, "status": "ok", "error": None,
            "workspace_fraction": ws, "min_stiffness_Nm_per_rad": kmin,
            "metrics": {"workspace_fraction": ws, "min_stiffness_Nm_per_rad": kmin, "tilt_cone_deg": 30.0 * ws,
                        "median_min_stiffness_Nm_per_rad": kmin + 2.0}}


@pytest.fixture
def results(tmp_path):
    d23 = hexagon.PAPER_PLATFORM_CHORDS_M[1]          # the paper's chord: this design is the paper's
    rows = [_record(0, {"platform_d23_m": d23}, 0.70, 14.0),
            _record(1, {"platform_d23_m": 0.080}, 0.80, 12.0),
            _record(2, {"platform_d23_m": 0.110}, 0.60, 15.0),
            _record(3, {"platform_d23_m": 0.100}, 0.75, 14.5),   # dominates the paper's
            _record(4, {"platform_d23_m": 0.070}, 0.50, 9.0)]
    rows.append({"id": "bad", "settings": "s", "index": 5, "params": {"platform_d23_m": -1.0}, "status": "invalid",
                 "error": "must be > 0", "workspace_fraction": None, "min_stiffness_Nm_per_rad": None, "metrics": None})
    path = tmp_path / "sweep.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in rows))
    return path


def test_report_of_results(results, tmp_path, capsys):
    out = tmp_path / "rep"
    with record_figures() as figures:
        assert main(["report", str(results), "--out", str(out), "--top", "4"]) == 0
    assert set(figures) == {"pareto", "geometry"}
    assert [p for name, d in figures.items() for p in problems(name, d)] == []
    assert "index.html" in capsys.readouterr().out
    page = parse(out / "index.html")
    data = json.loads((out / page.data_json).read_text())
    assert unresolved(page, out) == [] and "pareto.png" in page.images and "geometry.png" in page.images
    assert page.frames == ["designs.html"] and (out / "designs.html").stat().st_size <= 3_000_000
    assert mismatches(page, data) == [] and len(page.cells) >= 20
    front = sorted(d["params"]["platform_d23_m"] for d in data["pareto_front"])
    assert front == [0.08, 0.1, 0.11]                  # by hand: 1, 3, 2 are not beaten in both
    assert data["paper_design"]["designs_dominating_it"] == 1 and not data["paper_design"]["on_pareto_front"]
    verdict = page.sections[0]["verdict"]
    assert "dominated by 1 designs" in verdict and "5 valid" in verdict
    assert [d["pareto_layer"] for d in data["best"]] == [1, 1, 1, 2]


def test_report_errors(tmp_path, results, capsys):
    assert main(["report", str(tmp_path / "missing.jsonl")]) == 2
    empty = tmp_path / "empty.jsonl"
    empty.write_text("")
    assert main(["report", str(empty), "--out", str(tmp_path / "r1")]) == 2
    busy = tmp_path / "busy"
    busy.mkdir()
    (busy / "mine.txt").write_text("keep")
    assert main(["report", str(results), "--out", str(busy)]) == 2
    assert (busy / "mine.txt").read_text() == "keep"
    assert main(["report", str(results), "--top", "0", "--out", str(tmp_path / "r2")]) == 2
    err = capsys.readouterr().err
    assert err.count("csjm: error:") == 4


def test_report_with_the_sweep_file_marks_the_paper(tmp_path):
    sweep = tmp_path / "s.toml"
    sweep.write_text("""
[base]
platform_radius_m = 0.05795112883571237
[parameters.platform_gamma_deg]
values = [9.9, 40.0]
[sampling]
orientations = 20
[loads]
tau_ext = [[0.0, 0.0, 0.0]]
[metrics]
shaping_poses = 0
""")
    res = tmp_path / "r.jsonl"
    assert main(["sweep", str(sweep), "--out", str(res), "--workers", "1", "--no-progress"]) == 0
    assert main(["report", str(res), "--sweep", str(sweep)]) == 0
    out = tmp_path / "r_report"
    page = parse(out / "index.html")
    data = json.loads((out / "design_report.json").read_text())
    assert unresolved(page, out) == [] and mismatches(page, data) == []
    gamma = np.degrees(hexagon.circle_from_chords(*hexagon.PAPER_PLATFORM_CHORDS_M)[1])
    assert data["paper_design"]["params"]["platform_gamma_deg"] == pytest.approx(gamma)
    assert "paper's design" in page.sections[0]["verdict"]
