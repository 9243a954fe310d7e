"""The position pipeline (``rtl/stream/position_stage.py``) against its numpy model in
``amaranth.sim``: random centre positions, stalls and clears; every tap, the read address
one edge ahead and the write-back's valid one edge ahead."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.position_stage import PositionStage
from tests.conftest import model_contract

FIELDS = ("valid", "addr", "row", "group", "last", "fresh")


@pytest.mark.parametrize(("model", "frac_bits", "lanes", "bank_words"), [
    ("dog4", 6, 2, 8),   # read at stage Q - 3 > 0, three banks
    ("fsm", 6, 2, 1024),  # radius 0: the read at stage 0, the centre's own address
])
def test_taps_follow_the_model(amaranth_sim, model: str, frac_bits: int, lanes: int,
                               bank_words: int) -> None:
    c = model_contract(model, 6, 8, frac_bits=frac_bits)
    geo = StreamGeometry(c, lanes, bank_words)
    dut = PositionStage(geo)
    rng = np.random.default_rng(2)
    cycles, words = 400, geo.beats_per_frame
    clear = rng.random(cycles) < 0.03
    advance = ~clear & (rng.random(cycles) < 0.75)
    addr = rng.integers(0, words, cycles + 1)
    centre = {"valid": rng.random(cycles + 1) < 0.8, "addr": addr,
              "row": addr // geo.groups, "group": addr % geo.groups,
              "last": addr == words - 1, "fresh": rng.random(cycles + 1) < 0.3}
    want = dut.model(advance, clear, {k: v.astype(np.int64) for k, v in centre.items()})
    bank_bits = (bank_words - 1).bit_length()
    read, write = dut.read, dut.write
    counts = {"read": 0, "write": 0}

    async def bench(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        ahead = None  # (read addr if advancing, if not; write valid next) of the last cycle
        bank_line = [-1, -1]  # read addresses of the last two advance edges
        for t in range(cycles):
            for k in FIELDS:
                ctx.set(getattr(dut.centre, k), int(centre[k][t]))
            ctx.set(dut.centre_next_addr, int(addr[t + 1]))
            ctx.set(dut.ctl.advance, int(advance[t]))
            ctx.set(dut.ctl.clear, int(clear[t]))
            got = {"read_addr": ctx.get(read.addr), "read_valid": ctx.get(read.valid),
                   "fresh": ctx.get(dut.fresh), "fresh_ahead": ctx.get(dut.fresh_ahead),
                   **{f"write_{k}": ctx.get(getattr(write, k))
                      for k in ("addr", "row", "group", "last", "valid")}}
            for name, value in got.items():
                if want[name][t] >= 0:
                    assert value == want[name][t], (t, name)
            assert ctx.get(write.en) == int(advance[t]) & got["write_valid"]
            if ahead is not None:
                assert got["read_addr"] == ahead[0] and got["write_valid"] == ahead[1], t
            if bank_line[0] >= 0:
                assert ctx.get(read.bank) == bank_line[0] >> bank_bits, t
            ahead = ((ctx.get(read.addr_next_adv) if advance[t] else
                      ctx.get(read.addr_next_hold)), ctx.get(write.valid_next))
            if advance[t]:
                bank_line = [bank_line[1], got["read_addr"]]
            counts["read"] += got["read_valid"]
            counts["write"] += int(advance[t]) & got["write_valid"]
            await ctx.tick()

    amaranth_sim.run(dut, bench)
    assert counts["read"] > 100 and counts["write"] > 100
