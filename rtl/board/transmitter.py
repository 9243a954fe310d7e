"""The transmitter: beats in the core domain to pins, with the receiver's framing.

:class:`LinkTransmitter` writes each beat (``payload``, ``sof``, ``eol``) into an
``LinkFifo`` (core domain ``sync`` -> its SCLK domain ``tx``; registered on
the ``tx`` side); there, one link word
per two SCLK cycles: training (for :data:`RESET_TRAINING` words after the ``tx``
reset, which follows the core domain's ``rst`` through a ``ResetSynchronizer``, and
while ``train`` is high), else a beat when the FIFO has one, else an idle
word (:mod:`rvsm.rtl.board.model`: TRAIN on the data pairs, framing ``SYNC << 4``). Each
word leaves as two 4-bit gear words, bits 0-3 first, through the
:class:`~rvsm.rtl.board.gearing.Serialiser`. A beat arriving while the FIFO is full is
lost and sets ``overflow`` (sticky). The link words of a beat are
:func:`~rvsm.rtl.board.model.beat_words`'.
"""

from __future__ import annotations

from amaranth.hdl import Cat, ClockDomain, Const, Module, Mux, ResetSignal, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.cdc import FFSynchronizer, ResetSynchronizer
from amaranth.lib.wiring import In, Out

from rvsm.rtl.board.gearing import Serialiser
from rvsm.rtl.board.link_fifo import LinkFifo
from rvsm.rtl.board.model import (
    EOL,
    GEAR_BITS,
    MARK,
    PARITY,
    SOF,
    SYNC,
    TRAIN,
    TRAIN_PERIOD,
    VALID,
    WORD_BITS,
    LinkFormat,
)
from rvsm.rtl.board.receiver import FIFO_DEPTH, beat_layout

__all__ = ["RESET_TRAINING", "LinkTransmitter"]

#: Training words sent after the transmitter's reset (four MARK periods).
RESET_TRAINING = 4 * TRAIN_PERIOD


class LinkTransmitter(wiring.Component):
    """Transmitter of a :class:`LinkFormat` link: ``beats`` (a stream in the core domain,
    always ready), ``train``, ``clock`` (the transmit bit/edge clock) in; ``pins``,
    ``clock_out`` (forwarded clock), ``overflow`` out."""

    def __init__(self, fmt: LinkFormat, primitive: str = "behavioural"):
        self.format = fmt
        self.primitive = primitive
        super().__init__({
            "beats": In(stream.Signature(beat_layout(fmt.payload_bits))),
            "train": In(1), "clock": In(1),
            "pins": Out(fmt.pairs), "clock_out": Out(1), "overflow": Out(1),
        })

    def elaborate(self, platform: object) -> Module:
        m = Module()
        fmt, n, f = self.format, self.format.pairs, self.format.framing_pair
        m.domains += ClockDomain("tx")  # its clock is the gearing's SCLK
        m.submodules.gearing = ser = Serialiser(n, self.primitive, "tx")
        m.d.comb += [ser.clock.eq(self.clock), self.pins.eq(ser.pins),
                     self.clock_out.eq(ser.clock_out)]
        m.submodules.tx_reset = ResetSynchronizer(ResetSignal("sync"), domain="tx")
        # the beat's parity is computed here, in the core domain, and crosses with it
        # (timing: not a wide XOR behind the FIFO's read port at the SCLK rate). Timing:
        # the beat is registered once with per-byte partial parities, and the FIFO is
        # written from those registers a core cycle later (the full-width XOR tree from
        # the array's registers to the FIFO's memory did not fit one core cycle).
        m.submodules.fifo = fifo = LinkFifo(fmt.payload_bits + 3, FIFO_DEPTH, "sync", "tx",
                                            link="r")
        raw = self.beats.payload.payload
        beat_r = Signal(fmt.payload_bits + 2)
        parts = Signal(-(-fmt.payload_bits // WORD_BITS))
        valid_r = Signal()
        m.d.sync += [beat_r.eq(self.beats.payload.as_value()), valid_r.eq(self.beats.valid),
                     parts.eq(Cat(raw[k:k + WORD_BITS].xor()
                                  for k in range(0, fmt.payload_bits, WORD_BITS)))]
        m.d.comb += [fifo.w_data.eq(Cat(beat_r, parts.xor())),
                     fifo.w_en.eq(valid_r), self.beats.ready.eq(1)]
        with m.If(valid_r & ~fifo.w_rdy):
            m.d.sync += self.overflow.eq(1)

        train = Signal()
        m.submodules.train_sync = FFSynchronizer(self.train, train, o_domain="tx")
        phase = Signal()
        left = Signal(range(RESET_TRAINING + 1), init=RESET_TRAINING)
        period = Signal(range(TRAIN_PERIOD))
        m.d.tx += phase.eq(~phase)
        # Timing: registered; ``left`` changes only at ~phase cycles (two apart), so at
        # each it is exact (``train``, a synchronised level, is one cycle later).
        training = Signal(init=1)
        busy = Signal(init=1)  # left != 0, registered likewise
        m.d.tx += [training.eq((left != 0) | train), busy.eq(left != 0)]
        payload = fifo.r_data[:fmt.payload_bits]
        sof, eol = fifo.r_data[fmt.payload_bits], fifo.r_data[fmt.payload_bits + 1]
        padded = Cat(payload, Const(0, fmt.data_pairs * WORD_BITS - fmt.payload_bits))
        parity = fifo.r_data[fmt.payload_bits + 2]
        beat_frame = Cat(Const(VALID, 1), sof, eol, parity, Const(SYNC, 4))
        assert (SOF, EOL, PARITY) == (2, 4, 8)
        train_word = Mux(period == TRAIN_PERIOD - 1, MARK, TRAIN)
        take = ~phase & ~training & fifo.r_rdy
        m.d.comb += fifo.r_en.eq(take)
        # Timing: the gear words are registered from ``word`` alone (the serialiser's
        # registers sit by the pins, far from the FIFO): the low half one cycle after
        # the word is chosen, the high half the cycle after.
        word = [Signal(WORD_BITS, name=f"word{k}") for k in range(n)]
        with m.If(~phase):
            with m.If(training):
                m.d.tx += period.eq(period + 1)
                with m.If(busy):
                    m.d.tx += left.eq(left - 1)
            for k in range(n):
                nxt = Mux(training, train_word, Mux(
                    fifo.r_rdy,
                    beat_frame if k == f else padded[WORD_BITS * k:WORD_BITS * (k + 1)],
                    Const(SYNC << 4, WORD_BITS) if k == f else Const(TRAIN, WORD_BITS)))
                m.d.tx += [word[k].eq(nxt), ser.words[k].eq(word[k][GEAR_BITS:])]
        with m.Else():
            for k in range(n):
                m.d.tx += ser.words[k].eq(word[k][:GEAR_BITS])
        return m
