"""Kernel weight quantisation and its error report (SPEC section 5).

A float weight ``K`` becomes ``w = q(K * 2**frac_bits)``, a signed two's-complement
integer of ``bits`` bits (``-2**(bits-1) .. 2**(bits-1) - 1``); its value is
``w / 2**frac_bits``. ``q`` is ``"truncate"`` (floor: drop the low bits, so -0.3 LSB
becomes -1) or ``"round-half-up"`` (``floor(x + 0.5)``). ``K * 2**frac_bits`` is exact
in float64 (a power-of-two scale), so the rounding is the only error.
FSM's 1x1 kernel of 1.0 goes through the same path (it becomes ``2**frac_bits``).
"""

from __future__ import annotations

import numpy as np

from rvsm.model.fixed.adc import quantise
from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.widths import signed_range
from rvsm.model.kernels.receptive_fields import model_spec


def quantise_kernel(kernel: np.ndarray, frac_bits: int, rounding: str) -> np.ndarray:
    """``q(kernel * 2**frac_bits)`` as ``(2L+1, 2L+1) int64`` (no range check)."""
    return quantise(np.asarray(kernel, dtype=np.float64) * float(2**frac_bits), rounding)


def quantise_model(model: str, frac_bits: int, rounding: str) -> list[np.ndarray]:
    """Integer kernels of every scale of ``model``: ``S`` arrays ``(2L+1, 2L+1) int64``."""
    return [quantise_kernel(k, frac_bits, rounding) for k in model_spec(model).kernels()]


def model_contract(model: str, height: int, width: int, frac_bits: int = 6,
                   accumulator_bits: int = 10, shift: int = 1, reset: str = "subtract",
                   adc_bits: int = 4) -> ArrayContract:
    """A small contract straight from ``model``'s kernels quantised round-half-up to
    ``frac_bits`` (no design point): for tests, timing diagrams and examples."""
    kernels = quantise_model(model, frac_bits, "round-half-up")
    weights = tuple(tuple(tuple(int(v) for v in row) for row in k) for k in kernels)
    return ArrayContract(height, width, adc_bits, weights, shift, accumulator_bits,
                         model != "fsm", reset)


def weight_error_report(model: str, bits: int, frac_bits: int, rounding: str) -> list[dict]:
    """Per scale: the quantisation error of the weights.

    Each entry has ``scale`` (index), ``sigma`` (None for FSM), ``taps``, ``zero_taps``
    (non-zero float weights quantised to 0), ``int_min``/``int_max`` against
    ``range_min``/``range_max``, ``max_abs_error`` and ``rms_error`` (weight units) and
    in LSBs, and ``sum_float``/``sum_fixed``, ``abs_sum_float``/``abs_sum_fixed``.
    """
    spec = model_spec(model)
    lo, hi = signed_range(bits)
    lsb = 2.0 ** -frac_bits
    out = []
    for s, k in enumerate(spec.kernels()):
        w = quantise_kernel(k, frac_bits, rounding)
        err = w * lsb - k
        out.append({
            "scale": s,
            "sigma": spec.scales[s] if spec.scales else None,
            "taps": int(k.size),
            "zero_taps": int(np.count_nonzero((w == 0) & (k != 0))),
            "int_min": int(w.min()),
            "int_max": int(w.max()),
            "range_min": lo,
            "range_max": hi,
            "max_abs_error": float(np.abs(err).max()),
            "max_abs_error_lsb": float(np.abs(err).max() / lsb),
            "rms_error": float(np.sqrt(np.mean(err**2))),
            "sum_float": float(k.sum()),
            "sum_fixed": float(w.sum() * lsb),
            "abs_sum_float": float(np.abs(k).sum()),
            "abs_sum_fixed": float(np.abs(w).sum() * lsb),
        })
    return out
