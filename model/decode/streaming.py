"""Streaming evaluation: reconstruct and score a spike file chunk by chunk (SPEC section 4).

Same definitions, same numbers as :func:`rvsm.model.decode.evaluation.evaluate_spikes` on the
whole array, with memory bounded by one chunk plus ``O(T / chunk_steps)`` boundary images:

- TFI needs, at step ``t``, the first spike *after* ``t``, possibly chunks ahead, and the
  recording's last two spikes. A backward pre-pass over the file stores, per chunk, each
  pixel's first spike at or after the chunk's end (``(num_chunks, H, W) int32``) and the
  last two spikes of the recording; the forward pass then fills ``last`` and ``next``
  within each chunk from those carries (look-ahead across chunk borders).
- The RVSM coefficients are causal: their ``(S, H, W)`` state is carried from chunk to
  chunk. The least-squares inverse (``method="inverse"``) decodes the scored steps in
  order with warm starts, so it gathers their coefficients ``(N, S, H, W)`` first.
- TFP reads each scored step's window straight from the file.

Scores are computed per scored step (brightness matching and metrics are per frame) and
averaged over all of them at the end, exactly as the whole-array path does.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from skimage.metrics import structural_similarity

from rvsm.model.decode.evaluation import scored_steps, warmup_steps
from rvsm.model.decode.metrics import DATA_RANGE, frame_mse
from rvsm.model.decode.reconstruction import (
    DEFAULT_TFP_WINDOW,
    match_brightness,
    resolve_method,
    rvsm_image,
)
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.receptive_fields import ModelSpec, model_spec
from rvsm.model.scene.scene import Scene
from rvsm.model.spikes.source import SpikeSource

DEFAULT_EVAL_CHUNK = 256


def _tfi_prepass(source: SpikeSource, chunk_steps: int):
    """Backward pass: ``(next_after (C, H, W) int32, final (H, W), before_final (H, W))``.

    ``next_after[c]`` is each pixel's first spike at or after the end of chunk ``c`` (``T``
    if none); ``final`` / ``before_final`` its last and second-to-last spike (-1 if none).
    """
    n, _, h, w = source.shape
    starts = list(range(0, n, chunk_steps))
    next_after = np.empty((len(starts), h, w), dtype=np.int32)
    nxt = np.full((h, w), n, dtype=np.int32)
    final = np.full((h, w), -1, dtype=np.int32)
    before = np.full((h, w), -1, dtype=np.int32)
    for c in range(len(starts) - 1, -1, -1):
        t0 = starts[c]
        t1 = min(t0 + chunk_steps, n)
        next_after[c] = nxt
        mask = source.read(t0, t1)[:, 0] != 0
        t = np.arange(t0, t1, dtype=np.int32).reshape(-1, 1, 1)
        idx = np.where(mask, t, np.int32(-1))
        last_in = idx.max(axis=0)
        second_in = np.where(idx < last_in[None], idx, np.int32(-1)).max(axis=0)
        first_in = np.where(mask, t, np.int32(n)).min(axis=0)
        has = last_in >= 0
        nxt = np.where(has, first_in, nxt)
        unset = final < 0
        final_new = np.where(unset, last_in, final)
        before = np.where(unset, second_in, np.where(before < 0, last_in, before))
        final = final_new
    return next_after, final, before


def _tfi_chunks(source: SpikeSource, phi: float, steps: np.ndarray, chunk_steps: int):
    """Yield ``(positions, images (N, H, W) float64)`` of TFI at the scored ``steps``."""
    n = source.num_steps
    next_after, final, before_final = _tfi_prepass(source, chunk_steps)
    final_isi = (final - before_final).astype(np.float64)
    spiked = final >= 0
    last_carry = np.full(final.shape, -1, dtype=np.int32)
    for c, t0 in enumerate(range(0, n, chunk_steps)):
        t1 = min(t0 + chunk_steps, n)
        mask = source.read(t0, t1)[:, 0] != 0
        t = np.arange(t0, t1, dtype=np.int32).reshape(-1, 1, 1)
        last = np.where(mask, t, np.int32(-1))
        last[0] = np.maximum(last[0], last_carry)
        np.maximum.accumulate(last, axis=0, out=last)
        last_carry = last[-1].copy()
        sel = np.flatnonzero((steps >= t0) & (steps < t1))
        if sel.size == 0:
            continue
        first_ge = np.where(mask, t, np.int32(n))
        np.minimum(first_ge[-1], next_after[c], out=first_ge[-1])
        rev = first_ge[::-1]
        np.minimum.accumulate(rev, axis=0, out=rev)
        nxt = np.empty_like(first_ge)
        nxt[:-1] = first_ge[1:]
        nxt[-1] = next_after[c]
        local = steps[sel] - t0
        lst = last[local]
        nx = nxt[local]
        isi = np.where(nx < n, (nx - lst).astype(np.float64), final_isi[None])
        out = np.zeros(isi.shape, dtype=np.float64)
        np.divide(float(phi), isi, out=out, where=spiked[None] & (isi > 0))
        yield sel, out


def _rvsm_chunks(source: SpikeSource, spec: ModelSpec, phis, steps: np.ndarray,
                 chunk_steps: int, images: bool = True):
    """Yield ``(positions, images)`` of the RVSM adjoint at the scored ``steps`` (or
    ``(positions, coefficients)`` with ``images=False``)."""
    n, s_count = source.shape[:2]
    phi = np.broadcast_to(np.asarray(phis, dtype=np.float64).reshape(-1), (s_count,))
    phi = phi[:, None, None]
    k = np.zeros(source.shape[1:], dtype=np.float64)
    t_prev = np.full(source.shape[1:], -1.0)
    last_needed = int(steps.max())
    for t0 in range(0, min(n, last_needed + 1), chunk_steps):
        t1 = min(t0 + chunk_steps, n, last_needed + 1)
        arr = source.read(t0, t1)
        sel = np.flatnonzero((steps >= t0) & (steps < t1))
        coeffs = np.empty((sel.size,) + source.shape[1:], dtype=np.float64)
        for t in range(t0, t1):
            st = arr[t - t0]
            fired = st != 0
            if fired.any():
                np.copyto(k, st * phi / (t - t_prev), where=fired)
                t_prev[fired] = t
            coeffs[steps[sel] == t] = k
        if sel.size:
            yield sel, (rvsm_image(coeffs, spec) if images else coeffs)


def _inverse_all(source: SpikeSource, spec: ModelSpec, phis, steps: np.ndarray,
                 chunk_steps: int):
    """The least-squares inverse decodes the scored steps in order, each warm-started from
    the previous one, so it runs once on all of them: their coefficients ``(N, S, H, W)``
    are gathered (streaming) and decoded together."""
    from rvsm.model.decode.inverse import inverse_images

    coeffs = np.empty((steps.size,) + source.shape[1:], dtype=np.float64)
    for sel, part in _rvsm_chunks(source, spec, phis, steps, chunk_steps, images=False):
        coeffs[sel] = part
    yield np.arange(steps.size), inverse_images(coeffs, spec)


def _tfp_chunks(source: SpikeSource, phi: float, steps: np.ndarray, window: int,
                batch: int = 16):
    n = source.num_steps
    for i in range(0, steps.size, batch):
        sel = np.arange(i, min(i + batch, steps.size))
        images = np.empty((sel.size,) + source.shape[2:], dtype=np.float64)
        for j, pos in enumerate(sel):
            lo = int(np.clip(steps[pos] - window // 2, 0, n))
            hi = int(np.clip(lo + window, 0, n))
            counts = np.count_nonzero(source.read(lo, hi)[:, 0], axis=0).astype(np.float64)
            images[j] = counts * float(phi) / float(hi - lo)
        yield sel, images


def evaluate_source(
    source: SpikeSource,
    scene: Scene,
    model: str | ModelSpec,
    phis: Sequence[float] | np.ndarray | float,
    method: str = "auto",
    match: str = "gain",
    steps: Sequence[int] | np.ndarray | None = None,
    chunk_steps: int = DEFAULT_EVAL_CHUNK,
) -> dict:
    """Score a spike file (or any :class:`SpikeSource`) against ``scene``, streaming.

    Same arguments and result as :func:`rvsm.model.decode.evaluation.evaluate_spikes`.
    """
    spec = model if isinstance(model, ModelSpec) else model_spec(model)
    n, s_count, h, w = source.shape
    if s_count != spec.num_scales:
        raise RvsmError(f"spikes of shape {source.shape} do not fit model {spec.name} "
                        f"(expected (T, {spec.num_scales}, H, W))")
    if n != scene.num_steps or (h, w) != scene.shape:
        raise RvsmError(f"spikes {source.shape} do not match scene {scene.name!r} "
                        f"({scene.num_steps} steps of {scene.shape[0]}x{scene.shape[1]})")
    if int(chunk_steps) < 1:
        raise RvsmError(f"chunk_steps must be >= 1, got {chunk_steps}")
    how = resolve_method(method, spec)
    warm = warmup_steps(scene, phis)
    chosen = scored_steps(scene, phis) if steps is None else np.atleast_1d(
        np.asarray(steps, dtype=np.int64))
    if chosen.size == 0 or chosen.min() < 0 or chosen.max() >= n:
        raise RvsmError(f"steps must lie in 0..{n - 1}")
    phi_arr = np.atleast_1d(np.asarray(phis, dtype=np.float64))
    if how == "tfi":
        parts = _tfi_chunks(source, float(phi_arr[0]), chosen, int(chunk_steps))
    elif how == "tfp":
        parts = _tfp_chunks(source, float(phi_arr[0]), chosen, DEFAULT_TFP_WINDOW)
    elif how == "inverse":
        parts = _inverse_all(source, spec, phi_arr, chosen, int(chunk_steps))
    else:
        parts = _rvsm_chunks(source, spec, phi_arr, chosen, int(chunk_steps))
    mse = np.empty(chosen.size)
    ssim = np.empty(chosen.size)
    for sel, raw in parts:
        truth = np.stack([scene.brightness(int(t), int(t) + 1)[0] for t in chosen[sel]])
        recon = np.clip(match_brightness(raw, truth, match), 0.0, DATA_RANGE)
        mse[sel] = frame_mse(recon, truth)
        ssim[sel] = [structural_similarity(truth[i], recon[i], data_range=DATA_RANGE)
                     for i in range(len(sel))]
    with np.errstate(divide="ignore"):
        psnr = 10.0 * np.log10(DATA_RANGE**2 / mse)
    return {
        "mse": float(mse.mean()),
        "psnr": float(psnr.mean()),
        "ssim": float(np.mean(ssim)),
        "num_scored": int(chosen.size),
        "warmup": int(warm),
        "method": how,
    }
