"""Exact decimal-to-double conversion in compiled code: the value ``float(text)`` gives, fast.

:func:`decimal_to_float` turns a decimal significand ``w`` (at most 19
digits, exact) and a power of ten ``q`` into the double nearest to
``w * 10**q`` (ties to even), as Python's ``float`` does:

* Clinger's fast path: ``w < 10**15`` and ``|q| <= 22`` are both exact
  doubles, so one IEEE multiplication or division rounds correctly;
* the Eisel-Lemire algorithm (as in Go's ``strconv`` and Wuffs): ``w`` times
  a 128-bit truncation of ``10**q``, accepted only when the truncation cannot
  change the rounding, else it reports failure;
* otherwise (failure, more digits, subnormal or overflowing results) the
  caller's fallback, the C library's correctly rounded ``strtod``.
"""

from __future__ import annotations

import math

import numpy as np
from llvmlite import ir
from numba import njit
from numba.core import types
from numba.extending import intrinsic

_Q_MIN, _Q_MAX = -348, 347
_EXACT_POW10 = np.array([10.0 ** k for k in range(23)])   # exact in float64
_LOW9 = np.uint64(0x1FF)
_U0, _U1, _U9, _U53 = np.uint64(0), np.uint64(1), np.uint64(9), np.uint64(53)


def _powers_of_ten_128() -> tuple[np.ndarray, np.ndarray]:
    """High and low 64-bit words of ``floor(10**q * 2**(127 - k))``, ``k = floor(log2 10**q)``."""
    hi = np.empty(_Q_MAX - _Q_MIN + 1, np.uint64)
    lo = np.empty_like(hi)
    for i, q in enumerate(range(_Q_MIN, _Q_MAX + 1)):
        if q >= 0:
            k = (10 ** q).bit_length() - 1
            T = (10 ** q << (127 - k)) if k <= 127 else (10 ** q >> (k - 127))
        else:
            k = -(10 ** -q).bit_length()
            T = (1 << (127 - k)) // 10 ** -q
        assert 1 << 127 <= T < 1 << 128 and (217706 * q) >> 16 == k
        hi[i], lo[i] = T >> 64, T & ((1 << 64) - 1)
    return hi, lo


_POW10_HI, _POW10_LO = _powers_of_ten_128()


@intrinsic
def _mul_64x64(typingctx, a, b):
    """The 128-bit product of two uint64 as ``(high, low)`` words (one machine multiplication)."""
    sig = types.UniTuple(types.uint64, 2)(types.uint64, types.uint64)

    def codegen(context, builder, signature, args):
        i128 = ir.IntType(128)
        product = builder.mul(builder.zext(args[0], i128), builder.zext(args[1], i128))
        high = builder.trunc(builder.lshr(product, ir.Constant(i128, 64)), ir.IntType(64))
        low = builder.trunc(product, ir.IntType(64))
        return context.make_tuple(builder, signature.return_type, [high, low])

    return sig, codegen


@intrinsic
def _leading_zeros(typingctx, a):
    """Number of leading zero bits of a non-zero uint64."""
    sig = types.int64(types.uint64)

    def codegen(context, builder, signature, args):
        return builder.ctlz(args[0], ir.Constant(ir.IntType(1), 1))

    return sig, codegen


@njit(cache=True, nogil=True)
def _eisel_lemire(w, q, pow10_hi, pow10_lo):
    """``(value, ok)``: the double nearest ``w * 10**q`` for ``0 < w < 2**64``, or ``ok`` false."""
    if q < _Q_MIN or q > _Q_MAX:
        return 0.0, False
    clz = _leading_zeros(w)
    w = w << np.uint64(clz)
    exp2 = ((217706 * q) >> 16) + 64 + 1023 - clz
    i = q - _Q_MIN
    x_hi, x_lo = _mul_64x64(w, pow10_hi[i])
    if x_hi & _LOW9 == _LOW9 and x_lo + w < w:         # the low word of 10**q may carry
        y_hi, y_lo = _mul_64x64(w, pow10_lo[i])
        merged_hi, merged_lo = x_hi, x_lo + y_hi
        if merged_lo < x_lo:
            merged_hi += _U1
        if merged_hi & _LOW9 == _LOW9 and merged_lo + _U1 == _U0 and y_lo + w < w:
            return 0.0, False
        x_hi, x_lo = merged_hi, merged_lo
    msb = x_hi >> np.uint64(63)
    mantissa = x_hi >> (msb + _U9)
    exp2 -= 1 - np.int64(msb)
    if x_lo == _U0 and x_hi & _LOW9 == _U0 and mantissa & np.uint64(3) == _U1:
        return 0.0, False                               # halfway between two doubles: undecided
    mantissa = (mantissa + (mantissa & _U1)) >> _U1
    if mantissa >> _U53 > _U0:
        mantissa = mantissa >> _U1
        exp2 += 1
    if exp2 < 1 or exp2 > 0x7FE:                        # subnormal or infinite
        return 0.0, False
    return math.ldexp(float(mantissa), exp2 - 1075), True


@njit(cache=True, nogil=True)
def decimal_to_float(w, digits, q):
    """The double nearest ``w * 10**q`` (non-negative), or ``ok`` false to use a fallback.

    Parameters
    ----------
    w : uint64
        The decimal significand (exact), ``digits`` digits long (at most 19).
    digits : int
        Number of digits of ``w`` (0 when ``w`` is 0).
    q : int
        Power of ten.

    Returns
    -------
    tuple of (float, bool)
        The value and whether it is exact (correctly rounded).
    """
    if w == _U0:
        return 0.0, True
    if digits <= 15 and -22 <= q <= 22:
        value = float(w)
        return (value * _EXACT_POW10[q] if q >= 0 else value / _EXACT_POW10[-q]), True
    return _eisel_lemire(w, q, _POW10_HI, _POW10_LO)
