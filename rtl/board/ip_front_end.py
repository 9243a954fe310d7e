"""The AXI IP on a board: pixel codes in over the receive link, spikes out over the
transmit link, registers over SPI.

:class:`IpBoardFrontEnd` joins, in the core clock domain ``sync``::

    rx pins -> LinkReceiver -> beats (P*N code bits, sof, eol)
      -> s_axis of RvsmAxisIp (lane i's code into its byte-padded slot; tuser = sof,
         tlast = eol; the receiver's FIFO is read while tready is high)
      -> m_axis (pos, neg, row, group, eof; tuser, tlast; always ready)
      -> LinkTransmitter beats (payload pos then neg, 2*S*P bits; sof = tuser,
         eol = tlast: positions implied by the framing) -> tx pins
    spi pins -> SpiBridge -> s_axil of the IP

The link's registers (:func:`~rvsm.rtl.board.status.link_registers` at
:data:`~rvsm.rtl.board.status.LINK_BASE`, 0x080) are the IP's ``extra_registers``:
their live fields are driven from the receiver's status, one register stage behind
(the register file's read multiplexer starts at flip-flops), and
``LINK_CONTROL.train`` / ``counters_reset`` drive the receiver's control and the
transmitter's training. ``train_request`` (a board pin to the sensor) is
``LINK_CONTROL.train`` or not locked. The IP and the bare array stay usable without
this front end; :class:`~rvsm.rtl.board.front_end.BoardFrontEnd` is the front end of
the bare array.
"""

from __future__ import annotations

from amaranth.hdl import Cat, Module, Signal
from amaranth.lib import wiring
from amaranth.lib.data import View
from amaranth.lib.wiring import In, Out

from rvsm.model.fixed.contract import ArrayContract
from rvsm.rtl.board.front_end import link_formats
from rvsm.rtl.board.receiver import LinkReceiver
from rvsm.rtl.board.spi_bridge import SpiBridge, SpiSignature
from rvsm.rtl.board.status import LINK_BASE, link_registers, register_values
from rvsm.rtl.board.transmitter import LinkTransmitter
from rvsm.rtl.ip.axis import spike_tdata_layout, video_lane_bits
from rvsm.rtl.ip.register_map import ADDR_BITS, RegisterMap
from rvsm.rtl.ip.wrapper import RvsmAxisIp
from rvsm.rtl.ports import verilog_ports
from rvsm.rtl.verilog_memories import convert_verilog

__all__ = ["IpBoardFrontEnd", "ip_front_end_verilog"]


class IpBoardFrontEnd(wiring.Component):
    """Receiver -> :class:`RvsmAxisIp` -> transmitter for ``contract`` at ``lanes``
    lanes, registers over SPI (module docstring).

    Ports: ``rx_clock``, ``rx_pins`` (receive link: ``rx_format.pairs`` pairs),
    ``tx_clock`` (transmit bit/edge clock), ``tx_pins``, ``tx_clock_out``,
    ``train_request``, ``spi`` In(:class:`SpiSignature`), ``tx_overflow`` (a beat met
    the transmitter's full FIFO: the transmit link is slower than the receive link).
    ``regmap``: the IP's map with the link registers; ``ip``, ``receiver``,
    ``transmitter``, ``bridge``: the parts."""

    def __init__(self, contract: ArrayContract, lanes: int,
                 fifo_depth: int = RvsmAxisIp.FIFO_DEPTH, primitive: str = "behavioural"):
        self.contract = contract
        self.primitive = primitive
        self.rx_format, self.tx_format = link_formats(contract, lanes)
        self.link_registers = link_registers(self.rx_format.pairs, LINK_BASE)
        self.ip = RvsmAxisIp(contract, lanes, fifo_depth, extra_registers=self.link_registers)
        self.geometry = self.ip.geometry
        self.regmap: RegisterMap = self.ip.regmap
        self.receiver = LinkReceiver(self.rx_format, primitive)
        self.transmitter = LinkTransmitter(self.tx_format, primitive)
        self.bridge = SpiBridge(ADDR_BITS)
        super().__init__({
            "rx_clock": In(1), "rx_pins": In(self.rx_format.pairs),
            "tx_clock": In(1), "tx_pins": Out(self.tx_format.pairs),
            "tx_clock_out": Out(1), "train_request": Out(1),
            "spi": In(SpiSignature()), "tx_overflow": Out(1),
        })

    @property
    def lag(self) -> int:
        """The IP's lag (beats): output ``p`` leaves after input beat ``p + lag``."""
        return self.ip.lag

    def elaborate(self, platform: object) -> Module:
        m = Module()
        rx, ip, tx, regs = self.receiver, self.ip, self.transmitter, self.ip.regs
        m.submodules.receiver, m.submodules.ip = rx, ip
        m.submodules.transmitter, m.submodules.bridge = tx, self.bridge
        wiring.connect(m, wiring.flipped(self.spi), self.bridge.spi)
        wiring.connect(m, self.bridge.bus, ip.s_axil)
        c, lanes = self.contract, self.geometry.lanes
        train = regs.value["LINK_CONTROL.train"]
        m.d.comb += [rx.clock.eq(self.rx_clock), rx.pins.eq(self.rx_pins),
                     tx.clock.eq(self.tx_clock), self.tx_pins.eq(tx.pins),
                     self.tx_clock_out.eq(tx.clock_out), self.tx_overflow.eq(tx.overflow),
                     tx.train.eq(train), rx.control.train.eq(train),
                     rx.control.counters_reset.eq(regs.pulse["LINK_CONTROL.counters_reset"]),
                     self.train_request.eq(train | ~rx.status.locked)]

        # receive beats -> s_axis: each lane's N code bits into its byte-padded slot
        beat, n, b = rx.beats.payload, c.adc_bits, video_lane_bits(c.adc_bits)
        for i in range(lanes):
            m.d.comb += ip.s_axis.tdata[i * b:i * b + n].eq(beat.payload[i * n:(i + 1) * n])
        m.d.comb += [ip.s_axis.tuser.eq(beat.sof), ip.s_axis.tlast.eq(beat.eol),
                     ip.s_axis.tvalid.eq(rx.beats.valid), rx.beats.ready.eq(ip.s_axis.tready)]

        # m_axis -> transmit beats: pos then neg; the position is implied by sof/eol
        out = View(spike_tdata_layout(c.num_scales, lanes, c.height, self.geometry.groups),
                   ip.m_axis.tdata)
        m.d.comb += [tx.beats.payload.payload.eq(Cat(out.pos, out.neg)),
                     tx.beats.payload.sof.eq(ip.m_axis.tuser),
                     tx.beats.payload.eol.eq(ip.m_axis.tlast),
                     tx.beats.valid.eq(ip.m_axis.tvalid),
                     ip.m_axis.tready.eq(tx.beats.ready)]

        # the link registers' live fields, registered
        request = Signal()
        m.d.comb += request.eq(self.train_request)
        values = register_values(rx.status, train, request)
        for reg in self.link_registers:
            for f in reg.fields:
                if f.live:
                    m.d.sync += regs.value[f"{reg.name}.{f.name}"].eq(
                        values[reg.name][f.lsb:f.lsb + f.width])
        return m


def ip_front_end_verilog(front_end: IpBoardFrontEnd, top: str = "rvsm_board_ip") -> str:
    """Verilog of ``front_end`` with module name ``top``: ports ``rx_clock``,
    ``rx_pins``, ``tx_clock``, ``tx_pins``, ``tx_clock_out``, ``train_request``,
    ``spi_sclk``, ``spi_cs_n``, ``spi_mosi``, ``spi_miso``, ``tx_overflow``, ``clk``,
    ``rst`` (:func:`rvsm.rtl.ports.verilog_ports`)."""
    return convert_verilog(front_end, top, verilog_ports(front_end))
