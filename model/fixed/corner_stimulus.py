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

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from rvsm.model.fixed.contract import (
    ArrayContract,
    FixedEventIntegrator,
    FixedIntegrator,
    arithmetic_shift,
    integer_receptive_sums,
    make_integrator,
)
from rvsm.model.fixed.stimulus import Stimulus
from rvsm.model.fixed.widths import unsigned_max
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kinds.sensor_kind import Output

__all__ = ["BINS", "corner_stimulus", "coverage", "coverage_summary", "min_steps"]

#: Coverage bins, per scale: codes at 0 / full scale (the pixel's own code), an
#: accumulator exactly at +threshold / -threshold, pre-saturation value above the top /
#: below the bottom rail, +1 / -1 spikes, a clear mid-stream that drops a non-zero
#: accumulator.
BINS: tuple[str, ...] = ("code_zero", "code_full", "exact_threshold_pos",
                         "exact_threshold_neg", "rail_high", "rail_low", "spike_pos",
                         "spike_neg", "clear_mid_stream")

MIN_STEPS = 12
#: Missing bins a summary line names before it counts the rest.
MAX_LISTED = 10


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


def min_steps(contract: ArrayContract) -> int:
    """The fewest steps :func:`corner_stimulus` takes for ``contract``."""
    return max(MIN_STEPS, 2 * (len(_segment_images(contract, level=0)) + 1))


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
    need = min_steps(c)
    if isinstance(steps, bool) or int(steps) < need:
        raise RvsmError(f"a random/corner stimulus for this point needs --steps >= "
                        f"{need}, got {steps}")
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
    thresholds = c.storable_thresholds(thresholds.astype(np.int64), rng)
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
    (:func:`~.stimulus.open_stimulus`) is read a range of steps at a time. The event
    sensor's bins follow its rules (:func:`_event_bins`); each output rule's bins are
    its :class:`_Bins` in :data:`_BINS_OF`."""
    c = stim.contract
    rule = _BINS_OF[c.kind.output]
    full = unsigned_max(c.adc_bits)
    counts = np.zeros((c.num_scales, len(BINS)), dtype=np.int64)
    idx = {b: i for i, b in enumerate(BINS)}
    integ = make_integrator(c.kind, stim.thresholds, c.accumulator_bits, c.signed, c.reset)
    for t0, t1, clear in stim.step_ranges(COVERAGE_CHUNK_STEPS):
        codes = np.asarray(stim.codes[t0:t1], dtype=np.int64)
        sums = _shifted(c, codes)
        if clear:
            counts[:, idx["clear_mid_stream"]] += rule.dropped(integ)
            integ.clear()
        for b in range(t1 - t0):
            counts[:, idx["code_zero"]] += int((codes[b] == 0).sum())
            counts[:, idx["code_full"]] += int((codes[b] == full).sum())
            rule.step(integ, sums[b], counts, idx)
    return _reachable(c, counts)


def _spike_bins(integ: FixedIntegrator, sums: np.ndarray, counts: np.ndarray,
                idx: dict[str, int]) -> None:
    """One step of the spike camera's bins: rails and exact hits before the compare."""
    axes = (1, 2)
    pre = integ.acc + sums
    counts[:, idx["rail_high"]] += (pre > integ.hi).sum(axis=axes)
    counts[:, idx["rail_low"]] += (pre < integ.lo).sum(axis=axes)
    clipped = np.clip(pre, integ.lo, integ.hi)
    counts[:, idx["exact_threshold_pos"]] += (clipped == integ.thr).sum(axis=axes)
    counts[:, idx["exact_threshold_neg"]] += (clipped == -integ.thr).sum(axis=axes)
    spikes = integ.step(sums)
    counts[:, idx["spike_pos"]] += (spikes == 1).sum(axis=axes)
    counts[:, idx["spike_neg"]] += (spikes == -1).sum(axis=axes)


def _event_bins(integ: FixedEventIntegrator, sums: np.ndarray, counts: np.ndarray,
                idx: dict[str, int]) -> None:
    """One step of the event sensor's bins, by its rules (:class:`FixedEventIntegrator`):
    exact hits are ``d = sum - ref == +-thr``, the rails the references' (a capture or
    an update leaving the W-bit range), spikes the ON/OFF events (a mid-stream clear
    counts the captured non-zero references it drops, in :func:`coverage`)."""
    axes = (1, 2)
    thr = integ.thr
    if integ.captured:
        d = sums - integ.ref
        counts[:, idx["exact_threshold_pos"]] += (d == thr).sum(axis=axes)
        counts[:, idx["exact_threshold_neg"]] += (d == -thr).sum(axis=axes)
        up = (d >= thr).astype(np.int64)
        new = integ.ref + thr * (up - ((d <= -thr) & (up == 0)))
    else:
        new = sums
    counts[:, idx["rail_high"]] += (new > integ.hi).sum(axis=axes)
    counts[:, idx["rail_low"]] += (new < integ.lo).sum(axis=axes)
    events = integ.step(sums)
    counts[:, idx["spike_pos"]] += (events == 1).sum(axis=axes)
    counts[:, idx["spike_neg"]] += (events == -1).sum(axis=axes)


def _spike_dropped(integ: FixedIntegrator) -> np.ndarray:
    """Per scale, the non-zero accumulators a clear drops."""
    return (integ.acc != 0).sum(axis=(1, 2))


def _event_dropped(integ: FixedEventIntegrator) -> np.ndarray | int:
    """Per scale, the captured non-zero references a clear drops."""
    return (integ.ref != 0).sum(axis=(1, 2)) if integ.captured else 0


def _spike_reachable(c: ArrayContract, s_lo: int) -> dict[str, bool]:
    """The spike camera's bins a scale with least sum ``s_lo`` can reach (the others
    are)."""
    return {"rail_low": s_lo < 0, "exact_threshold_neg": c.signed and s_lo < 0,
            "spike_neg": c.signed and s_lo < 0}


def _event_reachable(c: ArrayContract, s_lo: int) -> dict[str, bool]:
    """The event sensor's: OFF events whenever the response falls; a reference goes
    below 0 only with negative sums."""
    return {"rail_low": s_lo < 0}


@dataclass(frozen=True)
class _Bins:
    """How one output rule fills the bins: what a clear drops, one step's bins, and
    which bins a scale can reach."""

    dropped: Callable
    step: Callable
    reachable: Callable[[ArrayContract, int], dict[str, bool]]


#: The bins of each output rule (:class:`~rvsm.model.kinds.sensor_kind.Output`).
_BINS_OF = {Output.SPIKES: _Bins(_spike_dropped, _spike_bins, _spike_reachable),
            Output.EVENTS: _Bins(_event_dropped, _event_bins, _event_reachable)}


def _reachable(c: ArrayContract, counts: np.ndarray) -> list[dict[str, int | None]]:
    """Per scale the bin counts, ``None`` for the bins the contract cannot reach."""
    out: list[dict[str, int | None]] = []
    reachable_of = _BINS_OF[c.kind.output].reachable
    for scale in range(c.num_scales):
        s_lo, _ = c.sum_range(scale)
        reachable = reachable_of(c, s_lo)
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
        shown = ", ".join(missing[:MAX_LISTED])
        more = f", and {len(missing) - MAX_LISTED} more" if len(missing) > MAX_LISTED else ""
        tail = f" (missing: {shown}{more})" if missing else ""
        lines.append(f"scale {scale}: {len(hit)}/{len(live)} bins hit{tail}")
    return lines
