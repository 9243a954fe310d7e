"""The SPI-to-AXI4-Lite bridge against its model (:mod:`rvsm.rtl.board.spi_model`),
joined to a real register file (``AxiLiteRegisters``, its model ``RegisterFileModel``):
random frames (writes, reads, unmapped and out-of-range addresses, unknown commands,
frames cut short) at SCLK rates asynchronous to the core clock, every MISO bit compared;
and a slow bus answering a read too late."""

from __future__ import annotations

import numpy as np
import pytest
from amaranth.hdl import Module
from amaranth.lib import wiring
from amaranth.sim import Simulator

from rvsm.rtl.board.spi_bridge import MIN_PHASE_CYCLES, SpiBridge
from rvsm.rtl.board.spi_drive import spi_read, spi_transfer
from rvsm.rtl.board.spi_model import (
    READ,
    WRITE,
    SpiBridgeModel,
    SpiStatus,
    read_frame,
    write_frame,
)
from rvsm.rtl.ip.axi_lite import AxiLiteRegisters
from rvsm.rtl.ip.register_map import Field, Register, RegisterMap
from rvsm.rtl.ip.register_model import RegisterFileModel

CORE = 10e-9
REGMAP = RegisterMap((
    Register("ID", 0x000, (Field("magic", 0, 32, "RO", 0x5256534D, "id"),), "id"),
    Register("CTRL", 0x004, (Field("a", 0, 8, "RW", 3, "a"),
                             Field("b", 8, 4, "RW", 0, "b", max=9)), "control"),
    Register("LIVE", 0x008, (Field("v", 0, 16, "RO", 0, "live", live=True),), "live"),
    Register("SCRATCH", 0x0FC, (Field("x", 0, 32, "RW", 0, "scratch"),), "scratch"),
), 12, 0, 8, 1, 1)
LIVE = 0xBEEF


def _frames(rng: np.random.Generator, n: int) -> list[tuple[bytes, int | None]]:
    """Random frames (MOSI bytes, bits clocked or None for all)."""
    addrs = [0x000, 0x004, 0x008, 0x0FC, 0x010, 0x0FFF, 0x1004, 0x8000]
    frames: list[tuple[bytes, int | None]] = []
    for _ in range(n):
        kind = rng.integers(0, 10)
        addr = int(rng.choice(addrs))
        if kind < 4:
            data = int(rng.choice([rng.integers(0, 1 << 32), 0x905, 0xA05]))
            frames.append((write_frame(addr, data), None))
        elif kind < 8:
            frames.append((read_frame(addr), None))
        elif kind == 8:
            frames.append((bytes([int(rng.choice([0x00, 0x01, 0xFF]))]) + bytes(6), None))
        else:
            frame = write_frame(addr, 1) if rng.random() < 0.5 else read_frame(addr)
            frames.append((frame, int(rng.integers(1, 40))))
    # every kind at least once: unknown command, a cut write, an address beyond 12 bits
    return [*frames, (bytes([0x5A]) + bytes(6), None), (write_frame(0x4, 7), 30),
            (read_frame(0x8000), None)]


def _run(frames: list[tuple[bytes, int | None]], half: float) -> list[bytes]:
    m = Module()
    m.submodules.bridge = bridge = SpiBridge(REGMAP.addr_bits)
    m.submodules.regs = regs = AxiLiteRegisters(REGMAP)
    m.d.comb += regs.value["LIVE.v"].eq(LIVE)
    wiring.connect(m, bridge.bus, regs.bus)
    got: list[bytes] = []
    sim = Simulator(m)
    sim.add_clock(CORE)

    async def bench(ctx) -> None:  # noqa: ANN001
        await ctx.delay(7.3 * CORE)
        for mosi, bits in frames:
            got.append(await spi_transfer(ctx, bridge.spi, mosi, half, bits))
        got.append(await spi_transfer(ctx, bridge.spi, bytes(1), half))  # the last status

    sim.add_testbench(bench)
    sim.run()
    return got


def _model(frames: list[tuple[bytes, int | None]]) -> list[bytes]:
    model = SpiBridgeModel(RegisterFileModel(REGMAP, {"LIVE.v": LIVE}), REGMAP.addr_bits)
    return [model.transfer(mosi, bits) for mosi, bits in [*frames, (bytes(1), None)]]


@pytest.mark.parametrize("half_cycles", [MIN_PHASE_CYCLES + 0.37, 17.81])
def test_bridge_matches_its_model_on_random_frames(half_cycles: float) -> None:
    frames = _frames(np.random.default_rng(int(half_cycles)), 24 if half_cycles < 10 else 8)
    want = _model(frames)
    assert _run(frames, half_cycles * CORE) == want
    statuses = [SpiStatus.decode(b[0]) for b in want]
    assert any(s.bad for s in statuses) and any(s.resp for s in statuses)
    assert any(f[0][0] == READ and f[1] is None and b[4:] != bytes(4)
               for f, b in zip(frames, want, strict=False))


def test_write_then_read_back_and_the_status_of_each() -> None:
    frames = [(write_frame(0x0FC, 0xCAFEF00D), None), (read_frame(0x0FC), None),
              (write_frame(0x008, 1), None), (read_frame(0x008), None),
              (bytes([WRITE, 0x10, 0x04]) + bytes(4), None)]
    got = _run(frames, 6.1 * CORE)
    assert got == _model(frames)
    assert int.from_bytes(got[1][4:], "big") == 0xCAFEF00D
    assert int.from_bytes(got[3][4:], "big") == LIVE
    # statuses: reset, write OKAY, read OKAY, write to RO -> SLVERR, read OKAY,
    # address 0x1004 beyond 12 bits -> SLVERR
    assert [SpiStatus.decode(b[0]).resp for b in got] == [0, 0, 0, 2, 0, 2]


def test_a_read_answered_too_late_reads_zero_and_says_late() -> None:
    dut = SpiBridge(12)
    got: dict[str, object] = {}
    sim = Simulator(dut)
    sim.add_clock(CORE)

    async def slow_slave(ctx) -> None:  # noqa: ANN001
        ctx.set(dut.bus.arready, 1)
        await ctx.tick().until(dut.bus.arvalid)
        ctx.set(dut.bus.arready, 0)
        await ctx.tick().repeat(300)  # longer than the turnaround byte
        ctx.set(dut.bus.rdata, 0x12345678)
        ctx.set(dut.bus.rvalid, 1)
        await ctx.tick().until(dut.bus.rready)
        ctx.set(dut.bus.rvalid, 0)

    async def bench(ctx) -> None:  # noqa: ANN001
        half = 5.5 * CORE
        got["data"] = await spi_read(ctx, dut.spi, 0x10, half)
        await ctx.delay(400 * CORE)
        got["status"] = SpiStatus.decode((await spi_transfer(ctx, dut.spi, bytes(1), half))[0])
        got["after"] = SpiStatus.decode((await spi_transfer(ctx, dut.spi, bytes(1), half))[0])

    sim.add_process(slow_slave)
    sim.add_testbench(bench)
    sim.run()
    assert got["data"] == 0
    assert got["status"] == SpiStatus(resp=0, late=True, bad=False)
    assert got["after"] == SpiStatus(resp=0, late=False, bad=True)  # command 0x00: bad
