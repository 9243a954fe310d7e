"""Seeded random and corner stimuli, and their coverage bins (against the twin)."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.model.fixed.contract import FixedIntegrator, arithmetic_shift, integer_receptive_sums
from rvsm.model.fixed.corner_stimulus import BINS, corner_stimulus, coverage, coverage_summary
from rvsm.model.infra.errors import RvsmError


def test_same_seed_same_stimulus_and_expectation_from_the_contract(small_contract) -> None:
    c = small_contract("dog4", 4, 5)
    a, b = corner_stimulus(c, 7, 90), corner_stimulus(c, 7, 90)
    assert np.array_equal(a.codes, b.codes) and np.array_equal(a.thresholds, b.thresholds)
    assert a.clear_before == b.clear_before and a.clear_before
    assert not np.array_equal(a.codes, corner_stimulus(c, 8, 90).codes)
    assert a.codes.shape == (90, 4, 5) and a.check()
    full = (1 << c.adc_bits) - 1
    assert a.codes.min() == 0 and a.codes.max() == full
    assert a.thresholds.min() >= 1 and a.thresholds.max() == (1 << c.threshold_bits) - 1


def test_coverage_counts_match_the_twin(small_contract) -> None:
    """Spike bins equal the expectation's spikes; rail bins the integrator's saturation."""
    c = small_contract("dog4", 5, 5)
    stim = corner_stimulus(c, 3, 120)
    cov = coverage(stim)
    assert len(cov) == c.num_scales and all(set(b) == set(BINS) for b in cov)
    for s, bins in enumerate(cov):
        assert bins["spike_pos"] == int((stim.spikes[:, s] == 1).sum())
        assert bins["spike_neg"] == int((stim.spikes[:, s] == -1).sum())
        assert bins["code_zero"] == int((stim.codes == 0).sum())
    # saturation: replay segment by segment, as ArrayContract.run does
    sums = arithmetic_shift(integer_receptive_sums(stim.codes.astype(np.int64),
                                                   c.weight_arrays), c.shift)
    bounds = [0, *stim.clear_before, stim.num_steps]
    saturated = np.zeros(c.num_scales, dtype=np.int64)
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        integ = FixedIntegrator(stim.thresholds, c.accumulator_bits, c.signed, c.reset)
        for t in range(a, b):
            integ.step(sums[t])
        saturated += integ.saturated
    got = [(bins["rail_high"] or 0) + (bins["rail_low"] or 0) for bins in cov]
    assert got == saturated.tolist()


def test_corners_are_reached_on_a_signed_array(small_contract) -> None:
    """dog1 on 6x6: every reachable bin of every scale is hit."""
    c = small_contract("dog1", 6, 6)
    cov = coverage(corner_stimulus(c, 1, 200))
    missing = [(s, b) for s, bins in enumerate(cov) for b, n in bins.items() if n == 0]
    assert missing == []
    assert all("9/9 bins hit" in line for line in coverage_summary(cov))


def test_unsigned_model_marks_the_negative_bins_unreachable(small_contract) -> None:
    c = small_contract("fsm", 4, 4, frac_bits=0, acc_bits=6, shift=0, reset="zero")
    cov = coverage(corner_stimulus(c, 2, 60))
    assert all(b["rail_low"] is None and b["spike_neg"] is None for b in cov)
    assert all(b["rail_high"] > 0 and b["exact_threshold_pos"] > 0 for b in cov)


def test_too_few_steps_is_one_clear_error(small_contract) -> None:
    with pytest.raises(RvsmError, match="--steps >="):
        corner_stimulus(small_contract("dog4", 3, 3), 1, 5)


def test_a_shared_threshold_point_gets_one_threshold_per_scale() -> None:
    """Regression plans draw random and corner stimuli for every point: an array with one
    threshold register per scale must get thresholds it can hold (the regression of the
    shipped ECP5-85 point refused 32 of 42 runs before)."""
    import dataclasses

    from rvsm.model.fixed.design_point import DesignPoint

    point = dataclasses.replace(DesignPoint(height=6, width=8, model="dog2"),
                                threshold_storage="shared")
    c = point.contract()
    for seed in range(4):
        stim = corner_stimulus(c, seed, 40)
        flat = stim.thresholds.reshape(c.num_scales, -1)
        assert (flat == flat[:, :1]).all()  # one value per scale
        assert np.array_equal(stim.spikes, c.run(stim.codes.astype(np.int64),
                                                 stim.thresholds, stim.clear_before))
    per_pixel = dataclasses.replace(point, threshold_storage="per-pixel").contract()
    thr = corner_stimulus(per_pixel, 0, 40).thresholds.reshape(per_pixel.num_scales, -1)
    assert (thr != thr[:, :1]).any()  # per pixel: as before, a pattern
