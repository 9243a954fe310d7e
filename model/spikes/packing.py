"""Two-bit packing of spike trains: four signed spikes per byte (for HDF5 storage).

A spike ``v`` in {-1, 0, 1} is the two-bit code ``v & 3`` (0 -> 00, 1 -> 01, -1 -> 11, the
two's complement of 2 bits); pixel ``x`` of a row goes to bits ``2 (x mod 4)`` and up of
byte ``x // 4`` (least significant first). A row of ``W`` pixels packs to ``ceil(W / 4)``
bytes, the unused high bits of the last byte are 0. Packing runs in parallel (numba) over
rows; unpacking is a table lookup.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange


@njit(parallel=True, cache=True)
def _pack(rows, out):
    n, w = rows.shape
    nb = out.shape[1]
    for i in prange(n):
        src = rows[i]
        dst = out[i]
        for j in range(nb):
            byte = 0
            for k in range(4):
                x = 4 * j + k
                if x < w:
                    byte |= (np.int64(src[x]) & 3) << (2 * k)
            dst[j] = np.uint8(byte)


@njit(parallel=True, cache=True)
def _count(rows):
    n, w = rows.shape
    nz = np.zeros(n, dtype=np.int64)
    neg = np.zeros(n, dtype=np.int64)
    for i in prange(n):
        a = 0
        b = 0
        for x in range(w):
            v = rows[i, x]
            a += v != 0
            b += v < 0
        nz[i] = a
        neg[i] = b
    return nz, neg


def packed_width(width: int) -> int:
    """Bytes per packed row of ``width`` pixels."""
    return (int(width) + 3) // 4


def pack_spikes(spikes: np.ndarray) -> np.ndarray:
    """``(..., W) int8`` in {-1, 0, 1} -> ``(..., ceil(W / 4)) uint8``."""
    arr = np.ascontiguousarray(spikes, dtype=np.int8)
    rows = arr.reshape(-1, arr.shape[-1])
    out = np.empty((rows.shape[0], packed_width(arr.shape[-1])), dtype=np.uint8)
    _pack(rows, out)
    return out.reshape(arr.shape[:-1] + (out.shape[1],))


def _table() -> np.ndarray:
    codes = np.arange(256)
    fields = (codes[:, None] >> (2 * np.arange(4))[None]) & 3
    return np.where(fields == 3, -1, np.where(fields == 2, 0, fields)).astype(np.int8)


_UNPACK = _table()


def unpack_spikes(packed: np.ndarray, width: int) -> np.ndarray:
    """Inverse of :func:`pack_spikes`: ``(..., ceil(W / 4)) uint8`` -> ``(..., W) int8``."""
    arr = np.asarray(packed, dtype=np.uint8)
    out = _UNPACK[arr].reshape(arr.shape[:-1] + (4 * arr.shape[-1],))
    return np.ascontiguousarray(out[..., :width])


def count_spikes(spikes: np.ndarray) -> tuple[np.ndarray, int]:
    """``(non-zero per scale (S,) int64, negative total)`` of ``(B, S, H, W) int8``."""
    arr = np.ascontiguousarray(spikes, dtype=np.int8)
    b, s = arr.shape[:2]
    nz, neg = _count(arr.reshape(-1, arr.shape[-1]))
    per_scale = nz.reshape(b, s, -1).sum(axis=(0, 2))
    return per_scale, int(neg.sum())
