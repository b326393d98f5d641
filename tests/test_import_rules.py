"""The package's import rules, read off the real import graph (grimp, the engine of import-linter).

The layer contracts themselves are checked by ``lint-imports`` in CI (pyproject.toml,
``[tool.importlinter]``); this module checks the rule import-linter has no contract for: a
private module (a name starting with ``_``) is imported only from inside its own package.
"""

from __future__ import annotations

import grimp
import pytest


def _private_parent(module: str) -> str | None:
    """The package that owns ``module``'s first private component, or ``None`` if it has none."""
    parts = module.split(".")
    for k in range(1, len(parts)):
        if parts[k].startswith("_") and not parts[k].startswith("__"):
            return ".".join(parts[:k])
    return None


def _violations(graph) -> list[tuple[str, str]]:
    bad = []
    for importer in sorted(graph.modules):
        for imported in sorted(graph.find_modules_directly_imported_by(importer)):
            parent = _private_parent(imported)
            if parent is not None and not (importer == parent or importer.startswith(parent + ".")):
                bad.append((importer, imported))
    return bad


def test_private_modules_are_imported_only_from_their_own_package():
    graph = grimp.build_graph("csjm_opt")
    assert _violations(graph) == []


@pytest.mark.parametrize("importer, imported, allowed", [
    ("csjm_opt.shaping.shaper", "csjm_opt.planning._kernels", False),
    ("csjm_opt.planning.planner", "csjm_opt.planning._kernels", True),
    ("csjm_opt.planning.sub.mod", "csjm_opt.planning._kernels", True),
    ("csjm_opt.model.rig", "csjm_opt._validate", True),
    ("csjm_opt.control.plants.mujoco", "csjm_opt.control.controllers._tensions", False),
])
def test_the_rule_flags_a_cross_package_private_import(importer, imported, allowed):
    """The checker itself, on a graph built by hand: it must be able to fail."""
    graph = grimp.ImportGraph()
    graph.add_import(importer=importer, imported=imported)
    assert (_violations(graph) == []) == allowed


def test_every_subpackage_sits_in_a_layer_of_the_contract():
    """A new subpackage outside the layers contract would be checked by nothing."""
    import pathlib
    import tomllib

    root = pathlib.Path(__file__).resolve().parents[1]
    config = tomllib.loads((root / "pyproject.toml").read_text())["tool"]["importlinter"]
    layers = next(c for c in config["contracts"] if c["type"] == "layers")["layers"]
    named = {m.strip() for layer in layers for m in layer.replace(":", "|").split("|")}
    package = root / "csjm_opt"
    children = {f"csjm_opt.{p.name}" for p in package.iterdir() if (p / "__init__.py").exists()}
    children |= {f"csjm_opt.{p.stem}" for p in package.glob("*.py") if p.stem != "__init__"}
    assert children - named == set()
