"""Word alignment of one pair: 4-bit gear words to 8-bit link words, bit slip on TRAIN.

:class:`WordAligner` keeps the last 16 bits of its pair (four gear words) and, at every
``strobe`` (every other SCLK: one link word per core cycle), registers the 8-bit window
starting ``slip`` bits into them (``slip`` 0..7). While searching it compares the
window with :data:`~rvsm.rtl.board.model.TRAIN`: a match counts, a
:data:`~rvsm.rtl.board.model.MARK` is neutral, anything else moves ``slip`` on by one
bit and starts the count again; :data:`GOOD_WORDS` matches in a row make the pair
``aligned``. ``restart`` drops the alignment. Since TRAIN's eight rotations differ, one
slip matches; any bit slip of the incoming stream is found within 8 wrong words plus
the count. Domain ``sync`` (the receiver renames it to its SCLK domain).
"""

from __future__ import annotations

from amaranth.hdl import Cat, Module, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from rvsm.rtl.board.model import GEAR_BITS, MARK, TRAIN, WORD_BITS

__all__ = ["GOOD_WORDS", "WordAligner"]

#: Consecutive TRAIN words (MARK neutral) that make a pair aligned.
GOOD_WORDS = 4


class WordAligner(wiring.Component):
    """One pair's word aligner: ``gear`` (4 bits a cycle, bit 0 first), ``strobe`` (take
    a word this cycle), ``search`` (look for TRAIN while not aligned), ``restart`` in;
    ``word`` (registered at each strobe), ``window`` (the word a strobe now would take;
    registered, valid at strobes: strobes are at least two cycles apart),
    ``aligned``, ``slip`` out. ``latency``: cycles from a word's last gear bits to
    ``word`` (at most one strobe period, 2)."""

    latency = 2

    def __init__(self) -> None:
        super().__init__({
            "gear": In(GEAR_BITS), "strobe": In(1), "search": In(1), "restart": In(1),
            "word": Out(WORD_BITS), "window": Out(WORD_BITS), "aligned": Out(1),
            "slip": Out(3),
        })

    def elaborate(self, platform: object) -> Module:
        m = Module()
        hist = Signal(4 * GEAR_BITS)
        good = Signal(range(GOOD_WORDS))
        nxt = Cat(hist[GEAR_BITS:], self.gear)
        m.d.sync += hist.eq(nxt)
        # Timing: the window is registered from the next history every cycle; ``slip``
        # changes only at a strobe and strobes are two cycles apart, so at every strobe
        # it equals hist.bit_select(slip) exactly. The TRAIN/MARK compares are
        # registered for all eight slips (off the slip loop); at a strobe ``slip`` only
        # picks one, so the loop slip -> compare -> slip is a mux and the decision.
        windows = [nxt[s:s + WORD_BITS] for s in range(WORD_BITS)]
        trains, marks = Signal(WORD_BITS), Signal(WORD_BITS)
        m.d.sync += [self.window.eq(nxt.bit_select(self.slip, WORD_BITS)),
                     trains.eq(Cat(w == TRAIN for w in windows)),
                     marks.eq(Cat(w == MARK for w in windows))]
        is_train, is_mark = trains.bit_select(self.slip, 1), marks.bit_select(self.slip, 1)
        with m.If(self.strobe):
            m.d.sync += self.word.eq(self.window)
        with m.If(self.restart):
            m.d.sync += [self.aligned.eq(0), good.eq(0)]
        with m.Elif(self.strobe & self.search & ~self.aligned):
            with m.If(is_train):
                m.d.sync += good.eq(good + 1)
                with m.If(good == GOOD_WORDS - 1):
                    m.d.sync += self.aligned.eq(1)
            with m.Elif(~is_mark):
                m.d.sync += [good.eq(0), self.slip.eq(self.slip + 1)]
        return m
