r"""One compiled pass over the bytes of a CSV table of numbers: the fast path of the log reader.

:func:`scan_rows` reads *plain* rows (ASCII numbers in the leading numeric
columns, optional surrounding spaces or tabs, ``\n`` or ``\r\n`` line ends,
no quotes; every number finite, ids whole and within +-(2^53 - 1): what
the strict parser would accept) straight from the file's bytes into a float64 array and stops at
the first line that is not plain, leaving that line to the strict row-by-row
parser of :mod:`csjm_opt.measurement._log_reader` (which names the line and
column of a fault, or accepts what only it can read, such as quoted cells,
``1_000`` or exotic white space), then carries on after it.

Numbers: a cell must match ``[+-]digits[.digits][(e|E)[+-]digits]`` (at least
one digit before the exponent). Its value is exactly the one ``float(cell)``
gives: :func:`csjm_opt.measurement._decimal_float.decimal_to_float` for
significands of up to 19 digits, else the C library's ``strtod``, correctly
rounded on glibc, musl and macOS. Where no such ``strtod`` is found,
:data:`AVAILABLE` is false and the caller uses its strict parser throughout.
"""

from __future__ import annotations

import ctypes
import sys

import llvmlite.binding as ll
import numpy as np
from llvmlite import ir
from numba import njit
from numba.core import cgutils, types
from numba.extending import intrinsic

from .._limits import MAX_EXACT_INT
from ._decimal_float import decimal_to_float

#: Status of :func:`scan_rows`: the end of the data was reached, or a line that is not plain.
END, NOT_PLAIN = 0, 1

_COMMA, _LF, _CR, _QUOTE, _NUL, _SPACE, _TAB = 44, 10, 13, 34, 0, 32, 9
_MAX_TOKEN = 62          # longer numbers go to the strict parser


def _find_strtod() -> int | None:
    """Address of the C library's correctly rounded ``strtod``, or ``None``."""
    if not sys.platform.startswith(("linux", "darwin")):
        return None   # the Windows C runtimes have not always rounded correctly
    try:
        return ctypes.cast(ctypes.CDLL(None).strtod, ctypes.c_void_p).value
    except (OSError, AttributeError):
        return None


_STRTOD_ADDRESS = _find_strtod()
#: Whether the compiled scanner can be used on this platform.
AVAILABLE = _STRTOD_ADDRESS is not None
if AVAILABLE:
    ll.add_symbol("csjm_opt_strtod", _STRTOD_ADDRESS)


@intrinsic
def _strtod(typingctx, text_address, end_address):
    """``strtod(char *text, char **end)`` on raw addresses (the symbol is bound at import)."""
    sig = types.float64(types.intp, types.intp)

    def codegen(context, builder, signature, args):
        char_p = ir.IntType(8).as_pointer()
        fnty = ir.FunctionType(ir.DoubleType(), [char_p, char_p.as_pointer()])
        fn = cgutils.get_or_insert_function(builder.module, fnty, "csjm_opt_strtod")
        return builder.call(fn, [builder.inttoptr(args[0], char_p),
                                 builder.inttoptr(args[1], char_p.as_pointer())])

    return sig, codegen


@njit(cache=True, nogil=True)
def _number(buf, p, scratch, end_slot):
    """Parse one numeric cell from ``buf[p]``: ``(position after it, value, ok)``.

    The position is that of the cell's terminator (spaces and tabs around the
    number skipped); the caller checks the terminator.
    """
    n = buf.size
    while p < n and (buf[p] == _SPACE or buf[p] == _TAB):
        p += 1
    start = p
    negative = False
    if p < n and (buf[p] == 43 or buf[p] == 45):   # + -
        negative = buf[p] == 45
        p += 1
    mantissa = np.uint64(0)
    digits = 0           # significant digits kept in ``mantissa``
    exp10 = 0
    exact = True         # every significant digit is in ``mantissa``
    seen = False
    while p < n and 48 <= buf[p] <= 57:
        d = buf[p] - 48
        seen = True
        if digits < 19:
            if digits > 0 or d > 0:
                mantissa = mantissa * np.uint64(10) + np.uint64(d)
                digits += 1
        else:
            exp10 += 1
            exact = exact and d == 0
        p += 1
    if p < n and buf[p] == 46:   # .
        p += 1
        while p < n and 48 <= buf[p] <= 57:
            d = buf[p] - 48
            seen = True
            if digits < 19:
                if digits > 0 or d > 0:
                    mantissa = mantissa * np.uint64(10) + np.uint64(d)
                    digits += 1
                exp10 -= 1
            else:
                exact = exact and d == 0
            p += 1
    if not seen:
        return p, 0.0, False
    if p < n and (buf[p] == 101 or buf[p] == 69):   # e E
        p += 1
        e_negative = False
        if p < n and (buf[p] == 43 or buf[p] == 45):
            e_negative = buf[p] == 45
            p += 1
        if not (p < n and 48 <= buf[p] <= 57):
            return p, 0.0, False
        e = 0
        while p < n and 48 <= buf[p] <= 57:
            if e < 100000:
                e = e * 10 + (buf[p] - 48)
            p += 1
        exp10 += -e if e_negative else e
    stop = p
    while p < n and (buf[p] == _SPACE or buf[p] == _TAB):
        p += 1
    if exact:
        value, ok = decimal_to_float(mantissa, digits, exp10)
        if ok:
            return p, -value if negative else value, True
    length = stop - start
    if length > _MAX_TOKEN:
        return p, 0.0, False
    for k in range(length):
        scratch[k] = buf[start + k]
    scratch[length] = 0
    address = scratch.ctypes.data
    value = _strtod(address, end_slot.ctypes.data)
    if end_slot[0] - address != length:   # e.g. another locale's decimal point
        return p, 0.0, False
    return p, value, True


@njit(cache=True, nogil=True)
def _scan(buf, pos, line, row, n_int, n_num, n_cells, values, lines, extra_lo, extra_hi, max_int):
    n = buf.size
    scratch = np.zeros(_MAX_TOKEN + 2, np.uint8)
    end_slot = np.zeros(1, np.intp)
    while pos < n:
        c = buf[pos]
        if c == _LF:                                   # blank line
            pos += 1
            line += 1
            continue
        if c == _CR and pos + 1 < n and buf[pos + 1] == _LF:
            pos += 2
            line += 1
            continue
        if row >= values.shape[0]:
            return pos, line, row, NOT_PLAIN
        p = pos
        cell = 0
        plain = True
        while True:
            if cell < n_num:
                p, value, plain = _number(buf, p, scratch, end_slot)
                if not plain or not abs(value) < np.inf or (
                        cell < n_int and (value != np.floor(value) or abs(value) > max_int)):
                    plain = False
                    break
                values[row, cell] = value
            else:
                lo = p
                while p < n and buf[p] != _COMMA and buf[p] != _LF and buf[p] != _CR \
                        and buf[p] != _QUOTE and buf[p] != _NUL:
                    p += 1
                extra_lo[row, cell - n_num] = lo
                extra_hi[row, cell - n_num] = p
            cell += 1
            if p >= n:
                break
            t = buf[p]
            if t == _COMMA and cell < n_cells:
                p += 1
                continue
            if t == _LF:
                p += 1
                break
            if t == _CR and p + 1 < n and buf[p + 1] == _LF:
                p += 2
                break
            plain = False                  # too many cells, a quote, NUL, a lone CR, junk after a number
            break
        if not plain or cell < n_num:
            return pos, line, row, NOT_PLAIN
        for j in range(cell, n_cells):     # short rows: missing extra cells are empty
            extra_lo[row, j - n_num] = 0
            extra_hi[row, j - n_num] = 0
        lines[row] = line
        row += 1
        line += 1
        pos = p
    return pos, line, row, END


def scan_rows(buf: np.ndarray, pos: int, line: int, row: int, n_int: int, n_cells: int, values: np.ndarray,
              lines: np.ndarray, extra_lo: np.ndarray, extra_hi: np.ndarray) -> tuple[int, int, int, int]:
    r"""Read plain rows from ``buf[pos:]`` until the end or a line that is not plain.

    Parameters
    ----------
    buf : ndarray of uint8
        The file's bytes (header excluded or ``pos`` past it).
    pos : int
        Byte offset of the first line to read.
    line : int
        Its 1-based line number (counted in ``\n``).
    row : int
        Index of the first row of ``values`` to fill.
    n_int : int
        The first ``n_int`` columns hold integer ids: a value there must be
        whole and within +-(2^53 - 1).
    n_cells : int
        Largest number of cells a row may have (the header's); at least
        ``values.shape[1]``.
    values : ndarray of float64, shape (m, n_num)
        Receives the leading ``n_num`` numeric cells of each row.
    lines : ndarray of int64, shape (m,)
        Receives each row's line number.
    extra_lo, extra_hi : ndarray of int64, shape (m, n_cells - n_num)
        Receive the byte range of each further (text) cell; ``0, 0`` when a
        row is short of it.

    Returns
    -------
    tuple of int
        ``(pos, line, row, status)``: where reading stopped, the line number
        there, the number of rows filled so far, and :data:`END` or
        :data:`NOT_PLAIN` (``pos`` is then the start of that line). A row is
        also left unread (``NOT_PLAIN``) when ``values`` is full.
    """
    return _scan(buf, pos, line, row, n_int, values.shape[1], n_cells, values, lines, extra_lo, extra_hi,
                 float(MAX_EXACT_INT))


@njit(cache=True, nogil=True)
def _gather(buf, lo, hi, out):
    for i in range(lo.size):
        for k in range(hi[i] - lo[i]):
            out[i, k] = buf[lo[i] + k]


def text_column(buf: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The cells ``buf[lo[i]:hi[i]]`` as a numpy string array (UTF-8 decoded).

    Parameters
    ----------
    buf : ndarray of uint8
        The file's bytes.
    lo, hi : ndarray of int64, shape (m,)
        Byte range of each cell.

    Returns
    -------
    ndarray of str, shape (m,)
    """
    width = max(1, int((hi - lo).max(initial=0)))
    cells = np.zeros((lo.size, width), np.uint8)
    _gather(buf, lo, hi, cells)
    raw = cells.view(f"S{width}").ravel()
    if not cells.max(initial=0) & 0x80:
        return raw.astype(f"U{width}")
    return np.char.decode(raw, "utf-8")
