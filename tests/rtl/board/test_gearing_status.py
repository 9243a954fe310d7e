"""The gearing's two implementations behind one interface, and the link registers."""

from __future__ import annotations

import numpy as np
import pytest
from amaranth.back import rtlil
from amaranth.hdl import ClockDomain, Module
from amaranth.sim import Simulator

from rvsm.model.fixed.point_toml import load_design_point
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.board.front_end import BoardFrontEnd
from rvsm.rtl.board.gearing import (
    Deserialiser,
    DeserialiserSignature,
    Serialiser,
    SerialiserSignature,
)
from rvsm.rtl.board.status import LINK_BASE, link_registers
from rvsm.rtl.ip.register_map import RegisterMap


def test_both_gearings_have_one_signature() -> None:
    for primitive in ("behavioural", "ecp5"):
        m = Module()
        m.domains += [ClockDomain("rx"), ClockDomain("tx")]
        m.submodules.des = des = Deserialiser(3, primitive)
        m.submodules.ser = ser = Serialiser(3, primitive)
        assert des.signature == DeserialiserSignature(3) != SerialiserSignature(3)
        assert ser.signature == SerialiserSignature(3)
        assert ("IDDRX2F" in rtlil.convert(m, ports=[])) == (primitive == "ecp5")
    with pytest.raises(RvsmError, match="unknown gearing"):
        Deserialiser(3, "xilinx")


def test_ecp5_front_end_instantiates_the_primitives() -> None:
    point = load_design_point("tests/data/formal-tiny.toml").with_size(4, 8)
    fe = BoardFrontEnd(point.contract(), 2, primitive="ecp5")
    text = rtlil.convert(fe)
    rx, tx = fe.rx_format.pairs, fe.tx_format.pairs
    assert text.count("cell \\IDDRX2F") == rx
    assert text.count("cell \\ODDRX2F") == tx + 1  # the pairs and the forwarded clock
    assert text.count("cell \\ECLKSYNCB") == 2 and text.count("cell \\CLKDIVF") == 2
    assert 'parameter \\DIV "2.0"' in text


def test_behavioural_gearing_loops_back_bit_exactly() -> None:
    """Serialiser -> pins -> deserialiser (on the forwarded clock): the 4-bit words come
    out as they went in, in order, one per SCLK."""
    m = Module()
    m.domains += [ClockDomain("rx"), ClockDomain("tx")]
    m.submodules.ser = ser = Serialiser(2)
    m.submodules.des = des = Deserialiser(2)
    m.d.comb += [des.pins.eq(ser.pins), des.clock.eq(ser.clock_out)]
    sent = np.random.default_rng(0).integers(0, 256, 40)  # pair 0 low nibble, pair 1 high
    got: list[int] = []
    sim = Simulator(m)

    async def bit_clock(ctx) -> None:  # noqa: ANN001
        while True:
            ctx.set(ser.clock, 1)
            await ctx.delay(0.5e-9)
            ctx.set(ser.clock, 0)
            await ctx.delay(0.5e-9)

    async def bench(ctx) -> None:  # noqa: ANN001
        await ctx.tick("tx")
        for word in [*sent.tolist(), *[0] * 6]:  # set after an SCLK edge, as a register
            ctx.set(ser.words.as_value(), word)
            await ctx.tick("tx")
            got.append(ctx.get(des.words.as_value()))

    sim.add_process(bit_clock)
    sim.add_testbench(bench)
    sim.run()
    lag = next(i for i in range(8) if got[i:i + len(sent)] == sent.tolist())
    assert lag <= Deserialiser.latency + 3  # a few SCLK cycles through the two registers


def test_link_registers_fit_the_ip_map_style() -> None:
    regs = link_registers(36)
    names = [r.name for r in regs]
    assert names[:3] == ["LINK_STATUS", "LINK_CONTROL", "LINK_LOSSES"]
    assert names[3:] == [f"LINK_ERRORS{k}" for k in range(9)]
    assert regs[0].offset == LINK_BASE and regs[-1].offset == LINK_BASE + 12 + 4 * 8
    RegisterMap(regs, 12, 1, 8, 1, 1)  # offsets distinct and aligned, fields fit 32 bits
    last = regs[-1].fields
    assert [f.name for f in last] == ["pair32", "pair33", "pair34", "pair35"]
    assert "framing" in last[-1].desc


def test_docs_board_link_register_table_is_the_rendering_of_the_shipped_point() -> None:
    """docs/board.md's link register table is ``link_registers_markdown`` of the shipped
    point's receive link (40 lanes of 7-bit codes: 36 pairs), at the IP's extra window."""
    from pathlib import Path

    from rvsm.model.fixed.point_toml import load_design_point
    from rvsm.rtl.board.front_end import link_formats
    from rvsm.rtl.board.status import link_registers_markdown
    from rvsm.rtl.ip.register_map import EXTRA_WINDOW

    rx, _ = link_formats(load_design_point("points/ecp5-85-40khz.toml").contract(), 40)
    regs = link_registers(rx.pairs)
    assert all(r.offset in EXTRA_WINDOW for r in regs)
    doc = Path(__file__).resolve().parents[3] / "docs" / "board.md"
    table = doc.read_text().split("<!-- link-registers:begin -->\n")[1] \
        .split("<!-- link-registers:end -->")[0]
    assert table == link_registers_markdown(regs)
