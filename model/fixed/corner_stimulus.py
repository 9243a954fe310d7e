"""Seeded random and corner-case stimuli for the RTL, and their functional coverage.

:func:`corner_stimulus` builds, for any :class:`~.core.ArrayContract`, a stimulus whose
segments aim at the corners of the datapath: ADC codes at 0 and at full scale, a
checkerboard and its inverse (the largest positive and negative weighted sums of a
centre-surround kernel), a constant code whose sums equal some pixels' thresholds
exactly, and random codes; the array is cleared before every segment and at random
steps inside the random one. Thresholds mix the top of the range (so the accumulators
hit both saturation rails), exact-hit values and random ones.

:func:`coverage` measures, per scale, how many accumulator-steps of any stimulus fall in
each bin (:data:`BINS`), by replaying it through :class:`~.core.FixedIntegrator`, the
same integrator as the bit-exact model. A bin a contract cannot reach (the negative rail
of an unsigned model) is ``None``.
"""

from __future__ import annotations

import numpy as np

from rvsm.model.fixed.core import (
    ArrayContract,
    FixedIntegrator,
    arithmetic_shift,
    integer_receptive_sums,
)
from rvsm.model.fixed.stimulus import Stimulus
from rvsm.model.fixed.widths import signed_range, unsigned_max
from rvsm.model.infra.errors import RvsmError

__all__ = ["BINS", "corner_stimulus", "coverage", "coverage_summary"]

#: Coverage bins, per scale: codes at 0 / full scale (the pixel's own code), an
#: accumulator exactly at +threshold / -threshold, pre-saturation value above the top /
#: below the bottom rail, +1 / -1 spikes, a clear mid-stream that drops a non-zero
#: accumulator.
BINS: tuple[str, ...] = ("code_zero", "code_full", "exact_threshold_pos",
                         "exact_threshold_neg", "rail_high", "rail_low", "spike_pos",
                         "spike_neg", "clear_mid_stream")

MIN_STEPS = 12


#: Steps whose sums :func:`coverage` holds at once.
COVERAGE_CHUNK_STEPS = 32


def _shifted(contract: ArrayContract, codes: np.ndarray) -> np.ndarray:
    """Shifted weighted sums ``(T, S, H, W) int64`` of ``codes (T, H, W)``."""
    return arithmetic_shift(integer_receptive_sums(codes, contract.weight_arrays),
                            contract.shift)


def _negative_extreme(contract: ArrayContract, scale: int) -> np.ndarray:
    """Codes ``(H, W)`` giving the centre pixel its most negative sum at ``scale``: full
    scale under the kernel's negative weights, 0 elsewhere."""
    h, w = contract.height, contract.width
    k = contract.weight_arrays[scale]
    half = k.shape[0] // 2
    r0, c0 = h // 2, w // 2
    img = np.zeros((h, w), dtype=np.int64)
    for dy in range(-half, half + 1):
        for dx in range(-half, half + 1):
            r, c = r0 + dy, c0 + dx
            if 0 <= r < h and 0 <= c < w and k[half + dy, half + dx] < 0:
                img[r, c] = unsigned_max(contract.adc_bits)
    return img


def corner_stimulus(contract: ArrayContract, seed: int, steps: int) -> Stimulus:
    """A seeded ``steps``-step random and corner stimulus for ``contract`` (expected
    spikes from :meth:`ArrayContract.run`); same seed, same stimulus.

    Segments, each after a clear: codes 0, full scale, a checkerboard, its inverse, a
    checkerboard of a random level (thresholds of a third of the accumulators equal its
    sums: exact hits of +threshold and -threshold), per scale with negative weights the
    image giving the centre pixel its most negative sum, then random codes with two
    clears inside.
    """
    c = contract
    h, w, s = c.height, c.width, c.num_scales
    images = _segment_images(c, level=0)
    need = 2 * (len(images) + 1)
    if isinstance(steps, bool) or int(steps) < max(MIN_STEPS, need):
        raise RvsmError(f"a random/corner stimulus for this point needs --steps >= "
                        f"{max(MIN_STEPS, need)}, got {steps}")
    rng = np.random.default_rng(seed)
    full = unsigned_max(c.adc_bits)
    top = (1 << c.threshold_bits) - 1
    level = int(rng.integers(1, full + 1))
    images = _segment_images(c, level)
    n = steps // (len(images) + 1)
    parts = [np.broadcast_to(img, (n, h, w)) for img in images]
    parts.append(rng.integers(0, full + 1, (steps - len(images) * n, h, w)))
    codes = np.concatenate(parts).astype(np.int64)
    starts = [i * n for i in range(1, len(parts))]
    last = starts[-1]
    inside = rng.choice(np.arange(last + 1, steps), size=min(2, steps - last - 1),
                        replace=False)
    clears = tuple(sorted({int(t) for t in starts} | {int(t) for t in inside}))

    exact = np.clip(np.abs(_shifted(c, images[4][None])[0]), 1, top)
    kind = rng.integers(0, 3, (s, h, w))
    random_thr = rng.integers(1, max(2, top // 4) + 1, (s, h, w))
    thresholds = np.where(kind == 0, top, np.where(kind == 1, exact, random_thr))
    thresholds = thresholds.astype(np.int64)
    spikes = c.run(codes, thresholds, clears)
    meta = {"kind": "stimulus", "generator": "corner", "seed": int(seed), "steps": int(steps)}
    return Stimulus(codes.astype(np.uint16), thresholds, spikes, c, None, meta, clears)


def _segment_images(c: ArrayContract, level: int) -> list[np.ndarray]:
    """The constant images of :func:`corner_stimulus`'s corner segments, in order."""
    full = unsigned_max(c.adc_bits)
    yy, xx = np.indices((c.height, c.width))
    checker = ((yy + xx) % 2).astype(np.int64)
    images = [np.zeros_like(checker), np.full_like(checker, full), checker * full,
              (1 - checker) * full, checker * level]
    images += [_negative_extreme(c, scale) for scale in range(c.num_scales)
               if (c.weight_arrays[scale] < 0).any()]
    return images


def coverage(stim: Stimulus) -> list[dict[str, int | None]]:
    """Per scale, accumulator-steps of ``stim`` in each of :data:`BINS` (None: the
    contract cannot reach that bin). Runs chunk by chunk: a lazy stimulus
    (:func:`~.stimulus.open_stimulus`) is read a range of steps at a time."""
    c = stim.contract
    lo, hi = signed_range(c.accumulator_bits)
    full = unsigned_max(c.adc_bits)
    integ = FixedIntegrator(stim.thresholds, c.accumulator_bits, c.signed, c.reset)
    thr = integ.thr
    counts = np.zeros((c.num_scales, len(BINS)), dtype=np.int64)
    idx = {b: i for i, b in enumerate(BINS)}
    axes = (1, 2)
    for t0, t1, clear in stim.step_ranges(COVERAGE_CHUNK_STEPS):
        codes = np.asarray(stim.codes[t0:t1], dtype=np.int64)
        sums = _shifted(c, codes)
        if clear:
            counts[:, idx["clear_mid_stream"]] += (integ.acc != 0).sum(axis=axes)
            integ.acc[...] = 0
        for b in range(t1 - t0):
            counts[:, idx["code_zero"]] += int((codes[b] == 0).sum())
            counts[:, idx["code_full"]] += int((codes[b] == full).sum())
            pre = integ.acc + sums[b]
            counts[:, idx["rail_high"]] += (pre > hi).sum(axis=axes)
            counts[:, idx["rail_low"]] += (pre < lo).sum(axis=axes)
            clipped = np.clip(pre, lo, hi)
            counts[:, idx["exact_threshold_pos"]] += (clipped == thr).sum(axis=axes)
            counts[:, idx["exact_threshold_neg"]] += (clipped == -thr).sum(axis=axes)
            spikes = integ.step(sums[b])
            counts[:, idx["spike_pos"]] += (spikes == 1).sum(axis=axes)
            counts[:, idx["spike_neg"]] += (spikes == -1).sum(axis=axes)
    out: list[dict[str, int | None]] = []
    for scale in range(c.num_scales):
        s_lo, s_hi = c.sum_range(scale)
        reachable = {"rail_low": s_lo < 0, "exact_threshold_neg": c.signed and s_lo < 0,
                     "spike_neg": c.signed and s_lo < 0}
        out.append({b: (int(counts[scale, i]) if reachable.get(b, True) else None)
                    for i, b in enumerate(BINS)})
    return out


def coverage_summary(cov: list[dict[str, int | None]]) -> list[str]:
    """One line per scale: ``scale 0: 8/9 bins (missing: rail_low)``."""
    lines = []
    for scale, bins in enumerate(cov):
        live = {b: n for b, n in bins.items() if n is not None}
        hit = [b for b, n in live.items() if n > 0]
        missing = [b for b in live if b not in hit]
        tail = f" (missing: {', '.join(missing)})" if missing else ""
        lines.append(f"scale {scale}: {len(hit)}/{len(live)} bins hit{tail}")
    return lines
