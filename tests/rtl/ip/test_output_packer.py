"""The IP's output packer (``rtl/ip/output_packer.py``, combinational) against its model:
every field of the FIFO word, and a beat meeting a full FIFO dropped."""

from __future__ import annotations

import numpy as np
from amaranth.lib.data import View

from rvsm.rtl.ip.output_packer import OutputPacker
from rvsm.rtl.stream.dimensions import StreamGeometry
from tests.conftest import model_contract


def test_output_packer_follows_its_model(amaranth_sim) -> None:
    c = model_contract("dog4", 4, 8)
    dut = OutputPacker(StreamGeometry(c, 2))
    rng = np.random.default_rng(9)
    sp = dut.spikes.payload
    cases = [{"row": int(rng.integers(0, c.height)), "group": int(rng.integers(0, 4)),
              "last": int(rng.integers(0, 2)), "pos": int(rng.integers(0, 256)),
              "neg": int(rng.integers(0, 256)), "valid": int(rng.integers(0, 2)),
              "ready": int(rng.integers(0, 2))} for _ in range(200)]
    word = View(dut.word, dut.beats.payload)

    async def bench(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        for x in cases:
            for name in ("row", "group", "last", "pos", "neg"):
                ctx.set(getattr(sp, name), x[name])
            ctx.set(dut.spikes.valid, x["valid"])
            ctx.set(dut.beats.ready, x["ready"])
            want = dut.model(x["row"], x["group"], x["last"], x["pos"], x["neg"])
            assert {k: ctx.get(getattr(word, k)) for k in want} == want
            assert ctx.get(dut.beats.valid) == x["valid"]
            assert ctx.get(dut.drop) == (x["valid"] and not x["ready"])
            await ctx.delay(1e-6)

    amaranth_sim.run(dut, bench)
    assert dut.model(0, 0, 0, 0, 0)["tuser"] == 1 and dut.model(1, 3, 0, 0, 0)["tlast"] == 1
