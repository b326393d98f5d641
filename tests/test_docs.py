"""The repository documents itself: README commands match CI, no reference leaves the
repository, every API page names an importable module, and the guide's code snippets run."""

from __future__ import annotations

import importlib
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_readme_test_command_is_what_ci_runs():
    readme = (ROOT / "README.md").read_text()
    blocks = re.findall(r"```bash\n(.*?)\n```", readme, re.S)
    assert blocks[0].endswith("&& csjm demo")                     # first: the main job
    ci = (ROOT / ".ci" / "run").read_text().strip().splitlines()[-1]
    assert blocks[1] == ci                                        # second: exactly the CI line
    assert len(readme.splitlines()) <= 220


def _tracked_files() -> list[Path]:
    try:
        out = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True, check=True).stdout
        files = [ROOT / f for f in out.splitlines()]
    except (OSError, subprocess.CalledProcessError):               # not a git checkout: scan the tree
        files = [p for p in ROOT.rglob("*") if ".git" not in p.parts]
    return [p for p in files if p.is_file() and p.suffix in {".py", ".md", ".toml", ".yml", ".txt", ""}]


def test_nothing_refers_to_files_outside_the_repository():
    pattern = re.compile(r"SPEC\.md|ERRATA\.md|\.\./shared")
    offenders = [str(p.relative_to(ROOT)) for p in _tracked_files()
                 if p != Path(__file__).resolve() and pattern.search(p.read_text(errors="ignore"))]
    assert offenders == []


@pytest.mark.parametrize("page", sorted((ROOT / "docs" / "api").glob("*.md")), ids=lambda p: p.name)
def test_api_pages_name_importable_modules(page):
    modules = re.findall(r"^::: ([\w.]+)", page.read_text(), re.M)
    assert modules
    for name in modules:
        importlib.import_module(name)


def test_public_subpackage_names_are_documented_somewhere():
    """Every name in a documented subpackage's ``__all__`` has a docstring (so it shows in the API pages)."""
    missing = []
    for pkg in ("csjm_opt", "csjm_opt.identification", "csjm_opt.measurement", "csjm_opt.shaping",
                "csjm_opt.design", "csjm_opt.planning", "csjm_opt.model"):
        mod = importlib.import_module(pkg)
        for name in mod.__all__:
            obj = getattr(mod, name)
            if callable(obj) and not (getattr(obj, "__doc__", None) or "").strip():
                missing.append(f"{pkg}.{name}")
    assert missing == []


def test_errata_numbers_on_the_conventions_page_are_what_the_code_computes():
    from csjm_opt.identification import paper_report

    page = " ".join((ROOT / "docs" / "conventions.md").read_text().split())   # lines joined
    rep = paper_report()
    e_theta = ", ".join(f"{c['E_theta_rad']:.3f}" for c in rep["table4"])
    assert e_theta in page                                                     # erratum 5
    col_c = max(c["col_C_max_entry_error"] for c in rep["table4"])
    assert f"column C to {col_c:.4f}" in page                                  # erratum 4
    printed = [c["col_C_max_entry_error_K_printed"] for c in rep["table4"]]
    assert f"errors of {min(printed):.3f}-{max(printed):.3f}" in page
    assert f"`-hat(tau0)` to {rep['table3']['K_L_printed_vs_minus_hat_tau0']:.3f}" in page   # erratum 1
    m = re.search(r"\|\|R\^T R - I\|\| = ([\d.]+) \(tolerance [\d.]+\), det = ([\d.]+)", rep["R0_printed_rejected"])
    assert m and f"`||R0^T R0 - I|| = {float(m.group(1)):.3f}`" in page                  # erratum 3
    assert f"`det R0 = {float(m.group(2)):.3f}`" in page


def test_library_never_picks_a_matplotlib_backend_or_shows_figures():
    """Only the command line (cli/) and scripts choose Agg; library plot functions return axes."""
    offenders = []
    for path in (ROOT / "csjm_opt").rglob("*.py"):
        if "cli" in path.relative_to(ROOT / "csjm_opt").parts:
            continue
        text = path.read_text()
        for needle in ("matplotlib.use(", "plt.show(", "pyplot.show("):
            if needle in text:
                offenders.append(f"{path.relative_to(ROOT)}: {needle}")
    assert offenders == []


def test_importing_the_package_imports_no_plotting_or_cluster_library():
    code = ("import sys, csjm_opt, csjm_opt.identification, csjm_opt.shaping, csjm_opt.design; "
            "print(sorted(m for m in ('matplotlib.pyplot', 'mujoco', 'distributed') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                         env={**os.environ, "PYTHONPATH": str(ROOT)}, check=True).stdout
    assert out.strip() == "[]"


@pytest.mark.parametrize("plot", ["plot_convergence", "plot_verification"])
def test_identification_plots_draw_on_the_given_axes(plot):
    import matplotlib
    from matplotlib.figure import Figure

    from csjm_opt import identification

    matplotlib.use("Agg")
    ax = Figure().subplots()
    if plot == "plot_convergence":
        n = np.arange(5, 9.0)
        curve = identification.ConvergenceCurve(n, n, n, n, 0.1 * n)
        returned = identification.plot_convergence(curve, ax=ax)
    else:
        R = np.eye(3)[None].repeat(3, 0)
        v = identification.verify_increments(np.eye(3), np.eye(3), np.zeros((3, 3)), R)
        returned = identification.plot_verification([v], ax=ax)
    assert returned is ax and (ax.lines or ax.patches)


def test_top_level_import_loads_no_heavy_library_and_changes_no_setting():
    """``import csjm_opt`` stays light (PEP 562 lazy names); the heavy libraries load on first use."""
    heavy = ("scipy", "numba", "casadi", "mujoco", "matplotlib", "dask", "qpsolvers")
    code = ("import sys, os; import csjm_opt; "
            f"print(sorted(m for m in {heavy!r} if m in sys.modules)); "
            "print(sorted(k for k in os.environ if k.startswith('NUMBA'))); "
            "csjm_opt.plan_tensions; print('numba' in sys.modules, 'casadi' in sys.modules)")
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA")}
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                         env={**env, "PYTHONPATH": str(ROOT)}, check=True).stdout.split("\n")
    assert out[0] == "[]" and out[1] == "[]" and out[2] == "True False"     # the planner needs no CasADi


def test_importing_the_model_leaves_numbas_threading_layer_alone():
    code = ("import numba, csjm_opt; import csjm_opt.model, csjm_opt.planning; "
            "print(numba.config.THREADING_LAYER)")
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA")}
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                         env={**env, "PYTHONPATH": str(ROOT), "CSJM_NO_WARM_UP": "1"}, check=True).stdout
    assert out.strip() == "default"


def test_lazy_top_level_names_resolve_and_are_listed():
    import csjm_opt

    assert set(csjm_opt.__all__) <= set(dir(csjm_opt))
    for name in csjm_opt.__all__:
        assert getattr(csjm_opt, name) is not None
    with pytest.raises(AttributeError):
        csjm_opt.no_such_name  # noqa: B018
