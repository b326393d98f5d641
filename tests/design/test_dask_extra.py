"""Dask is an extra: without it, ``--dask`` fails with one line naming the extra."""

import sys

import pytest

from csjm_opt.errors import DesignError


def test_dask_missing_gives_one_line_naming_the_extra(monkeypatch):
    from csjm_opt.design._dask_backend import _run_dask

    monkeypatch.setitem(sys.modules, "distributed", None)      # import distributed -> ImportError
    with pytest.raises(DesignError, match=r'pip install -e "\.\[dask\]"') as err:
        list(_run_dask([], None, None, 1, 1.0))
    assert "\n" not in str(err.value)


def test_the_dev_extra_holds_what_the_tests_import():
    import tomllib
    from pathlib import Path

    project = tomllib.loads((Path(__file__).resolve().parents[2] / "pyproject.toml").read_text())["project"]
    assert not any(d.startswith("dask") for d in project["dependencies"])
    dev = " ".join(project["optional-dependencies"]["dev"])
    for needed in ("pytest", "pytest-xdist", "hypothesis", "dask[distributed]"):
        assert needed in dev
