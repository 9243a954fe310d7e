"""The numpy engine of the fixed twin: the vectorised reference of :mod:`.fused`.

Steps run in blocks: the analogue brightness ``I_t`` of a block (+ dark current from the
point's :class:`~rvsm.model.noise.sensor.NoiseSource`, the same streams as the float
twin's), its ADC codes (:mod:`.adc`) and exact integer receptive sums for the whole block
at once (:mod:`.core`), then the per-step arithmetic shift, saturation, compare, fire and
reset over whole ``(S, H, W)`` arrays (:class:`~.core.FixedIntegrator`; for the event
sensor the log ADC and :class:`~.core.FixedEventIntegrator`). The spikes are exactly
``point.contract().run(codes, thresholds)``.
"""

from __future__ import annotations

import numpy as np

from rvsm.model.fixed.contract import (
    arithmetic_shift,
    bit_length_histogram,
    integer_receptive_sums,
    make_integrator,
)
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.noise.sensor import NoiseSource
from rvsm.model.sampling.config import DEFAULT_BLOCK_STEPS
from rvsm.model.scene.scene import Scene


def step_codes(scene: Scene, point: DesignPoint, noise: NoiseSource | None, t0: int,
               t1: int) -> np.ndarray:
    """ADC codes ``(t1 - t0, H, W) int64`` of steps ``t0 .. t1 - 1``: the scene's
    brightness plus ``noise``'s dark current (``point.noise_source()``, or None) through
    the point's ADC (its sensor's law: linear, or the event sensor's log)."""
    analog = scene.brightness(t0, t1)
    if noise is not None:
        analog += noise.dark_current_at(t0, t1 - t0)
    return point.rules.adc_codes(point, analog)


class NumpyFixedTwin:
    """State of the numpy engine of ``point``'s fixed twin on ``scene``, run chunk by chunk.

    ``thresholds`` is ``(S, H, W) int64``; :meth:`run` advances over steps ``t0 .. t1 - 1``
    (consecutive) and returns spikes ``(t1 - t0, S, H, W) int8``, the interface of
    :class:`.fused.FusedFixedTwin`; :meth:`stats` gives the datapath counters so far.
    Blocks are ``block_steps`` long (the spikes do not depend on it). ``keep_codes`` keeps
    every step's ADC codes in :attr:`codes` ``(T, H, W) uint16``; ``histograms`` counts
    the bit lengths of the sums and accumulators.
    """

    def __init__(self, scene: Scene, point: DesignPoint, thresholds: np.ndarray,
                 block_steps: int = DEFAULT_BLOCK_STEPS, keep_codes: bool = False,
                 histograms: bool = False):
        self.scene = scene
        self.point = point
        self.noise = point.noise_source()
        self.weights = point.contract().weight_arrays
        self.block_steps = int(block_steps)
        self.integrator = make_integrator(
            point.kind, thresholds, point.accumulator_bits, point.signed, point.reset,
            track=True, histogram=histograms,
        )
        s = point.num_scales
        big, small = np.iinfo(np.int64).max, np.iinfo(np.int64).min
        self.sum_min, self.sum_max = np.full(s, big), np.full(s, small)
        self.shifted_min, self.shifted_max = np.full(s, big), np.full(s, small)
        self.sum_hist = np.zeros((s, 64), dtype=np.int64) if histograms else None
        self.codes = (np.zeros((scene.num_steps,) + point.shape, dtype=np.uint16)
                      if keep_codes else None)
        self.next_step = 0

    def _codes(self, t0: int, t1: int) -> np.ndarray:
        """ADC codes ``(t1 - t0, H, W) int64`` of steps ``t0 .. t1 - 1``."""
        return step_codes(self.scene, self.point, self.noise, t0, t1)

    def run(self, t0: int, t1: int, out: np.ndarray | None = None) -> np.ndarray:
        """Spikes ``(t1 - t0, S, H, W) int8`` of steps ``t0 .. t1 - 1``."""
        if t0 != self.next_step:
            raise ValueError(f"chunks must be consecutive: expected step {self.next_step}")
        if out is None:
            out = np.empty((t1 - t0, self.point.num_scales) + self.point.shape, dtype=np.int8)
        shift = self.point.shift
        for b0 in range(t0, t1, self.block_steps):
            b1 = min(b0 + self.block_steps, t1)
            codes = self._codes(b0, b1)
            if self.codes is not None:
                self.codes[b0:b1] = codes
            sums = integer_receptive_sums(codes, self.weights)
            np.minimum(self.sum_min, sums.min(axis=(0, 2, 3)), out=self.sum_min)
            np.maximum(self.sum_max, sums.max(axis=(0, 2, 3)), out=self.sum_max)
            if self.sum_hist is not None:
                self.sum_hist += bit_length_histogram(sums)
            shifted = arithmetic_shift(sums, shift) if shift else sums
            np.minimum(self.shifted_min, shifted.min(axis=(0, 2, 3)), out=self.shifted_min)
            np.maximum(self.shifted_max, shifted.max(axis=(0, 2, 3)), out=self.shifted_max)
            for b in range(b1 - b0):
                out[b0 - t0 + b] = self.integrator.step(shifted[b])
        self.next_step = t1
        return out

    def stats(self) -> dict[str, np.ndarray | None]:
        """Per-scale ``(S,) int64`` counters (``sum_min``, ``sum_max``, ``shifted_min``,
        ``shifted_max``, ``acc_min``, ``acc_max``, ``saturated``) and the ``(S, 64)``
        histograms ``sum_hist``, ``acc_hist`` (None unless ``histograms``)."""
        integ = self.integrator
        return {"sum_min": self.sum_min.copy(), "sum_max": self.sum_max.copy(),
                "shifted_min": self.shifted_min.copy(),
                "shifted_max": self.shifted_max.copy(),
                "acc_min": integ.acc_min.copy(), "acc_max": integ.acc_max.copy(),
                "saturated": integ.saturated.copy(), "sum_hist": self.sum_hist,
                "acc_hist": integ.acc_hist}
