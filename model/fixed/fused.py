"""Fused numba kernel of the fixed twin: ADC, integer sums, shift, saturate, fire, reset.

:class:`FusedFixedTwin` runs a design point chunk by chunk; :func:`_fixed_chunk` processes
tiles of rows in parallel and, inside a tile, loops over the chunk's steps: interpolate the
brightness of the tile's rows plus a halo of ``L`` rows (SPEC section 1's expression), add
the dark current (counter-based streams, :mod:`rvsm.model.noise.streams`), ADC (the
rounding and clipping of :mod:`.adc`), exact receptive sums with the integer weights
(the row sums of :mod:`rvsm.model.sampling.row_sums`), arithmetic right shift (floor
division by ``2**shift``), W-bit saturating accumulators, compare with the integer
thresholds, reset.

Exact integers: the integer arithmetic runs in the narrowest type that holds every
per-step sum and accumulator value exactly (:func:`exact_dtype`, checked from the
contract): float32 when they stay below ``2**24`` (the default design point: twice the
SIMD lanes of float64), float64 below ``2**53``, otherwise int64; floats hold integers
exactly in those ranges and their loops vectorise. Either way the spikes and the datapath
statistics are the integers of :func:`rvsm.model.fixed.contract.run_integer_array`, for any
tile size, chunk length and thread count.

Every inner loop indexes slices with the loop variable alone (``row[x]``, never
``row[x + lmax]``): numba's negative-index wraparound check on a computed index keeps
LLVM from vectorising the loop (measured: 1.5x on the whole fixed twin).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange, types
from numba.extending import overload

from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.widths import signed_range
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.orbits import kernel_orbits
from rvsm.model.noise.streams import ZIG_RATIO, ZIG_X, check_coordinates, pixel_normal
from rvsm.model.sampling.fused import DEFAULT_TILE_ROWS, check_chunk, chunk_frames
from rvsm.model.sampling.row_sums import row_pairs, scale_sum
from rvsm.model.scene.scene import Scene

#: integers of magnitude below ``2**bits`` are exact in the type (its mantissa + 1 bits)
EXACT_BITS = {np.float32: 24, np.float64: 53}


def shift_down(v, shift, scale):
    """``floor(v / 2**shift)``: ``v >> shift`` for integers, ``floor(v * scale)`` (``scale =
    2**-shift``, exact) for integer-valued floats."""
    if isinstance(v, (float, np.floating)):
        return np.floor(v * scale)
    return v >> shift


@overload(shift_down, jit_options={"cache": True})
def _shift_down_impl(v, shift, scale):
    if isinstance(v, types.Float):
        return lambda v, shift, scale: np.floor(v * scale)
    return lambda v, shift, scale: v >> shift


def one_like(v):
    """1 in the type of ``v`` (``zero + 1`` would promote float32 to float64 in numba)."""
    return type(v)(1)


@overload(one_like, jit_options={"cache": True})
def _one_like_impl(v):
    ty = v
    return lambda v: ty(1)


# Only min/max and sums of integer-valued floats (exact in any order) run under these
# flags; no flag may touch the analogue interpolation, dark current or ADC.
_INTEGER_FASTMATH = {"nnan", "ninf", "nsz", "reassoc"}


@njit(fastmath=_INTEGER_FASTMATH, cache=True)
def _range_row(analog, width, out):
    """``out = (min(out[0], analog), max(out[1], analog))`` over one row."""
    lo = out[0]
    hi = out[1]
    for x in range(width):
        v = analog[x]
        lo = min(lo, v)
        hi = max(hi, v)
    out[0] = lo
    out[1] = hi


def as_exact_int(v):
    """The integer-valued ``v`` as an integer: int32 for float32 (exact below ``2**24``),
    int64 for float64 and integers. LLVM vectorises integer min/max reductions, not float
    ones (numba's float ``min`` carries NaN tests that fast-math flags do not remove)."""
    return np.int32(v) if isinstance(v, np.float32) else np.int64(v)


@overload(as_exact_int, jit_options={"cache": True})
def _as_exact_int_impl(v):
    if isinstance(v, types.Float):
        ty = types.int32 if v.bitwidth == 32 else types.int64
        return lambda v: ty(v)
    return lambda v: v


@njit(fastmath=_INTEGER_FASTMATH, cache=True)
def _integrate_fixed_row(sums, acc, thr, spikes, st, width, shift, scale, lo, hi, signed,
                         zero_reset):
    """:func:`_integrate_fixed_row_fast` that also tracks the row's sum and accumulator
    min/max into ``st`` (as integers: the reductions vectorise, measured 1.3x the loop
    without them against 5x with float reductions and branches); the shifted sums' range
    is the shift of the sums' range (``floor(v / 2**shift)`` is monotone)."""
    zero = lo - lo
    one = one_like(zero)
    sgn = one if signed else zero
    keep = zero if zero_reset else one
    sat = 0
    smin = as_exact_int(sums[0])
    smax = smin
    vmin = as_exact_int(acc[0] + shift_down(sums[0], shift, scale))
    vmax = vmin
    for x in range(width):
        sm = sums[x]
        ism = as_exact_int(sm)
        smin = min(smin, ism)
        smax = max(smax, ism)
        v = acc[x] + shift_down(sm, shift, scale)
        iv = as_exact_int(v)
        vmin = min(vmin, iv)
        vmax = max(vmax, iv)
        sat += (v > hi) | (v < lo)
        v = min(max(v, lo), hi)
        th = thr[x]
        p = one if v >= th else zero
        n = sgn * (one if v <= -th else zero) * (one - p)
        sp = p - n
        spikes[x] = np.int8(sp)
        fired = p + n
        acc[x] = (one - fired) * v + fired * keep * (v - th * sp)
    st[0] = min(st[0], smin)
    st[1] = max(st[1], smax)
    st[2] = min(st[2], shift_down(smin, shift, scale))
    st[3] = max(st[3], shift_down(smax, shift, scale))
    st[4] = min(st[4], vmin)
    st[5] = max(st[5], vmax)
    st[6] += sat


@njit(fastmath=_INTEGER_FASTMATH, cache=True)
def _integrate_fixed_row_fast(sums, acc, thr, spikes, st, width, shift, scale, lo, hi,
                              signed, zero_reset):
    """Shift, saturate, compare, fire and reset one row of one scale; ``st[6]`` counts the
    saturated accumulators. Branch-free, so the loop vectorises."""
    zero = lo - lo
    one = one_like(zero)
    sgn = one if signed else zero
    keep = zero if zero_reset else one
    sat = 0
    for x in range(width):
        v = acc[x] + shift_down(sums[x], shift, scale)
        sat += (v > hi) | (v < lo)
        v = min(max(v, lo), hi)
        th = thr[x]
        p = one if v >= th else zero
        n = sgn * (one if v <= -th else zero) * (one - p)
        sp = p - n
        spikes[x] = np.int8(sp)
        fired = p + n
        acc[x] = (one - fired) * v + fired * keep * (v - th * sp)
    st[6] += sat


@njit(inline="always", cache=True)
def _add_dark(key, t, y, width, mean, sd, zx, zr, analog):
    for x in range(width):
        analog[x] = analog[x] + (mean + sd * pixel_normal(key, t, y, x, zx, zr))


@njit(parallel=True, cache=True)
def _fixed_chunk(frames, fidx, aw, thr, acc, weights, halves, lmax, gain, half, top,
                 shift, scale, lo, hi, signed, zero_reset, noisy, key, t0, mean, sd, zx, zr,
                 tile_rows, out, stats, analog_range, check_range, ranges):
    num_scales, height, width = acc.shape
    num_steps = fidx.shape[0]
    num_tiles = (height + tile_rows - 1) // tile_rows
    for ti in prange(num_tiles):
        y0 = ti * tile_rows
        y1 = min(height, y0 + tile_rows)
        rows = y1 - y0
        nrows = rows + 2 * lmax
        pad = np.zeros((nrows, width + 2 * lmax), dtype=weights.dtype)
        pairs = np.empty((lmax + 1, nrows, width), dtype=weights.dtype)
        analog = np.empty(width)
        sums = np.empty(width, dtype=weights.dtype)
        st = stats[ti]
        arange = np.zeros(2)
        for b in range(num_steps):
            f = fidx[b]
            a = aw[b]
            oma = 1.0 - a
            for r in range(nrows):
                y = y0 - lmax + r
                if y < 0 or y >= height:
                    continue
                f0 = frames[f, y]
                if a == 0.0:
                    for x in range(width):
                        analog[x] = f0[x]
                else:
                    f1 = frames[f + 1, y]
                    for x in range(width):
                        analog[x] = oma * f0[x] + a * f1[x]
                if noisy:
                    _add_dark(key, t0 + b, y, width, mean, sd, zx, zr, analog)
                prow = pad[r, lmax:lmax + width]  # a slice: no wraparound check
                if check_range:
                    _range_row(analog, width, arange)
                for x in range(width):
                    v = analog[x]
                    c = np.floor(v * gain + half)
                    c = 0.0 if c < 0.0 else (top if c > top else c)
                    prow[x] = c
            row_pairs(pad, nrows, lmax, width, pairs)
            for r in range(rows):
                y = y0 + r
                for s in range(num_scales):
                    scale_sum(pairs, lmax + r, weights[s], halves[s], width, sums)
                    if ranges:
                        _integrate_fixed_row(sums, acc[s, y], thr[s, y], out[b, s, y], st[s],
                                             width, shift, scale, lo, hi, signed, zero_reset)
                    else:
                        _integrate_fixed_row_fast(sums, acc[s, y], thr[s, y], out[b, s, y],
                                                  st[s], width, shift, scale, lo, hi, signed,
                                                  zero_reset)
        amin = arange[0]
        amax = arange[1]
        analog_range[ti, 0] = min(analog_range[ti, 0], amin)
        analog_range[ti, 1] = max(analog_range[ti, 1], amax)


def exact_dtype(point: DesignPoint) -> type:
    """The narrowest of float32, float64 and int64 that holds every value of ``point``'s
    integer datapath exactly.

    Every partial receptive sum lies in the contract's sum range, and an accumulator plus a
    shifted sum is below ``2**(accumulator_bits - 1) + bound`` in magnitude.
    """
    contract = point.contract()
    bound = max(max(-lo, hi) for lo, hi in
                (contract.sum_range(s) for s in range(contract.num_scales)))
    largest = bound + (1 << (point.accumulator_bits - 1)) + 1
    for dtype, bits in EXACT_BITS.items():
        if largest < (1 << bits):
            return dtype
    return np.int64


class FusedFixedTwin:
    """State and fused chunk kernel of the fixed twin of ``point`` on ``scene``.

    ``thresholds`` is ``(S, H, W) int64``; :meth:`run` advances over steps ``t0 .. t1 - 1``
    (consecutive) and returns spikes ``(t1 - t0, S, H, W) int8``; :meth:`stats` gives the
    datapath counters so far (per scale: sum, shifted and accumulator min/max, saturated).
    """

    def __init__(self, scene: Scene, point: DesignPoint, thresholds: np.ndarray,
                 tile_rows: int = DEFAULT_TILE_ROWS, ranges: bool = True):
        if not point.rules.fused_twin:
            raise RvsmError("the fused fixed twin runs the spike camera; the event sensor "
                            "runs the numpy engine (rvsm.model.fixed.twin.make_twin)")
        self.scene = scene
        self.ranges = bool(ranges)
        self.point = point
        contract = point.contract()
        _, weights, halves, self.lmax = kernel_orbits(contract.weight_arrays)
        dtype = exact_dtype(point)
        self.dtype = dtype
        self.weights = np.ascontiguousarray(weights, dtype=dtype)
        self.halves = halves
        self.thr = np.ascontiguousarray(thresholds, dtype=dtype)
        self.acc = np.zeros_like(self.thr)
        lo, hi = signed_range(point.accumulator_bits)
        self.lo, self.hi = dtype(lo), dtype(hi)
        self.shift = np.int64(point.shift)
        self.scale = dtype(2.0 ** -point.shift) if dtype is not np.int64 else 0.0
        self.gain = float(point.adc_gain)
        if point.adc_rounding == "truncate":
            self.half = 0.0
        elif point.adc_rounding == "round-half-up":
            self.half = 0.5
        else:  # pragma: no cover - the design point validates it
            raise RvsmError(f"unknown ADC rounding {point.adc_rounding!r}")
        self.top = float((1 << point.adc_bits) - 1)
        self.signed = bool(point.signed)
        self.zero_reset = point.reset == "zero"
        self.tile_rows = max(1, int(tile_rows))
        num_tiles = -(-scene.shape[0] // self.tile_rows)
        s = point.num_scales
        # float32 twins count in float64 (exact counts up to 2**53)
        stats_dtype = np.int64 if dtype is np.int64 else np.float64
        big = np.finfo(np.float64).max if dtype is not np.int64 else np.iinfo(np.int64).max
        self._stats = np.zeros((num_tiles, s, 7), dtype=stats_dtype)
        self._stats[:, :, 0::2] = big
        self._stats[:, :, 1::2] = -big
        self._stats[:, :, 6] = 0
        noise = point.noise_source()
        if noise is not None:
            check_coordinates(scene.num_steps, scene.shape)
            self.key = noise.dark_key
            self.mean, self.sd = noise.dark_mean_sd
            self.noisy = True
        else:
            self.key, self.mean, self.sd, self.noisy = np.uint64(0), 0.0, 0.0, False
        self.next_step = 0

    def run(self, t0: int, t1: int, out: np.ndarray | None = None) -> np.ndarray:
        """Spikes ``(t1 - t0, S, H, W) int8`` of steps ``t0 .. t1 - 1``."""
        check_chunk(self.scene, t0, t1, self.next_step)
        frames, fidx, aw = chunk_frames(self.scene, t0, t1)
        s, h, w = self.acc.shape
        if out is None:
            out = np.empty((t1 - t0, s, h, w), dtype=np.int8)
        analog_range = np.zeros((self._stats.shape[0], 2))
        _fixed_chunk(
            frames, fidx, aw,
            self.thr, self.acc, self.weights, self.halves, self.lmax, self.gain, self.half,
            self.top, self.shift, self.scale, self.lo, self.hi, self.signed, self.zero_reset,
            self.noisy, self.key, int(t0), self.mean, self.sd, ZIG_X, ZIG_RATIO, self.tile_rows,
            out, self._stats, analog_range, self.point.adc_clip == "error", self.ranges,
        )
        if self.point.adc_clip == "error":
            lo, hi = float(analog_range[:, 0].min()), float(analog_range[:, 1].max())
            fs = self.point.adc_full_scale
            if lo < 0 or hi > fs:
                raise RvsmError(
                    f"adc.clip = 'error': analogue input {lo:g}..{hi:g} leaves the ADC range "
                    f"0..{fs:g}; raise adc.full_scale or use adc.clip = 'saturate'"
                )
        self.next_step = t1
        return out

    def stats(self) -> dict[str, np.ndarray | None]:
        """Per-scale ``(S,) int64`` counters: ``sum_min``, ``sum_max``, ``shifted_min``,
        ``shifted_max``, ``acc_min``, ``acc_max`` (None unless ``ranges``), ``saturated``."""
        st = self._stats
        names = ("sum_min", "sum_max", "shifted_min", "shifted_max", "acc_min", "acc_max")
        out = {}
        for i, name in enumerate(names):
            if not self.ranges:
                out[name] = None
                continue
            col = st[:, :, i].min(axis=0) if i % 2 == 0 else st[:, :, i].max(axis=0)
            if self.dtype is not np.int64:
                limit = np.iinfo(np.int64)
                col = np.where(np.isfinite(col) & (np.abs(col) < 2.0**62), col,
                               limit.max if i % 2 == 0 else limit.min)
            out[name] = col.astype(np.int64)
        out["saturated"] = st[:, :, 6].sum(axis=0).astype(np.int64)
        return out
