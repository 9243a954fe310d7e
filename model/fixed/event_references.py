"""What the fixed-point event sensor reports at its capture step, for decoding.

A decoder of fixed-point events (SPEC section 7) needs the integer references captured at
step 0 (``clamp(shifted sum)`` of the first step's log ADC codes) and the integer nominal
contrast thresholds, both converted to log-intensity units by the point's
``threshold_scale`` (``2**f * 2**frac_bits / 2**shift`` LSBs per log unit): then
``R_hat(t) = ref + C * (events up to t)`` is exactly the twin's reference in log units.
"""

from __future__ import annotations

import numpy as np

from rvsm.model.fixed.contract import arithmetic_shift, integer_receptive_sums
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.numpy_engine import step_codes
from rvsm.model.fixed.widths import signed_range
from rvsm.model.scene.scene import Scene

__all__ = ["fixed_event_references"]


def fixed_event_references(scene: Scene, point: DesignPoint) -> tuple[np.ndarray, np.ndarray]:
    """``(references (S, H, W), contrasts (S,))`` in log-intensity units of ``point``'s
    event sensor (``array.sensor = "dvs"``) on ``scene``."""
    codes = step_codes(scene, point, point.noise_source(), 0, 1)
    sums = arithmetic_shift(integer_receptive_sums(codes, point.contract().weight_arrays),
                            point.shift)[0]
    lo, hi = signed_range(point.accumulator_bits)
    scale = point.threshold_scale
    refs = np.clip(sums, lo, hi).astype(np.float64) / scale
    return refs, point.nominal_thresholds().astype(np.float64) / scale
