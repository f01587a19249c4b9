"""exp, expm1, log and log1p as straight-line arithmetic, for the compiled passes' vector loops.

The library's functions are one call a lane inside a vectorised loop (exp and log) or keep
the loop from vectorising at all (expm1 and log1p); these are polynomials and bit
operations the compiler turns into vector instructions. Each is within a few ulp of the
library's result over the range it states (tests/laws/test_elementary.py measures the
bound), not the same bits: a pass that uses them agrees with the scalar pass to round-off.

- ``exp(x)``, -708 < x < 709: x = k ln 2 + r with |r| <= ln 2 / 2 (Cody and Waite: ln 2 in
  two parts, the first with trailing zero bits so that k ln2_hi is exact), e^r by its
  Taylor series to r^13, 2^k from the exponent bits.
- ``expm1(x)``, -708 < x < 709: the series to x^14 for |x| < ln 2 / 2, e^x - 1 beyond.
- ``log(x)``, x a positive normal number: x = 2^e m with sqrt(2)/2 < m <= sqrt(2) from the
  bits, ln m = 2 atanh(s), s = f / (2 + f), f = m - 1 (exact), written ln m = f - s (f - R)
  with R = 2 (s^2 / 3 + s^4 / 5 + ...) to s^22.
- ``log1p(y)``, y > -1, 1 + y a normal number: log(u) + (y - (u - 1)) / u, u = 1 + y (the
  rounding of u corrected to first order).

Plain functions (Python's arithmetic without numba, through ``struct`` for the bits);
:func:`compile_bits` gives the compiled passes their bit casts.
"""
from __future__ import annotations

import math
import struct

LN2_HI = 6.93147180369123816490e-01     # ln 2 to 32 bits: k LN2_HI is exact for |k| < 2^21
LN2_LO = 1.90821492927058770002e-10     # ln 2 - LN2_HI
INV_LN2 = 1.0 / math.log(2.0)
SQRT2 = math.sqrt(2.0)
HALF_LN2 = 0.5 * math.log(2.0)
MANTISSA = (1 << 52) - 1
ONE_BITS = 1023 << 52
#: 1 / n! for n = 0 ... 14
F = tuple(1.0 / math.factorial(n) for n in range(15))
#: 2 / (2k + 1) for k = 1 ... 11
G = tuple(2.0 / (2 * k + 1) for k in range(1, 12))


def float_of_bits(i):
    """The double whose IEEE bits are the int64 ``i``."""
    return struct.unpack("<d", struct.pack("<q", i))[0]


def bits_of_float(x):
    """The IEEE bits of the double ``x`` as an int64."""
    return struct.unpack("<q", struct.pack("<d", x))[0]


def exp(x):
    """e^x for -708 < x < 709 (module docstring)."""
    k = math.floor(x * INV_LN2 + 0.5)
    r = (x - k * LN2_HI) - k * LN2_LO
    q = F[2] + r * (F[3] + r * (F[4] + r * (F[5] + r * (F[6] + r * (F[7] + r * (F[8] + r * (F[9] + r * (
        F[10] + r * (F[11] + r * (F[12] + r * F[13]))))))))))
    return (1.0 + (r + r * r * q)) * float_of_bits((int(k) + 1023) << 52)


def expm1(x):
    """e^x - 1 for -708 < x < 709 (module docstring)."""
    q = F[2] + x * (F[3] + x * (F[4] + x * (F[5] + x * (F[6] + x * (F[7] + x * (F[8] + x * (F[9] + x * (
        F[10] + x * (F[11] + x * (F[12] + x * (F[13] + x * F[14])))))))))))
    return x + x * x * q if abs(x) < HALF_LN2 else exp(x) - 1.0


def log(x):
    """ln x for a positive normal number x (module docstring)."""
    bits = bits_of_float(x)
    e = (bits >> 52) - 1023
    m = float_of_bits((bits & MANTISSA) | ONE_BITS)
    big = m > SQRT2
    m = m * 0.5 if big else m
    e = float(e + 1 if big else e)
    f = m - 1.0
    s = f / (2.0 + f)
    z = s * s
    R = z * (G[0] + z * (G[1] + z * (G[2] + z * (G[3] + z * (G[4] + z * (G[5] + z * (G[6] + z * (G[7] + z * (
        G[8] + z * (G[9] + z * G[10]))))))))))
    return e * LN2_HI + (f - (s * (f - R) - e * LN2_LO))


def log1p(y):
    """ln(1 + y) for y > -1 with 1 + y a normal number (module docstring)."""
    u = 1.0 + y
    return log(u) + (y - (u - 1.0)) / u


def compile_bits(numba):
    """The compiled :func:`float_of_bits` and :func:`bits_of_float`: one LLVM bitcast each."""
    from numba.core import types
    from numba.extending import intrinsic, overload

    @intrinsic
    def _to_float(typingctx, i):
        def codegen(context, builder, signature, args):
            return builder.bitcast(args[0], context.get_value_type(types.float64))
        return types.float64(types.int64), codegen

    @intrinsic
    def _to_int(typingctx, x):
        def codegen(context, builder, signature, args):
            return builder.bitcast(args[0], context.get_value_type(types.int64))
        return types.int64(types.float64), codegen

    @overload(float_of_bits, inline="always")
    def _float_of_bits_typed(i):
        return lambda i: _to_float(i)

    @overload(bits_of_float, inline="always")
    def _bits_of_float_typed(x):
        return lambda x: _to_int(x)


NAMES = ("exp", "expm1", "log", "log1p")
_COMPILED = []


def compile_functions():
    """Replace this module's functions by numba's, inlined where they are called (once;
    the bit casts with them): the compiled passes call them by these names."""
    if _COMPILED:
        return
    import numba

    from ..jit import njit

    compile_bits(numba)
    g = globals()
    for name in NAMES:
        g[name] = njit(error_model="numpy", inline="always")(g[name])
    _COMPILED.append(True)
