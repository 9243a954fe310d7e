"""Lane-to-lane deskew: per pair a short delay line, set when every pair sees MARK.

Each pair's aligned words may lag the others by whole words (skew of up to 7 bits
plus each pair's own word boundary). :class:`Deskew` takes, at each ``strobe``, one
word per pair; while ``start`` is high it notes the strobe at which each pair first
shows :data:`~rvsm.rtl.board.model.MARK` (counted from the first pair that does) and,
once all have, delays each pair by ``last - own`` words, so MARK leaves every pair at
the same strobe. Pairs more than ``DEPTH - 1`` words apart are not deskewed: the count
starts again at the next MARK (``retries`` counts it). ``start`` low clears it. Domain
``sync`` (renamed by the receiver).
"""

from __future__ import annotations

from amaranth.hdl import Array, Cat, Module, Mux, Signal, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from rvsm.rtl.board.model import MARK, WORD_BITS

__all__ = ["DEPTH", "Deskew"]

#: Delay line length per pair (words): pairs up to DEPTH - 1 words apart are deskewed.
DEPTH = 4


class Deskew(wiring.Component):
    """``pairs`` word lanes: ``words``, ``strobe``, ``start`` in; ``out`` (the deskewed
    words, registered at each strobe), ``done``, ``delays`` (words per pair) and a
    one-cycle ``retry`` out. ``latency``: one strobe period plus the chosen delay."""

    def __init__(self, pairs: int):
        self.pairs = pairs
        layout = data.ArrayLayout(unsigned(WORD_BITS), pairs)
        super().__init__({
            "words": In(layout), "strobe": In(1), "start": In(1),
            "out": Out(layout), "done": Out(1), "retry": Out(1),
            "delays": Out(data.ArrayLayout(unsigned(2), pairs)),
        })

    def elaborate(self, platform: object) -> Module:
        m = Module()
        n = self.pairs
        marked = Signal(n)
        arrive = [Signal(2, name=f"arrive{i}") for i in range(n)]
        count = Signal(2)
        last = Signal(2)
        running = Signal()
        settled = Signal()  # delays set; ``out`` follows them from the next strobe
        # Timing: the MARK compares and the delays are registered every cycle; ``words``
        # and the state change only at strobes (two cycles apart), so at every strobe
        # they equal their combinational values exactly.
        is_mark = Signal(n)
        m.d.sync += is_mark.eq(Cat(self.words[i] == MARK for i in range(n)))
        newly = is_mark & ~marked
        base = Signal(2)
        m.d.comb += base.eq(Mux(running, count, 0))
        for i in range(n):
            line = [Signal(WORD_BITS, name=f"line{i}_{d}") for d in range(DEPTH - 1)]
            taps = Array([self.words[i], *line])
            m.d.sync += self.delays[i].eq(last - arrive[i])
            with m.If(self.strobe):
                m.d.sync += [line[0].eq(self.words[i]),
                             *(line[d].eq(line[d - 1]) for d in range(1, DEPTH - 1)),
                             self.out[i].eq(taps[self.delays[i]])]
            with m.If(self.strobe & self.start & ~settled & newly[i]):
                m.d.sync += arrive[i].eq(base)
        m.d.sync += self.retry.eq(0)
        with m.If(~self.start):
            m.d.sync += [marked.eq(0), running.eq(0), self.done.eq(0), last.eq(0),
                         settled.eq(0)]
        with m.Elif(self.strobe & settled):
            m.d.sync += self.done.eq(1)
        with m.Elif(self.strobe & ~settled):
            with m.If((marked | newly).all()):
                m.d.sync += [settled.eq(1), last.eq(base), marked.eq(0), running.eq(0)]
            with m.Elif(running & (count == DEPTH - 1)):
                m.d.sync += [marked.eq(0), running.eq(0), self.retry.eq(1)]
            with m.Else():
                m.d.sync += marked.eq(marked | newly)
                with m.If(running | newly.any()):
                    m.d.sync += [running.eq(1), count.eq(base + 1)]
        return m
