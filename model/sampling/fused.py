"""Fused numba kernels of the float samplers: the time loop inside, tiles of rows in parallel.

:class:`FusedFloatSampler` runs a scene chunk by chunk in time. Per chunk, the frames the
chunk touches are filtered once (:func:`filter_frames`, parallel over rows); then
:func:`_float_chunk` processes tiles of ``tile_rows`` rows in parallel (``prange``), and
inside each tile loops over the chunk's steps with the tile's accumulators in cache:
interpolate between filtered frames, add the filtered dark current (drawn inside the tile
from the counter-based streams of :mod:`rvsm.model.noise.streams`, with a halo of ``L``
rows), integrate, compare, fire, reset. Row sums are the shared kernels of :mod:`.row_sums`
(:func:`.row_sums.ladder_sum` for ladder models). Each step of a tile is one call of
:func:`_step_rows`, compiled ``noalias`` and indexing its arrays directly (no row views);
accumulators and thresholds start on cache lines. FSM reads the frames themselves, so a
chunk runs in :func:`view_spans`, ranges whose rendered frames are views (no copy).

Every float operation is the one :mod:`.numpy_engine` does, in the same order (filtering
in the orbit order of :mod:`rvsm.model.kernels.orbits`), and every pixel's arithmetic
depends on nothing but its own coordinates, so the spikes are bit-identical to the numpy
engine for any tile size, chunk length and thread count.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from rvsm.model.infra.noalias import NoAliasCompiler
from rvsm.model.infra.simd import aligned_copy
from rvsm.model.kernels.orbits import kernel_orbits
from rvsm.model.noise.sensor import NoiseParams, NoiseSource
from rvsm.model.noise.streams import ZIG_RATIO, ZIG_X, check_coordinates, normal_row
from rvsm.model.sampling.config import SamplerConfig
from rvsm.model.sampling.row_sums import is_ladder, ladder_sum, row_pairs, scale_sum
from rvsm.model.scene.scene import Scene

DEFAULT_TILE_ROWS = 16


def view_spans(scene: Scene, t0: int, t1: int) -> list[tuple[int, int]]:
    """Steps ``t0 .. t1 - 1`` as consecutive ranges whose frames (:meth:`Scene.frame_span`)
    the scene's source hands out without a copy: for a source with ``block_frames = B``
    (:class:`rvsm.model.scene.library.RenderedFrames`), the steps between frames ``k B``
    and ``(k + 1) B - 1`` in one range, those between frames ``(k + 1) B - 1`` and
    ``(k + 1) B`` (two frames copied) in another; ``[(t0, t1)]`` for any other source."""
    block = getattr(scene.frame_source, "block_frames", 0)
    if block < 2 or t1 <= t0:
        return [(t0, t1)]
    m = scene.steps_per_frame
    cuts = {t0, t1}
    for f in range(t0 // m, (t1 - 1) // m + 1):
        if f % block == block - 1:  # steps of frame f read frames f and f + 1
            cuts.update(t for t in (f * m, (f + 1) * m) if t0 < t < t1)
    edges = sorted(cuts)
    return list(zip(edges[:-1], edges[1:], strict=True))


def check_chunk(scene: Scene, t0: int, t1: int, next_step: int) -> None:
    """``ValueError`` unless steps ``t0 .. t1 - 1`` continue at ``next_step`` and lie in
    the scene: the fused kernels index frames unchecked (a step past the scene would read
    past its frames)."""
    if t0 != next_step:
        raise ValueError(f"chunks must be consecutive: expected step {next_step}")
    if t1 > scene.num_steps:
        raise ValueError(f"step {t1 - 1} is past the scene's {scene.num_steps} steps")


def chunk_frames(scene: Scene, t0: int, t1: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What a fused kernel needs for steps ``t0 .. t1 - 1``: the scene's frames the chunk
    touches ``(F, H, W)`` (read on demand, :meth:`Scene.frame_range`), each step's first
    frame as an index into them ``(T,) int64`` and its interpolation weight
    ``(T,) float64`` (:meth:`Scene.frame_weights`)."""
    f, a = scene.frame_weights(t0, t1)
    first, end = scene.frame_span(t0, t1)
    return (scene.frame_range(first, end), (f - first).astype(np.int64),
            np.ascontiguousarray(a, dtype=np.float64))


@njit(inline="always", cache=True)
def _filter_rows(pairs, r0, nrows, weights, halves, ladder, width, row, out):
    """``out[s, r, x]``: receptive sums of rows ``r0 .. r0 + nrows - 1`` of the padded
    image whose row pairs are ``pairs``: :func:`.row_sums.ladder_sum` (every scale in one
    pass, through ``row (S, W)``) if ``ladder``, else :func:`.row_sums.scale_sum` per
    scale; the same sums bit for bit."""
    for r in range(nrows):
        if ladder:
            ladder_sum(pairs, r0 + r, pairs.shape[1], weights, width, row)
            for s in range(weights.shape[0]):
                for x in range(width):
                    out[s, r, x] = row[s, x]
        else:
            for s in range(weights.shape[0]):
                scale_sum(pairs, r0 + r, weights[s], halves[s], width, out[s, r])


@njit(parallel=True, cache=True)
def _filter_frames(padded, weights, halves, ladder, lmax, height, width, tile_rows, out):
    num_frames = padded.shape[0]
    num_scales = weights.shape[0]
    num_tiles = (height + tile_rows - 1) // tile_rows
    for i in prange(num_frames * num_tiles):
        f = i // num_tiles
        y0 = (i - f * num_tiles) * tile_rows
        rows = min(height, y0 + tile_rows) - y0
        pairs = np.empty((lmax + 1, rows + 2 * lmax, width))
        local = np.empty((num_scales, rows, width))
        row = np.empty((num_scales, width))
        row_pairs(padded[f, y0:y0 + rows + 2 * lmax], rows + 2 * lmax, lmax, width, pairs)
        _filter_rows(pairs, lmax, rows, weights, halves, ladder, width, row, local)
        out[f, :, y0:y0 + rows] = local


def filter_frames(frames: np.ndarray, weights, halves, lmax: int, tile_rows: int = 32,
                  out: np.ndarray | None = None, padded: np.ndarray | None = None) -> np.ndarray:
    """Receptive sums ``(F, S, H, W) float64`` of ``frames (F, H, W)`` in orbit order.

    ``out`` and ``padded`` (``(F', H + 2L, W + 2L)`` zeros outside, ``F' >= F``) are
    optional buffers to reuse.
    """
    f, h, w = frames.shape
    if padded is None or padded.shape[0] < f:
        padded = np.zeros((f, h + 2 * lmax, w + 2 * lmax))
    padded = padded[:f]
    padded[:, lmax:lmax + h, lmax:lmax + w] = frames
    if out is None or out.shape[0] < f:
        out = np.empty((f, weights.shape[0], h, w))
    out = out[:f]
    _filter_frames(padded, weights, halves, is_ladder(halves), lmax, h, w, tile_rows, out)
    return out


@njit(inline="always", cache=True)
def _drive(kf, f, a, oma, dark, noisy, s, y, r, x):
    """The drive of pixel ``(y, x)`` of scale ``s``: the filtered frames ``kf[f]`` and
    ``kf[f + 1]`` interpolated with weight ``a`` (``kf[f]`` alone when ``a`` is 0), plus
    the dark current ``dark[s, r, x]`` if ``noisy`` (the numpy engine's operations)."""
    d = kf[f, s, y, x] if a == 0.0 else kf[f, s, y, x] * oma + kf[f + 1, s, y, x] * a
    return d + dark[s, r, x] if noisy else d


@njit(inline="always", cache=True)
def _integrate_row(kf, f, a, oma, dark, noisy, acc, thr, out, s, y, r, b, width, signed,
                   zero_reset):
    """Integrate row ``y`` of scale ``s`` by its drive (:func:`_drive`), compare, fire,
    reset (the numpy Integrator's rules); spikes into ``out[b, s, y]``. Indexes the arrays
    directly (a row view costs numba two reference-count calls)."""
    if zero_reset:
        if signed:
            for x in range(width):
                v = acc[s, y, x] + _drive(kf, f, a, oma, dark, noisy, s, y, r, x)
                th = thr[s, y, x]
                sp = np.int8(1) if v >= th else (np.int8(-1) if v <= -th else np.int8(0))
                out[b, s, y, x] = sp
                acc[s, y, x] = v if sp == 0 else 0.0
        else:
            for x in range(width):
                v = acc[s, y, x] + _drive(kf, f, a, oma, dark, noisy, s, y, r, x)
                fired = v >= thr[s, y, x]
                out[b, s, y, x] = np.int8(1) if fired else np.int8(0)
                acc[s, y, x] = 0.0 if fired else v
    else:
        for x in range(width):
            v = acc[s, y, x] + _drive(kf, f, a, oma, dark, noisy, s, y, r, x)
            th = thr[s, y, x]
            if v >= th:
                out[b, s, y, x] = 1
                v = v - th
            elif signed and v <= -th:
                out[b, s, y, x] = -1
                v = v + th
            else:
                out[b, s, y, x] = 0
            acc[s, y, x] = v


@njit(cache=True, error_model="numpy", pipeline_class=NoAliasCompiler)
def _step_rows(kf, f, a, thr, acc, noisy, dark, y0, y1, signed, zero_reset, out, b):
    """One step of rows ``y0 .. y1 - 1``, every scale (:func:`_integrate_row`; the tile's
    dark current ``dark[s, y - y0]``). Compiled ``noalias``: every array argument is a
    distinct allocation."""
    num_scales = acc.shape[0]
    width = acc.shape[2]
    oma = 1.0 - a
    for y in range(y0, y1):
        for s in range(num_scales):
            _integrate_row(kf, f, a, oma, dark, noisy, acc, thr, out, s, y, y - y0, b, width,
                           signed, zero_reset)


@njit(parallel=True, cache=True)
def _float_chunk(kf, fidx, aw, thr, acc, signed, zero_reset, noisy, key, t0, mean, sd,
                 zx, zr, weights, halves, ladder, lmax, tile_rows, out):
    num_scales, height, width = acc.shape
    num_steps = fidx.shape[0]
    num_tiles = (height + tile_rows - 1) // tile_rows
    halo = lmax if noisy else 0
    for ti in prange(num_tiles):
        y0 = ti * tile_rows
        y1 = min(height, y0 + tile_rows)
        rows = y1 - y0
        pad = np.zeros((rows + 2 * halo, width + 2 * halo))
        pairs = np.empty((halo + 1, rows + 2 * halo, width)) if noisy else np.empty((1, 1, 1))
        dark = np.empty((num_scales, rows, width)) if noisy else np.empty((1, 1, 1))
        row = np.empty((num_scales, width))
        for b in range(num_steps):
            if noisy:
                for r in range(rows + 2 * halo):
                    y = y0 - halo + r
                    if y >= 0 and y < height:
                        normal_row(key, t0 + b, y, width, mean, sd, zx, zr, pad[r], halo)
                row_pairs(pad, rows + 2 * halo, halo, width, pairs)
                _filter_rows(pairs, halo, rows, weights, halves, ladder, width, row, dark)
            _step_rows(kf, fidx[b], aw[b], thr, acc, noisy, dark, y0, y1, signed, zero_reset,
                       out, b)


def dark_current_stream(noise: NoiseParams | None, scene: Scene, num_scales: int
                        ) -> tuple[bool, np.uint64, float, float]:
    """What a fused kernel needs to draw the dark current itself: ``(noisy, key, mean,
    sd)`` of ``noise``'s stream (:class:`NoiseSource`; coordinates checked), or
    ``(False, 0, 0.0, 0.0)`` without noise."""
    if noise is None:
        return False, np.uint64(0), 0.0, 0.0
    check_coordinates(scene.num_steps, scene.shape)
    src = NoiseSource(noise, scene.shape, num_scales)
    mean, sd = src.dark_mean_sd
    return True, src.dark_key, mean, sd


class FusedFloatSampler:
    """The float sampler's state and fused chunk kernel for one scene and configuration.

    ``thresholds`` is ``(S, H, W) float64`` (from :func:`.config.accumulator_thresholds`);
    :meth:`run` advances the accumulators over steps ``t0 .. t1 - 1`` (consecutive calls
    must cover consecutive ranges) and returns ``(t1 - t0, S, H, W) int8`` spikes.
    """

    def __init__(self, scene: Scene, config: SamplerConfig, thresholds: np.ndarray,
                 tile_rows: int = DEFAULT_TILE_ROWS):
        spec = config.spec
        self.scene = scene
        _, self.weights, self.halves, self.lmax = kernel_orbits(spec.kernels())
        self.weights = np.ascontiguousarray(self.weights, dtype=np.float64)
        self.ladder = is_ladder(self.halves)
        # on cache lines: no 8-lane load or store straddles two
        self.thr = aligned_copy(np.asarray(thresholds, dtype=np.float64))
        self.acc = aligned_copy(np.zeros_like(self.thr))
        self.signed = bool(spec.signed)
        self.zero_reset = config.reset == "zero"
        self.tile_rows = max(1, int(tile_rows))
        self.noisy, self.key, self.mean, self.sd = dark_current_stream(
            config.noise, scene, spec.num_scales)
        self.next_step = 0
        self._kf: np.ndarray | None = None
        self._padded: np.ndarray | None = None

    def run(self, t0: int, t1: int, out: np.ndarray | None = None) -> np.ndarray:
        """Spikes ``(t1 - t0, S, H, W) int8`` of steps ``t0 .. t1 - 1``."""
        check_chunk(self.scene, t0, t1, self.next_step)
        s, h, w = self.acc.shape
        if out is None:
            out = np.empty((t1 - t0, s, h, w), dtype=np.int8)
        # FSM reads the frames themselves: in ranges of steps whose frames are views (no
        # copy of the chunk's frames); a filtering model copies them anyway
        spans = view_spans(self.scene, t0, t1) if self.lmax == 0 else [(t0, t1)]
        for u0, u1 in spans:
            self._run(u0, u1, out[u0 - t0:u1 - t0])
        self.next_step = t1
        return out

    def _run(self, t0: int, t1: int, out: np.ndarray) -> None:
        scene = self.scene
        frames, fidx, aw = chunk_frames(scene, t0, t1)
        if self.lmax == 0:  # FSM: 0 + 1.0 * v is v
            kf = frames[:, None]
        else:
            nf = frames.shape[0]
            if self._kf is None or self._kf.shape[0] < nf:
                h, w = scene.shape
                self._kf = np.empty((nf, self.weights.shape[0], h, w))
                self._padded = np.zeros((nf, h + 2 * self.lmax, w + 2 * self.lmax))
            kf = filter_frames(frames, self.weights, self.halves, self.lmax,
                               out=self._kf, padded=self._padded)
        _float_chunk(
            kf, fidx, aw,
            self.thr, self.acc, self.signed, self.zero_reset, self.noisy, self.key,
            int(t0), self.mean, self.sd, ZIG_X, ZIG_RATIO, self.weights, self.halves,
            self.ladder, self.lmax, self.tile_rows, out,
        )
