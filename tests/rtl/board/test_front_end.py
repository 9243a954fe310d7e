"""amaranth.sim tests of the transmitter and of the board front end through its links:
serial bit streams in (skewed, a bit slip), spikes out decoded by the link model and
compared with the fixed twin (ArrayContract.run)."""

from __future__ import annotations

import numpy as np
from amaranth.sim import Simulator

from rvsm.model.fixed.point_toml import load_design_point
from rvsm.rtl.board.drive import HALF_BIT_S, capture_link, drive_link, sensor_bits
from rvsm.rtl.board.front_end import BoardFrontEnd
from rvsm.rtl.board.model import LinkFormat, deserialise, skewed, spike_beats_to_frames
from rvsm.rtl.board.transmitter import LinkTransmitter
from rvsm.rtl.stream.drive import write_thresholds


def _pins_to_bits(samples: list[int], pairs: int) -> np.ndarray:
    s = np.array(samples, dtype=np.int64)
    return ((s[None, :] >> np.arange(pairs)[:, None]) & 1).astype(np.uint8)


async def _tx_clock(ctx, clock, half: float) -> None:  # noqa: ANN001
    while True:
        ctx.set(clock, 1)
        await ctx.delay(half)
        ctx.set(clock, 0)
        await ctx.delay(half)


def test_transmitter_words_match_the_model() -> None:
    fmt = LinkFormat(12)
    rng = np.random.default_rng(0)
    payload = rng.integers(0, 1 << 12, 30)
    sof, eol = rng.integers(0, 2, 30), rng.integers(0, 2, 30)
    dut = LinkTransmitter(fmt)
    samples: list[int] = []
    sim = Simulator(dut)
    sim.add_clock(7.3e-9, domain="sync")

    async def bench(ctx) -> None:  # noqa: ANN001
        for _ in range(200):  # the reset training passes
            await ctx.tick()
        for k in range(30):
            ctx.set(dut.beats.payload.payload, int(payload[k]))
            ctx.set(dut.beats.payload.sof, int(sof[k]))
            ctx.set(dut.beats.payload.eol, int(eol[k]))
            ctx.set(dut.beats.valid, 1)
            await ctx.tick()
            ctx.set(dut.beats.valid, k % 3 == 0)  # gaps: idle words between beats
            await ctx.tick()
        ctx.set(dut.beats.valid, 0)
        for _ in range(40):
            await ctx.tick()
        assert ctx.get(dut.overflow) == 0

    async def clock(ctx) -> None:  # noqa: ANN001
        await _tx_clock(ctx, dut.clock, 0.55e-9)

    async def capture(ctx) -> None:  # noqa: ANN001
        await capture_link(ctx, dut.clock_out, dut.pins, fmt.pairs, samples)

    sim.add_process(clock)
    sim.add_process(capture)
    sim.add_testbench(bench)
    sim.run()
    got = deserialise(fmt, _pins_to_bits(samples, fmt.pairs))
    # beat k, then beat k again when valid stays high for its second cycle (k % 3 == 0)
    sent = [(int(payload[k]), int(sof[k]), int(eol[k]))
            for k in range(30) for _ in range(1 + (k % 3 == 0))]
    words = [(int.from_bytes(np.packbits(p, bitorder="little").tobytes(), "little"), int(s),
              int(e)) for p, s, e in zip(got.payload, got.sof, got.eol, strict=True)]
    assert words == sent
    assert got.errors.tolist() == [0] * fmt.pairs


def test_front_end_spikes_match_the_twin_through_the_links() -> None:
    point = load_design_point("tests/data/formal-tiny.toml").with_size(4, 8)
    c, lanes, steps = point.contract(), 2, 3
    dut = BoardFrontEnd(c, lanes)
    rng = np.random.default_rng(1)
    codes = rng.integers(0, 1 << c.adc_bits, (steps, 4, 8))
    thr = point.integer_thresholds()
    want = c.run(codes, thr)
    bits = sensor_bits(dut.rx_format, codes, lanes, c.adc_bits, dut.lag)
    bits = skewed(bits, [3, 6], fill=1)  # skew between the pairs and a bit slip
    samples: list[int] = []
    status: dict[str, object] = {}
    sim = Simulator(dut)
    sim.add_clock(4.3e-9, domain="sync")

    async def link(ctx) -> None:  # noqa: ANN001
        await ctx.delay(300e-9)
        await drive_link(ctx, dut.rx_clock, dut.rx_pins, bits, HALF_BIT_S)

    async def bench(ctx) -> None:  # noqa: ANN001
        await write_thresholds(ctx, dut, thr)
        await ctx.delay(bits.shape[1] * 2 * HALF_BIT_S + 300e-9)
        status["errors"] = [ctx.get(dut.status.lane_errors[i])
                            for i in range(dut.rx_format.pairs)]
        status["framing"] = ctx.get(dut.framing_errors)
        status["overflow"] = ctx.get(dut.tx_overflow)

    async def clock(ctx) -> None:  # noqa: ANN001
        await _tx_clock(ctx, dut.tx_clock, 0.55e-9)

    async def capture(ctx) -> None:  # noqa: ANN001
        await capture_link(ctx, dut.tx_clock_out, dut.tx_pins, dut.tx_format.pairs, samples)

    sim.add_process(link)
    sim.add_process(clock)
    sim.add_process(capture)
    sim.add_testbench(bench)
    sim.run()
    capture = deserialise(dut.tx_format, _pins_to_bits(samples, dut.tx_format.pairs))
    got = spike_beats_to_frames(capture, c.num_scales, 4, 8, lanes)
    assert got.shape[0] >= steps
    assert np.array_equal(got[:steps], want)
    assert np.count_nonzero(want) > 0
    assert status == {"errors": [0] * dut.rx_format.pairs, "framing": 0, "overflow": 0}
    assert capture.errors.tolist() == [0] * dut.tx_format.pairs
