"""Counter-based Gaussian streams: noise keyed by (seed, stream, step, row, column).

Every normal deviate is a pure function of its coordinates, so the noise a pixel sees does
not depend on the order in which pixels, tiles, threads or chunks are processed.

Definition (all arithmetic modulo 2**64):

- ``mix64(z)`` is SplitMix64's finaliser; ``key(seed, stream) = mix64(mix64(seed + G) ^
  mix64(stream + 2 G))`` with ``G = 0x9E3779B97F4A7C15``.
- Pixel ``(y, x)`` at step ``t`` has counter ``c = (t << 32) | (y << 16) | x`` (``y, x <
  2**16``, ``t < 2**28``); its ``j``-th 64-bit draw is ``h_j = mix64(key + (16 c + j + 1)
  G)`` (SplitMix64's output number ``16 c + j`` of the stream seeded with ``key``) for
  ``j < 16``, and ``h_j = mix64(h_{j-1} ^ key)`` beyond (never needed in practice).
- A draw becomes a standard normal by Doornik's 128-layer ziggurat (ZIGNOR, 2005): layer
  ``i = h & 127`` and ``u = 2 (h >> 11) 2**-53 - 1`` from disjoint bits; accept
  ``u x_i`` when ``|u| < x_{i+1} / x_i`` (98.8 % of draws); otherwise the wedge or tail
  test takes further draws of the same pixel. The tables are computed once in float64.

The same compiled functions produce the noise for the numpy reference paths and for the
fused kernels, so both see bit-identical deviates (the rare wedge/tail cases call libm's
``exp``/``log`` per element; Intel SVML vector maths is switched off, in
``rvsm.model/__init__``, so that a vectorised and a scalar loop would round alike).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

MASK64 = (1 << 64) - 1
GOLDEN = 0x9E3779B97F4A7C15
_G = np.uint64(GOLDEN)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_S30, _S27, _S31, _S11 = np.uint64(30), np.uint64(27), np.uint64(31), np.uint64(11)
_ONE = np.uint64(1)
_INV53 = 1.0 / 9007199254740992.0  # 2**-53

#: Stream numbers: dark current, then fixed-pattern offset / gain per scale.
STREAM_DARK = 0
STREAM_VOS = 16
STREAM_THETA = 32
MAX_COORD = 1 << 16
MAX_STEPS = 1 << 28


def mix64_int(z: int) -> int:
    """SplitMix64's finaliser on a Python int (for keys)."""
    z &= MASK64
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK64
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK64
    return z ^ (z >> 31)


def stream_key(seed: int, stream: int) -> np.uint64:
    """The 64-bit key of one stream of one seed."""
    a = mix64_int(int(seed) + GOLDEN)
    b = mix64_int(int(stream) + 2 * GOLDEN)
    return np.uint64(mix64_int(a ^ b))


@njit(inline="always", cache=True)
def _mix64(z):
    z = (z ^ (z >> _S30)) * _M1
    z = (z ^ (z >> _S27)) * _M2
    return z ^ (z >> _S31)


def ziggurat_tables() -> tuple[np.ndarray, np.ndarray]:
    """Doornik's ZIGNOR tables ``(x (129,), ratio (128,))`` for 128 layers."""
    c, r, v = 128, 3.442619855899, 9.91256303526217e-3
    x = np.zeros(c + 1)
    f = math.exp(-0.5 * r * r)
    x[0] = v / f
    x[1] = r
    for i in range(2, c):
        x[i] = math.sqrt(-2.0 * math.log(v / x[i - 1] + f))
        f = math.exp(-0.5 * x[i] * x[i])
    ratio = x[1:] / x[:-1]
    return x, ratio


ZIG_X, ZIG_RATIO = ziggurat_tables()
ZIG_R = float(ZIG_X[1])
_SIXTEEN = np.uint64(16)
_MASK7 = np.uint64(127)


@njit(inline="always", cache=True)
def pixel_counter(t, y, x):
    """Counter of pixel ``(y, x)`` at step ``t`` (uint64)."""
    return (np.uint64(t) << np.uint64(32)) | (np.uint64(y) << _SIXTEEN) | np.uint64(x)


@njit(inline="always", cache=True)
def _draw(key, c, j, prev):
    if j < 16:
        return _mix64(key + (c * _SIXTEEN + np.uint64(j) + _ONE) * _G)
    return _mix64(prev ^ key)


@njit(inline="always", cache=True)
def _uniform_open(h):
    return (np.float64(h >> _S11) + 1.0) * _INV53  # (0, 1]


@njit(cache=True)
def _slow_normal(key, c, h, zx, zr):
    """Wedge and tail cases of the ziggurat (about 1.2 % of draws)."""
    j = 0
    while True:
        i = np.int64(h & _MASK7)
        u = 2.0 * (np.float64(h >> _S11) * _INV53) - 1.0
        if abs(u) < zr[i]:
            return u * zx[i]
        if i == 0:
            while True:
                j += 1
                h = _draw(key, c, j, h)
                xt = math.log(_uniform_open(h)) / zx[1]
                j += 1
                h = _draw(key, c, j, h)
                yt = math.log(_uniform_open(h))
                if -2.0 * yt >= xt * xt:
                    return xt - zx[1] if u < 0.0 else zx[1] - xt
        x = u * zx[i]
        f0 = math.exp(-0.5 * (zx[i] * zx[i] - x * x))
        f1 = math.exp(-0.5 * (zx[i + 1] * zx[i + 1] - x * x))
        j += 1
        h = _draw(key, c, j, h)
        if f1 + (f0 - f1) * (np.float64(h >> _S11) * _INV53) < 1.0:
            return x
        j += 1
        h = _draw(key, c, j, h)


@njit(inline="always", cache=True)
def pixel_normal(key, t, y, x, zx, zr):
    """The standard normal deviate of pixel ``(y, x)`` at step ``t`` in stream ``key``."""
    c = pixel_counter(t, y, x)
    h = _mix64(key + (c * _SIXTEEN + _ONE) * _G)
    i = np.int64(h & _MASK7)
    u = 2.0 * (np.float64(h >> _S11) * _INV53) - 1.0
    if abs(u) < zr[i]:
        return u * zx[i]
    return _slow_normal(key, c, h, zx, zr)


@njit(inline="always", cache=True)
def normal_row(key, t, y, width, mean, sd, zx, zr, out, offset):
    """``out[offset + x] = mean + sd * z(t, y, x)`` for ``x = 0 .. width - 1``."""
    row = out[offset:offset + width]
    for x in range(width):
        row[x] = mean + sd * pixel_normal(key, t, y, x, zx, zr)


@njit(parallel=True, cache=True)
def _normal_block(key, t0, num_steps, height, width, mean, sd, zx, zr):
    out = np.empty((num_steps, height, width))
    for i in prange(num_steps * height):
        b = i // height
        y = i - b * height
        normal_row(key, t0 + b, y, width, mean, sd, zx, zr, out[b, y], 0)
    return out


def check_coordinates(num_steps_end: int, shape: tuple[int, int]) -> None:
    """Refuse arrays the counter layout cannot name uniquely."""
    from rvsm.model.infra.errors import RvsmError

    h, w = shape
    if h > MAX_COORD or w > MAX_COORD:
        raise RvsmError(f"noise streams support arrays up to {MAX_COORD}x{MAX_COORD}")
    if num_steps_end > MAX_STEPS:
        raise RvsmError(f"noise streams support up to {MAX_STEPS} steps")


def normal_block(
    key: np.uint64, t0: int, num_steps: int, shape: tuple[int, int], mean: float, sd: float
) -> np.ndarray:
    """``mean + sd * z`` for steps ``t0 .. t0 + num_steps - 1``: ``(B, H, W) float64``."""
    check_coordinates(t0 + num_steps, shape)
    return _normal_block(
        np.uint64(key), int(t0), int(num_steps), int(shape[0]), int(shape[1]),
        float(mean), float(sd), ZIG_X, ZIG_RATIO,
    )
