"""Checks of in-memory spike arrays shared by every spike format."""

from __future__ import annotations

import numpy as np

from rvsm.model.infra.errors import RvsmError


def check_spikes(spikes: np.ndarray, source: str) -> np.ndarray:
    """``spikes`` as ``(T, S, H, W) int8``, refused unless 4-D integers in {-1, 0, 1};
    ``source`` names them in the error."""
    if spikes.ndim != 4:
        raise RvsmError(f"{source}: spikes must have shape (T, S, H, W), got {spikes.shape}")
    if not np.issubdtype(spikes.dtype, np.integer):
        raise RvsmError(f"{source}: spikes must be integers, got dtype {spikes.dtype}")
    if spikes.size and (spikes.min() < -1 or spikes.max() > 1):
        raise RvsmError(f"{source}: spikes must hold only -1, 0 and 1")
    return spikes.astype(np.int8, copy=False)


def single_scale_spikes(spikes: np.ndarray, purpose: str) -> np.ndarray:
    """``(T, H, W)`` or ``(T, 1, H, W)`` spikes -> ``(T, H, W)``; refuses several scales.

    ``purpose`` names what needs one bit per pixel, for the error message.
    """
    arr = np.asarray(spikes)
    if arr.ndim == 4:
        if arr.shape[1] != 1:
            raise RvsmError(
                f"{purpose} needs single-scale (FSM) spikes; these have {arr.shape[1]} scales"
            )
        arr = arr[:, 0]
    if arr.ndim != 3:
        raise RvsmError(
            f"{purpose} needs spikes (T, H, W) or (T, 1, H, W), got shape {arr.shape}"
        )
    return arr
