"""The input and output layers: permissions, same-file detection, special files, vectorised log reading."""

from __future__ import annotations

import os
import stat

import numpy as np
import pytest

from csjm_opt._fileio import atomic_write_text, check_output, read_text
from csjm_opt.errors import InvalidInput
from csjm_opt.measurement.logfile import COLUMNS, MeasurementLog


@pytest.mark.parametrize("umask, mode", [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_outputs_get_the_usual_permissions(tmp_path, umask, mode):
    old = os.umask(umask)
    try:
        path = atomic_write_text(tmp_path / "out.txt", "x\n")
    finally:
        os.umask(old)
    assert stat.S_IMODE(path.stat().st_mode) == mode
    assert [p.name for p in tmp_path.iterdir()] == ["out.txt"]      # no temporary file left


def test_output_naming_an_input_through_a_link_is_refused(tmp_path):
    src = tmp_path / "rig.toml"
    src.write_text("data")
    os.link(src, tmp_path / "hard.toml")
    os.symlink(src, tmp_path / "soft.toml")
    for alias in ("hard.toml", "soft.toml", "sub/../rig.toml"):
        (tmp_path / "sub").mkdir(exist_ok=True)
        with pytest.raises(InvalidInput, match="input"):
            check_output(tmp_path / alias, src, name="--json")
    check_output(tmp_path / "new.json", src, name="--json")              # a fresh path is fine
    assert src.read_text() == "data"


def test_special_files_are_refused_without_blocking(tmp_path):
    os.mkfifo(tmp_path / "pipe")
    with pytest.raises(InvalidInput, match="FIFO"):
        read_text(tmp_path / "pipe", InvalidInput, "log file")
    with pytest.raises(InvalidInput, match="folder"):
        read_text(tmp_path, InvalidInput, "log file")


def _plain_log(n: int = 40) -> str:
    rng = np.random.default_rng(0)
    rows = [",".join([str(i), str(i // 8)] + [repr(float(x)) for x in rng.uniform(0.1, 0.2, 6)]
                     + [repr(float(x)) for x in rng.normal(size=3)]
                     + [repr(float(x)) for x in rng.normal(size=3) * 0.1])
            for i in range(n)]
    return ",".join(COLUMNS) + "\n" + "\n".join(rows) + "\n"


def test_vectorised_and_strict_readers_agree():
    text = _plain_log()
    fast = MeasurementLog.from_text(text)
    # a quoted cell sends the same numbers through the strict csv reader
    head, first, rest = text.split("\n", 2)
    cells = first.split(",")
    cells[2] = f'"{cells[2]}"'
    strict = MeasurementLog.from_text("\n".join([head, ",".join(cells), rest]))
    for a, b in ((fast.sample, strict.sample), (fast.cycle, strict.cycle),
                 (fast.rest_lengths_m, strict.rest_lengths_m), (fast.tau_ext_A_Nm, strict.tau_ext_A_Nm),
                 (fast.rotvec_rad, strict.rotvec_rad)):
        assert a.dtype.kind == b.dtype.kind and np.array_equal(a, b)
    # blank lines are skipped by both; line numbers in errors count them (row 2 is on line 4)
    lines = text.split("\n")
    cells = lines[2].split(",")
    cells[8] = "1e19"
    lines[2] = ",".join(cells)
    with pytest.raises(InvalidInput, match=":4 column 'tau_x'"):
        MeasurementLog.from_text("\n".join(lines[:1] + [""] + lines[1:]))
