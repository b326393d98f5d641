"""Every file the package writes is readable by others under the usual umask (figures included)."""

from __future__ import annotations

import os
import stat

import matplotlib

matplotlib.use("Agg")

import pytest  # noqa: E402

from csjm_opt import _plotting as plots  # noqa: E402


@pytest.mark.parametrize("umask, mode", [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_a_saved_figure_gets_the_usual_permissions(tmp_path, umask, mode):
    fig = plots.figure().figure()
    fig.gca().plot([0, 1], [0, 1])
    old = os.umask(umask)
    try:
        path = plots.save(fig, tmp_path / "f.png")
    finally:
        os.umask(old)
    assert stat.S_IMODE(path.stat().st_mode) == mode
    assert [p.name for p in tmp_path.iterdir()] == ["f.png"]
