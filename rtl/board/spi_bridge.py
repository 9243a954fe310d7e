"""An SPI slave (mode 0, 4 pins) bridged to an AXI4-Lite master: the register bus of a
board, in the core clock domain alone.

:class:`SpiBridge` samples ``sclk``, ``cs_n`` and ``mosi`` with the core clock: each
passes a two-flip-flop ``FFSynchronizer`` and edges are found by comparing with the
previous sample (oversampling; no clock domain of its own), so SCLK must be slow beside
the core clock: every SCLK phase, the time from ``cs_n`` falling to the first SCLK rise,
from the last fall to ``cs_n`` rising, and ``cs_n`` high between frames, each at least
:data:`MIN_PHASE_CYCLES` core cycles (``f_sclk <= f_core / 10``: 10 MHz at 100 MHz).
MISO changes at most :data:`MISO_DELAY_CYCLES` core cycles after the SCLK fall that
calls for it. The frame format and status byte are :mod:`rvsm.rtl.board.spi_model`'s
(its :class:`~rvsm.rtl.board.spi_model.SpiBridgeModel` is this component's model).
MISO is driven at all times (0 outside a frame).
"""

from __future__ import annotations

from amaranth.hdl import Cat, Const, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.cdc import FFSynchronizer
from amaranth.lib.wiring import In, Out

from rvsm.rtl.board.spi_model import (
    BAD,
    LATE,
    READ,
    SLVERR,
    STATUS_MARK,
    WRITE,
    WRITE_FRAME_BITS,
)
from rvsm.rtl.ip.axi_lite import AxiLiteSignature

__all__ = ["MIN_PHASE_CYCLES", "MISO_DELAY_CYCLES", "SpiBridge", "SpiSignature"]

#: Core cycles each SCLK phase (and CS_n lead, lag and idle time) must last at least.
MIN_PHASE_CYCLES = 5
#: Core cycles from a pin's change to the bridge acting on it: two synchroniser
#: flip-flops and the registered action (MISO changes that late after an SCLK fall).
MISO_DELAY_CYCLES = 3
#: Rising SCLK edges after which the command byte and the address are in.
_CMD_BITS, _ADDR_BITS = 8, 24
#: The rising edge after which a read's data goes out (command, address, turnaround).
_DATA_BIT = 32


class SpiSignature(wiring.Signature):
    """The four SPI pins, the master's view: ``sclk``, ``cs_n``, ``mosi`` driven by the
    master, ``miso`` by the slave (a slave takes ``In(SpiSignature())``)."""

    def __init__(self) -> None:
        super().__init__({"sclk": Out(1), "cs_n": Out(1, init=1), "mosi": Out(1),
                          "miso": In(1)})


class SpiBridge(wiring.Component):
    """``spi`` In(:class:`SpiSignature`) -> ``bus`` Out(``AxiLiteSignature(addr_bits)``),
    one clock domain ``sync``. ``busy``: a bus transaction is in flight."""

    def __init__(self, addr_bits: int):
        self.addr_bits = addr_bits
        super().__init__({"spi": In(SpiSignature()), "bus": Out(AxiLiteSignature(addr_bits)),
                          "busy": Out(1)})

    def elaborate(self, platform: object) -> Module:
        m = Module()
        spi, bus = self.spi, self.bus
        sclk, cs_n, mosi = Signal(), Signal(init=1), Signal()
        for name, pin, synced in (("sclk", spi.sclk, sclk), ("cs_n", spi.cs_n, cs_n),
                                  ("mosi", spi.mosi, mosi)):
            m.submodules[f"{name}_sync"] = FFSynchronizer(pin, synced, init=synced.init)
        sclk_was, cs_was = Signal(), Signal(init=1)
        m.d.sync += [sclk_was.eq(sclk), cs_was.eq(cs_n)]
        rise = ~cs_n & sclk & ~sclk_was
        fall = ~cs_n & ~sclk & sclk_was
        start, end = cs_was & ~cs_n, ~cs_was & cs_n

        count = Signal(range(128))           # rising edges in this frame (saturating)
        shift_in = Signal(32)
        cmd = Signal(8)
        out = Signal(32)                     # MISO shift register, bit 31 on the pin
        resp, flags = Signal(2), Signal(4)   # last response; BAD | LATE of this frame
        rdata, have_rdata = Signal(32), Signal()
        addr = Signal(16)                    # the frame's address, once in
        m.d.comb += spi.miso.eq(out[31])

        # the bus side: one transaction at a time
        ar, aw, w, r_wait, b_wait = Signal(), Signal(), Signal(), Signal(), Signal()
        m.d.comb += [bus.arvalid.eq(ar), bus.awvalid.eq(aw), bus.wvalid.eq(w),
                     bus.wstrb.eq(0xF), bus.rready.eq(1), bus.bready.eq(1),
                     self.busy.eq(ar | aw | w | r_wait | b_wait)]
        with m.If(bus.arvalid & bus.arready):
            m.d.sync += ar.eq(0)
        with m.If(bus.awvalid & bus.awready):
            m.d.sync += aw.eq(0)
        with m.If(bus.wvalid & bus.wready):
            m.d.sync += w.eq(0)
        with m.If(bus.rvalid & r_wait):
            m.d.sync += [r_wait.eq(0), rdata.eq(bus.rdata), have_rdata.eq(1),
                         resp.eq(bus.rresp)]
        with m.If(bus.bvalid & b_wait):
            m.d.sync += [b_wait.eq(0), resp.eq(bus.bresp)]

        # the SPI side
        bit_in = Cat(mosi, shift_in[:31])    # the shift register after this rise
        nxt = count + 1
        def in_range(a: Signal) -> Signal:
            return a[self.addr_bits:] == 0 if self.addr_bits < 16 else Const(1)

        with m.If(start):
            m.d.sync += [count.eq(0), cmd.eq(0), have_rdata.eq(0), flags.eq(0),
                         out.eq(Cat(Const(0, 24), resp, flags[2:4], Const(STATUS_MARK >> 4,
                                                                              4)))]
        with m.If(rise):
            m.d.sync += [shift_in.eq(bit_in), count.eq(Mux(count == 127, count, nxt))]
            with m.If(nxt == _CMD_BITS):
                m.d.sync += cmd.eq(bit_in[:8])
                with m.If((bit_in[:8] != READ) & (bit_in[:8] != WRITE)):
                    m.d.sync += flags.eq(flags | BAD)
            issue, ok = Signal(), Signal()
            with m.If(nxt == _ADDR_BITS):
                m.d.sync += addr.eq(bit_in[:16])
            with m.If((nxt == _ADDR_BITS) & (cmd == READ)):
                m.d.comb += [issue.eq(1), ok.eq(in_range(bit_in[:16]))]
                with m.If(~ok):
                    m.d.sync += [resp.eq(SLVERR), rdata.eq(0), have_rdata.eq(1)]
                with m.Elif(~self.busy):
                    m.d.sync += [ar.eq(1), r_wait.eq(1), bus.araddr.eq(bit_in[:16])]
            with m.If((nxt == WRITE_FRAME_BITS) & (cmd == WRITE)):
                m.d.comb += [issue.eq(1), ok.eq(in_range(addr))]
                with m.If(~ok):
                    m.d.sync += resp.eq(SLVERR)
                with m.Elif(~self.busy):
                    m.d.sync += [aw.eq(1), w.eq(1), b_wait.eq(1), bus.wdata.eq(bit_in),
                                 bus.awaddr.eq(addr)]
            with m.If(issue & ok & self.busy):
                m.d.sync += flags.eq(flags | LATE)
        with m.If(fall):
            with m.If((count == _DATA_BIT) & (cmd == READ)):
                m.d.sync += out.eq(Mux(have_rdata, rdata, 0))
                with m.If(~have_rdata):
                    m.d.sync += flags.eq(flags | LATE)
            with m.Else():
                m.d.sync += out.eq(out << 1)
        with m.If(end):
            m.d.sync += out.eq(0)
            short = ((cmd == WRITE) & (count < WRITE_FRAME_BITS)) \
                | ((cmd == READ) & (count < _ADDR_BITS))
            with m.If((count >= _CMD_BITS) & short):
                m.d.sync += flags.eq(flags | BAD)
        return m
