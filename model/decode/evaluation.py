"""Score spikes against a scene's ground truth (SPEC section 4): the shared evaluation API.

Pipeline: choose scored steps (after a warm-up, on original frames) -> reconstruct
(:mod:`reconstruction`) -> match brightness per frame -> clip to [0, 255] -> MSE / PSNR /
SSIM averaged over the scored steps (:mod:`metrics`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from rvsm.model.decode.metrics import DATA_RANGE, image_metrics
from rvsm.model.decode.reconstruction import match_brightness, reconstruct, resolve_method
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.receptive_fields import ModelSpec, model_spec
from rvsm.model.scene.scene import Scene

WARMUP_PERCENTILE = 5.0


def _num_steps(scene_or_truth: Scene | np.ndarray) -> int:
    if isinstance(scene_or_truth, Scene):
        return scene_or_truth.num_steps
    return int(np.asarray(scene_or_truth).shape[0])


def warmup_steps(scene_or_truth: Scene | np.ndarray, phi: float | Sequence[float]) -> int:
    """Steps to skip before scoring, so that (nearly) every pixel has spiked twice.

    With ``b = max(5th percentile of the first frame's brightness, 1)`` (8-bit units) a
    pixel at ``b`` needs ``ceil(phi / b)`` steps per spike; the warm-up is twice that,
    capped at ``T // 2``. ``scene_or_truth`` is a :class:`Scene` or a per-step truth stack
    ``(T, H, W)``; ``phi`` the (largest) nominal threshold.
    """
    phi_max = float(np.max(np.atleast_1d(np.asarray(phi, dtype=np.float64))))
    if isinstance(scene_or_truth, Scene):
        first = scene_or_truth.frame_range(0, 1)[0]
    else:
        first = np.asarray(scene_or_truth, dtype=np.float64)[0]
    b = max(float(np.percentile(first, WARMUP_PERCENTILE)), 1.0)
    return int(min(2 * math.ceil(phi_max / b), _num_steps(scene_or_truth) // 2))


def scored_steps(
    scene: Scene, phi: float | Sequence[float], stride: int | None = None
) -> np.ndarray:
    """Step indices scored: multiples of ``stride`` at or after the warm-up, ``(N,) int64``.

    ``stride`` defaults to ``scene.steps_per_frame`` (the steps that fall on original
    frames, whose ground truth is an undistorted frame). Never empty: if the warm-up
    swallows every candidate, the last step ``T - 1`` is scored.
    """
    stride = scene.steps_per_frame if stride is None else int(stride)
    if stride < 1:
        raise RvsmError(f"stride must be >= 1, got {stride}")
    start = warmup_steps(scene, phi)
    steps = np.arange(0, scene.num_steps, stride, dtype=np.int64)
    steps = steps[steps >= start]
    return steps if steps.size else np.array([scene.num_steps - 1], dtype=np.int64)


def _prepare(spikes, scene: Scene, model):
    spec = model if isinstance(model, ModelSpec) else model_spec(model)
    arr = np.asarray(getattr(spikes, "spikes", spikes))
    if arr.ndim == 3:
        arr = arr[:, None]
    if arr.ndim != 4 or arr.shape[1] != spec.num_scales:
        raise RvsmError(
            f"spikes of shape {arr.shape} do not fit model {spec.name} "
            f"(expected (T, {spec.num_scales}, H, W))"
        )
    if arr.shape[0] != scene.num_steps or arr.shape[2:] != scene.shape:
        raise RvsmError(
            f"spikes {arr.shape} do not match scene {scene.name!r} "
            f"({scene.num_steps} steps of {scene.shape[0]}x{scene.shape[1]})"
        )
    return arr, spec


def reconstruct_for_display(
    spikes,
    scene: Scene,
    model: str | ModelSpec,
    phis: Sequence[float] | np.ndarray | float,
    steps: Sequence[int] | np.ndarray,
    method: str = "auto",
    match: str = "gain",
) -> tuple[np.ndarray, np.ndarray]:
    """``(truth, recon)``, each ``(N, H, W) float64`` at ``steps``; ``recon`` is
    brightness-matched and clipped to [0, 255], ready to show or score."""
    arr, spec = _prepare(spikes, scene, model)
    steps = np.atleast_1d(np.asarray(steps, dtype=np.int64))
    truth = np.stack([scene.brightness(int(t), int(t) + 1)[0] for t in steps])
    raw = reconstruct(arr, spec, phis, steps, method)
    recon = np.clip(match_brightness(raw, truth, match), 0.0, DATA_RANGE)
    return truth, recon


def evaluate_spikes(
    spikes,
    scene: Scene,
    model: str | ModelSpec,
    phis: Sequence[float] | np.ndarray | float,
    method: str = "auto",
    match: str = "gain",
    steps: Sequence[int] | np.ndarray | None = None,
) -> dict:
    """Score spikes ``(T, S, H, W)`` (or a ``SpikeTrain``) against ``scene``.

    ``phis`` are the nominal per-scale thresholds (``config.phis``); ``steps`` defaults to
    :func:`scored_steps`. Returns ``{"mse", "psnr", "ssim", "num_scored", "warmup",
    "method"}`` (method resolved, e.g. ``tfi``; ``warmup`` in steps).
    """
    arr, spec = _prepare(spikes, scene, model)
    how = resolve_method(method, spec)
    warm = warmup_steps(scene, phis)
    chosen = scored_steps(scene, phis) if steps is None else np.asarray(steps, dtype=np.int64)
    truth, recon = reconstruct_for_display(arr, scene, spec, phis, chosen, how, match)
    scores = image_metrics(recon, truth)
    return {
        "mse": scores["mse"],
        "psnr": scores["psnr"],
        "ssim": scores["ssim"],
        "num_scored": int(np.size(chosen)),
        "warmup": int(warm),
        "method": how,
    }
