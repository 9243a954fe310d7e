"""Image-quality metrics (SPEC section 4) and the robustness indices (paper eqs. 12-14).

Image metrics take ``(N, H, W)`` stacks in 8-bit units, score frame by frame and average
over frames. The reconstruction is clipped to ``[0, 255]`` before scoring (a displayable
image; the ground truth is already in range). PSNR of an exact frame (MSE 0) is ``inf``
and the average is then ``inf`` too; callers that tabulate it print ``inf``.
"""

from __future__ import annotations

import numpy as np
from skimage.metrics import structural_similarity

from rvsm.model.infra.errors import RvsmError

DATA_RANGE = 255.0


def _pair(recon: np.ndarray, truth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r = np.asarray(recon, dtype=np.float64)
    g = np.asarray(truth, dtype=np.float64)
    if r.ndim == 2 and g.ndim == 2:
        r, g = r[None], g[None]
    if r.shape != g.shape or r.ndim != 3:
        raise RvsmError(f"recon {r.shape} and truth {g.shape} must both be (N, H, W)")
    return np.clip(r, 0.0, DATA_RANGE), g


def frame_mse(recon: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Per-frame mean squared error ``(N,)`` (recon clipped to [0, 255])."""
    r, g = _pair(recon, truth)
    return ((r - g) ** 2).mean(axis=(1, 2))


def mse(recon: np.ndarray, truth: np.ndarray) -> float:
    """Mean over frames of the per-frame MSE, in squared 8-bit units."""
    return float(frame_mse(recon, truth).mean())


def psnr(recon: np.ndarray, truth: np.ndarray) -> float:
    """Mean over frames of ``10 log10(255^2 / MSE)`` in dB; ``inf`` if any frame is exact."""
    m = frame_mse(recon, truth)
    with np.errstate(divide="ignore"):
        values = 10.0 * np.log10(DATA_RANGE**2 / m)
    return float(values.mean())


def ssim(recon: np.ndarray, truth: np.ndarray) -> float:
    """Mean over frames of scikit-image's SSIM (``data_range=255``, default 7x7 window)."""
    r, g = _pair(recon, truth)
    if min(r.shape[1:]) < 7:
        raise RvsmError(f"SSIM needs images of at least 7x7 pixels, got {r.shape[1:]}")
    return float(
        np.mean([structural_similarity(g[i], r[i], data_range=DATA_RANGE) for i in range(len(r))])
    )


def image_metrics(recon: np.ndarray, truth: np.ndarray) -> dict[str, float]:
    """``{"mse", "psnr", "ssim"}`` of a ``(N, H, W)`` reconstruction against the truth."""
    return {"mse": mse(recon, truth), "psnr": psnr(recon, truth), "ssim": ssim(recon, truth)}


def robustness_indices(spikes: np.ndarray) -> dict:
    """Robustness indices of a spike array ``(T, S, H, W)`` (SPEC section 4, paper 4.3).

    - ``ass`` = I1 = ``sum |S| / T`` (spikes per step, all accumulators);
    - ``asas`` = I2 = ``I1 / (H W S)`` (spikes per step per accumulator);
    - ``asass`` = I3 per scale = ``sum_t,y,x |S_s| / T / (H W)`` (list of S floats).

    I3 follows the SPEC (per step and per pixel), not the paper's eq. 14, which omits the
    ``1/T`` and, for FSM, equals I1; with the SPEC's form FSM's I3 equals its I2.
    """
    arr = np.asarray(spikes)
    if arr.ndim == 3:
        arr = arr[:, None]
    if arr.ndim != 4:
        raise RvsmError(f"spikes must be (T, S, H, W), got shape {arr.shape}")
    t, s, h, w = arr.shape
    per_scale = np.count_nonzero(arr, axis=(0, 2, 3)).astype(np.float64)
    i1 = float(per_scale.sum() / t)
    return {
        "ass": i1,
        "asas": i1 / (h * w * s),
        "asass": [float(v / t / (h * w)) for v in per_scale],
    }
