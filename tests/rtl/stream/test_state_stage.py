"""The state memories (``rtl/stream/state_stage.py``) against their numpy model in
``amaranth.sim``: random reads, write-backs and threshold writes (many meeting the read
of their word), stalls; banks of 8 words. Every threshold word delivered equals the
model's (the registered write and its forwarding included), and every accumulator word
the model defines."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.memory_target import GENERIC_MEMORY
from rvsm.rtl.stream.state_stage import StateModel, StateStage
from tests.conftest import model_contract


def _lanes(word: int, bits: int, lanes: int) -> list[int]:
    return [(word >> (i * bits)) & ((1 << bits) - 1) for i in range(lanes)]


def _pack(values, bits: int) -> int:  # noqa: ANN001 - a sequence of ints
    return sum(int(v) << (i * bits) for i, v in enumerate(values))


def _run(amaranth_sim, geo: StateStage, mutation: str | None = None,
         cycles: int = 600) -> dict[str, int]:
    """Drive a :class:`StateStage`; assert every defined word against
    :class:`StateModel`; return the counts compared."""
    dut = StateStage(geo, GENERIC_MEMORY, mutation)
    model = StateModel(geo)
    c = geo.contract
    p, wa, tw, scales = geo.lanes, c.accumulator_bits, c.threshold_bits, c.num_scales
    words = geo.beats_per_frame
    bank_bits = (geo.bank_words - 1).bit_length()
    rng = np.random.default_rng(5)
    counts = {"thr": 0, "acc": 0, "forwarded": 0}

    async def bench(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        raddr, bank_line = 0, [0, 0]
        for _ in range(cycles):
            advance = bool(rng.random() < 0.75)
            nxt = int(rng.integers(0, words))
            wvalid = bool(rng.random() < 0.5)
            waddr = int(rng.integers(0, words))
            wdata = rng.integers(0, 1 << wa, (scales, p))
            bus = None
            if rng.random() < 0.4:  # a threshold write, often at the word read next
                word = int(rng.choice([nxt, raddr, int(rng.integers(0, words))]))
                scale = int(rng.integers(0, 1 << max(1, (scales - 1).bit_length())))
                values = rng.integers(1, 1 << tw, p)
                if geo.shared_thresholds:  # one register per scale: one value
                    values[:] = values[0]
                bus = (scale, word, values)
                counts["forwarded"] += word == (nxt if advance else raddr)
            ctx.set(dut.ctl.advance, int(advance))
            ctx.set(dut.read.addr, raddr)
            ctx.set(dut.read.addr_next_adv, nxt)
            ctx.set(dut.read.addr_next_hold, raddr)
            ctx.set(dut.read.bank, bank_line[0] >> bank_bits)
            ctx.set(dut.write.en, int(advance and wvalid))
            ctx.set(dut.write.valid, int(wvalid))
            ctx.set(dut.write.addr, waddr)
            for s in range(scales):
                ctx.set(dut.write_data[s], _pack(wdata[s], wa))
            ctx.set(dut.thr.we, int(bus is not None))
            if bus is not None:
                ctx.set(dut.thr.addr, geo.threshold_address(*bus[:2]))
                ctx.set(dut.thr.data, geo.threshold_data(bus[2]))
            await ctx.tick()
            model.edge(advance, raddr, advance and wvalid, wvalid, waddr, wdata, bus)
            if advance:
                bank_line = [bank_line[1], raddr]
                raddr = nxt
            if model.words is None:
                continue
            acc, thr = model.words
            for s in range(scales):
                assert _lanes(ctx.get(dut.words.thr[s]), tw, p) == list(thr[s]), s
                counts["thr"] += 1
                got = _lanes(ctx.get(dut.words.acc[s]), wa, p)
                for i in range(p):
                    if acc[s, i] >= 0:
                        assert got[i] == acc[s, i], (s, i)
                        counts["acc"] += 1

    amaranth_sim.run(dut, bench)
    return counts


def test_state_follows_its_model(amaranth_sim) -> None:
    geo = StreamGeometry(model_contract("dog3", 6, 8, frac_bits=6), 2, bank_words=8)
    assert len(geo.bank_sizes) == 3
    counts = _run(amaranth_sim, geo)
    assert counts["thr"] > 1000 and counts["acc"] > 500 and counts["forwarded"] > 50


def test_a_forwarding_bug_disagrees_with_the_model(amaranth_sim) -> None:
    geo = StreamGeometry(model_contract("dog3", 6, 8, frac_bits=6), 2, bank_words=8)
    with pytest.raises(AssertionError):
        _run(amaranth_sim, geo, "stream.no_threshold_forwarding")


def _shared(contract, thresholds: tuple[int, ...]):  # noqa: ANN001, ANN202 - a contract
    return dataclasses.replace(contract, shared_thresholds=thresholds)


def test_shared_threshold_registers_follow_the_model(amaranth_sim) -> None:
    """threshold.storage = "shared": one register per scale, configured to the nominal
    thresholds, written by scale with a memory word's timing (the model's every word of
    the scale)."""
    geo = StreamGeometry(_shared(model_contract("dog3", 6, 8, frac_bits=6), (5, 9, 300)),
                         2, bank_words=8)
    assert geo.shared_thresholds and geo.state_bits["thresholds"] == 0
    counts = _run(amaranth_sim, geo)
    assert counts["thr"] > 1000 and counts["acc"] > 500 and counts["forwarded"] > 50


def test_shared_thresholds_start_at_the_nominal_ones(amaranth_sim) -> None:
    """With no write at all the registers deliver the contract's nominal thresholds."""
    geo = StreamGeometry(_shared(model_contract("dog2", 6, 8, frac_bits=6), (7, 11)), 2)
    dut, model = StateStage(geo), StateModel(geo)
    got = []

    async def bench(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        for _ in range(geo.READ_STAGES + 1):
            ctx.set(dut.ctl.advance, 1)
            await ctx.tick()
        got.extend(_lanes(ctx.get(dut.words.thr[s]), geo.contract.threshold_bits, 2)
                   for s in range(2))

    amaranth_sim.run(dut, bench)
    assert got == [[7, 7], [11, 11]] == [list(model.thr[s, 0]) for s in range(2)]
