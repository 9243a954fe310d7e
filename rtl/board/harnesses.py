"""Formal harnesses of the link's word alignment and deskew (docs/formal.md, "Links").

Both drive their block from a *transmitter* the harness models: free words (``AnySeq``)
under the protocol's assumptions, sent through a free but constant skew (``AnyConst``),
and compare what the block gives with what was sent. They are checked with the
project's sby flow (:func:`rvsm.sim.formal.sby.run_sby`, ``multiclock off``: one step
is one edge of the link's SCLK domain, which both blocks live in).

* :class:`AlignerProperties` (:class:`~rvsm.rtl.board.aligner.WordAligner`): 4-bit gear
  words of a bit stream delayed by ``delay`` bits (0..7: every bit slip against the
  strobe), ``strobe`` every other step as in the receiver. ``stream="training"``: the
  first :data:`TRAIN_WORDS` words are TRAIN, with MARK anywhere at least
  :data:`MARK_SPACING` words apart, then any words; ``align.in_time`` (aligned from the
  :data:`ALIGN_WORDS`-th word on), ``align.slip`` (aligned only at the slip that frames
  the sent words), ``align.window`` / ``align.word`` (the window at every strobe and the
  registered word after it are the sent word). ``stream="no_train"``: any words whose
  received bit stream never shows TRAIN at any offset, ``search`` and ``restart``
  free; ``align.needs_train`` (never aligned).
* :class:`DeskewProperties` (:class:`~rvsm.rtl.board.deskew.Deskew`): ``pairs`` lanes,
  lane ``i`` delayed by ``lag_i`` (0..DEPTH-1 words, ``AnyConst``), MARK on every lane
  at once at least :data:`MARK_SPACING` strobes apart and never otherwise, ``strobe``
  and ``start`` free; ``deskew.delays`` (once ``done`` each lane waits
  ``max(lag) - lag_i``), ``deskew.same_cycle`` (once ``done`` every lane's output is the
  word sent ``max(lag)`` strobes before: all from one transmit cycle),
  ``deskew.in_time`` (``done`` by :data:`DESKEW_STROBES` strobes after a MARK sent while
  ``start`` stays high).
"""

from __future__ import annotations

from collections.abc import Callable

from amaranth.asserts import AnyConst, AnySeq
from amaranth.hdl import Array, Cat, Module, Mux, Signal, Value

from rvsm.rtl.board.aligner import WordAligner
from rvsm.rtl.board.deskew import DEPTH, Deskew
from rvsm.rtl.board.model import GEAR_BITS, MARK, TRAIN, WORD_BITS
from rvsm.rtl.formal_harness import FormalHarness

__all__ = ["ALIGN_WORDS", "DESKEW_STROBES", "MARK_SPACING", "STREAMS", "TRAIN_WORDS",
           "AlignerProperties", "DeskewProperties"]

#: Training words the aligner harness sends before any words.
TRAIN_WORDS = 16
#: Words (from the first) after which the aligner must be aligned, every slip.
ALIGN_WORDS = 14
#: Least words between two MARKs the harnesses send (the protocol: 16).
MARK_SPACING = 8
#: Strobes after the one that sends a MARK (``start`` high) by which ``Deskew`` is ``done``.
DESKEW_STROBES = DEPTH
#: The aligner harness's streams.
STREAMS = ("training", "no_train")


def _saturating(m: Module, name: str, limit: int, step: Value, clear: Value | None = None,
                init: int = 0) -> Signal:
    """A counter of ``step`` s stopping at ``limit``, 0 after ``clear``."""
    count = Signal(range(limit + 1), name=name, init=init)
    with m.If(step & (count != limit)):
        m.d.sync += count.eq(count + 1)
    if clear is not None:
        with m.If(clear):
            m.d.sync += count.eq(0)
    return count


class AlignerProperties(FormalHarness):
    """One :class:`WordAligner` (built by ``aligner``, a mutant in the tests) fed a bit
    stream delayed by a free constant ``delay`` bits (module docstring)."""

    provable = False

    def __init__(self, stream: str = "training",
                 aligner: Callable[[], WordAligner] = WordAligner) -> None:
        super().__init__()
        if stream not in STREAMS:
            raise ValueError(f"stream must be one of {STREAMS}, got {stream!r}")
        self.stream = stream
        self.aligner = aligner
        #: Steps (SCLK edges) checked: the training and a few data words after it.
        self.depth = 2 * TRAIN_WORDS + 8 if stream == "training" else 28
        self.cover_depth = 2 * ALIGN_WORDS + 2

    def elaborate(self, platform: object) -> Module:
        m = Module()
        m.submodules.dut = dut = self.aligner()
        delay = AnyConst(3)  # bits the received stream lags the sent one
        # the transmitter: word k in steps 2k (bits 0-3) and 2k+1 (bits 4-7)
        half = Signal()
        m.d.sync += half.eq(~half)
        sent = _saturating(m, "words_sent", TRAIN_WORDS, half)  # words completed
        held, word = Signal(WORD_BITS), Signal(WORD_BITS)
        fresh = AnySeq(WORD_BITS)
        m.d.comb += word.eq(Mux(half, held, fresh))
        m.d.sync += held.eq(word)
        if self.stream == "training":
            since = _saturating(m, "since_mark", MARK_SPACING, ~half, init=MARK_SPACING,
                                clear=~half & (word == MARK))
            training = (word == TRAIN) | ((word == MARK) & (since == MARK_SPACING))
            self.check(m, "assume.training", half | (sent == TRAIN_WORDS) | training,
                       "the first words are TRAIN, MARK at least MARK_SPACING apart",
                       "assume")
        gear = Mux(half, word[GEAR_BITS:], word[:GEAR_BITS])
        sent_bits = Signal(3 * GEAR_BITS)  # the last three gear words sent
        m.d.sync += sent_bits.eq(Cat(sent_bits[GEAR_BITS:], gear))
        line = Cat(sent_bits, gear)
        rx = Signal(GEAR_BITS)
        m.d.comb += rx.eq(Array(line[12 - k:16 - k] for k in range(8))[delay])
        strobe = half  # as the receiver's phase: a word at every other step
        m.d.comb += [dut.gear.eq(rx), dut.strobe.eq(strobe)]
        if self.stream == "no_train":
            self._no_train(m, dut, rx)
        else:
            self._training(m, dut, delay, word, half, sent)
        return m

    def _training(self, m: Module, dut: WordAligner, delay: Value, word: Value,
                  half: Value, sent: Value) -> None:
        m.d.comb += [dut.search.eq(1), dut.restart.eq(0)]
        older, oldest = Signal(WORD_BITS), Signal(WORD_BITS)
        with m.If(half):
            m.d.sync += [older.eq(word), oldest.eq(older)]
        # at a strobe (step 2k+1) the window of slip delay ^ 4 holds sent word k-1
        # (delay < 4) or k-2
        expected = Mux(delay < 4, older, oldest)
        right_slip = delay ^ 4
        self.check(m, "align.in_time", (sent < ALIGN_WORDS) | dut.aligned,
                   f"aligned once {ALIGN_WORDS} words are sent, every slip")
        self.check(m, "align.slip", ~dut.aligned | (dut.slip == right_slip),
                   "aligned only at the slip that frames the sent words")
        self.check(m, "align.window", ~(half & dut.aligned) | (dut.window == expected),
                   "once aligned the window at every strobe is the sent word")
        was, then = Signal(), Signal(WORD_BITS)
        m.d.sync += [was.eq(half & dut.aligned), then.eq(expected)]
        self.check(m, "align.word", ~was | (dut.word == then),
                   "once aligned the word registered at a strobe is the sent word")
        for k in range(8):
            self.check(m, "cover.aligned_every_slip", dut.aligned & (delay == k),
                       "aligned at each of the 8 stream delays", "cover")

    def _no_train(self, m: Module, dut: WordAligner, rx: Value) -> None:
        m.d.comb += [dut.search.eq(AnySeq(1)), dut.restart.eq(AnySeq(1))]
        got = Signal(3 * GEAR_BITS)  # the last three gear words received
        m.d.sync += got.eq(Cat(got[GEAR_BITS:], rx))
        seen = Cat(got, rx)
        clean = Cat(seen[k:k + WORD_BITS] != TRAIN for k in range(9)).all()
        self.check(m, "assume.no_train", clean,
                   "TRAIN at no offset of the received bit stream", "assume")
        self.check(m, "align.needs_train", ~dut.aligned,
                   "never aligned on a stream without TRAIN")


class DeskewProperties(FormalHarness):
    """:class:`Deskew` of ``pairs`` lanes, each delayed by a free constant ``lag_i``
    words (module docstring)."""

    provable = False

    def __init__(self, pairs: int = 3, deskew: Callable[[int], Deskew] = Deskew,
                 free_strobe: bool = False) -> None:
        super().__init__()
        self.pairs = pairs
        self.free_strobe = free_strobe
        self.deskew = deskew
        #: Steps checked: two MARK periods and the deskew after them, at a strobe every
        #: other cycle (the receiver's word rate: the deskew registers its MARK compares
        #: and delays between strobes).
        self.depth = 2 * (2 * MARK_SPACING + DESKEW_STROBES + 4)
        self.cover_depth = self.depth

    def elaborate(self, platform: object) -> Module:
        m = Module()
        n = self.pairs
        m.submodules.dut = dut = self.deskew(n)
        # strobes at most every other cycle, as the receiver gives them
        phase = Signal()
        m.d.sync += phase.eq(~phase)
        strobe = Signal()
        if self.free_strobe:
            was = Signal()
            m.d.comb += strobe.eq(AnySeq(1))
            m.d.sync += was.eq(strobe)
            self.check(m, "assume.strobe_spacing", ~(strobe & was),
                       "no two strobes in consecutive cycles")
        else:
            m.d.comb += strobe.eq(phase)
        start, mark = Signal(), AnySeq(1)
        with m.If(strobe):  # start changes at strobes, as the receiver's link FSM's
            m.d.sync += start.eq(AnySeq(1))
        m.d.comb += [dut.strobe.eq(strobe), dut.start.eq(start)]
        lags = [AnyConst(2) for _ in range(n)]
        most: Value = lags[0]
        for lag in lags[1:]:
            most = Mux(lag > most, lag, most)
        latest = Signal(2)
        m.d.comb += latest.eq(most)
        since = _saturating(m, "since_mark", MARK_SPACING, strobe, init=MARK_SPACING,
                            clear=strobe & mark)
        self.check(m, "assume.mark_spacing", ~(strobe & mark) | (since == MARK_SPACING),
                   "MARK on every lane at once, at least MARK_SPACING strobes apart",
                   "assume")
        outs = []
        for i in range(n):
            # one free bit a word picks TRAIN or 0: any sequence, no stray MARK
            # the word of this strobe period, held between strobes as the receiver's
            # words are (drawn at the strobe before)
            sent = Signal(WORD_BITS, name=f"sent{i}")
            with m.If(strobe):
                m.d.sync += sent.eq(Mux(mark, MARK, Mux(AnySeq(1), TRAIN, 0)))
            past = [Signal(WORD_BITS, name=f"sent{i}_{k}") for k in range(1, DEPTH)]
            with m.If(strobe):
                m.d.sync += [past[0].eq(sent),
                             *(past[k].eq(past[k - 1]) for k in range(1, DEPTH - 1))]
            taps = Array([sent, *past])
            m.d.comb += dut.words[i].eq(taps[lags[i]])
            expected = Signal(WORD_BITS, name=f"expected{i}")
            with m.If(strobe):
                m.d.sync += expected.eq(taps[latest])
            outs.append((dut.out[i], expected, dut.delays[i], lags[i]))
        for out, expected, delay, lag in outs:
            # the delays and MARK compares are registered between strobes: the lane
            # words are checked where the receiver takes them, at its strobes
            self.check(m, "deskew.delays", ~strobe | ~dut.done | (delay == latest - lag),
                       "once done each lane waits max(lag) - its lag words (at strobes)")
            self.check(m, "deskew.same_cycle", ~strobe | ~dut.done | (out == expected),
                       "once done every lane gives the word sent max(lag) strobes before "
                       "(at strobes)")
        # strobes since a MARK shown to the deskew while start has stayed high (0: none);
        # a MARK drawn at a strobe is shown from that strobe to the next
        shown = Signal()
        with m.If(strobe):
            m.d.sync += shown.eq(mark)
        after = Signal(range(DESKEW_STROBES + 2), name="after_mark")
        with m.If(~start):
            m.d.sync += after.eq(0)
        with m.Elif(strobe & (after == 0) & shown):
            m.d.sync += after.eq(1)
        with m.Elif(strobe & (after != 0) & (after != DESKEW_STROBES + 1)):
            m.d.sync += after.eq(after + 1)
        self.check(m, "deskew.in_time", (after <= DESKEW_STROBES) | dut.done,
                   f"done {DESKEW_STROBES} strobes after a MARK sent while start is high")
        self.check(m, "cover.done_at_full_skew",
                   dut.done & (latest == DEPTH - 1) & Cat(lag == 0 for lag in lags).any(),
                   "done with lanes DEPTH - 1 words apart", "cover")
        self.check(m, "cover.retry", dut.retry, "a deskew started again", "cover")
        return m
