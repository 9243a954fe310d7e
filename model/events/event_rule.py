"""The event rule of SPEC section 7 for one accumulator, inlined into the fused kernels.

:func:`event_step` compares a response with its reference and threshold and fires at
most one event: ON when ``R - ref >= C``, OFF when ``R - ref <= -C`` (and not ON), the
reference moving by exactly ``C`` toward the response. Branch-free (selects, not jumps),
so the loops that call it vectorise; the fused engine's row loop
(:mod:`.fused`) and the generated four-scale loop (:mod:`.ladder_kernels`) both call it,
and :mod:`.numpy_engine` does the same float operations on whole arrays.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["event_step", "event_step_at"]


@njit(inline="always", cache=True)
def event_step(resp, thr, ref, out, x):
    """Apply the rule to accumulator ``x``: response ``resp`` (a float), thresholds and
    references ``thr, ref (W,)`` (``ref[x]`` moves), events ``out (W,) int8``."""
    r = ref[x]
    d = resp - r
    c = thr[x]
    on = d >= c
    off = (d <= -c) & (not on)
    out[x] = np.int8(on) - np.int8(off)
    ref[x] = r + c if on else (r - c if off else r)


@njit(inline="always", cache=True)
def event_step_at(resp, thr, ref, out, s, y, x):
    """:func:`event_step` on accumulator ``(s, y, x)`` of whole arrays ``thr, ref
    (S, H, W)`` and ``out (S, H, W) int8`` (no row views: the generated ladder loops index
    their arguments directly)."""
    r = ref[s, y, x]
    d = resp - r
    c = thr[s, y, x]
    on = d >= c
    off = (d <= -c) & (not on)
    out[s, y, x] = np.int8(on) - np.int8(off)
    ref[s, y, x] = r + c if on else (r - c if off else r)
