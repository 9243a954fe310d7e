"""BorderCoverage: per lane and border band, against a per-accumulator loop."""

from __future__ import annotations

import numpy as np

from rvsm.model.kernels.geometry import kernel_radius
from rvsm.rtl.stream.coverage import SIDES, BorderCoverage


def test_border_bins_match_a_slow_count(small_contract) -> None:
    """Counts fed in chunks equal a loop over every accumulator; unreachable bins (lanes
    with no column in a side band) are None; an unsigned model has no spike_neg."""
    c = small_contract("dog2", 7, 12)
    lanes = 4
    rng = np.random.default_rng(8)
    spikes = rng.choice([-1, 0, 0, 1], (9, c.num_scales, 7, 12)).astype(np.int8)
    cov = BorderCoverage(c, lanes)
    for part in np.split(spikes, [2, 3, 7]):
        cov.update(part)
    bins = cov.bins()
    r = kernel_radius(c.weight_arrays)
    want = {(s, side, i): 0 for s in range(c.num_scales) for side in SIDES
            for i in range(lanes)}
    reach = set()
    for y in range(7):
        for x in range(12):
            sides = [n for n, inside in (("top", y < r), ("bottom", y >= 7 - r),
                                         ("left", x < r), ("right", x >= 12 - r)) if inside]
            for side in sides:
                reach.add((side, x % lanes))
                for s in range(c.num_scales):
                    want[(s, side, x % lanes)] += int(np.count_nonzero(spikes[:, s, y, x]))
    for s in range(c.num_scales):
        assert bins[s]["spike_pos"] == int((spikes[:, s] == 1).sum())
        assert bins[s]["spike_neg"] == int((spikes[:, s] == -1).sum())
        for side in SIDES:
            for i in range(lanes):
                got = bins[s][f"{side}_lane{i}"]
                assert got == (want[(s, side, i)] if (side, i) in reach else None)
    assert any(bins[0][f"left_lane{i}"] is None for i in range(lanes))  # r < lanes
    fsm = small_contract("fsm", 4, 4)
    assert BorderCoverage(fsm, 2).bins()[0]["spike_neg"] is None
    gauss = small_contract("gauss2", 4, 4)  # non-negative weights: no -1 spike
    assert all(b["spike_neg"] is None for b in BorderCoverage(gauss, 2).bins())
