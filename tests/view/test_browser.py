"""The view page in a real browser (headless Chromium over the DevTools protocol).

Checks: the page loads with no console error and fetches nothing but itself; a screenshot shows the
rig (differs from a blank page and from the same page at another pose, in the plot's area); the
numbers shown equal the API's (``co.plan_tensions``, ``co.stiffness``'s eigenvalues) to the digits
shown, frame by frame; a pose the rig cannot hold renders and names the cables at their bounds.
Skipped (with the reason) only when no Chromium is installed (``.ci/run`` installs it).
"""

from __future__ import annotations

import io
import re

import numpy as np
import pytest

import csjm_opt as co
from csjm_opt.view import poses_view
from tests.chromium_cdp import Browser, find_chromium

CHROMIUM = find_chromium()
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="no Chromium installed (apt-get install chromium; "
                                                         ".ci/run installs it when missing)")
READY = "document.body && document.body.dataset.ready === '1'"
LOAD_TIMEOUT_S = 180.0     # the machine is shared; a page normally takes a few seconds
MAX_BYTES = 3_000_000
ROTVEC, TAU = np.array([0.25, 0.1, 0.0]), np.array([0.5, 0.2, 0.0])
STEPS = (0.0, 0.5, 1.0)                                               # frames 0-2: along the path to ROTVEC, TAU
BAD_ROTVEC, BAD_TAU = np.array([0.3, 0.1, 0.0]), np.array([20.0, 0.0, 0.0])   # frame 3: a load the rig cannot hold


def load_page(browser, folder):
    """One page (4 frames, frame 2 shown first), loaded once; screenshots of two poses."""
    Rs = co.so3.exp(np.vstack([np.outer(STEPS, ROTVEC), BAD_ROTVEC]))
    page = poses_view(co.paper_rig(), Rs, np.vstack([np.outer(STEPS, TAU), BAD_TAU]), initial=2)
    path = page.write(folder / "view.html")
    tab = browser.new_page()
    tab.goto(path.as_uri())
    tab.wait_for(READY, LOAD_TIMEOUT_S)
    rect = tab.eval("(() => {const r = document.getElementById('plot').getBoundingClientRect();"
                    " return [r.left, r.top, r.right, r.bottom].map(Math.round);})()")
    shots = {2: tab.screenshot()}
    tab.eval("csjmView.show(0)", LOAD_TIMEOUT_S)
    shots[0] = tab.screenshot()
    return {"page": page, "path": path, "tab": tab, "rect": rect, "shots": shots}


def _plot_pixels(png: bytes, rect: list[int]) -> np.ndarray:
    from PIL import Image

    img = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=np.int16)
    left, top, right, bottom = rect
    return img[top:bottom, left:right]


def check_one_small_file_with_no_web_address(feasible):
    text = feasible["path"].read_text(encoding="utf-8")
    assert feasible["path"].stat().st_size <= MAX_BYTES
    assert "http://" not in text and "https://" not in text
    assert "<script src" not in text and "<link" not in text


def check_no_console_error_and_no_fetch(feasible):
    tab = feasible["tab"]
    assert tab.console_errors() == []
    urls = tab.requested_urls()
    assert urls == [feasible["path"].as_uri()], urls
    assert tab.eval("typeof Plotly") == "object" and tab.eval("document.querySelectorAll('#plot canvas').length") > 0


def check_screenshot_shows_the_rig(browser, feasible, tmp_path):
    rect = feasible["rect"]
    empty = tmp_path / "blank.html"
    empty.write_text("<!DOCTYPE html><html><body></body></html>")
    blank_tab = browser.new_page()
    blank_tab.goto(empty.as_uri())
    blank_tab.wait_for("document.readyState === 'complete'", LOAD_TIMEOUT_S)
    blank = _plot_pixels(blank_tab.screenshot(), rect)
    shown, other = (_plot_pixels(feasible["shots"][k], rect) for k in (2, 0))
    differs = lambda a, b: np.count_nonzero(np.abs(a - b).max(axis=-1) > 40)  # noqa: E731
    area = shown.shape[0] * shown.shape[1]
    assert differs(shown, blank) > 0.02 * area          # the rig is drawn, not a white box
    assert differs(shown, other) > 0.002 * area         # another pose (upright, unloaded) looks different
    # the cables are drawn in the tension colour scale: many saturated (non-grey) pixels
    saturated = (shown.max(axis=-1) - shown.min(axis=-1)) > 60
    assert np.count_nonzero(saturated) > 0.002 * area


def _shown(tab) -> dict[str, list[str]]:
    cells = tab.eval("[...document.querySelectorAll('#numbers [data-q]')].map(e => [e.dataset.q, e.textContent])")
    out: dict[str, list[str]] = {}
    for q, text in cells:
        out.setdefault(q, []).append(text.strip())
    return out


def _equal_to_digits(text: str, value: float) -> bool:
    decimals = len(text.split(".")[1]) if "." in text else 0
    return abs(float(text) - value) <= 0.5 * 10.0 ** -decimals + 1e-9 * max(1.0, abs(value))


def check_numbers_equal_the_api_frame_by_frame(feasible):
    tab, rig = feasible["tab"], co.paper_rig()
    for k, s in enumerate(STEPS):
        tab.eval(f"csjmView.show({k})", LOAD_TIMEOUT_S)
        shown = _shown(tab)
        R = co.so3.exp(s * ROTVEC)
        T = co.plan_tensions(rig, R, s * TAU).tensions
        eig = np.linalg.eigvalsh(co.stiffness(rig, R, T))
        assert len(shown["tension"]) == len(rig.platform_holes_A_m)
        assert all(_equal_to_digits(t, v) for t, v in zip(shown["tension"], T)), (shown["tension"], T)
        assert all(_equal_to_digits(t, v) for t, v in zip(shown["eig"], eig)), (shown["eig"], eig)
        assert "Held" in shown["status"][0]


def check_a_pose_the_rig_cannot_hold_names_the_cables(feasible):
    rig = co.paper_rig()
    with pytest.raises(co.InfeasibleLoad) as info:
        co.plan_tensions(rig, co.so3.exp(BAD_ROTVEC), BAD_TAU)
    tab = feasible["tab"]
    tab.eval("csjmView.show(3)", LOAD_TIMEOUT_S)
    assert tab.console_errors() == []
    shown = _shown(tab)
    status = shown["status"][0]
    assert status.startswith("NOT held")
    # the moment left unbalanced is the planner's distance to the wrench-feasible set
    left = float(re.search(r"leave ([0-9.e+-]+) N m", status).group(1))
    assert left == pytest.approx(info.value.distance_Nm, rel=5e-3)
    T = np.array([float(t) for t in shown["tension"]])
    assert np.all(T >= rig.t_min_N - 1e-9) and np.all(T <= rig.t_max_N + 1e-9)
    named = {int(c) for c in re.findall(r"(\d+) \(t_m(?:in|ax)\)", status)}
    at_bound = {i + 1 for i, t in enumerate(T) if t in (rig.t_min_N, rig.t_max_N)}
    assert named == at_bound and named
    assert "eig" not in shown       # no equilibrium, so no K


def test_view_page_in_chromium(tmp_path):
    """One browser, one page load (a few seconds on an idle machine), every check in turn (one xdist worker)."""
    browser = Browser(CHROMIUM)
    try:
        feasible = load_page(browser, tmp_path)
        check_one_small_file_with_no_web_address(feasible)
        check_no_console_error_and_no_fetch(feasible)
        check_screenshot_shows_the_rig(browser, feasible, tmp_path)
        check_numbers_equal_the_api_frame_by_frame(feasible)
        check_a_pose_the_rig_cannot_hold_names_the_cables(feasible)
        check_no_console_error_and_no_fetch(feasible)        # still none after every frame was shown
    finally:
        browser.close()
