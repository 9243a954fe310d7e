"""Constant-weight shift-and-add sums are exact."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.rtl.amaranth_sim import run_simulation
from rvsm.rtl.receptive_sum import ReceptiveSum, csd_digits


@pytest.mark.parametrize("value", [0, 1, 3, 7, 11, 236, 1023, 4095, 12345])
def test_csd_digits_reconstruct(value: int) -> None:
    digits = csd_digits(value)
    assert sum(d << k for k, d in digits) == value
    shifts = [k for k, _ in digits]
    assert all(b - a >= 2 for a, b in zip(shifts, shifts[1:], strict=False))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_weighted_sum_exact(seed: int) -> None:
    rng = np.random.default_rng(seed)
    weights = [int(w) for w in rng.integers(-300, 300, 9)]
    weights[3] = weights[5]  # shared weights exercise grouping
    weights[4] = 0
    dut = ReceptiveSum(weights, 8)
    cases = [rng.integers(0, 256, 9) for _ in range(30)]
    cases += [np.zeros(9, int), np.full(9, 255)]

    async def bench(ctx) -> None:  # noqa: ANN001
        for x in cases:
            ctx.set(dut.inputs, sum(int(v) << (8 * i) for i, v in enumerate(x)))
            assert ctx.get(dut.sum) == int(np.dot(weights, x))

    run_simulation(dut, bench)
