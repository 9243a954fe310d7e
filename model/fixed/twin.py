"""The fixed twin: a scene through the bit-accurate contract of a design point (SPEC 5).

Per step ``t``: analogue brightness ``I_t`` (+ dark current, when the point has noise) ->
ADC codes (:mod:`.adc`) -> exact integer receptive-field sums with the quantised weights
-> arithmetic right shift -> W-bit saturating accumulators -> compare with each
accumulator's integer threshold -> spike +1 / -1 -> reset (:mod:`.core`). The noise comes
from the same :class:`~rvsm.model.noise.sensor.NoiseSource` (same seed, same streams) as the float
sampler, so float and fixed see identical analogue noise.

Two engines with identical spikes and statistics: ``"fused"`` (default; numba, the time
loop inside, :mod:`.fused`) and ``"numpy"`` (vectorised: steps in blocks, ADC and sums for
a whole block at once, the per-step loop over whole ``(S, H, W)`` arrays). The spikes are
exactly ``point.contract().run(codes, thresholds)``.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np

from rvsm.model.fixed.adc import adc_codes
from rvsm.model.fixed.core import (
    ArrayContract,
    FixedIntegrator,
    arithmetic_shift,
    bit_length_histogram,
    integer_receptive_sums,
)
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.infra.memory import require_spike_memory
from rvsm.model.infra.progress import progress_bar
from rvsm.model.noise.sensor import NoiseSource
from rvsm.model.sampling.samplers import DEFAULT_BLOCK_STEPS, sampling_meta
from rvsm.model.scene.scene import Scene


@dataclass
class FixedStats:
    """What the datapath saw, per scale (all ``(S,) int64`` unless said otherwise).

    ``saturated``: accumulator-steps whose pre-saturation value left the W-bit range;
    ``sum_min``/``sum_max``: per-step weighted sums before the shift; ``shifted_min`` /
    ``shifted_max``: after it; ``acc_min``/``acc_max``: accumulators after adding a step's
    sum, before saturation; ``sum_hist``/``acc_hist``: ``(S, 64)`` counts of the bit
    lengths of ``|sum|`` (before the shift) and ``|acc|`` (None unless requested);
    ``steps``, ``accumulators``: T and H*W.
    """

    steps: int
    accumulators: int
    saturated: np.ndarray
    sum_min: np.ndarray
    sum_max: np.ndarray
    shifted_min: np.ndarray
    shifted_max: np.ndarray
    acc_min: np.ndarray
    acc_max: np.ndarray
    sum_hist: np.ndarray | None = None
    acc_hist: np.ndarray | None = None


@dataclass
class FixedRun:
    """Fixed-twin output: ``spikes (T, S, H, W) int8`` in {-1, 0, 1}.

    ``thresholds`` is ``(S, H, W) int64`` (accumulator LSBs); ``codes`` the ADC codes
    ``(T, H, W) uint16`` when kept; ``meta`` the spike file's metadata.
    """

    spikes: np.ndarray
    thresholds: np.ndarray
    point: DesignPoint
    contract: ArrayContract
    stats: FixedStats
    meta: dict = field(default_factory=dict)
    codes: np.ndarray | None = None


def fit_point(scene: Scene, point: DesignPoint) -> DesignPoint:
    """``point`` sized to the scene: the array follows the scene's ``(H, W)``."""
    return point if scene.shape == point.shape else point.with_size(*scene.shape)


def code_blocks(
    scene: Scene, point: DesignPoint, noise: NoiseSource | None, block_steps: int
) -> Iterator[tuple[int, int, np.ndarray]]:
    """Yield ``(t0, t1, codes (B, H, W) int64)``: the ADC codes of steps ``t0..t1-1``.

    ``noise`` supplies the dark current (drawn in step order, as the float sampler does).
    """
    for t0, t1 in scene.blocks(block_steps):
        analog = scene.brightness(t0, t1)
        if noise is not None:
            analog += noise.dark_current(t1 - t0)
        yield t0, t1, adc_codes(
            analog, point.adc_bits, point.adc_full_scale, point.adc_rounding, point.adc_clip
        )


def simulate_fixed(
    scene: Scene,
    point: DesignPoint,
    progress: bool = False,
    block_steps: int = DEFAULT_BLOCK_STEPS,
    keep_codes: bool = False,
    histograms: bool = False,
    engine: str = "fused",
    ranges: bool = True,
) -> FixedRun:
    """Run the fixed twin of ``point`` over ``scene``; see the module docstring.

    A scene whose ``(H, W)`` differs from the point's runs on the same point resized to
    it (:func:`fit_point`); ``meta`` records the size used. ``keep_codes`` keeps the ADC
    codes (for stimulus files); ``histograms`` fills the profiling histograms (both run
    the numpy engine). ``engine`` is ``"fused"`` (numba, default) or ``"numpy"``;
    ``ranges=False`` lets the fused engine skip the min/max statistics (None then).
    """
    if engine == "fused" and not keep_codes and not histograms:
        from rvsm.model.fixed.fused import stream_fixed
        from rvsm.model.sampling.stream import ArraySink

        sink = ArraySink()
        run = stream_fixed(scene, point, sink, progress=progress, ranges=ranges)
        run.spikes = sink.spikes
        return run
    if engine not in ("fused", "numpy"):
        from rvsm.model.infra.errors import RvsmError

        raise RvsmError(f"engine must be fused or numpy, got {engine!r}")
    point = fit_point(scene, point)
    contract = point.contract()
    noise = point.noise_source()
    thresholds = point.integer_thresholds(noise)
    integrator = FixedIntegrator(
        thresholds, point.accumulator_bits, point.signed, point.reset,
        track=True, histogram=histograms,
    )
    weights = contract.weight_arrays
    s_count, (h, w), t_total = point.num_scales, point.shape, scene.num_steps
    require_spike_memory(scene, s_count, 3 if keep_codes else 1)
    spikes = np.zeros((t_total, s_count, h, w), dtype=np.int8)
    codes_out = np.zeros((t_total, h, w), dtype=np.uint16) if keep_codes else None
    big, small = np.iinfo(np.int64).max, np.iinfo(np.int64).min
    sum_min, sum_max = np.full(s_count, big), np.full(s_count, small)
    sh_min, sh_max = np.full(s_count, big), np.full(s_count, small)
    sum_hist = np.zeros((s_count, 64), dtype=np.int64) if histograms else None
    bar = progress_bar(t_total, f"fixed {point.model} {scene.name}", progress)
    for t0, t1, codes in code_blocks(scene, point, noise, block_steps):
        if codes_out is not None:
            codes_out[t0:t1] = codes
        sums = integer_receptive_sums(codes, weights)
        np.minimum(sum_min, sums.min(axis=(0, 2, 3)), out=sum_min)
        np.maximum(sum_max, sums.max(axis=(0, 2, 3)), out=sum_max)
        if sum_hist is not None:
            sum_hist += bit_length_histogram(sums)
        shifted = arithmetic_shift(sums, point.shift) if point.shift else sums
        np.minimum(sh_min, shifted.min(axis=(0, 2, 3)), out=sh_min)
        np.maximum(sh_max, shifted.max(axis=(0, 2, 3)), out=sh_max)
        for b in range(t1 - t0):
            spikes[t0 + b] = integrator.step(shifted[b])
        bar.update(t1 - t0)
    bar.close()
    stats = FixedStats(
        steps=t_total,
        accumulators=h * w,
        saturated=integrator.saturated.copy(),
        sum_min=sum_min, sum_max=sum_max,
        shifted_min=sh_min, shifted_max=sh_max,
        acc_min=integrator.acc_min.copy(), acc_max=integrator.acc_max.copy(),
        sum_hist=sum_hist, acc_hist=integrator.acc_hist,
    )
    meta = fixed_meta(scene, point, thresholds, stats)
    return FixedRun(spikes, thresholds, point, contract, stats, meta, codes_out)


def fixed_meta(
    scene: Scene, point: DesignPoint, thresholds: np.ndarray, stats: FixedStats
) -> dict:
    """Spike-file metadata: the float sampler's keys plus the design point and counters."""
    return {
        **sampling_meta(scene, point.sampler_config()),
        "kind": "fixed",
        "height": point.shape[0],
        "width": point.shape[1],
        "design_point": point.to_dict(),
        "nominal_thresholds": [int(v) for v in point.nominal_thresholds()],
        "threshold_min": int(thresholds.min()),
        "threshold_max": int(thresholds.max()),
        "saturated": [int(v) for v in stats.saturated],
    }
