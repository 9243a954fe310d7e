"""The numpy engine of the float samplers: the vectorised reference of :mod:`.fused`.

Every model integrates per step, then compares, then resets; the spike of step ``t`` is
decided from the accumulation that includes step ``t``. FSM is the one-scale case with a
1x1 kernel of weight 1 that only fires +1. Receptive-field sums are linear, so the frames
are filtered once and the per-step drive is interpolated between filtered frames (SPEC
section 1's formula applied after the filter); only the dark current, new every step, is
filtered per step. Filtering uses the fixed float order of
:mod:`rvsm.model.kernels.orbits`, so the fused engine gives bit-identical spikes.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import numpy as np

from rvsm.model.kernels.orbits import orbit_receptive_sums
from rvsm.model.noise.sensor import NoiseSource
from rvsm.model.sampling.config import DEFAULT_BLOCK_STEPS, SamplerConfig
from rvsm.model.scene.scene import Scene


def iter_step_drives(
    scene: Scene, config: SamplerConfig, block_steps: int = DEFAULT_BLOCK_STEPS
) -> Iterator[tuple[int, np.ndarray]]:
    """Yield ``(t, drive)`` for every step: ``drive (S, H, W) float64`` is the input of
    every accumulator at step ``t`` (receptive-field sum of brightness plus filtered dark
    current). The array is a reused buffer: consume it before the next iteration.

    Per block of ``block_steps`` steps, the frames the block touches are read
    (:meth:`Scene.frame_range`) and filtered, each frame once (:func:`_filtered_window`); a
    step between frames is ``(1 - a) KF[f] + a KF[f+1]`` (SPEC section 1's interpolation
    applied after the linear filter, frame by frame, so the block length changes no
    value). Dark current is drawn and filtered per block too. This is the numpy
    reference engine.
    """
    kernels = config.spec.kernels()
    noise = NoiseSource(config.noise, scene.shape, len(kernels)) if config.noise else None
    buf = np.empty((len(kernels),) + scene.shape)
    tmp = np.empty_like(buf)
    window = (0, np.empty((0, len(kernels)) + scene.shape))
    for t0, t1 in scene.blocks(block_steps):
        f, a = scene.frame_weights(t0, t1)
        first, end = scene.frame_span(t0, t1)
        window = _filtered_window(scene, kernels, first, end, window)
        filtered = window[1][first - window[0]:]  # (F', S, H, W) from frame `first`
        f = f - first
        dark = (
            orbit_receptive_sums(noise.dark_current(t1 - t0), kernels)
            if noise is not None else None
        )
        for b in range(t1 - t0):
            if a[b] == 0.0:
                drive = filtered[f[b]]
            else:
                np.multiply(filtered[f[b]], 1.0 - a[b], out=buf)
                np.multiply(filtered[f[b] + 1], a[b], out=tmp)
                buf += tmp
                drive = buf
            if dark is not None:
                np.add(drive, dark[b], out=buf)
                drive = buf
            yield t0 + b, drive


def _filtered_window(
    scene: Scene, kernels: Sequence[np.ndarray], first: int, end: int,
    window: tuple[int, np.ndarray],
) -> tuple[int, np.ndarray]:
    """Receptive sums of frames ``first .. end - 1`` as ``(start, (n, S, H, W) float64)``
    with ``start <= first``, reusing ``window`` (the previous one): frames it holds from
    ``first`` on are kept, only the frames after it are read and filtered."""
    start, held = window
    if start <= first and end <= start + len(held):
        return window
    keep = held[first - start:] if start <= first < start + len(held) else held[:0]
    new = orbit_receptive_sums(scene.frame_range(first + len(keep), end), kernels)
    return first, (np.concatenate([keep, new]) if len(keep) else new)


class Integrator:
    """The per-step integrate / compare / fire / reset state of ``S x H x W`` accumulators.

    ``thresholds`` is ``(S, H, W)``; ``signed`` models fire -1 at ``acc <= -thr``.
    """

    def __init__(self, thresholds: np.ndarray, signed: bool, reset: str):
        self.thr = np.ascontiguousarray(thresholds, dtype=np.float64)
        self.neg_thr = -self.thr
        self.signed = signed
        self.reset = reset
        self.acc = np.zeros_like(self.thr)
        self._pos = np.empty(self.thr.shape, dtype=bool)
        self._neg = np.empty(self.thr.shape, dtype=bool)
        self._fired = np.empty(self.thr.shape, dtype=bool)
        # +1 wins where a threshold is 0 and both comparisons hold.
        self._zero_thr = bool(np.any(self.thr == 0))

    def step(self, drive: np.ndarray, out: np.ndarray) -> None:
        """Integrate one step's ``drive (S, H, W)`` and write spikes into ``out (S, H, W)
        int8``."""
        acc = self.acc
        acc += drive
        if not self.signed:
            fired = out.view(bool)  # int8 0/1 and bool share a layout: compare in place
            np.greater_equal(acc, self.thr, out=fired)
            if self.reset == "zero":
                np.copyto(acc, 0.0, where=fired)
            else:
                np.subtract(acc, self.thr, out=acc, where=fired)
            return
        pos, neg = self._pos, self._neg
        np.greater_equal(acc, self.thr, out=pos)
        np.less_equal(acc, self.neg_thr, out=neg)
        if self._zero_thr:
            neg &= ~pos
        np.subtract(pos.view(np.int8), neg.view(np.int8), out=out)
        if self.reset == "zero":
            np.logical_or(pos, neg, out=self._fired)
            np.copyto(acc, 0.0, where=self._fired)
        else:
            np.subtract(acc, self.thr, out=acc, where=pos)
            np.add(acc, self.thr, out=acc, where=neg)


class NumpyFloatSampler:
    """The numpy engine's state for one scene and configuration, run chunk by chunk.

    ``thresholds`` is ``(S, H, W) float64`` (:func:`.config.accumulator_thresholds`);
    :meth:`run` advances over steps ``t0 .. t1 - 1`` (consecutive calls cover consecutive
    ranges), the same interface as :class:`.fused.FusedFloatSampler`. The dark current is
    drawn in blocks of ``block_steps`` (the spikes do not depend on it).
    """

    def __init__(self, scene: Scene, config: SamplerConfig, thresholds: np.ndarray,
                 block_steps: int = DEFAULT_BLOCK_STEPS):
        spec = config.spec
        self.integrator = Integrator(thresholds, spec.signed, config.reset)
        self.drives = iter_step_drives(scene, config, block_steps)
        self.shape = (spec.num_scales,) + scene.shape
        self.next_step = 0

    def run(self, t0: int, t1: int, out: np.ndarray | None = None) -> np.ndarray:
        """Spikes ``(t1 - t0, S, H, W) int8`` of steps ``t0 .. t1 - 1``."""
        if t0 != self.next_step:
            raise ValueError(f"chunks must be consecutive: expected step {self.next_step}")
        if out is None:
            out = np.empty((t1 - t0,) + self.shape, dtype=np.int8)
        for b in range(t1 - t0):
            _, drive = next(self.drives)
            self.integrator.step(drive, out[b])
        self.next_step = t1
        return out
