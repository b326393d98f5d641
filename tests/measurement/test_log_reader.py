"""The fast log reader against the strict row-by-row reader (csv module + float) on generated logs.

Same rows, bit-identical values, same line numbers and extra cells on valid
logs of every shape the format allows; the same error (message, line,
column) on every kind of bad cell, wherever it sits.
"""

from decimal import Decimal, getcontext

import numpy as np
import pytest

from csjm_opt.errors import DataFileError
from csjm_opt.measurement import _fast_csv, _log_reader
from csjm_opt.measurement._log_checks import _check_rows
from csjm_opt.measurement._log_reader import COLUMNS, read_log_bytes, read_log_strict
from csjm_opt.measurement.logfile import MeasurementLog

pytestmark = pytest.mark.skipif(not _fast_csv.AVAILABLE, reason="no correctly rounded strtod here")
HEADER = ",".join(COLUMNS)


def strict_log(text: str, source: str) -> MeasurementLog:
    """The reference: every row through the csv module and float(), then the same value checks."""
    rows = read_log_strict(text, source)
    V = rows.values
    log = MeasurementLog(V[:, 0].astype(np.int64), V[:, 1].astype(np.int64), V[:, 2:8], V[:, 8:11],
                         V[:, 11:14], rows.extra, source)
    _check_rows(log, source, rows.lines)
    return log


def _cells(rng, n):
    """Valid cells in many spellings: repr, fixed, scientific, signs, spaces."""
    L = 0.05 + 0.2 * rng.random((n, 6))
    tau = rng.normal(size=(n, 3)) * 10.0 ** rng.integers(-4, 2, (n, 1))
    rv = rng.normal(size=(n, 3)) * 0.3
    out = []
    for row in np.hstack([L, tau, rv]).tolist():
        cells = []
        for x in row:
            style = rng.integers(6)
            cells.append([repr(x), f"{x:.6f}", f"{x:.4e}", f"{x:+.9E}", f" {x:.3f}\t", f"{x:.17g}"][style])
        out.append(cells)
    return out


def _log_text(rng, n=300, extra=0, newline="\n", trailing=True, blank=False, quoted=0.0, note="x"):
    header = HEADER + "".join(f",note{j}" for j in range(extra))
    cycle = np.cumsum(rng.random(n) < 0.1)
    lines = [header]
    for i, cells in enumerate(_cells(rng, n)):
        extras = [f"{note}{i}" if j % 2 == 0 else "" for j in range(extra)]
        if extra and rng.random() < 0.2:
            extras = extras[:int(rng.integers(0, extra))]      # short row: missing extras are empty
        if rng.random() < quoted:
            extras = [f'"a, ""{i}"""'] + extras[1:] if extras else extras
            cells[3] = f'"{cells[3]}"'
        lines.append(",".join([str(1000 + i), str(int(cycle[i]))] + cells + extras))
        if blank and rng.random() < 0.1:
            lines.append("")
    return newline.join(lines) + (newline if trailing else "")


def _same(a: MeasurementLog, b: MeasurementLog) -> None:
    for name in ("sample", "cycle", "rest_lengths_m", "tau_ext_A_Nm", "rotvec_rad"):
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.shape == y.shape
        assert np.array_equal(x.view(np.uint64) if x.dtype == float else x,
                              y.view(np.uint64) if y.dtype == float else y), name   # bit-identical
    assert list(a.extra) == list(b.extra)
    for k in a.extra:
        assert a.extra[k].tolist() == b.extra[k].tolist()


@pytest.mark.parametrize("kw", [
    {}, {"extra": 2}, {"extra": 3, "newline": "\r\n"}, {"trailing": False}, {"extra": 1, "trailing": False},
    {"blank": True, "newline": "\r\n"}, {"quoted": 0.3, "extra": 2}, {"extra": 1, "note": "café ✓"},
])
def test_fast_reader_equals_strict_reader(kw):
    rng = np.random.default_rng(len(str(kw)))
    text = _log_text(rng, **kw)
    _same(MeasurementLog.from_text(text, "g.csv"), strict_log(text, "g.csv"))


def test_mostly_quoted_log_is_left_to_the_strict_parser(monkeypatch):
    monkeypatch.setattr(_log_reader, "_STRICT_RUN", 5)
    text = _log_text(np.random.default_rng(8), quoted=0.9, extra=2, blank=True)
    _same(MeasurementLog.from_text(text, "q.csv"), strict_log(text, "q.csv"))
    lines = text.split("\n")
    lines[250] = lines[250].replace(",", ",,", 1)                   # an empty cycle cell near the end
    with pytest.raises(DataFileError) as got:
        MeasurementLog.from_text("\n".join(lines), "q.csv")
    with pytest.raises(DataFileError) as ref:
        strict_log("\n".join(lines), "q.csv")
    assert (str(got.value), got.value.line) == (str(ref.value), ref.value.line)


def test_without_the_compiled_pass_the_strict_parser_reads_everything(monkeypatch):
    text = _log_text(np.random.default_rng(9), n=50, extra=1, newline="\r\n")
    fast = MeasurementLog.from_text(text, "w.csv")
    monkeypatch.setattr(_fast_csv, "AVAILABLE", False)
    monkeypatch.setattr(_fast_csv, "scan_rows", None)     # would fail if called
    _same(MeasurementLog.from_text(text, "w.csv"), fast)


def test_text_with_a_lone_surrogate_is_read_strictly():
    text = _log_text(np.random.default_rng(10), n=5, extra=1, note="\udc80")
    _same(MeasurementLog.from_text(text, "s.csv"), strict_log(text, "s.csv"))


def test_file_and_text_agree(tmp_path):
    text = _log_text(np.random.default_rng(3), extra=1, newline="\r\n")
    path = tmp_path / "log.csv"
    path.write_bytes(b"\xef\xbb\xbf" + text.encode())          # with a byte-order mark
    _same(MeasurementLog.from_csv(path), strict_log(text, "g.csv"))


def test_plain_rows_never_reach_the_strict_parser(monkeypatch):
    calls = []
    real = _log_reader.strict_records
    monkeypatch.setattr(_log_reader, "strict_records", lambda *a: calls.append(a[2]) or real(*a))
    rng = np.random.default_rng(4)
    MeasurementLog.from_text(_log_text(rng, extra=2, newline="\r\n", blank=True), "p.csv")
    assert calls == []
    lines = _log_text(rng, n=20).split("\n")
    cells = lines[7].split(",")
    cells[1] = f'"{cells[1]}"'                   # a quoted cycle id: only the strict parser reads it
    lines[7] = ",".join(cells)
    MeasurementLog.from_text("\n".join(lines), "p.csv")
    assert calls == [8]


def _numbers_equal_float(strings):
    n = len(strings) // 12
    rows = [f"{i},0," + ",".join(strings[12 * i:12 * i + 12]) for i in range(n)]
    got = read_log_bytes((HEADER + "\n" + "\n".join(rows)).encode(), "n.csv").values[:, 2:]
    ref = np.array([float(s) for s in strings[:12 * n]]).reshape(n, 12)
    bad = np.flatnonzero(got.view(np.uint64).ravel() != ref.view(np.uint64).ravel())
    assert bad.size == 0, [strings[i] for i in bad[:5]]


def test_numbers_are_bit_identical_to_float():
    rng = np.random.default_rng(11)
    m = 12 * 1500
    bits = rng.integers(0, 2 ** 63 - 2 ** 52, m, dtype=np.int64)       # every finite double, either sign
    doubles = bits.view(np.float64) * np.where(rng.random(m) < 0.5, -1.0, 1.0)
    strings = [repr(float(x)) for x in doubles]
    for k in range(m):                                                   # decimal strings of 1 to 22 digits
        nd = int(rng.integers(1, 23))
        digits = "".join(map(str, rng.integers(0, 10, nd)))
        strings.append(f"{digits}e{int(rng.integers(-345, 300 - nd))}" if k % 2 else
                       f"-{digits[:nd // 2]}.{digits[nd // 2:]}")
    getcontext().prec = 80
    for _ in range(3000):                                                # exact midpoints of two doubles
        x = abs(float(rng.normal())) * 10.0 ** int(rng.integers(-30, 30))
        mid = (Decimal(x) + Decimal(float(np.nextafter(x, np.inf)))) / 2
        strings.append(format(mid, f".{int(rng.integers(14, 40))}e"))
    strings += ["0", "-0", "0e999", "-0.0e-999", "4.9e-324", "2.4703282292062328e-324", "1e-320",
                "2.2250738585072011e-308", "2.2250738585072014e-308", "1.7976931348623157e308",
                "9007199254740993", "9007199254740992.5", "123456789012345678901234567890", "000123.4500",
                "1.", ".5", "+.5e-3", "1E+2", "0.1", "0.30000000000000004"]
    strings += ["1"] * (-len(strings) % 12)
    _numbers_equal_float(strings)


HUGE = "1" * 400
BAD = ["", " ", "abc", "1e400", "-1e400", "nan", "inf", "1_0", "0x10", "1.2.3", "1e", "+", ".", "--1", "1e+",
       "\u0661", "1,5", '"1.5"', "1.5\r2", "1\x002", HUGE, "1e19", "2.5", "-0.5", "1e5", "6.3", "0"]


@pytest.mark.parametrize("column", [0, 1, 3, 9, 13])
@pytest.mark.parametrize("value", BAD)
def test_bad_cells_raise_the_strict_readers_error(column, value):
    rng = np.random.default_rng(column)
    lines = _log_text(rng, n=40, extra=1).split("\n")
    row = 1 + int(rng.integers(0, 40))
    cells = lines[row].split(",")
    cells[column] = value
    lines[row] = ",".join(cells)
    text = "\n".join(lines)
    try:
        expected = strict_log(text, "b.csv")
    except DataFileError as exc:
        with pytest.raises(DataFileError) as info:
            MeasurementLog.from_text(text, "b.csv")
        assert (str(info.value), info.value.line, info.value.column) == (str(exc), exc.line, exc.column)
        return
    _same(MeasurementLog.from_text(text, "b.csv"), expected)    # accepted by both (1_0, "1.5", ...)


@pytest.mark.parametrize("edit", ["dup", "cycle", "short", "long", "header", "lone-cr", "only-header", "empty"])
def test_bad_structure_raises_the_strict_readers_error(edit):
    lines = _log_text(np.random.default_rng(7), n=30).split("\n")
    if edit == "dup":
        lines[20] = lines[5].split(",", 1)[0] + "," + lines[20].split(",", 1)[1]
    elif edit == "cycle":
        lines[25] = ",".join(lines[25].split(",")[:1] + ["0"] + lines[25].split(",")[2:])
    elif edit == "short":
        lines[12] = ",".join(lines[12].split(",")[:9])
    elif edit == "long":
        lines[12] += ",1"
    elif edit == "header":
        lines[0] = lines[0].replace("tau_y", "ty")
    elif edit == "lone-cr":
        lines[9] = lines[9].replace(",", "\r", 1)
    elif edit == "only-header":
        lines = lines[:1]
    else:
        lines = []
    text = "\n".join(lines)
    with pytest.raises(DataFileError) as ref:
        strict_log(text, "s.csv")
    with pytest.raises(DataFileError) as got:
        MeasurementLog.from_text(text, "s.csv")
    assert (str(got.value), got.value.line, got.value.column) == (str(ref.value), ref.value.line, ref.value.column)
