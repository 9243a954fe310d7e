"""The input register (``rtl/stream/input_stage.py``) against its numpy model, random
valid and clear sequences in ``amaranth.sim``."""

from __future__ import annotations

import numpy as np

from rvsm.rtl.stream.input_stage import InputStage


def test_input_stage_follows_its_model(amaranth_sim) -> None:
    dut = InputStage(adc_bits=4, lanes=3)
    rng = np.random.default_rng(1)
    cycles = 300
    valid = rng.random(cycles) < 0.7
    clear = rng.random(cycles) < 0.1
    payload = rng.integers(0, 1 << 12, cycles)
    want = InputStage.model(valid, clear)
    seen = {"advance": 0, "clear": 0}

    async def bench(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        beat = 0
        for t in range(cycles):
            ctx.set(dut.codes.valid, int(valid[t]))
            ctx.set(dut.codes.payload.as_value(), int(payload[t]))
            ctx.set(dut.clear, int(clear[t]))
            assert ctx.get(dut.codes.ready) == int(not clear[t])
            assert ctx.get(dut.ctl.advance_next) == int(want["advance"][t])
            await ctx.tick()
            assert ctx.get(dut.ctl.advance) == int(want["advance"][t])
            assert ctx.get(dut.ctl.clear) == int(want["clear"][t])
            if want["loaded"][t]:
                beat = int(payload[t])
            assert ctx.get(dut.beat) == beat  # held between accepted beats
            seen["advance"] += int(want["advance"][t])
            seen["clear"] += int(want["clear"][t])

    amaranth_sim.run(dut, bench)
    assert seen["advance"] > 100 and seen["clear"] > 10


def test_a_stall_advances_only_in_the_mutation(amaranth_sim) -> None:
    """``stream.advance_during_stall``: a stalled cycle advances the pipeline (the model
    of the shipped stage says it must not)."""
    dut = InputStage(4, 2, mutation="stream.advance_during_stall")

    async def bench(ctx) -> None:  # noqa: ANN001
        ctx.set(dut.codes.valid, 0)
        await ctx.tick()
        assert ctx.get(dut.ctl.advance) == 1
        assert not InputStage.model(np.array([False]), np.array([False]))["advance"][0]

    amaranth_sim.run(dut, bench)
