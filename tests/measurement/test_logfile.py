"""Measurement log CSV (docs/conventions.md): strict reading, clear errors naming the line, atomic writing."""

import numpy as np
import pytest

from csjm_opt import DataFileError, so3
from csjm_opt.measurement.logfile import COLUMNS, MeasurementLog

HEADER = ",".join(COLUMNS)


def _row(sample, cycle, tau=(0.1, -0.2, 0.3), rv=(0.01, 0.02, 0.03)):
    return ",".join(str(x) for x in (sample, cycle, *([0.17] * 6), *tau, *rv))


def _text(*rows, header=HEADER):
    return "\n".join([header, *rows]) + "\n"


def test_round_trip_and_extra_columns(tmp_path):
    text = _text(_row(0, 1) + ",a", _row(1, 1) + ",b", _row(2, 5) + ",c", header=HEADER + ",note")
    log = MeasurementLog.from_text(text, "x.csv")
    assert len(log) == 3 and log.cycle_ids == [1, 5]
    assert list(log.extra["note"]) == ["a", "b", "c"]
    assert np.allclose(log.R[0], so3.exp([0.01, 0.02, 0.03]))
    path = tmp_path / "log.csv"
    log.to_csv(path)
    again = MeasurementLog.from_csv(path)
    assert np.array_equal(again.rest_lengths_m, log.rest_lengths_m)
    assert np.array_equal(again.rotvec_rad, log.rotvec_rad)
    with pytest.raises(Exception, match="refusing to overwrite"):
        log.to_csv(path)
    assert list(log.cycle_rows(1)) == [0, 1]


@pytest.mark.parametrize("text, line, fragment", [
    (_text(_row(0, 1), "1,1,0.17,0.17"), 3, "expected 14 values"),
    (_text(_row(0, 1), _row(1, 1).replace("-0.2", "")), 3, "missing value"),
    (_text(_row(0, 1).replace("-0.2", "abc")), 2, "not a number"),
    (_text(_row(0, 1), _row(1, 1).replace("-0.2", "inf")), 3, "not finite"),
    (_text(_row(0, 1), _row(0, 1)), 3, "duplicate sample id 0"),
    (_text(_row(0, 1), _row(1, 2), _row(2, 1)), 4, "not consecutive"),
    (_text(_row(0, 1.5)), 2, "integer"),
])
def test_malformed_rows_name_the_line(text, line, fragment):
    with pytest.raises(DataFileError, match=fragment) as info:
        MeasurementLog.from_text(text, "data.csv")
    assert info.value.line == line
    assert f"data.csv:{line}" in str(info.value)


def test_bad_header_and_empty_file():
    with pytest.raises(DataFileError, match="header must start with") as info:
        MeasurementLog.from_text(_text(_row(0, 1), header=HEADER.replace("tau_x", "tx")), "d.csv")
    assert info.value.line == 1 and "tau_x" in str(info.value)
    with pytest.raises(DataFileError, match="empty file"):
        MeasurementLog.from_text("", "d.csv")
    with pytest.raises(DataFileError, match="no data rows"):
        MeasurementLog.from_text(HEADER + "\n", "d.csv")


def test_missing_file(tmp_path):
    with pytest.raises(DataFileError, match="cannot read"):
        MeasurementLog.from_csv(tmp_path / "none.csv")
