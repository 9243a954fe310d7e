"""What the streaming array's property groups share (:mod:`.harnesses`): the output
beats expected from the accepted input beats and one symbolic word and scale of the
memories, watched (:func:`bookkeeping`, its record :class:`Watch`)."""

from __future__ import annotations

from dataclasses import dataclass

from amaranth.asserts import AnyConst
from amaranth.hdl import Module, Signal, Value

from rvsm.rtl.stream.array import RvsmStreamArray, StreamProbes
from rvsm.rtl.stream.harness_base import StreamHarness

__all__ = ["Watch", "bookkeeping"]


@dataclass(frozen=True)
class Watch:
    """What the property groups share: the probes, the accepted beats (``taken``), the
    next output position (``out_pos``), the expected write-back (``e1``, its position and
    whether it is in the first frame after a clear) and output (``e2``), the watched word
    and scale (``AnyConst``) and ``watched`` (the watched word is written back now)."""

    probes: StreamProbes
    taken: Value
    out_pos: Signal
    e1: Signal
    e1_pos: Signal
    e1_first: Signal
    e2: Signal
    e2_pos: Signal
    watch: Signal
    scale: Signal
    watched: Value


def bookkeeping(h: StreamHarness, m: Module, dut: RvsmStreamArray) -> Watch:
    """The output beats expected from the accepted ones, and the watched word and
    scale (:class:`Watch`), built in ``m`` by harness ``h`` around ``dut`` (its
    assumptions stated through ``h.check``)."""
    c, geo = h.contract, h.geometry
    words = geo.beats_per_frame
    taken = dut.codes.valid & dut.codes.ready
    clear = dut.clear
    # Output beats: accepted beat b >= lag releases position (b - lag) mod H*G at
    # the next edge (the write-back, e1) and presents it one cycle later (e2).
    releases = taken & h._beats(m, dut, geo.lag)
    out_pos = h._counter(m, "out_pos", clear, releases, words)
    first = Signal(init=1, name="first_frame")  # out_pos is in frame 0 after clear
    with m.If(clear):
        m.d.sync += first.eq(1)
    with m.Elif(releases & (out_pos == words - 1)):
        m.d.sync += first.eq(0)
    e1, e2 = Signal(name="exp_write"), Signal(name="exp_out")
    e1_pos, e2_pos = (Signal(range(words), name=n) for n in ("exp_write_pos",
                                                              "exp_out_pos"))
    e1_first = Signal(name="exp_write_first")
    m.d.sync += [e1.eq(releases), e1_pos.eq(out_pos), e1_first.eq(first),
                 e2.eq(e1), e2_pos.eq(e1_pos)]
    # Memories: one symbolic word and scale (``AnyConst``: the checks hold for
    # every word) is shadowed: thresholds as written (top rail at start) and, per
    # position, the word it must have read (at the edge after accepting beat
    # p + threshold_lag); accumulators as written back.
    watch = Signal(range(words), name="watch_word")
    m.d.comb += watch.eq(AnyConst(len(watch)))
    h.check(m, "assume.watch_word", watch < words,
               "the watched word exists", "assume")
    # ... and one symbolic scale: a shadow word of each kind in all.
    scale = Signal(range(max(2, c.num_scales)), name="watch_scale")
    m.d.comb += scale.eq(AnyConst(len(scale)))
    h.check(m, "assume.watch_scale", scale < c.num_scales,
               "the watched scale exists", "assume")
    return Watch(dut.probes, taken, out_pos, e1, e1_pos, e1_first, e2, e2_pos, watch,
                  scale, e1 & (e1_pos == watch))
