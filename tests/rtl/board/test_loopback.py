"""amaranth.sim of the link loopback (rtl/board/loopback.py) at 4x8, 2 lanes: thresholds
written while the link trains, three frames and the flush beats through the sensor
serialiser, the skewed receive pairs, the board front end and the board deserialiser;
every spike equal to ArrayContract.run, positions from the framing."""

from __future__ import annotations

import numpy as np
import pytest
from amaranth.hdl import Module, ResetInserter, Signal
from amaranth.sim import Simulator

from rvsm.model.fixed.point_toml import load_design_point
from rvsm.rtl.board.loopback import CORE_BITS, LinkLoopback


def test_frames_through_both_links_equal_the_twin() -> None:
    point = load_design_point("tests/data/formal-tiny.toml").with_size(4, 8)
    c, lanes, steps = point.contract(), 2, 3
    lb = LinkLoopback(c, lanes)
    geo = lb.geometry
    codes = np.random.default_rng(0).integers(0, 1 << c.adc_bits,
                                              (steps, c.height, c.width), dtype=np.int64)
    thr = point.integer_thresholds()
    expected = c.run(codes, thr)
    beats = [sum(int(v) << (i * c.adc_bits) for i, v in enumerate(row))
             for row in codes.reshape(-1, lanes)] + [0] * lb.lag
    out: list[tuple[int, ...]] = []
    m, rst = Module(), Signal()
    m.submodules.lb = ResetInserter({"sync": rst})(lb)

    async def bench(ctx) -> None:  # noqa: ANN001
        ctx.set(rst, 1)
        await ctx.tick().repeat(2 * CORE_BITS)
        ctx.set(rst, 0)
        for addr, data in lb.dut.threshold_writes(thr):  # held until the core's enable
            ctx.set(lb.thr.we, 1)
            ctx.set(lb.thr.addr, addr)
            ctx.set(lb.thr.data, data)
            await ctx.tick()
            ctx.set(lb.thr.we, 0)
            await ctx.tick().repeat(2 * CORE_BITS)
        k = 0
        for _ in range(4000):
            ctx.set(lb.codes.valid, k < len(beats))
            ctx.set(lb.codes.payload.as_value(), beats[k] if k < len(beats) else 0)
            ready = ctx.get(lb.codes.ready)
            await ctx.tick()
            k += int(ready and k < len(beats))
            if ctx.get(lb.spikes.valid):
                p = lb.spikes.payload
                out.append(tuple(ctx.get(f) for f in (p.row, p.group, p.pos, p.neg)))
            if len(out) == steps * geo.beats_per_frame:
                break
        assert ctx.get(lb.tx_link_errors) == 0 and ctx.get(lb.out_framing_errors) == 0
        assert ctx.get(lb.overflow) == 0

    sim = Simulator(m)
    sim.add_clock(1.25e-9)
    sim.add_testbench(bench)
    sim.run()
    assert len(out) == steps * geo.beats_per_frame
    got = np.zeros_like(expected)
    for k, (row, group, pos, neg) in enumerate(out):
        for s in range(c.num_scales):
            for i in range(lanes):
                b = s * lanes + i
                got[k // geo.beats_per_frame, s, row, group * lanes + i] = \
                    (pos >> b & 1) - (neg >> b & 1)
    assert np.count_nonzero(expected) > 0
    assert np.array_equal(got, expected)


def test_refuses_delays_beyond_its_skew_lines() -> None:
    c = load_design_point("tests/data/formal-tiny.toml").with_size(4, 8).contract()
    with pytest.raises(ValueError, match="delays"):
        LinkLoopback(c, 2, delays=(0, 30))
    with pytest.raises(ValueError, match="front_end"):
        LinkLoopback(c, 2, front_end="bare")
