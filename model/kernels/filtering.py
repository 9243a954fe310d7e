"""Receptive-field filtering with zero padding (SPEC section 2) and its adjoint.

``receptive_field_sums(stack, kernels)[b, s, y, x] = sum_{di,dj} K_s[di, dj] *
stack[b, y + di, x + dj]``, pixels outside the array counting 0 and the kernel not
renormalised at the border.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy import ndimage

# Templates this wide and wider are filtered as separable rank-one terms (measured faster
# for 7x7 and 9x9 at 250x400; direct 2-D correlation wins for 3x3 and 5x5).
SEPARABLE_FROM = 7
_RANK_ONE_CACHE: dict[tuple, list[tuple[np.ndarray, np.ndarray]]] = {}


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
        elif kernel.shape[0] >= SEPARABLE_FROM:
            _separable_correlate(stack, kernel, out[:, s])
        else:
            ndimage.correlate(stack, kernel[None], output=out[:, s], mode="constant", cval=0.0)
    return out


def _rank_one_terms(kernel: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Column/row factor pairs whose outer products sum to ``kernel`` (to ~1e-16).

    DoG kernels are rank 2 and Gauss kernels rank 1 (separable Gaussians); singular values
    below 1e-12 of the largest are dropped.
    """
    key = (kernel.shape, kernel.tobytes())
    if key not in _RANK_ONE_CACHE:
        u, sv, vt = np.linalg.svd(kernel)
        keep = sv > sv[0] * 1e-12
        _RANK_ONE_CACHE[key] = [(u[:, r] * sv[r], vt[r]) for r in np.flatnonzero(keep)]
    return _RANK_ONE_CACHE[key]


def _separable_correlate(stack: np.ndarray, kernel: np.ndarray, out: np.ndarray) -> None:
    """Zero-padded 2-D correlation of ``(B, H, W)`` as a sum of two 1-D passes per rank-one
    term: cheaper than a direct 2-D correlation for templates of 7x7 and up."""
    out[...] = 0.0
    for col, row in _rank_one_terms(kernel):
        tmp = ndimage.correlate1d(stack, col, axis=1, mode="constant", cval=0.0)
        out += ndimage.correlate1d(tmp, row, axis=2, mode="constant", cval=0.0)


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
