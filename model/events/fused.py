"""The fused numba engine of the event samplers.

Per block of steps, three compiled passes, each parallel over rows: brightness
(interpolated between the frames the block touches, plus the dark current) to log
intensity; the receptive sums of every step (:func:`~rvsm.model.sampling.fused.filter_frames`,
the orbit order); the event rule. Every float operation is the one :mod:`.numpy_engine`
does, in the same order, and the log is the shared kernel of :mod:`.log_intensity`, so
the events are bit-identical to the numpy engine for any block, chunk and thread count.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from rvsm.model.events.config import EventConfig
from rvsm.model.kernels.orbits import kernel_orbits
from rvsm.model.noise.sensor import NoiseSource
from rvsm.model.sampling.fused import chunk_frames, filter_frames
from rvsm.model.scene.scene import Scene

__all__ = ["FusedEventSampler"]

DEFAULT_BLOCK_STEPS = 16


@njit(parallel=True, cache=True)
def _log_steps(frames, fidx, aw, dark, noisy, out):
    """``out[b]``: ``ln(max(I_b, 0) + 1)`` with ``I_b`` interpolated (plus ``dark[b]``)."""
    num_steps, height, width = out.shape
    for i in prange(num_steps * height):
        b = i // height
        y = i - b * height
        f = fidx[b]
        a = aw[b]
        oma = 1.0 - a
        f0 = frames[f, y]
        dst = out[b, y]
        if a == 0.0:
            for x in range(width):
                dst[x] = f0[x]
        else:
            f1 = frames[f + 1, y]
            for x in range(width):
                dst[x] = oma * f0[x] + a * f1[x]
        if noisy:
            dk = dark[b, y]
            for x in range(width):
                dst[x] = dst[x] + dk[x]
        for x in range(width):
            v = dst[x]
            dst[x] = math.log((v if v > 0.0 else 0.0) + 1.0)


@njit(parallel=True, cache=True)
def _events(responses, thr, ref, first, out):
    """The event rule over ``responses (B, S, H, W)``; ``first``: step 0 captures."""
    num_steps, num_scales, height, width = responses.shape
    for i in prange(num_scales * height):
        s = i // height
        y = i - s * height
        th, rf = thr[s, y], ref[s, y]
        for b in range(num_steps):
            r = responses[b, s, y]
            o = out[b, s, y]
            if first and b == 0:
                for x in range(width):
                    rf[x] = r[x]
                    o[x] = 0
                continue
            for x in range(width):
                d = r[x] - rf[x]
                c = th[x]
                if d >= c:
                    o[x] = 1
                    rf[x] = rf[x] + c
                elif d <= -c:
                    o[x] = -1
                    rf[x] = rf[x] - c
                else:
                    o[x] = 0


class FusedEventSampler:
    """The fused event sampler's state for one scene and configuration; :meth:`run`
    covers steps ``t0 .. t1 - 1`` (consecutive calls, consecutive ranges)."""

    def __init__(self, scene: Scene, config: EventConfig, thresholds: np.ndarray,
                 block_steps: int = DEFAULT_BLOCK_STEPS):
        spec = config.spec
        self.scene = scene
        _, self.weights, self.halves, self.lmax = kernel_orbits(spec.kernels())
        self.weights = np.ascontiguousarray(self.weights, dtype=np.float64)
        self.thr = np.ascontiguousarray(thresholds, dtype=np.float64)
        self.ref = np.zeros_like(self.thr)
        self.captured: np.ndarray | None = None
        self.noise = (NoiseSource(config.noise, scene.shape, spec.num_scales)
                      if config.noise is not None else None)
        self.block_steps = max(1, int(block_steps))
        self.next_step = 0

    @property
    def references(self) -> np.ndarray | None:
        """The references captured at the first step ``(S, H, W)`` (None before it)."""
        return self.captured

    def run(self, t0: int, t1: int, out: np.ndarray | None = None) -> np.ndarray:
        """Events ``(t1 - t0, S, H, W) int8`` of steps ``t0 .. t1 - 1``."""
        if t0 != self.next_step:
            raise ValueError(f"chunks must be consecutive: expected step {self.next_step}")
        s, h, w = self.thr.shape
        if out is None:
            out = np.empty((t1 - t0, s, h, w), dtype=np.int8)
        empty = np.empty((1, 1, 1))
        for b0 in range(t0, t1, self.block_steps):
            b1 = min(t1, b0 + self.block_steps)
            frames, fidx, aw = chunk_frames(self.scene, b0, b1)
            frames = np.ascontiguousarray(frames, dtype=np.float64)
            dark = (self.noise.dark_current_at(b0, b1 - b0) if self.noise is not None
                    else empty)
            logs = np.empty((b1 - b0, h, w))
            _log_steps(frames, fidx, aw, dark, self.noise is not None, logs)
            if self.lmax == 0:  # the plain DVS: 0 + 1.0 * L is L
                responses = logs[:, None]
            else:
                responses = filter_frames(logs, self.weights, self.halves, self.lmax)
            _events(responses, self.thr, self.ref, b0 == 0,
                    out[b0 - t0:b1 - t0])
            if b0 == 0:
                self.captured = np.array(responses[0], dtype=np.float64)
        self.next_step = t1
        return out
