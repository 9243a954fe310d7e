"""The board front end: pixel codes in over the receive link, spikes out over the
transmit link, the streaming array between them.

:class:`BoardFrontEnd` joins :class:`~rvsm.rtl.board.receiver.LinkReceiver` (beats of
``P*N`` code bits) -> :class:`~rvsm.rtl.stream.array.RvsmStreamArray` (its ``codes``
stream natively: the receiver's FIFO is read while the array is ready) ->
:class:`~rvsm.rtl.board.transmitter.LinkTransmitter` (beats of ``2*S*P`` spike bits:
``pos`` then ``neg``, bit ``s*P + i``; positions implied by ``sof``/``eol``). The
array's threshold bus and ``clear`` stay ports, as on the bare array; the core and the
AXI IP remain usable without this front end. ``framing_errors`` counts accepted beats
whose ``sof``/``eol`` disagree with the array's position (counted from the last
``clear``); ``train_request`` is the pin asking the sensor for training.
"""

from __future__ import annotations

import numpy as np
from amaranth.hdl import Cat, Module, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from rvsm.model.fixed.contract import ArrayContract
from rvsm.rtl.board.model import LinkFormat
from rvsm.rtl.board.receiver import LinkReceiver
from rvsm.rtl.board.status import LinkControlSignature, LinkStatusSignature
from rvsm.rtl.board.transmitter import LinkTransmitter
from rvsm.rtl.ports import verilog_ports
from rvsm.rtl.stream.array import RvsmStreamArray
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.verilog_memories import convert_verilog

__all__ = ["BoardFrontEnd", "front_end_verilog", "link_formats"]

#: Bits of the framing error counter (saturating).
FRAMING_BITS = 16


def link_formats(contract: ArrayContract, lanes: int) -> tuple[LinkFormat, LinkFormat]:
    """The receive link (``P*N`` code bits a beat) and the transmit link (``2*S*P``
    spike bits a beat) of the front end."""
    return (LinkFormat(lanes * contract.adc_bits),
            LinkFormat(2 * contract.num_scales * lanes))


class BoardFrontEnd(wiring.Component):
    """Receiver -> streaming array -> transmitter for ``contract`` at ``lanes`` lanes.

    Ports: ``rx_clock``, ``rx_pins`` (receive link), ``tx_clock`` (transmit bit/edge
    clock), ``tx_pins``, ``tx_clock_out``, ``train_request``; ``thr`` and ``clear`` (the
    array's); ``status``, ``control``, ``framing_errors``, ``tx_overflow``. Core clock
    domain ``sync``; ``primitive``: the gearing (:mod:`rvsm.rtl.board.gearing`)."""

    def __init__(self, contract: ArrayContract, lanes: int, primitive: str = "behavioural"):
        self.contract = contract
        self.geometry = StreamGeometry(contract, lanes)
        self.primitive = primitive
        self.rx_format, self.tx_format = link_formats(contract, self.geometry.lanes)
        array_sig = RvsmStreamArray.interface(contract, self.geometry.lanes)
        super().__init__({
            "rx_clock": In(1), "rx_pins": In(self.rx_format.pairs),
            "tx_clock": In(1), "tx_pins": Out(self.tx_format.pairs),
            "tx_clock_out": Out(1), "train_request": Out(1),
            "thr": array_sig.members["thr"], "clear": In(1),
            "status": Out(LinkStatusSignature(self.rx_format.pairs)),
            "control": In(LinkControlSignature()),
            "framing_errors": Out(FRAMING_BITS), "tx_overflow": Out(1),
        })

    @property
    def lag(self) -> int:
        """The array's lag (beats): output ``p`` leaves after input beat ``p + lag``."""
        return self.geometry.lag

    def threshold_writes(self, thresholds: np.ndarray) -> list[tuple[int, int]]:
        """``(thr_addr, thr_data)`` of every threshold write for thresholds ``(S, H, W)``
        (the array's, :meth:`StreamGeometry.threshold_writes`)."""
        return self.geometry.threshold_writes(thresholds)

    def elaborate(self, platform: object) -> Module:
        m = Module()
        geo = self.geometry
        m.submodules.receiver = rx = LinkReceiver(self.rx_format, self.primitive)
        m.submodules.array = array = RvsmStreamArray(self.contract, geo.lanes)
        m.submodules.transmitter = tx = LinkTransmitter(self.tx_format, self.primitive)
        m.d.comb += [rx.clock.eq(self.rx_clock), rx.pins.eq(self.rx_pins),
                     tx.clock.eq(self.tx_clock), self.tx_pins.eq(tx.pins),
                     self.tx_clock_out.eq(tx.clock_out), self.tx_overflow.eq(tx.overflow),
                     tx.train.eq(self.control.train),
                     self.train_request.eq(self.control.train | ~rx.status.locked)]
        wiring.connect(m, rx.status, wiring.flipped(self.status))
        wiring.connect(m, wiring.flipped(self.control), rx.control)
        wiring.connect(m, wiring.flipped(self.thr), array.thr)
        m.d.comb += array.clear.eq(self.clear)

        # receive beats -> the array's codes; framing checked against the position
        beat = rx.beats.payload
        m.d.comb += [array.codes.payload.as_value().eq(beat.payload),
                     array.codes.valid.eq(rx.beats.valid), rx.beats.ready.eq(array.codes.ready)]
        position = Signal(range(geo.beats_per_frame))
        group = Signal(range(geo.groups))
        accepted = rx.beats.valid & rx.beats.ready
        with m.If(self.clear):
            m.d.sync += [position.eq(0), group.eq(0)]
        with m.Elif(accepted):
            last = position == geo.beats_per_frame - 1
            m.d.sync += [position.eq(0 if geo.beats_per_frame == 1 else
                                     (position + 1) * ~last),
                         group.eq((group + 1) * (group != geo.groups - 1))]
            wrong = (beat.sof != (position == 0)) | (beat.eol != (group == geo.groups - 1))
            with m.If(wrong & (self.framing_errors != (1 << FRAMING_BITS) - 1)):
                m.d.sync += self.framing_errors.eq(self.framing_errors + 1)

        # the array's spikes -> transmit beats
        out = array.spikes.payload
        m.d.comb += [tx.beats.payload.payload.eq(Cat(out.pos, out.neg)),
                     tx.beats.payload.sof.eq((out.row == 0) & (out.group == 0)),
                     tx.beats.payload.eol.eq(out.group == geo.groups - 1),
                     tx.beats.valid.eq(array.spikes.valid)]
        return m


def front_end_verilog(front_end: BoardFrontEnd, top: str = "rvsm_board") -> str:
    """Verilog of ``front_end`` with module name ``top``; ports named as
    :func:`rvsm.rtl.ports.verilog_ports` (``rx_pins``, ``status_locked``, ``thr_we``, ...)
    plus ``clk`` and ``rst`` of the core domain."""
    return convert_verilog(front_end, top, verilog_ports(front_end))
