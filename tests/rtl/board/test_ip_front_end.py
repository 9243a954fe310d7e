"""amaranth.sim of the AXI IP on a board (IpBoardFrontEnd) at 4x8, 2 lanes, behavioural
gearing: a sensor model sends serial bit streams (skew between the pairs, training
whenever the front end's ``train_request`` pin asks for it), the spikes out of the
transmit pins are decoded by the link model and compared with the fixed twin
(ArrayContract.run), and the link registers are read and written over SPI: locked and
aligned, a lost clock and a bit slip counted, a training request that re-trains."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from amaranth.sim import Simulator

from rvsm.model.fixed.point_toml import load_design_point
from rvsm.rtl.board.drive import capture_link
from rvsm.rtl.board.ip_front_end import IpBoardFrontEnd, ip_front_end_verilog
from rvsm.rtl.board.model import (
    LinkFormat,
    beat_words,
    deserialise,
    idle_words,
    pixel_beats,
    serialise,
    spike_beats_to_frames,
    training_words,
)
from rvsm.rtl.board.spi_drive import spi_read, spi_write

CORE = 4.3e-9       # core clock period (s)
RX_HALF = 4.0e-9    # half a bit of the receive link (s): 64 ns a word
TX_HALF = 3.9e-9    # the transmit link, a little faster
SPI_HALF = 5.3 * CORE
STEPS = 2
LINK_STATUS, LINK_CONTROL, LINK_LOSSES, LINK_ERRORS0 = 0x80, 0x84, 0x88, 0x8C


@dataclass
class Sensor:
    """The sensor side of the receive link, run as a process: queued items first
    (``("words", array)``, ``("pause", seconds)``, ``("slip", pair, bits)``), else 16
    training words while ``train_request`` is high, else 8 idle words. Pair ``i`` is
    ``delays[i]`` bits late (skew; a slip adds to it)."""

    fmt: LinkFormat
    delays: list[int]
    queue: list[tuple] = field(default_factory=list)
    period: int = 0
    done: int = 0
    tails: list[np.ndarray] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.tails = [np.ones(d, np.uint8) for d in self.delays]

    def _skew(self, bits: np.ndarray) -> np.ndarray:
        out = np.empty_like(bits)
        for i in range(bits.shape[0]):
            joined = np.concatenate([self.tails[i], bits[i]])
            out[i] = joined[:bits.shape[1]]
            self.tails[i] = joined[bits.shape[1]:]
        return out

    async def run(self, ctx, dut: IpBoardFrontEnd) -> None:  # noqa: ANN001
        while True:
            words = None
            if self.queue:
                item = self.queue.pop(0)
                if item[0] == "words":
                    words = item[1]
                elif item[0] == "pause":
                    await ctx.delay(item[1])
                else:
                    self.tails[item[1]] = np.concatenate([np.ones(item[2], np.uint8),
                                                          self.tails[item[1]]])
                self.done += 1
            elif ctx.get(dut.train_request):
                words = training_words(self.fmt, 16, self.period)
                self.period += 16
            else:
                words = idle_words(self.fmt, 8)
            if words is not None:
                await _drive(ctx, dut, self._skew(serialise(words)))

    async def send(self, ctx, *items: tuple) -> None:  # noqa: ANN001
        """Queue ``items`` and wait until they are on the wire."""
        target = self.done + len(items)
        self.queue.extend(items)
        while self.done < target:
            await ctx.delay(200e-9)


async def _drive(ctx, dut: IpBoardFrontEnd, bits: np.ndarray) -> None:  # noqa: ANN001
    """Bit streams ``(pairs, B)`` onto the receive pins, a bit per bit clock: the pins
    change with the falling edge (as :func:`~rvsm.rtl.board.drive.drive_link`, with one
    simulator step fewer a bit), the rising edge samples them."""
    shifts = np.arange(bits.shape[0])[:, None]
    for word in (bits.astype(np.int64) << shifts).sum(axis=0).tolist():
        ctx.set(dut.rx_clock, 0)
        ctx.set(dut.rx_pins, word)
        await ctx.delay(RX_HALF)
        ctx.set(dut.rx_clock, 1)
        await ctx.delay(RX_HALF)


def _setup(delays: list[int]):  # noqa: ANN202
    point = load_design_point("tests/data/formal-tiny-shared.toml").with_size(4, 8)
    c, lanes = point.contract(), 2
    dut = IpBoardFrontEnd(c, lanes)
    codes = np.random.default_rng(3).integers(0, 1 << c.adc_bits, (STEPS, 4, 8))
    want = c.run(codes, point.integer_thresholds())
    payload, sof, eol = pixel_beats(codes, lanes, c.adc_bits)
    g = 8 // lanes
    k = np.arange(len(payload), len(payload) + dut.lag) % (4 * g)  # the flush beats
    payload = np.concatenate([payload, np.zeros((dut.lag, payload.shape[1]), np.uint8)])
    words = beat_words(dut.rx_format, payload, np.concatenate([sof, k == 0]),
                       np.concatenate([eol, k % g == g - 1]))
    return dut, want, words, Sensor(dut.rx_format, delays)


def _simulate(dut: IpBoardFrontEnd, sensor: Sensor, bench,  # noqa: ANN001
              transmit: dict[str, bool] | None = None) -> list[int]:
    """Run ``bench(ctx)`` with the sensor, the transmit clock and the capture of the
    transmit pins; the pins sampled at every forwarded clock edge. The transmit clock
    runs while ``transmit["on"]`` (default: always; a stopped clock saves simulation)."""
    samples: list[int] = []
    transmit = {"on": True} if transmit is None else transmit
    sim = Simulator(dut)
    sim.add_clock(CORE, domain="sync")

    async def link(ctx) -> None:  # noqa: ANN001
        await sensor.run(ctx, dut)

    async def tx_clock(ctx) -> None:  # noqa: ANN001
        while True:
            if not transmit["on"]:
                await ctx.delay(100e-9)
                continue
            ctx.set(dut.tx_clock, 1)
            await ctx.delay(TX_HALF)
            ctx.set(dut.tx_clock, 0)
            await ctx.delay(TX_HALF)

    async def capture(ctx) -> None:  # noqa: ANN001
        await capture_link(ctx, dut.tx_clock_out, dut.tx_pins, dut.tx_format.pairs, samples)

    sim.add_testbench(link, background=True)  # it reads the train_request pin
    sim.add_process(tx_clock)
    sim.add_process(capture)
    sim.add_testbench(bench)
    sim.run()
    return samples


async def _wait_locked(ctx, dut: IpBoardFrontEnd, tries: int = 6) -> int:  # noqa: ANN001
    """Read LINK_STATUS over SPI until locked and aligned; its value."""
    for _ in range(tries):
        status = await spi_read(ctx, dut.spi, LINK_STATUS, SPI_HALF)
        if status & 3 == 3:
            return status
    raise AssertionError(f"the link did not lock: LINK_STATUS 0x{status:X}")


async def _until_locked(ctx, dut: IpBoardFrontEnd) -> None:  # noqa: ANN001
    """Wait (watching the receiver's status, not over SPI: cheaper) until locked."""
    for _ in range(200):
        await ctx.delay(100e-9)
        if ctx.get(dut.receiver.status.locked):
            return
    raise AssertionError("the link did not lock within 20 us")


def _spikes(dut: IpBoardFrontEnd, samples: list[int]) -> np.ndarray:
    s = np.array(samples, dtype=np.int64)
    bits = ((s[None, :] >> np.arange(dut.tx_format.pairs)[:, None]) & 1).astype(np.uint8)
    capture = deserialise(dut.tx_format, bits)
    assert capture.errors.tolist() == [0] * dut.tx_format.pairs
    return spike_beats_to_frames(capture, dut.contract.num_scales, 4, 8, 2)


def test_spikes_through_the_ip_front_end_equal_the_twin_and_spi_reads_the_link() -> None:
    dut, want, words, sensor = _setup([3, 6])  # skew between the pairs, a bit slip
    seen: dict[str, int] = {}

    async def bench(ctx) -> None:  # noqa: ANN001
        await _until_locked(ctx, dut)
        await sensor.send(ctx, ("words", words))
        await ctx.delay(40 * 2 * RX_HALF * 8)
        seen["status"] = await spi_read(ctx, dut.spi, LINK_STATUS, SPI_HALF)
        seen["errors"] = await spi_read(ctx, dut.spi, LINK_ERRORS0, SPI_HALF)
        seen["losses"] = await spi_read(ctx, dut.spi, LINK_LOSSES, SPI_HALF)
        seen["ip_status"] = await spi_read(ctx, dut.spi, 0x24, SPI_HALF)

    got = _spikes(dut, _simulate(dut, sensor, bench))
    assert got.shape[0] >= STEPS and np.count_nonzero(want) > 0
    assert np.array_equal(got[:STEPS], want)
    assert seen["status"] & 0xF == 0b0011  # locked, aligned, no train_request, no overflow
    assert (seen["errors"], seen["losses"]) == (0, 0)
    assert seen["ip_status"] & 0b11 == 0  # no IP overflow, no framing error


def test_a_lost_clock_and_a_bit_slip_are_counted_and_the_spikes_still_match() -> None:
    dut, want, words, sensor = _setup([2, 0])
    seen: dict[str, int] = {}
    transmit = {"on": False}

    async def bench(ctx) -> None:  # noqa: ANN001
        await _until_locked(ctx, dut)
        await sensor.send(ctx, ("pause", 600e-9))  # the forwarded clock stops: lock lost
        await ctx.delay(200e-9)
        await _until_locked(ctx, dut)              # the sensor trained again on request
        await sensor.send(ctx, ("slip", 0, 3))     # pair 0 slips 3 bits: errors, lock lost
        await ctx.delay(1e-6)
        await _until_locked(ctx, dut)
        seen["status"] = await spi_read(ctx, dut.spi, LINK_STATUS, SPI_HALF)
        transmit["on"] = True  # its 64 training words, then the data
        await ctx.delay(70 * 16 * TX_HALF)
        await sensor.send(ctx, ("words", words))
        await ctx.delay(40 * 2 * RX_HALF * 8)
        seen["losses"] = await spi_read(ctx, dut.spi, LINK_LOSSES, SPI_HALF)
        seen["errors"] = await spi_read(ctx, dut.spi, LINK_ERRORS0, SPI_HALF)

    got = _spikes(dut, _simulate(dut, sensor, bench, transmit))
    assert np.array_equal(got[:STEPS], want)
    assert seen["losses"] == 2 and seen["status"] & 0b111 == 0b011
    assert seen["errors"] & 0xFF >= 4          # pair 0: the bad words that dropped the lock
    assert seen["errors"] >> 8 & 0xFF == 0     # the framing lane: none


def test_a_training_request_over_spi_retrains_and_counters_reset_clears() -> None:
    dut, _, _, sensor = _setup([1, 5])
    seen: dict[str, object] = {}

    async def bench(ctx) -> None:  # noqa: ANN001
        await _until_locked(ctx, dut)
        seen["write"] = await spi_write(ctx, dut.spi, LINK_CONTROL, 1, SPI_HALF)
        seen["training"] = await spi_read(ctx, dut.spi, LINK_STATUS, SPI_HALF)
        await spi_write(ctx, dut.spi, LINK_CONTROL, 0, SPI_HALF)
        seen["relocked"] = await _wait_locked(ctx, dut)
        seen["losses"] = await spi_read(ctx, dut.spi, LINK_LOSSES, SPI_HALF)
        await spi_write(ctx, dut.spi, LINK_CONTROL, 2, SPI_HALF)  # counters_reset
        seen["cleared"] = await spi_read(ctx, dut.spi, LINK_LOSSES, SPI_HALF)

    _simulate(dut, sensor, bench, {"on": False})  # the transmit link is not needed
    assert seen["write"].resp == 0
    assert seen["training"] & 0b111 == 0b100    # not locked, not aligned, train_request
    assert seen["relocked"] & 0b111 == 0b011
    assert (seen["losses"], seen["cleared"]) == (1, 0)


def test_the_front_end_is_verilog_with_board_ports_and_the_link_registers_in_the_map() -> None:
    dut, _, _, _ = _setup([0, 0])
    verilog = ip_front_end_verilog(dut)
    header = verilog[verilog.index("module rvsm_board_ip("):].split(");")[0]
    ports = {p.strip() for p in header.split("(", 1)[1].split(",")}
    assert ports == {"rx_clock", "rx_pins", "tx_clock", "tx_pins", "tx_clock_out",
                     "train_request", "spi_sclk", "spi_cs_n", "spi_mosi", "spi_miso",
                     "tx_overflow", "clk", "rst"}
    assert [r.offset for r in dut.link_registers] == [0x80, 0x84, 0x88, 0x8C]
    assert dut.regmap["LINK_ERRORS0"].offset == LINK_ERRORS0
