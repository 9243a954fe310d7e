"""Images from spikes (SPEC section 4, paper section 3.2): TFI / TFP for FSM, RVSM decoding.

Conventions shared by every method here:

- Steps are 0-based indices ``t = 0..T-1`` into the spike array; a spike at ``t`` was
  decided from the accumulation that includes step ``t``.
- Every accumulator starts at 0 before step 0, exactly as after a reset, so the start of
  the recording acts as a *virtual spike at t = -1*: the first real spike at ``t1`` closes
  an interval of ``t1 + 1`` steps. TFI and the RVSM coefficients both use this.
- Brightness estimates are in the units of the threshold ``phi`` per step, i.e. 8-bit
  brightness for FSM. RVSM images are coefficient-domain sums and only meaningful after
  :func:`match_brightness`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.filtering import adjoint_sums
from rvsm.model.kernels.receptive_fields import ModelSpec, model_spec
from rvsm.model.spikes.arrays import single_scale_spikes

METHODS = ("auto", "tfi", "tfp", "rvsm", "inverse")
MATCH_MODES = ("gain", "affine")
DEFAULT_TFP_WINDOW = 32
_EPS = 1e-12


# --------------------------------------------------------------------------- helpers


def _as_steps(steps: Sequence[int] | np.ndarray | None, num_steps: int) -> np.ndarray:
    """Validate requested step indices: ``(N,) int64`` in ``0..T-1`` (all steps if None)."""
    if steps is None:
        return np.arange(num_steps, dtype=np.int64)
    arr = np.atleast_1d(np.asarray(steps, dtype=np.int64))
    if arr.ndim != 1 or arr.size == 0:
        raise RvsmError("steps must be a non-empty 1-D list of step indices")
    if arr.min() < 0 or arr.max() >= num_steps:
        raise RvsmError(f"steps must lie in 0..{num_steps - 1}, got {arr.min()}..{arr.max()}")
    return arr


def _single_scale(spikes: np.ndarray) -> np.ndarray:
    """``(T, H, W)`` or ``(T, 1, H, W)`` spikes -> ``(T, H, W)`` (TFI/TFP are FSM-only)."""
    return single_scale_spikes(spikes, "TFI/TFP (use method='rvsm' for RVSM spikes)")


def last_spike_index(spikes: np.ndarray) -> np.ndarray:
    """Index of the most recent spike at or before each step, ``-1`` where none yet.

    ``spikes`` is ``(T, ...)`` (any non-zero value is a spike); returns the same shape,
    ``int32``. Vectorised forward fill with ``np.maximum.accumulate`` along axis 0.
    """
    mask = np.asarray(spikes) != 0
    t = np.arange(mask.shape[0], dtype=np.int32).reshape((-1,) + (1,) * (mask.ndim - 1))
    idx = np.where(mask, t, np.int32(-1))
    np.maximum.accumulate(idx, axis=0, out=idx)
    return idx


def next_spike_index(spikes: np.ndarray) -> np.ndarray:
    """Index of the first spike strictly after each step, ``T`` where there is none.

    ``spikes`` is ``(T, ...)``; returns the same shape, ``int32``. Vectorised backward fill
    (``np.minimum.accumulate`` on the reversed time axis), then shifted by one step.
    """
    mask = np.asarray(spikes) != 0
    n = mask.shape[0]
    t = np.arange(n, dtype=np.int32).reshape((-1,) + (1,) * (mask.ndim - 1))
    first_ge = np.where(mask, t, np.int32(n))
    rev = first_ge[::-1]
    np.minimum.accumulate(rev, axis=0, out=rev)
    out = np.empty_like(first_ge)
    out[:-1] = first_ge[1:]
    out[-1] = n
    return out


# --------------------------------------------------------------------------- FSM


def tfi(
    spikes: np.ndarray, phi: float, steps: Sequence[int] | np.ndarray | None = None
) -> np.ndarray:
    """Texture From Interval (SpikeCV): brightness ``phi / ISI`` at the requested steps.

    ``spikes`` is ``(T, H, W)`` or ``(T, 1, H, W)``; returns ``(N, H, W) float64`` in the
    units of ``phi`` per step. At step ``t``, ``ISI = next - last`` with ``last`` the most
    recent spike at or before ``t`` and ``next`` the first spike after ``t``. Edges:

    - before the first spike, ``last`` is the virtual spike at ``-1`` (accumulators start
      at 0, as after a reset), so the ISI is the exact first interval ``t1 + 1``;
    - after the last spike (no ``next``), the last closed interval is reused
      (``t_last - t_before_last``, again with the virtual start);
    - a pixel that never spiked gets 0 (its true brightness is below ``phi / T``).
    """
    arr = _single_scale(spikes)
    n = arr.shape[0]
    idx = _as_steps(steps, n)
    last_all = last_spike_index(arr)
    nxt = next_spike_index(arr)[idx]
    last = last_all[idx]
    final = last_all[-1]  # (H, W): last spike of the recording, -1 if none
    before_final = np.where(
        final >= 1,
        np.take_along_axis(last_all, np.maximum(final - 1, 0)[None], axis=0)[0],
        -1,
    )
    final_isi = (final - before_final).astype(np.float64)  # >= 1 where final >= 0
    isi = np.where(nxt < n, (nxt - last).astype(np.float64), final_isi[None])
    spiked = (final >= 0)[None]
    out = np.zeros(isi.shape, dtype=np.float64)
    np.divide(float(phi), isi, out=out, where=spiked & (isi > 0))
    return out


def tfp(
    spikes: np.ndarray,
    phi: float,
    steps: Sequence[int] | np.ndarray | None = None,
    window: int = DEFAULT_TFP_WINDOW,
) -> np.ndarray:
    """Texture From Playback: ``count * phi / window`` over a window centred on each step.

    The window is ``[t - window // 2, t - window // 2 + window)`` clipped to the recording;
    the divisor is the clipped length. Returns ``(N, H, W) float64``.
    """
    arr = _single_scale(spikes)
    n = arr.shape[0]
    if isinstance(window, bool) or int(window) < 1:
        raise RvsmError(f"TFP window must be an integer >= 1, got {window!r}")
    window = int(window)
    idx = _as_steps(steps, n)
    csum = np.zeros((n + 1,) + arr.shape[1:], dtype=np.int32)
    np.cumsum(arr != 0, axis=0, dtype=np.int32, out=csum[1:])
    lo = np.clip(idx - window // 2, 0, n)
    hi = np.clip(lo + window, 0, n)
    counts = (csum[hi] - csum[lo]).astype(np.float64)
    return counts * float(phi) / (hi - lo).astype(np.float64)[:, None, None]


# --------------------------------------------------------------------------- RVSM


def rvsm_coefficients(
    spikes: np.ndarray, phis: Sequence[float] | np.ndarray, steps: Sequence[int] | None = None
) -> np.ndarray:
    """Paper eq. 10: per-accumulator coefficient ``K`` at the requested steps.

    ``spikes`` is ``(T, S, H, W)`` in {-1, 0, 1}; ``phis`` the nominal threshold per scale
    ``(S,)``. At a spike at step ``t``: ``K = spike * phi_s / (t - t_prev)``, ``t_prev``
    that accumulator's previous spike (the virtual spike ``-1`` for the first, i.e. the
    interval is ``t + 1``); otherwise ``K`` is held; ``K = 0`` before the first spike.
    Returns ``(N, S, H, W) float64``. Streams over steps (state is ``(S, H, W)``).
    """
    arr = np.asarray(spikes)
    if arr.ndim != 4:
        raise RvsmError(f"spikes must be (T, S, H, W), got shape {arr.shape}")
    n, s_count = arr.shape[:2]
    phi = np.broadcast_to(np.asarray(phis, dtype=np.float64).reshape(-1), (s_count,))
    phi = phi[:, None, None]
    idx = _as_steps(steps, n)
    order = np.argsort(idx, kind="stable")
    out = np.empty((idx.size,) + arr.shape[1:], dtype=np.float64)
    k = np.zeros(arr.shape[1:], dtype=np.float64)
    t_prev = np.full(arr.shape[1:], -1.0)
    pos = 0
    for t in range(int(idx.max()) + 1):
        st = arr[t]
        fired = st != 0
        if fired.any():
            np.copyto(k, st * phi / (t - t_prev), where=fired)
            t_prev[fired] = t
        while pos < idx.size and idx[order[pos]] == t:
            out[order[pos]] = k
            pos += 1
    return out


def _spec(model: str | ModelSpec) -> ModelSpec:
    return model if isinstance(model, ModelSpec) else model_spec(model)


def rvsm_image(coeffs: np.ndarray, model: str | ModelSpec) -> np.ndarray:
    """Paper eq. 11: ``sum_{s, y0, x0} K_s(y0, x0) * kernel_s`` placed at ``(y0, x0)``.

    ``coeffs`` is ``(N, S, H, W)``; returns ``(N, H, W) float64`` (the adjoint of the
    sampling filters, :func:`rvsm.model.kernels.filtering.adjoint_sums`).
    """
    kernels = _spec(model).kernels()
    c = np.asarray(coeffs, dtype=np.float64)
    if c.ndim != 4 or c.shape[1] != len(kernels):
        raise RvsmError(
            f"coefficients must be (N, {len(kernels)}, H, W) for this model, got {c.shape}"
        )
    return adjoint_sums(c, kernels)


def resolve_method(method: str, model: str | ModelSpec) -> str:
    """``auto`` -> ``tfi`` for FSM, ``rvsm`` otherwise; validates the name. ``rvsm`` is the
    paper's adjoint (eq. 11), ``inverse`` the least-squares inverse (:mod:`.inverse`)."""
    if method not in METHODS:
        raise RvsmError(f"unknown reconstruction method {method!r}; choose one of {METHODS}")
    spec = _spec(model)
    if method == "auto":
        return "tfi" if spec.family == "fsm" else "rvsm"
    if method in ("tfi", "tfp") and spec.num_scales != 1:
        raise RvsmError(f"{method} works on FSM spikes only; use rvsm for {spec.name}")
    return method


def reconstruct(
    spikes: np.ndarray,
    model: str | ModelSpec,
    phis: Sequence[float] | np.ndarray | float,
    steps: Sequence[int] | np.ndarray | None = None,
    method: str = "auto",
) -> np.ndarray:
    """Raw (unmatched) reconstruction ``(N, H, W) float64`` at ``steps`` (all if None).

    ``spikes`` is ``(T, S, H, W)`` (or ``(T, H, W)`` for FSM); ``phis`` the nominal
    threshold(s). ``method``: ``auto`` (TFI for FSM, RVSM adjoint otherwise), ``tfi``,
    ``tfp``, ``rvsm`` (the paper's eq. 11, the adjoint of the filters) or ``inverse`` (the
    regularised least-squares inverse of the filters,
    :func:`rvsm.model.decode.inverse.inverse_images`,
    steps decoded in the order given, each warm-started from the previous one).
    """
    spec = _spec(model)
    how = resolve_method(method, spec)
    arr = np.asarray(spikes)
    phi_arr = np.atleast_1d(np.asarray(phis, dtype=np.float64))
    if how == "tfi":
        return tfi(arr, float(phi_arr[0]), steps)
    if how == "tfp":
        return tfp(arr, float(phi_arr[0]), steps)
    if arr.ndim == 3:
        arr = arr[:, None]
    coeffs = rvsm_coefficients(arr, phi_arr, steps)
    if how == "inverse":
        from rvsm.model.decode.inverse import inverse_images

        return inverse_images(coeffs, spec)
    return rvsm_image(coeffs, spec)


def match_brightness(recon: np.ndarray, truth: np.ndarray, mode: str = "gain") -> np.ndarray:
    """Bring a reconstruction to the ground truth's brightness level, frame by frame.

    ``recon`` and ``truth`` are ``(N, H, W)``; returns ``(N, H, W) float64``.

    - ``gain``: ``g * recon`` with ``g = mean(truth) / mean(recon)`` so the means match;
      where ``|mean(recon)|`` is ~0 (e.g. an all-zero image) ``g = 1`` (left unchanged).
    - ``affine``: least-squares ``a * recon + b`` per frame; where ``recon`` is constant
      (zero variance) ``a = 0, b = mean(truth)`` (the best constant image).
    """
    if mode not in MATCH_MODES:
        raise RvsmError(f"unknown brightness match {mode!r}; choose one of {MATCH_MODES}")
    r = np.asarray(recon, dtype=np.float64)
    g = np.asarray(truth, dtype=np.float64)
    if r.shape != g.shape or r.ndim != 3:
        raise RvsmError(f"recon {r.shape} and truth {g.shape} must both be (N, H, W)")
    rm = r.mean(axis=(1, 2))
    gm = g.mean(axis=(1, 2))
    if mode == "gain":
        ok = np.abs(rm) > _EPS
        gain = np.ones_like(rm)
        gain[ok] = gm[ok] / rm[ok]
        return r * gain[:, None, None]
    rc = r - rm[:, None, None]
    var = (rc * rc).mean(axis=(1, 2))
    cov = (rc * (g - gm[:, None, None])).mean(axis=(1, 2))
    ok = var > _EPS * np.maximum(1.0, rm * rm)
    a = np.zeros_like(rm)
    a[ok] = cov[ok] / var[ok]
    b = gm - a * rm
    return r * a[:, None, None] + b[:, None, None]
