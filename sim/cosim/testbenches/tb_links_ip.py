"""cocotb testbench of the AXI IP on a board through its links (``IpBoardFrontEnd`` in
a :class:`~rvsm.rtl.board.loopback.LinkLoopback` with faults), registers over SPI.

Reads ``RVSM_LINKS_IP`` (an ``.npz`` from :mod:`rvsm.sim.cosim.ip_links_run`: input
beats ``beats_a`` and ``beats_b`` ``(K,)`` ints (the frames before and after the
faults, each followed by the ``lag`` flush beats), ``frames_a`` (beats of frames in
``beats_a``), ``clock_ps`` (the bit clock), ``spi_half_ns``, ``core_bits``) and writes its
JSON result to ``RVSM_RESULT``: the output ``beats`` (spike payload ints, in order),
every register read (``reads``: ``[label, address, value]``) and ``seconds``.

The sequence: reset (the bit clock is made in Verilog); wait for the link to lock (the
sensor trains while ``train_request`` is high); read ``STATUS``, ``LINK_STATUS``,
``LINK_ERRORS0``, ``LINK_LOSSES``; frames A and flush beats; ``CONTROL = clear``; a slip
on pair 0 (``fault``), relock; the forwarded clock stopped (``rx_run`` low) with
``LINK_STATUS`` read while it is stopped, then running again, relock; the link
registers read; frames B and flush beats; the registers read again. The
SPI master is mode 0, most significant bit first, frames as in docs/board.md.
"""

from __future__ import annotations

import json
import os
import time

import cocotb
import numpy as np
from cocotb.triggers import FallingEdge, ReadOnly, RisingEdge, Timer

from rvsm.rtl.board.spi_model import read_data, read_frame, write_frame

STATUS, CONTROL = 0x024, 0x020
LINK_STATUS, LINK_LOSSES, LINK_ERRORS0 = 0x080, 0x088, 0x08C
CLEAR = 0x1


class Bench:
    """The pins, the SPI master and the record of reads."""

    def __init__(self, dut, spi_half_ns: float, core_ns: float) -> None:  # noqa: ANN001
        self.dut, self.half, self.core_ns = dut, spi_half_ns, core_ns
        self.reads: list[list] = []
        self.beats: list[int] = []

    async def transfer(self, mosi: bytes) -> bytes:
        """One SPI frame (mode 0): MISO sampled before each rising SCLK edge."""
        d, n = self.dut, 8 * len(mosi)
        value, got = int.from_bytes(mosi, "big"), 0
        d.spi_cs_n.value = 0
        for k in range(n):
            d.spi_mosi.value = value >> (n - 1 - k) & 1
            await Timer(self.half, "ns")
            got = got << 1 | int(d.spi_miso.value)
            d.spi_sclk.value = 1
            await Timer(self.half, "ns")
            d.spi_sclk.value = 0
        await Timer(self.half, "ns")
        d.spi_cs_n.value, d.spi_mosi.value = 1, 0
        await Timer(self.half, "ns")
        return got.to_bytes(len(mosi), "big")

    async def read(self, label: str, addr: int) -> int:
        value = read_data(await self.transfer(read_frame(addr)))
        self.reads.append([label, addr, value])
        return value

    async def write(self, addr: int, data: int) -> None:
        await self.transfer(write_frame(addr, data))

    async def cycles(self, n: int) -> None:
        await Timer(n * self.core_ns, "ns")

    async def locked(self, timeout_cycles: int = 4000) -> None:
        """Until ``train_request`` has been low for 300 core cycles (the loopback's
        START_WAIT is 128)."""
        quiet = 0
        for _ in range(timeout_cycles // 10):
            await self.cycles(10)
            quiet = quiet + 10 if not int(self.dut.train_request.value) else 0
            if quiet >= 300:
                return
        raise AssertionError("the receive link did not lock")

    async def feed(self, beats: np.ndarray) -> None:
        """Each beat on ``codes`` until the loopback takes it (ready seen at a falling
        edge: taken at the next rising edge)."""
        d = self.dut
        for beat in beats:
            d.codes_payload.value, d.codes_valid.value = int(beat), 1
            while True:
                await FallingEdge(d.clk)
                if int(d.codes_ready.value):
                    break
            await RisingEdge(d.clk)
        d.codes_valid.value = 0

    async def capture(self) -> None:
        """Every output beat (registered: one clock cycle high each)."""
        while True:
            await RisingEdge(self.dut.spikes_valid)
            await ReadOnly()
            if int(self.dut.spikes_valid.value):
                self.beats.append(int(self.dut.spikes_payload.value))

    async def drained(self, count: int, timeout_cycles: int = 4000) -> None:
        for _ in range(timeout_cycles // 10):
            if len(self.beats) >= count:
                return
            await self.cycles(10)
        raise AssertionError(f"{len(self.beats)} output beats, {count} expected")

    async def link_registers(self, when: str) -> None:
        for name, addr in (("LINK_STATUS", LINK_STATUS), ("LINK_ERRORS0", LINK_ERRORS0),
                           ("LINK_LOSSES", LINK_LOSSES), ("STATUS", STATUS)):
            await self.read(f"{when}:{name}", addr)


@cocotb.test()
async def ip_links(dut) -> None:  # noqa: ANN001
    """Frames, a bit slip, a stopped forwarded clock, frames, all registers over SPI."""
    stim = np.load(os.environ["RVSM_LINKS_IP"])
    core_ns = int(stim["clock_ps"]) * int(stim["core_bits"]) / 1000
    b = Bench(dut, float(stim["spi_half_ns"]), core_ns)
    t0 = time.perf_counter()
    dut.rst.value = 1
    for name in ("spi_sclk", "spi_mosi", "fault", "frame_start", "codes_valid",
                 "codes_payload"):
        getattr(dut, name).value = 0
    dut.spi_cs_n.value, dut.rx_run.value = 1, 1
    for _ in range(32):
        await FallingEdge(dut.clk)
    dut.rst.value = 0
    cocotb.start_soon(b.capture())
    await b.locked()
    await b.link_registers("locked")
    beats_a, beats_b = stim["beats_a"], stim["beats_b"]
    frames_a = int(stim["frames_a"])
    await b.feed(beats_a)
    await b.drained(frames_a)
    await b.write(CONTROL, CLEAR)  # the flush beats' own positions are dropped
    dut.fault.value = 1  # pair 0 slips by fault_bits
    await b.cycles(300)
    await b.locked()
    await b.link_registers("slip")
    dut.rx_run.value = 0  # the forwarded clock stops
    await b.cycles(200)
    await b.read("stopped:LINK_STATUS", LINK_STATUS)
    dut.rx_run.value = 1
    await b.locked()
    await b.link_registers("relocked")
    dut.frame_start.value = 1
    await FallingEdge(dut.clk)
    dut.frame_start.value = 0
    await b.feed(beats_b)
    await b.drained(frames_a + len(beats_b) - (len(beats_a) - frames_a))
    await b.cycles(100)
    await b.link_registers("end")
    result = {"beats": b.beats, "reads": b.reads, "seconds": time.perf_counter() - t0,
              "tx_link_errors": int(dut.tx_link_errors.value),
              "out_framing_errors": int(dut.out_framing_errors.value),
              "overflow": int(dut.overflow.value)}
    with open(os.environ["RVSM_RESULT"], "w") as f:
        json.dump(result, f)
