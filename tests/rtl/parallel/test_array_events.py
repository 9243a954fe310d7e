"""The fully parallel array in event-sensor mode against the fixed twin (amaranth.sim)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rvsm.rtl.architectures.registry import get_architecture


@pytest.mark.parametrize(("model", "acc_bits"), [("fsm", 6), ("dog2", 7), ("gauss2", 12),
                                                 ("dog4", 12)])
def test_parallel_event_mode(small_contract, model: str, acc_bits: int) -> None:
    c = dataclasses.replace(small_contract(model, 4, 5, acc_bits=acc_bits), sensor="dvs",
                            signed=True)
    rng = np.random.default_rng(2)
    codes = rng.integers(0, 16, (8, 4, 5))
    thr = rng.integers(1, 30, (c.num_scales, 4, 5))
    result = get_architecture("parallel").run(c, codes, thr, clear_before=(4,))
    assert result["mismatches"] == 0, result.get("first_mismatch")
    assert result["compared"] == 8 * c.num_scales * 20
    assert np.count_nonzero(c.run(codes, thr, (4,)))
