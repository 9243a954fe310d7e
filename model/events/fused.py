"""The fused numba engine of the event samplers: the time loop inside, tiles of rows in
parallel, everything of a tile in cache.

:func:`_event_chunk` processes tiles of ``tile_rows`` rows in parallel (``prange``); per
tile and step it streams the tile's rows plus a halo of ``L`` rows, one at a time: the
brightness (interpolated between the chunk's frames, plus the dark current drawn inside
the tile from the counter-based streams of :mod:`rvsm.model.noise.streams`), its log
(:func:`.log_intensity.log_intensity_value`) and the row's pairs into a ring of rows
(:func:`_log_pairs`; the ladder sums take their rows modulo the ring; for the per-scale
sums each row is stored twice, so the window around any output row is consecutive). Once
a row's window is complete it forms every scale's receptive sum of it and applies the
event rule (:mod:`.event_rule`) to the row's accumulators and references: for the
``1..S`` ladders in one vectorised loop over all scales (:mod:`.ladder_kernels`, the sums
of :func:`~rvsm.model.sampling.row_sums.ladder_sum`, the responses never stored), two
output rows a pass (their windows share all but two rows of the ring: a ring of
``2L + 2`` rows; the last row of an odd tile alone), else
:func:`~rvsm.model.sampling.row_sums.scale_sum` per scale into a row of responses, then
the rule per scale (the orbit order either way; the first step's capture of the
references goes the second way too). :func:`_log_pairs` and the ladder loops index their
arrays directly instead of taking row views (each view costs two reference-count calls)
and are compiled ``noalias`` (:mod:`rvsm.model.infra.noalias`), so they vectorise without
runtime alias checks.

Every float operation is the one :mod:`.numpy_engine` does, in the same order, the log
is the same inlined function, no loop runs under ``fastmath``, and every pixel's
arithmetic depends on nothing but its own coordinates, so the events are bit-identical to
the numpy engine for any tile height, chunk length and thread count. Speed and where the
time goes: ``docs/events.md`` (section "Speed").
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from rvsm.model.events.config import EventConfig
from rvsm.model.events.event_rule import event_step
from rvsm.model.events.ladder_kernels import (
    ladder_events_1,
    ladder_events_1_2,
    ladder_events_2,
    ladder_events_2_2,
    ladder_events_3,
    ladder_events_3_2,
    ladder_events_4,
    ladder_events_4_2,
)
from rvsm.model.events.log_intensity import log_intensity_value
from rvsm.model.infra.noalias import NoAliasCompiler
from rvsm.model.infra.simd import aligned_copy
from rvsm.model.kernels.orbits import kernel_orbits
from rvsm.model.noise.streams import ZIG_RATIO, ZIG_X, normal_row
from rvsm.model.sampling.fused import check_chunk, chunk_frames, dark_current_stream
from rvsm.model.sampling.row_sums import is_ladder, ladder_sum, scale_sum
from rvsm.model.scene.scene import Scene

__all__ = ["DEFAULT_TILE_ROWS", "FusedEventSampler"]

#: Rows per tile (the log of the ``2L`` halo rows is recomputed per tile; a tile's
#: references and thresholds, ``16 S W`` bytes a row, stay in L2 across steps).
DEFAULT_TILE_ROWS = 32


@njit(inline="always", cache=True)
def _events_row(resp, th, rf, out, width, capture):
    """The event rule on one row of one scale (``capture``: store the references);
    branch-free, so the loop vectorises."""
    if capture:
        for x in range(width):
            rf[x] = resp[x]
            out[x] = 0
        return
    for x in range(width):
        event_step(resp[x], th, rf, out, x)


@njit(inline="always", cache=True)
def ladder_events(pairs, pr, ring, w, width, thr, ref, ev, y):
    """:mod:`.ladder_kernels`' ``ladder_events_S`` for the ``S = w.shape[0]`` scales."""
    num_scales = w.shape[0]
    if num_scales == 1:
        ladder_events_1(pairs, pr, ring, w, width, thr, ref, ev, y)
    elif num_scales == 2:
        ladder_events_2(pairs, pr, ring, w, width, thr, ref, ev, y)
    elif num_scales == 3:
        ladder_events_3(pairs, pr, ring, w, width, thr, ref, ev, y)
    else:
        ladder_events_4(pairs, pr, ring, w, width, thr, ref, ev, y)


@njit(inline="always", cache=True)
def ladder_events_two(pairs, pr, ring, w, width, thr, ref, ev, y):
    """:func:`ladder_events` for rows ``y`` and ``y + 1`` (padded rows ``pr``, ``pr + 1``)
    in one pass: :mod:`.ladder_kernels`' ``ladder_events_S_2``."""
    num_scales = w.shape[0]
    if num_scales == 1:
        ladder_events_1_2(pairs, pr, ring, w, width, thr, ref, ev, y)
    elif num_scales == 2:
        ladder_events_2_2(pairs, pr, ring, w, width, thr, ref, ev, y)
    elif num_scales == 3:
        ladder_events_3_2(pairs, pr, ring, w, width, thr, ref, ev, y)
    else:
        ladder_events_4_2(pairs, pr, ring, w, width, thr, ref, ev, y)


@njit(cache=True, error_model="numpy", pipeline_class=NoAliasCompiler)
def _log_pairs(frames, f, a, y, noisy, dark, lmax, width, pad, pairs, k, k2):
    """Row ``y`` of ``L`` at one step into ``pad (W + 2L,)`` (its middle ``W``; the
    brightness interpolated between frames ``f`` and ``f + 1`` with weight ``a``, plus
    the dark current ``dark (W,)`` if ``noisy``, then its log), then the row's pairs
    (:func:`.row_sums.row_pairs`) into ring slot ``k`` of ``pairs (L + 1, R, >= W)``, and
    slot ``k2`` too unless ``k2 < 0``. Indexes its arguments directly (no row views, no
    reference counts) by unsigned indices (no negative-index wraparound), compiled
    ``noalias``: the arrays must be distinct."""
    n = np.uint64(width)
    m = np.uint64(lmax)
    oma = 1.0 - a
    g = f + 1 if a != 0.0 else f
    if noisy:
        if a == 0.0:
            for x in range(n):
                pad[x + m] = log_intensity_value(frames[f, y, x] + dark[x])
        else:
            for x in range(n):
                pad[x + m] = log_intensity_value((oma * frames[f, y, x]
                                                  + a * frames[g, y, x]) + dark[x])
    elif a == 0.0:
        for x in range(n):
            pad[x + m] = log_intensity_value(frames[f, y, x])
    else:
        for x in range(n):
            pad[x + m] = log_intensity_value(oma * frames[f, y, x] + a * frames[g, y, x])
    for x in range(n):
        pairs[0, k, x] = pad[x + m]
    for b in range(1, lmax + 1):
        lo = np.uint64(lmax - b)
        hi = np.uint64(lmax + b)
        for x in range(n):
            pairs[b, k, x] = pad[x + lo] + pad[x + hi]
    if k2 >= 0:
        for b in range(lmax + 1):
            for x in range(n):
                pairs[b, k2, x] = pairs[b, k, x]


@njit(inline="always", cache=True)
def _aligned_ring(planes, slots, width):
    """Zeros ``(planes, slots, W8)``, ``W8`` = ``width`` rounded up to 8, starting at a
    64-byte boundary: every row starts on a cache line, so no 8-lane load or store of a
    row straddles two (numba's own arrays start at 32 bytes past one)."""
    w8 = (width + 7) // 8 * 8
    n = planes * slots * w8
    buf = np.zeros(n + 8)
    off = (64 - buf.ctypes.data % 64) % 64 // 8
    return buf[off:off + n].reshape((planes, slots, w8))


@njit(parallel=True, cache=True, error_model="numpy")
def _event_chunk(frames, fidx, aw, thr, ref, capture_first, noisy, key, t0, mean, sd,
                 zx, zr, weights, halves, ladder, lmax, tile_rows, two_rows, out):
    num_scales, height, width = thr.shape
    num_steps = fidx.shape[0]
    num_tiles = (height + tile_rows - 1) // tile_rows
    two_rows = two_rows and ladder
    # The rows one output row's sums read (two rows' for two rows a pass).
    ring = 2 * lmax + 2 if two_rows else 2 * lmax + 1
    for ti in prange(num_tiles):
        y0 = ti * tile_rows
        rows = min(height, y0 + tile_rows) - y0
        pad = np.zeros(width + 2 * lmax)  # one row of L, zero margins
        # Each padded row's pairs go to ring slot k; for the per-scale sums also to slot
        # k + ring, so the 2L + 1 rows around any output row are consecutive slots (what
        # scale_sum indexes; ladder_sum takes its rows modulo the ring).
        pairs = _aligned_ring(lmax + 1, 2 * ring, width)  # rows on cache lines
        twice = not ladder
        dark = np.empty(width)
        resp = np.empty((num_scales, width))
        for b in range(num_steps):
            capture = capture_first and b == 0
            for r in range(rows + 2 * lmax):
                y = y0 - lmax + r
                k = r % ring
                if y < 0 or y >= height:  # zero padding: L = 0
                    pairs[:, k] = 0.0
                    pairs[:, k + ring] = 0.0
                else:
                    if noisy:
                        normal_row(key, t0 + b, y, width, mean, sd, zx, zr, dark, 0)
                    _log_pairs(frames, fidx[b], aw[b], y, noisy, dark, lmax, width, pad,
                               pairs, k, k + ring if twice else -1)
                if r < 2 * lmax:
                    continue
                yo = y - lmax  # the output row whose window ends at row y
                pr = (r - 2 * lmax) % ring + lmax
                if ladder and not capture:  # sums and event rule in one loop
                    if not two_rows:
                        ladder_events(pairs, pr, ring, weights, width, thr, ref, out[b], yo)
                    elif (yo - y0) % 2 == 1:  # rows yo - 1 and yo in one pass
                        ladder_events_two(pairs, (r - 1 - 2 * lmax) % ring + lmax, ring,
                                          weights, width, thr, ref, out[b], yo - 1)
                    elif yo - y0 == rows - 1:  # the last row of an odd tile alone
                        ladder_events(pairs, pr, ring, weights, width, thr, ref, out[b], yo)
                    continue
                if ladder:
                    ladder_sum(pairs, pr, ring, weights, width, resp)
                else:
                    for s in range(num_scales):
                        scale_sum(pairs, pr, weights[s], halves[s], width, resp[s])
                for s in range(num_scales):
                    _events_row(resp[s], thr[s, yo], ref[s, yo], out[b, s, yo], width,
                                capture)


class FusedEventSampler:
    """The fused event sampler's state for one scene and configuration; :meth:`run`
    covers steps ``t0 .. t1 - 1`` (consecutive calls, consecutive ranges) and returns
    ``(t1 - t0, S, H, W) int8`` events. ``tile_rows`` and ``two_rows`` (the ladders' two
    output rows a pass; False: one) change the speed, never the events."""

    def __init__(self, scene: Scene, config: EventConfig, thresholds: np.ndarray,
                 tile_rows: int = DEFAULT_TILE_ROWS, two_rows: bool = True):
        spec = config.spec
        self.scene = scene
        _, self.weights, self.halves, self.lmax = kernel_orbits(spec.kernels())
        self.weights = np.ascontiguousarray(self.weights, dtype=np.float64)
        self.ladder = is_ladder(self.halves)
        self.thr = aligned_copy(np.asarray(thresholds, dtype=np.float64))
        self.ref = aligned_copy(np.zeros_like(self.thr))
        self.captured: np.ndarray | None = None
        self.tile_rows = max(1, int(tile_rows))
        self.two_rows = bool(two_rows)
        self.noisy, self.key, self.mean, self.sd = dark_current_stream(
            config.noise, scene, spec.num_scales)
        self.next_step = 0

    @property
    def references(self) -> np.ndarray | None:
        """The references captured at the first step ``(S, H, W)`` (None before it)."""
        return self.captured

    def run(self, t0: int, t1: int, out: np.ndarray | None = None) -> np.ndarray:
        """Events ``(t1 - t0, S, H, W) int8`` of steps ``t0 .. t1 - 1``."""
        check_chunk(self.scene, t0, t1, self.next_step)
        s, h, w = self.thr.shape
        if out is None:
            out = np.empty((t1 - t0, s, h, w), dtype=np.int8)
        if t0 == 0 and t1 > 0:  # step 0 alone: it captures the references
            self._chunk(0, 1, out[:1])
            self.captured = self.ref.copy()
            self._chunk(1, t1, out[1:])
        else:
            self._chunk(t0, t1, out)
        self.next_step = t1
        return out

    def _chunk(self, t0: int, t1: int, out: np.ndarray) -> None:
        if t1 <= t0:
            return
        frames, fidx, aw = chunk_frames(self.scene, t0, t1)
        _event_chunk(np.ascontiguousarray(frames, dtype=np.float64), fidx, aw, self.thr,
                     self.ref, t0 == 0, self.noisy, self.key, int(t0), self.mean, self.sd,
                     ZIG_X, ZIG_RATIO, self.weights, self.halves, self.ladder, self.lmax,
                     self.tile_rows, self.two_rows, out)
