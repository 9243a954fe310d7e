"""Log intensity ``L = ln(I + 1)`` of brightness ``I`` (8-bit units), one compiled kernel.

Both event engines take ``L`` from :func:`log_intensity`: numpy's own ``log`` uses SIMD
code on some CPUs (AVX-512) that differs from the C library's in the last bit for about
one value in ten thousand, so one shared kernel keeps the engines bit-identical on every
machine. Brightness below zero (a strong negative dark-current draw) is read as 0:
``L >= 0``, and the zero padding of the receptive fields is ``I = 0, L = 0``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

__all__ = ["log_intensity"]


@njit(parallel=True, cache=True)
def _log_rows(src, out):
    n, w = src.shape
    for r in prange(n):
        a, b = src[r], out[r]
        for x in range(w):
            v = a[x]
            b[x] = math.log((v if v > 0.0 else 0.0) + 1.0)


def log_intensity(brightness: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """``ln(max(I, 0) + 1)`` of ``brightness`` (any shape) as ``float64``."""
    src = np.ascontiguousarray(brightness, dtype=np.float64)
    if out is None:
        out = np.empty_like(src)
    w = src.shape[-1] if src.ndim else 1
    _log_rows(src.reshape(-1, w), out.reshape(-1, w))
    return out
