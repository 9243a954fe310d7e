"""Steps 1-2 of the integer contract (:mod:`rvsm.model.fixed.contract`): exact integer
receptive sums of ADC codes and the arithmetic right shift, with the bit-length
statistics of accumulator values."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rvsm.model.kernels.geometry import is_symmetric, symmetric_orbits

__all__ = ["arithmetic_shift", "bit_length_histogram", "bit_lengths",
           "integer_receptive_sums", "integer_receptive_sums_direct"]


def integer_receptive_sums(codes: np.ndarray, weights: Sequence[np.ndarray]) -> np.ndarray:
    """Exact weighted sums of ADC codes over each receptive field, zero outside the array.

    ``codes`` is ``(B, H, W)`` non-negative integers; ``weights`` ``S`` odd square integer
    arrays ``(2L+1, 2L+1)``; returns ``(B, S, H, W) int64``. Kernels with the 8-fold
    symmetry of the DoG / Gauss templates take a faster path that first sums the codes
    of each symmetry orbit (shared by all scales); the result is the same integers as
    :func:`integer_receptive_sums_direct`.
    """
    kernels = [np.asarray(k, dtype=np.int64) for k in weights]
    if all(is_symmetric(k) for k in kernels):
        return _symmetric_sums(np.asarray(codes, dtype=np.int64), kernels)
    return integer_receptive_sums_direct(codes, kernels)


def integer_receptive_sums_direct(
    codes: np.ndarray, weights: Sequence[np.ndarray]
) -> np.ndarray:
    """Tap-by-tap reference of :func:`integer_receptive_sums` (any kernel)."""
    codes = np.asarray(codes, dtype=np.int64)
    b, h, w = codes.shape
    out = np.zeros((b, len(weights), h, w), dtype=np.int64)
    for s, kernel in enumerate(weights):
        kernel = np.asarray(kernel, dtype=np.int64)
        half = kernel.shape[0] // 2
        padded = np.zeros((b, h + 2 * half, w + 2 * half), dtype=np.int64)
        padded[:, half:half + h, half:half + w] = codes
        target = out[:, s]
        for di in range(2 * half + 1):
            for dj in range(2 * half + 1):
                wt = int(kernel[di, dj])
                if wt:
                    target += wt * padded[:, di:di + h, dj:dj + w]
    return out


def _symmetric_sums(codes: np.ndarray, kernels: list[np.ndarray]) -> np.ndarray:
    """Sum codes per orbit ``{(+-a, +-b), (+-b, +-a)}`` once, then weight per scale."""
    bsz, h, w = codes.shape
    halves = [k.shape[0] // 2 for k in kernels]
    big = max(halves)
    padded = np.zeros((bsz, h + 2 * big, w + 2 * big), dtype=np.int64)
    padded[:, big:big + h, big:big + w] = codes
    # rows[b][:, y', x] = codes at (y', x - b) + (y', x + b), padded rows kept.
    rows = []
    for dj in range(big + 1):
        r = padded[:, :, big - dj:big - dj + w].copy()
        if dj:
            r += padded[:, :, big + dj:big + dj + w]
        rows.append(r)

    def cols(x: np.ndarray, di: int) -> np.ndarray:
        c = x[:, big - di:big - di + h].copy()
        if di:
            c += x[:, big + di:big + di + h]
        return c

    out = np.zeros((bsz, len(kernels), h, w), dtype=np.int64)
    tmp = np.empty((bsz, h, w), dtype=np.int64)
    for a, b in symmetric_orbits(big):
        users = [
            (s, int(k[halves[s] + a, halves[s] + b]))
            for s, k in enumerate(kernels) if halves[s] >= a
        ]
        users = [(s, wt) for s, wt in users if wt]
        if not users:
            continue
        orbit = cols(rows[b], a)
        if a != b:
            orbit += cols(rows[a], b)
        for s, wt in users:
            np.multiply(orbit, wt, out=tmp)
            out[:, s] += tmp
    return out


def arithmetic_shift(values: np.ndarray, shift: int) -> np.ndarray:
    """``values >> shift`` (floor of ``values / 2**shift``), as a hardware ``>>>`` does."""
    return np.right_shift(np.asarray(values, dtype=np.int64), int(shift))


def bit_lengths(values: np.ndarray) -> np.ndarray:
    """Bits of ``|v|`` (0 for 0, ``k`` for ``2**(k-1) <= |v| < 2**k``), ``int64``.

    Exact for ``|v| < 2**53``; used only for the profiling histograms.
    """
    _, exponent = np.frexp(np.abs(np.asarray(values, dtype=np.int64)).astype(np.float64))
    return exponent.astype(np.int64)


def bit_length_histogram(values: np.ndarray) -> np.ndarray:
    """Per scale (axis ``-3``), counts of :func:`bit_lengths`: ``(S, 64) int64``."""
    v = np.asarray(values)
    v = np.moveaxis(v.reshape((-1,) + v.shape[-3:]), 1, 0).reshape(v.shape[-3], -1)
    bits = np.minimum(bit_lengths(v), 63)
    return np.stack([np.bincount(row, minlength=64) for row in bits])
