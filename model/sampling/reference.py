"""A literal transcription of the SPEC's equations: the test oracle and benchmark baseline.

Per step it builds ``I_t`` from the frames, adds the dark current, forms every
accumulator's receptive-field sum by explicit shifts of a zero-padded image, integrates,
compares and resets. It shares no code with the engines (:mod:`.numpy_engine`,
:mod:`.fused`) beyond the kernels, the noise draws and the scene, so agreement is evidence
that the fast paths are right.
It is slow on purpose; do not use it for real work.
"""

from __future__ import annotations

import numpy as np

from rvsm.model.noise.sensor import NoiseSource
from rvsm.model.sampling.config import SamplerConfig
from rvsm.model.scene.scene import Scene


def reference_sample(scene: Scene, config: SamplerConfig) -> np.ndarray:
    """Spikes ``(T, S, H, W) int8`` computed step by step straight from SPEC section 2."""
    spec = config.spec
    kernels = spec.kernels()
    h, w = scene.shape
    s_count = spec.num_scales
    phis = config.phis
    noise = NoiseSource(config.noise, (h, w), s_count) if config.noise else None
    if noise is None:
        thr = np.broadcast_to(phis[:, None, None], (s_count, h, w)).astype(np.float64)
    else:
        thr = noise.thresholds(phis)
    thr = np.maximum(thr, 0.0)
    acc = np.zeros((s_count, h, w))
    out = np.zeros((scene.num_steps, s_count, h, w), dtype=np.int8)
    m = scene.steps_per_frame
    for t in range(scene.num_steps):
        if scene.hold:
            image = scene.frame_range(t // m, t // m + 1)[0].copy()
        else:
            f, a = t // m, (t % m) / m
            pair = scene.frame_range(f, f + 1 if a == 0 else f + 2)
            image = pair[0].copy() if a == 0 else (1 - a) * pair[0] + a * pair[1]
        if noise is not None:
            image = image + noise.dark_current(1)[0]
        for s, kernel in enumerate(kernels):
            half = kernel.shape[0] // 2
            padded = np.zeros((h + 2 * half, w + 2 * half))
            padded[half:half + h, half:half + w] = image
            total = np.zeros((h, w))
            for di in range(-half, half + 1):
                for dj in range(-half, half + 1):
                    total += kernel[di + half, dj + half] * padded[
                        half + di:half + di + h, half + dj:half + dj + w
                    ]
            acc[s] += total
            pos = acc[s] >= thr[s]
            neg = (acc[s] <= -thr[s]) & ~pos if spec.signed else np.zeros_like(pos)
            out[t, s] = pos.astype(np.int8) - neg.astype(np.int8)
            if config.reset == "zero":
                acc[s][pos | neg] = 0.0
            else:
                acc[s] -= thr[s] * out[t, s]
    return out
