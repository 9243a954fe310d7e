"""What a fixed-twin run returns: spikes, thresholds, datapath statistics, metadata.

The run itself is :mod:`.twin`; the engines are :mod:`.numpy_engine` and :mod:`.fused`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.design_point import DesignPoint
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
    """Fixed-twin output: ``spikes (T, S, H, W) int8`` in {-1, 0, 1} (``None`` when a run
    streamed them into a sink).

    ``thresholds`` is ``(S, H, W) int64`` (accumulator LSBs); ``codes`` the ADC codes
    ``(T, H, W) uint16`` when kept; ``meta`` the spike file's metadata.
    """

    spikes: np.ndarray | None
    thresholds: np.ndarray
    point: DesignPoint
    contract: ArrayContract
    stats: FixedStats
    meta: dict = field(default_factory=dict)
    codes: np.ndarray | None = None


def fixed_meta(
    scene: Scene, point: DesignPoint, thresholds: np.ndarray, stats: FixedStats | None
) -> dict:
    """Spike-file metadata: the float sampler's keys plus the design point and counters
    (``stats`` None: before the run, zero saturation counts)."""
    saturated = stats.saturated if stats is not None else np.zeros(point.num_scales, int)
    return {
        **point.rules.float_meta(scene, point),  # read as the float model's files are
        "height": point.shape[0],
        "width": point.shape[1],
        "design_point": point.to_dict(),
        "nominal_thresholds": [int(v) for v in point.nominal_thresholds()],
        "threshold_min": int(thresholds.min()),
        "threshold_max": int(thresholds.max()),
        "saturated": [int(v) for v in saturated],
    }
