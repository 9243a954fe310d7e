"""Receptive-field filtering with zero padding (SPEC section 2) and its adjoint.

``receptive_field_sums(stack, kernels)[b, s, y, x] = sum_{di,dj} K_s[di, dj] *
stack[b, y + di, x + dj]``, pixels outside the array counting 0 and the kernel not
renormalised at the border.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy import ndimage


def receptive_field_sums(stack: np.ndarray, kernels: Sequence[np.ndarray]) -> np.ndarray:
    """Weighted receptive-field sums of every image in ``stack``.

    ``stack`` is ``(B, H, W)``; ``kernels`` ``S`` odd square arrays; returns
    ``(B, S, H, W) float64``. A ``1x1`` kernel of 1.0 (FSM) returns the stack unchanged.
    """
    stack = np.asarray(stack, dtype=np.float64)
    out = np.empty((stack.shape[0], len(kernels)) + stack.shape[1:], dtype=np.float64)
    for s, kernel in enumerate(kernels):
        if kernel.shape == (1, 1):
            np.multiply(stack, kernel[0, 0], out=out[:, s])
        else:
            ndimage.correlate(stack, kernel[None], output=out[:, s], mode="constant", cval=0.0)
    return out


def adjoint_sums(coefficients: np.ndarray, kernels: Sequence[np.ndarray]) -> np.ndarray:
    """Adjoint of :func:`receptive_field_sums` summed over scales: place each kernel.

    ``coefficients`` is ``(S, H, W)`` (or ``(B, S, H, W)``); returns ``(H, W)`` (or
    ``(B, H, W)``) ``float64`` = ``sum_{s, y0, x0} c[s, y0, x0] * K_s`` centred at
    ``(y0, x0)``, clipped to the array.
    """
    c = np.asarray(coefficients, dtype=np.float64)
    batched = c.ndim == 4
    if not batched:
        c = c[None]
    out = np.zeros((c.shape[0],) + c.shape[2:], dtype=np.float64)
    for s, kernel in enumerate(kernels):
        flipped = kernel[::-1, ::-1]
        out += ndimage.correlate(c[:, s], flipped[None], mode="constant", cval=0.0)
    return out if batched else out[0]
