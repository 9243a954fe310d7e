"""Log intensity ``L = ln(I + 1)`` of brightness ``I`` (8-bit units): the model's own log.

The model's ``ln`` is :func:`ln_ge1`, a branch-free numba function (fdlibm's ``log``:
split ``x = 2**k * m`` with ``m`` in ``[sqrt(2)/2, sqrt(2))`` by integer operations on the
bits, ``s = (m - 1) / (m + 1)``, a degree-14 polynomial in ``s``), within 1 ulp of the
correctly rounded ``ln`` (measured: ``tests/model/events/test_log_intensity.py``). Every
engine inlines it: the numpy engine through :func:`log_intensity`, the fused one in its
tile kernel, the fixed twin's log ADC through :func:`log_intensity`, so the engines are
bit-identical on every machine (the C library's ``log`` and numpy's SIMD ``log`` differ in
the last bit from machine to machine), and the loops that call it vectorise (numba has no
vector ``math.log`` without SVML). It is compiled without ``fastmath`` (the compiler may
not reassociate or contract it into FMAs), so the vector and scalar code give the same
bits. Brightness below zero (a strong negative dark-current draw) and NaN are read as 0:
``L >= 0``, and the zero padding of the receptive fields is ``I = 0, L = 0``.
"""

from __future__ import annotations

import numpy as np
from llvmlite import ir
from numba import njit, prange, types
from numba.extending import intrinsic

__all__ = ["LOG_MAX_ULP", "ln_ge1", "log_intensity", "log_intensity_value"]

#: The largest error of :func:`ln_ge1` against the correctly rounded ``ln``, in units in
#: the last place (fdlibm's bound; the test measures it on inputs in ``[1, 2**20]``).
LOG_MAX_ULP = 1.0

_LN2_HI = 6.93147180369123816490e-01  # 0x3fe62e42fee00000: k * _LN2_HI is exact
_LN2_LO = 1.90821492927058770002e-10  # 0x3dea39ef35793c76
_LG1 = 6.666666666666735130e-01
_LG2 = 3.999999999940941908e-01
_LG3 = 2.857142874366239149e-01
_LG4 = 2.222219843214978396e-01
_LG5 = 1.818357216161805012e-01
_LG6 = 1.531383769920937332e-01
_LG7 = 1.479819860511658591e-01
#: adding it to the bits moves ``m`` from ``[1, 2)`` to ``[sqrt(2)/2, sqrt(2))``
_SHIFT = (0x3FF00000 - 0x3FE6A09E) << 32
_BASE = 0x3FE6A09E << 32
_MANT = (1 << 52) - 1


@intrinsic
def _bits(typingctx, x):
    """The IEEE bits of a float64 as int64 (a register move, vectorisable)."""
    if x != types.float64:
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))

    return types.int64(types.float64), codegen


@intrinsic
def _from_bits(typingctx, i):
    """The float64 whose IEEE bits are the int64 ``i``."""
    if i != types.int64:
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.DoubleType())

    return types.float64(types.int64), codegen


@njit(inline="always", cache=True, error_model="numpy")
def ln_ge1(x):
    """``ln(x)`` for a finite float64 ``x >= 1`` (``inf`` gives ``inf``), within 1 ulp."""
    ix = _bits(x) + _SHIFT
    k = (ix >> 52) - 1023
    f = _from_bits((ix & _MANT) + _BASE) - 1.0
    hfsq = 0.5 * f * f
    s = f / (2.0 + f)
    z = s * s
    w = z * z
    t1 = w * (_LG2 + w * (_LG4 + w * _LG6))
    t2 = z * (_LG1 + w * (_LG3 + w * (_LG5 + w * _LG7)))
    dk = np.float64(k)
    y = s * (hfsq + (t2 + t1)) + dk * _LN2_LO - hfsq + f + dk * _LN2_HI
    return y if x < np.inf else x


@njit(inline="always", cache=True, error_model="numpy")
def log_intensity_value(v):
    """``ln(max(v, 0) + 1)`` of one brightness (NaN reads as 0)."""
    return ln_ge1((v if v > 0.0 else 0.0) + 1.0)


@njit(parallel=True, cache=True, error_model="numpy")
def _log_rows(src, out):
    n, w = src.shape
    for r in prange(n):
        a, b = src[r], out[r]
        for x in range(w):
            b[x] = log_intensity_value(a[x])


def log_intensity(brightness: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """``ln(max(I, 0) + 1)`` of ``brightness`` (any shape) as ``float64`` (module doc)."""
    src = np.ascontiguousarray(brightness, dtype=np.float64)
    if out is None:
        out = np.empty_like(src)
    w = src.shape[-1] if src.ndim else 1
    _log_rows(src.reshape(-1, w), out.reshape(-1, w))
    return out
