"""The ADC: the one analogue -> digital boundary of the fixed twin (SPEC section 5).

``code = clip(q(b * (2**N - 1) / full_scale), 0, 2**N - 1)`` with ``b`` the analogue
brightness (8-bit units, dark current already added) and ``q`` the declared rounding:

- ``"truncate"``: ``floor(x)`` (what dropping the fraction bits of a two's-complement
  number does; for the non-negative ADC input it is plain truncation);
- ``"round-half-up"``: ``floor(x + 0.5)`` (ties go up: 2.5 -> 3, -2.5 -> -2).

Clipping: ``"saturate"`` (default) pins out-of-range inputs to code 0 / ``2**N - 1``;
``"error"`` refuses any input outside ``[0, full_scale]`` instead.

The event sensor (SPEC section 7) has a log ADC instead (:func:`log_adc_codes`):
``code = clip(q(ln(max(I, 0) + 1) * 2**f), 0, 2**N - 1)`` with the declared fraction bits
``f``, the same rounding ``q`` and clipping (``"error"`` refuses an input whose log code
exceeds ``2**N - 1``); the log is the float model's (:mod:`rvsm.model.events.log_intensity`).

The input is analogue, so this stage alone works on float64; everything after it is
exact integer arithmetic.
"""

from __future__ import annotations

import numpy as np

from rvsm.model.events.log_intensity import log_intensity
from rvsm.model.fixed.widths import unsigned_max
from rvsm.model.infra.errors import RvsmError

ROUNDINGS = ("truncate", "round-half-up")
ADC_CLIPS = ("saturate", "error")


def quantise(values: np.ndarray, rounding: str) -> np.ndarray:
    """Round float ``values`` to integers (``int64``) with a declared rounding rule."""
    x = np.asarray(values, dtype=np.float64)
    if not np.isfinite(x).all():
        raise RvsmError("analogue values to quantise are NaN or infinite; check the noise "
                        "intensity and the scene")
    if rounding == "truncate":
        out = np.floor(x)
    elif rounding == "round-half-up":
        out = np.floor(x + 0.5)
    else:
        raise RvsmError(f"rounding must be one of {ROUNDINGS}, got {rounding!r}")
    return out.astype(np.int64)


def adc_gain(bits: int, full_scale: float) -> float:
    """Codes per brightness unit: ``(2**bits - 1) / full_scale``."""
    return unsigned_max(bits) / float(full_scale)


def adc_codes(
    brightness: np.ndarray,
    bits: int,
    full_scale: float,
    rounding: str = "round-half-up",
    clip: str = "saturate",
) -> np.ndarray:
    """ADC codes ``(B, H, W) int64`` in ``0 .. 2**bits - 1`` for analogue ``brightness``.

    ``brightness`` is ``(B, H, W)`` float in 8-bit units; see the module docstring for
    the rounding and clipping rules.
    """
    b = np.asarray(brightness, dtype=np.float64)
    top = unsigned_max(bits)
    if clip == "error":
        lo, hi = float(b.min(initial=0.0)), float(b.max(initial=0.0))
        if lo < 0 or hi > full_scale:
            raise RvsmError(
                f"adc.clip = 'error': analogue input {lo:g}..{hi:g} leaves the ADC range "
                f"0..{full_scale:g}; raise adc.full_scale or use adc.clip = 'saturate'"
            )
    elif clip != "saturate":
        raise RvsmError(f"adc.clip must be one of {ADC_CLIPS}, got {clip!r}")
    codes = quantise(b * adc_gain(bits, full_scale), rounding)
    np.clip(codes, 0, top, out=codes)
    return codes


def log_adc_codes(
    brightness: np.ndarray,
    bits: int,
    frac_bits: int,
    rounding: str = "round-half-up",
    clip: str = "saturate",
) -> np.ndarray:
    """Log ADC codes ``(B, H, W) int64`` in ``0 .. 2**bits - 1`` of analogue
    ``brightness (B, H, W)`` (8-bit units): the module docstring's event-sensor rule."""
    x = log_intensity(brightness) * float(2 ** int(frac_bits))
    top = unsigned_max(bits)
    if clip == "error":
        hi = float(x.max(initial=0.0))
        if hi > top:
            raise RvsmError(
                f"adc.clip = 'error': ln(I + 1) * 2**{frac_bits} reaches {hi:g}, beyond the "
                f"{bits}-bit code {top}; raise adc.bits, lower adc.log_frac_bits or use "
                "adc.clip = 'saturate'")
    elif clip != "saturate":
        raise RvsmError(f"adc.clip must be one of {ADC_CLIPS}, got {clip!r}")
    codes = quantise(x, rounding)
    np.clip(codes, 0, top, out=codes)
    return codes
