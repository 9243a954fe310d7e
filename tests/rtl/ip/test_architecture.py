"""The IP as an Architecture value: Architecture.run with clears equals the twin."""

from __future__ import annotations

import numpy as np

from rvsm.rtl.ip.architecture import STREAM_AXIS
from tests.conftest import model_contract


def test_run_with_clears_matches_the_twin() -> None:
    c = model_contract("dog1", 4, 8)
    rng = np.random.default_rng(7)
    codes = rng.integers(0, 1 << c.adc_bits, (3, 4, 8))
    thr = rng.integers(1, 40, (c.num_scales, 4, 8))
    result = STREAM_AXIS.run(c, codes, thr, clear_before=(2,), lanes=2, fifo_depth=8)
    assert result["mismatches"] == 0 and result["compared"] == c.run(codes, thr).size
