"""The numpy engine of the event samplers: the vectorised reference of :mod:`.fused`.

Per block of steps: brightness ``I (B, H, W)`` (SPEC section 1's interpolation,
:meth:`Scene.brightness`) plus the dark current when noisy, the log intensity
(:func:`.log_intensity.log_intensity`), the receptive sums of every step
(:func:`~rvsm.model.kernels.orbits.orbit_receptive_sums`, the fixed float order), then the
event rule of SPEC section 7 step by step: the first step captures the references and
emits nothing; afterwards ``d = R - ref``, ``d >= C`` is ON (+1, ``ref += C``), else
``d <= -C`` is OFF (-1, ``ref -= C``); at most one event per accumulator and step.
"""

from __future__ import annotations

import numpy as np

from rvsm.model.events.config import EventConfig
from rvsm.model.events.log_intensity import log_intensity
from rvsm.model.kernels.orbits import orbit_receptive_sums
from rvsm.model.noise.sensor import NoiseSource
from rvsm.model.scene.scene import Scene

__all__ = ["DEFAULT_BLOCK_STEPS", "NumpyEventSampler", "log_brightness"]

#: Steps filtered at a time (memory: ``B * S * H * W`` floats).
DEFAULT_BLOCK_STEPS = 16


def log_brightness(scene: Scene, noise: NoiseSource | None, t0: int, t1: int) -> np.ndarray:
    """``L (t1 - t0, H, W) float64`` of steps ``t0 .. t1 - 1``: the scene's brightness plus
    the dark current (when ``noise``), through :func:`log_intensity`."""
    brightness = scene.brightness(t0, t1)
    if noise is not None:
        brightness += noise.dark_current_at(t0, t1 - t0)
    return log_intensity(brightness)


class EventIntegrator:
    """References and the event rule for ``S x H x W`` accumulators (module doc)."""

    def __init__(self, thresholds: np.ndarray):
        self.thr = np.ascontiguousarray(thresholds, dtype=np.float64)
        self.neg_thr = -self.thr
        self.ref: np.ndarray | None = None
        self.captured: np.ndarray | None = None  # the references of the first step
        self._pos = np.empty(self.thr.shape, dtype=bool)
        self._neg = np.empty(self.thr.shape, dtype=bool)

    def step(self, response: np.ndarray, out: np.ndarray) -> None:
        """One step's responses ``(S, H, W)``; events into ``out (S, H, W) int8``."""
        if self.ref is None:
            self.ref = np.array(response, dtype=np.float64)
            self.captured = self.ref.copy()
            out[...] = 0
            return
        d = response - self.ref
        pos, neg = self._pos, self._neg
        np.greater_equal(d, self.thr, out=pos)
        np.less_equal(d, self.neg_thr, out=neg)
        neg &= ~pos
        np.subtract(pos.view(np.int8), neg.view(np.int8), out=out)
        np.add(self.ref, self.thr, out=self.ref, where=pos)
        np.subtract(self.ref, self.thr, out=self.ref, where=neg)


class NumpyEventSampler:
    """The numpy engine's state for one scene and configuration, run chunk by chunk:
    :meth:`run` covers steps ``t0 .. t1 - 1`` (consecutive calls, consecutive ranges),
    the interface of :class:`.fused.FusedEventSampler`."""

    def __init__(self, scene: Scene, config: EventConfig, thresholds: np.ndarray,
                 block_steps: int = DEFAULT_BLOCK_STEPS):
        spec = config.spec
        self.scene = scene
        self.kernels = spec.kernels()
        self.noise = (NoiseSource(config.noise, scene.shape, spec.num_scales)
                      if config.noise is not None else None)
        self.integrator = EventIntegrator(thresholds)
        self.block_steps = max(1, int(block_steps))
        self.shape = (spec.num_scales,) + scene.shape
        self.next_step = 0

    @property
    def references(self) -> np.ndarray | None:
        """The references captured at the first step ``(S, H, W)`` (None before it)."""
        return self.integrator.captured

    def run(self, t0: int, t1: int, out: np.ndarray | None = None) -> np.ndarray:
        """Events ``(t1 - t0, S, H, W) int8`` of steps ``t0 .. t1 - 1``."""
        if t0 != self.next_step:
            raise ValueError(f"chunks must be consecutive: expected step {self.next_step}")
        if out is None:
            out = np.empty((t1 - t0,) + self.shape, dtype=np.int8)
        for b0 in range(t0, t1, self.block_steps):
            b1 = min(t1, b0 + self.block_steps)
            responses = orbit_receptive_sums(log_brightness(self.scene, self.noise, b0, b1),
                                             self.kernels)
            for b in range(b1 - b0):
                self.integrator.step(responses[b], out[b0 - t0 + b])
        self.next_step = t1
        return out
