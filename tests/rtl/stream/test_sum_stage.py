"""The receptive sums (``rtl/stream/sum_stage.py``) against their numpy model in
``amaranth.sim``: random windows and stalls; the sums of the window presented at an
advance edge come out ``delay`` advance edges later, exact in every lane and scale."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.model.fixed.contract import integer_receptive_sums
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.sum_stage import SumStage
from rvsm.rtl.stream.window_stage import WindowStage
from tests.conftest import model_contract


@pytest.mark.parametrize(("model", "lanes"), [("dog4", 2), ("dog2", 3), ("gauss3", 1),
                                              ("fsm", 2)])
def test_sums_follow_the_model(amaranth_sim, model: str, lanes: int) -> None:
    c = model_contract(model, 6, 6, frac_bits=6)
    geo = StreamGeometry(c, lanes)
    dut = SumStage(geo)
    n, cells, scales = c.adc_bits, len(geo.window_cells()), c.num_scales
    rng = np.random.default_rng(lanes)
    windows = rng.integers(0, 1 << n, (200, cells))
    windows[:20] = (1 << n) - 1  # the sums' extremes too
    windows[20:40] = 0
    want = SumStage.model(geo, windows)
    bits = [geo.sum_bits(s) for s in range(scales)]
    compared = []

    async def bench(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        k = 0  # windows taken at advance edges
        while k < len(windows):
            advance = rng.random() < 0.7
            word = sum(int(v) << (j * n) for j, v in enumerate(windows[k]))
            ctx.set(dut.window.as_value(), word)
            ctx.set(dut.ctl.advance, int(advance))
            await ctx.tick()
            k += advance
            if k >= dut.delay and advance:
                source = k - dut.delay + 1  # 1-based: delay registers, the last at edge k
                for i in range(lanes):
                    for s in range(scales):
                        got = ctx.get(dut.sums[i][f"s{s}"])
                        assert got == int(want[source - 1, i, s]) % (1 << bits[s]), \
                            (source, i, s)
                compared.append(source)

    amaranth_sim.run(dut, bench)
    assert len(compared) > 150


def test_the_model_is_the_contract_s_receptive_sum() -> None:
    """The sums of a frame's windows (:meth:`WindowStage.model`) are the contract's integer
    receptive sums of that frame (zero padding), pixel by pixel."""
    c = model_contract("dog4", 5, 6, frac_bits=6)
    geo = StreamGeometry(c, 3)
    frame = np.random.default_rng(0).integers(0, 1 << c.adc_bits, (5, 6))
    sums = SumStage.model(geo, WindowStage.model(geo, frame))  # (H*G, P, S)
    want = integer_receptive_sums(frame[None], c.weight_arrays)[0]  # (S, H, W)
    got = sums.reshape(5, geo.groups, 3, c.num_scales).transpose(3, 0, 1, 2).reshape(
        c.num_scales, 5, 6)
    np.testing.assert_array_equal(got, want)
