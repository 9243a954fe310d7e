"""amaranth.sim tests of small arrays against :meth:`ArrayContract.run`."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.model.kernels.receptive_fields import MODEL_NAMES
from rvsm.rtl.parallel.array import RvsmArray
from rvsm.rtl.parallel.drive import simulate
from rvsm.rtl.parallel.pixel_cell import PixelCell


def test_valid_rises_latency_cycles_after_the_strobe(small_contract, amaranth_sim) -> None:
    """Measured, not read off the constant: cycles from a strobe edge to ``valid``."""
    dut = RvsmArray(small_contract("dog1", 2, 3))
    seen: list[int] = []

    async def bench(ctx) -> None:  # noqa: ANN001
        ctx.set(dut.strobe, 1)
        await ctx.tick()
        ctx.set(dut.strobe, 0)
        for cycle in range(1, 6):
            if ctx.get(dut.valid):
                seen.append(cycle)
            await ctx.tick()

    amaranth_sim.run(dut, bench)
    assert seen == [RvsmArray.LATENCY] == [PixelCell.LATENCY]


@pytest.mark.parametrize("model", MODEL_NAMES)
def test_every_model_matches_contract(model: str, small_contract, amaranth_sim) -> None:
    c = small_contract(model, 3, 5, acc_bits=12)
    rng = np.random.default_rng(3)
    codes = rng.integers(0, 16, (25, 3, 5))
    thr = rng.integers(1, 200, (c.num_scales, 3, 5))
    want = c.run(codes, thr)
    assert np.array_equal(simulate(c, codes, thr, vcd_path=amaranth_sim.vcd_path()), want)


@pytest.mark.parametrize("reset", ["zero", "subtract"])
def test_extremes_saturation_and_clear(reset: str, small_contract, amaranth_sim) -> None:
    c = small_contract("dog2", 4, 4, acc_bits=8, shift=0, reset=reset)
    rng = np.random.default_rng(5)
    codes = np.concatenate([np.zeros((4, 4, 4), int), np.full((6, 4, 4), 15),
                            rng.integers(0, 16, (10, 4, 4))])
    thr = np.full((c.num_scales, 4, 4), 127)  # top rail: reached only when saturated
    thr[0, 1:3, 1:3] = rng.integers(1, 127, (2, 2))
    clears = (7, 13)
    want = np.concatenate([c.run(codes[a:b], thr) for a, b in ((0, 7), (7, 13), (13, 20))])
    got = simulate(c, codes, thr, clear_before=clears, vcd_path=amaranth_sim.vcd_path())
    assert np.array_equal(got, want)
    assert (want == -1).any() and (want == 1).any()


def _shared(c, thresholds):  # noqa: ANN001, ANN202 - a contract
    import dataclasses

    return dataclasses.replace(c, shared_thresholds=thresholds)


def test_shared_thresholds_by_scale(small_contract, amaranth_sim) -> None:
    """threshold.storage = "shared": one register per scale (cfg_addr = s), reset to the
    nominal thresholds: spikes right with no load, and with a load by scale."""
    c = _shared(small_contract("dog2", 3, 4, acc_bits=12), (30, 80))
    assert RvsmArray.interface(c).members["cfg"].signature.addr_bits == 1
    rng = np.random.default_rng(9)
    codes = rng.integers(0, 16, (12, 3, 4))
    loaded = np.broadcast_to(np.array([50, 9])[:, None, None], (2, 3, 4))
    assert RvsmArray.threshold_writes(c, loaded) == [(0, 50), (1, 9)]
    assert np.array_equal(simulate(c, codes, loaded), c.run(codes, loaded))
    dut = RvsmArray(c)
    got = []

    async def bench(ctx) -> None:  # noqa: ANN001
        for t in range(len(codes)):
            flat = sum(int(v) << (4 * k) for k, v in enumerate(codes[t].ravel()))
            ctx.set(dut.codes, flat)
            ctx.set(dut.strobe, 1)
            await ctx.tick()
            ctx.set(dut.strobe, 0)
            pos, neg = ctx.get(dut.spike_pos), ctx.get(dut.spike_neg)
            got.append([((pos >> a) & 1) - ((neg >> a) & 1) for a in range(24)])

    amaranth_sim.run(dut, bench)
    nominal = np.broadcast_to(np.array([30, 80])[:, None, None], (2, 3, 4))
    want = c.run(codes, nominal)
    assert np.array_equal(np.array(got).reshape(want.shape), want) and np.abs(want).sum()
