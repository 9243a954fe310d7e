"""Formal checks of the streaming array (``rvsm formal --arch stream``).

Five checks, each one sby run of a harness driving
:class:`~rvsm.rtl.stream.array.RvsmStreamArray` from free inputs (``AnySeq``: codes,
``codes.valid``, ``clear``, threshold writes; no domain reset, which does what ``clear``
does; :class:`~rvsm.rtl.stream.harness_base.StreamHarness`), checked by bounded model
checking to two frames plus the lag plus two cycles (``2*H*G + lag + 2``): every input
sequence of that many clock cycles. This module holds the four property groups and the
factories of every check; the fifth, the miter with the parallel array, is
:class:`~rvsm.rtl.stream.equivalence_harness.StreamEquivalence`.

:class:`StreamProperties` states the protocol and the tail's arithmetic from the
harness's own bookkeeping (beats counted at the ports, shadows of one symbolic word of
the memories: an ``AnyConst`` word and scale, so the checks hold for every word; the
accumulator memories start with any contents, as RAM at power-up), observing the array's
internal :class:`~rvsm.rtl.stream.array.StreamProbes`. Stalls,
clears and threshold writes are free at every cycle. Its properties come in four groups
(:data:`PROPERTY_GROUPS`), each its own check so that sby keeps only that group's cone of
logic, and each stated by its own method (:meth:`StreamProperties._protocol`,
``_state``, ``_thresholds``, ``_tail``) from the bookkeeping they share
(:func:`~.property_watch.bookkeeping`):

* ``protocol``: ``handshake.ready`` (``codes.ready`` is low exactly while ``clear`` is
  high); ``output.one_per_beat`` (an output beat and its write-back exactly for each
  accepted beat from the ``lag``-th after a clear on, two cycles after its acceptance:
  none lost, none duplicated, none invented by a stall); ``output.raster_order``
  (positions ``row*G + group`` in raster order from 0 after each clear, ``last`` on a
  frame's last position); ``rmw.no_read_while_pending`` (no accumulator word is read
  while the write-back of its previous read is pending; a clear drops pending writes);
* ``state``: ``state.fresh_after_clear`` / ``state.read_back`` (the accumulator a
  position adds to is 0 in the first frame after a clear, else exactly what the
  previous frame wrote back to that word);
* ``thresholds``: ``threshold.read_timing`` (position ``p``'s state words are read at
  word ``p``, exactly at the edge after accepting beat ``p + threshold_lag``) and
  ``threshold.timing`` (a position compares against the threshold written last before
  that edge, as ``docs/stream-array.md`` says; thresholds start at the top rail),
  writes at any time; with stepping stones for the solver (smtbmc assumes each step's
  assertions in the later steps): ``threshold.memory`` (the memory's watched word,
  through its formal-only probe port, is what was written one edge after the bus),
  ``threshold.read_stage`` and ``threshold.compare_stage`` (the memory output and the
  tail's first stage hold the watched position's word);
* ``tail``: ``saturation.clamps`` (the saturated total is the pre-saturation total
  clamped to the rails: never wraps), ``fire.spike_implies_threshold`` /
  ``fire.threshold_implies_spike`` (+1 exactly when the total reached the threshold, -1
  only when it reached minus the threshold, never both),
  ``reset.<zero|subtract>`` (the word written back is what the reset mode leaves);
* covers (``--mode cover``): a +1 and a -1 spike and the high rail on every scale and
  lane, the low rail on some scale (from a cleared accumulator it takes a surround's
  large negative sums), a clear in mid-frame, a threshold write meeting the read of its
  word.
"""

from __future__ import annotations

from amaranth.asserts import AnySeq
from amaranth.hdl import Array, Cat, Module, Mux, Signal, Value, signed

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.widths import signed_range
from rvsm.rtl.capabilities import require_spike_sensor
from rvsm.rtl.formal_harness import ElaborateAfter
from rvsm.rtl.stream.array import RvsmStreamArray
from rvsm.rtl.stream.equivalence_harness import StreamEquivalence
from rvsm.rtl.stream.harness_base import StreamHarness
from rvsm.rtl.stream.property_watch import Watch, bookkeeping
from rvsm.rtl.stream.signatures import threshold_word_bits, top_threshold_word

__all__ = ["PROPERTY_GROUPS", "SYNTHESISED_GROUPS", "StreamProperties", "stream_check",
           "stream_equivalence"]


#: The property groups of :class:`StreamProperties`, each its own check (sby run).
PROPERTY_GROUPS = ("protocol", "state", "thresholds", "tail")
_GROUP_PREFIXES = {
    "protocol": ("handshake.", "output.", "rmw.", "cover.clear_mid_frame"),
    "state": ("state.",),
    "thresholds": ("threshold.", "cover.threshold_write_meets_read"),
    "tail": ("saturation.", "fire.", "reset.", "cover.spike_", "cover.saturate_"),
}
#: Groups whose bounded and cover checks run faster when yosys synthesises the model
#: before the solver sees it (smtbmc ``--syn``), measured at 3x4, P=2, dog2, depth 25
#: (docs/formal.md, "Times"): bmc ``protocol`` 48 -> 17 s, ``thresholds`` 79 -> 36 s,
#: ``tail`` 35 -> 27 s; ``state`` is slower with it (43 -> 156 s), as are the
#: equivalence miters (16 -> 22 s).
SYNTHESISED_GROUPS = frozenset({"protocol", "thresholds", "tail"})


class StreamProperties(StreamHarness):
    """The streaming array's protocol, memory and tail properties (module docstring);
    ``groups`` (:data:`PROPERTY_GROUPS`) chooses which are stated: a group's cone of
    logic is all sby keeps, so one group per check keeps each query small."""

    def __init__(self, contract: ArrayContract, lanes: int = 1,
                 mutation: str | None = None,
                 groups: tuple[str, ...] = PROPERTY_GROUPS) -> None:
        super().__init__(contract, lanes, mutation)
        unknown = set(groups) - set(PROPERTY_GROUPS)
        if unknown:
            raise ValueError(f"unknown property group {sorted(unknown)[0]!r}")
        self.groups = tuple(groups)

    #: The accumulator memories start with any contents (RAM at power-up): every
    #: property must hold from any RAM state, and a clear that misses a bank shows
    #: within the bound (``state.fresh_after_clear`` in the first frame).
    power_up_memories = ("dut.state_stage.acc_s*",)

    def smtbmc_options(self, mode: str) -> tuple[str, ...]:
        """``--syn`` in bmc and cover mode when every chosen group is one of
        :data:`SYNTHESISED_GROUPS`."""
        if mode in ("bmc", "cover") and set(self.groups) <= SYNTHESISED_GROUPS:
            return ("--syn",)
        return ()

    @staticmethod
    def group_of(name: str) -> str:
        """The group (:data:`PROPERTY_GROUPS`) of the property ``name``."""
        for group, prefixes in _GROUP_PREFIXES.items():
            if name.startswith(prefixes):
                return group
        raise ValueError(f"property {name!r} belongs to no group")

    def check(self, m: Module, name: str, test: Value, description: str,
              kind: str = "assert", src_loc_at: int = 0) -> None:
        """:meth:`FormalHarness.check` for the chosen groups' properties (and every
        assumption)."""
        if kind == "assume" or self.group_of(name) in self.groups:
            super().check(m, name, test, description, kind, src_loc_at + 1)

    def elaborate(self, platform: object) -> Module:
        m = Module()
        dut = self._array(m)
        geo, c = self.geometry, self.contract
        tw = c.threshold_bits
        words = geo.beats_per_frame
        wb = threshold_word_bits(words)
        m.d.comb += [dut.thr.we.eq(AnySeq(1)), dut.thr.addr.eq(AnySeq(len(dut.thr.addr))),
                     dut.thr.data.eq(AnySeq(len(dut.thr.data)))]
        per_word = len(dut.thr.data) // tw  # P thresholds, or one (shared thresholds)
        in_range = Cat(*[dut.thr.data[i * tw:(i + 1) * tw] != 0
                         for i in range(per_word)]).all()
        where = (dut.thr.addr < c.num_scales) if geo.shared_thresholds else (
            (dut.thr.addr[:wb] < words) & (dut.thr.addr[wb:] < c.num_scales))
        self.check(m, "assume.threshold_write", ~dut.thr.we | (in_range & where),
            "a threshold write holds thresholds in 1 .. 2**(W-1)-1 at an existing word "
            "and scale", "assume")
        m.submodules.properties = ElaborateAfter(lambda platform: self._properties(dut))
        return m

    def _properties(self, dut: RvsmStreamArray) -> Module:
        """Every group's properties (:meth:`check` keeps the chosen groups'), once the
        array is elaborated (its probes)."""
        m = Module()
        w = bookkeeping(self, m, dut)
        self._protocol(m, dut, w)
        self._thresholds(m, dut, w)
        c = self.contract
        # every lane's total and accumulator one advance earlier, at the write-back
        delayed = [[self._delayed(m, s, i, lane, w.probes.advance)
                    for i, lane in enumerate(lanes)] for s, lanes in enumerate(w.probes.lanes)]
        self._state(m, w, delayed)
        below = self._tail(m, w, delayed)
        if c.signed:
            # from a cleared accumulator the low rail takes a surround's large negative
            # sums: within two frames some scales (dog2's centre) cannot reach it
            self.check(m, "cover.saturate_low", Cat(*below).any(),
                       "a total below the low rail (some scale and lane)", "cover")
        return m

    def _protocol(self, m: Module, dut: RvsmStreamArray, w: Watch) -> None:
        """``handshake.*``, ``output.*``, ``rmw.*``, ``cover.clear_mid_frame``."""
        geo, probes = self.geometry, w.probes
        words = geo.beats_per_frame
        clear = dut.clear
        self.check(m, "handshake.ready", dut.codes.ready == ~clear,
                   "codes.ready is low exactly while clear is high")
        self.check(m, "output.one_per_beat",
                   (dut.spikes.valid == w.e2) & (probes.acc_write_en == w.e1),
                   "an output beat (and its write-back) for each accepted beat from the "
                   "lag-th after a clear on, two cycles after its acceptance")
        out = dut.spikes.payload
        self.check(m, "output.raster_order",
                   ~dut.spikes.valid | ((out.row * geo.groups + out.group == w.e2_pos)
                                        & (out.last == (w.e2_pos == words - 1))),
                   "output positions advance in raster order from 0 after a clear; last "
                   "marks a frame's last position")
        # Read-modify-write: a word read is pending until written back (or flushed).
        pending = Signal(words, name="acc_pending")
        read, write = probes.acc_read_valid, probes.acc_write_en
        self.check(m, "rmw.no_read_while_pending",
                   ~read | ~pending.bit_select(probes.acc_read_addr, 1),
                   "no accumulator word is read while the write-back of its previous read "
                   "is pending")
        for a in range(words):
            with m.If(probes.clear):
                m.d.sync += pending[a].eq(0)
            with m.Elif(read & (probes.acc_read_addr == a)):
                m.d.sync += pending[a].eq(1)
            with m.Elif(write & (probes.acc_write_addr == a)):
                m.d.sync += pending[a].eq(0)
        mid = clear & (w.out_pos != 0)
        self.check(m, "cover.clear_mid_frame", mid,
                   "a clear after some positions of a frame were output", "cover")

    def _thresholds(self, m: Module, dut: RvsmStreamArray, w: Watch) -> None:
        """``threshold.*`` and ``cover.threshold_write_meets_read``: the watched word's
        shadow as written, and as each position read it."""
        c, geo, probes = self.contract, self.geometry, w.probes
        p, words, tw = geo.lanes, geo.beats_per_frame, c.threshold_bits
        wb = threshold_word_bits(words)
        watch, scale = w.watch, w.scale
        top_word = top_threshold_word(tw, p)
        bus = dut.thr
        reads = w.taken & self._beats(m, dut, geo.threshold_lag)
        read_pos = self._counter(m, "thr_read_pos", dut.clear, reads, words)
        r1, r1_pos = Signal(name="thr_read"), Signal(range(words), name="thr_read_word")
        m.d.sync += [r1.eq(reads), r1_pos.eq(read_pos)]
        self.check(m, "threshold.read_timing",
                   (probes.acc_read_valid == r1) & (~r1 | (probes.acc_read_addr == r1_pos)),
                   "the state memories are read for position p, at word p, exactly at the "
                   "edge after accepting beat p + threshold_lag")
        p_we, p_addr = Signal(name="p_thr_we"), Signal.like(bus.addr, name="p_thr_addr")
        m.d.sync += [p_we.eq(bus.we), p_addr.eq(bus.addr)]
        self.check(m, "cover.threshold_write_meets_read",
                   r1 & p_we & (p_addr[:wb] == r1_pos),
                   "a threshold write lands at the edge that reads its word", "cover")
        shadow = Signal(p * tw, init=top_word, name="thr_shadow")
        with m.If(bus.we & (bus.addr[:wb] == watch)
                  & ((bus.addr[wb:] == scale) if c.num_scales > 1 else 1)):
            m.d.sync += shadow.eq(bus.data)
        # a stepping stone for the solver (each step's assertions are assumed in the
        # later steps): the memory's watched word, read through its formal-only probe
        # port, is the shadow one edge later (the bus is registered)
        shadow_d = Signal(p * tw, init=top_word, name="thr_shadow_d")
        m.d.sync += shadow_d.eq(shadow)
        memories = probes.threshold_memories
        m.d.comb += [memory.probe_addr.eq(watch) for memory in memories]
        self.check(m, "threshold.memory",
                   Array(memory.probe_data for memory in memories)[scale] == shadow_d,
                   "the threshold memory's watched word holds what was written to it, "
                   "one edge after the bus (the bus is registered)")
        # the watched word as each read found it: position p's read is the
        # (lag - threshold_lag)-th before its write-back (the reads of p+1 ..
        # p + lag - threshold_lag - 1 come between), so a delay line of reads suffices
        line = [Signal(p * tw, init=top_word, name=f"thr_seen{k}")
                for k in range(geo.lag - geo.threshold_lag)]
        with m.If(r1):
            m.d.sync += [line[0].eq(shadow)] + [line[k].eq(line[k - 1])
                                               for k in range(1, len(line))]
        seen = line[-1]
        by_scale = probes.lanes
        thr2 = Array(Cat(*[lane["thr2"] for lane in lanes]) for lanes in by_scale)[scale]
        # more stepping stones: the watched position's threshold word at each stage
        # of the tail (memory output after READ_STAGES advance edges from the read,
        # thr1 one edge later), tracked by tags moving at advance edges; a read a
        # stage on is one capture further down the delay line
        rs = geo.READ_STAGES
        tags = [Signal(name=f"thr_tag{k}") for k in range(1, rs + 2)]
        with m.If(probes.advance):
            m.d.sync += [tags[0].eq(r1 & (r1_pos == watch))] + [
                tags[k].eq(tags[k - 1]) for k in range(1, len(tags))]
        with m.If(probes.clear):
            m.d.sync += [tag.eq(0) for tag in tags]
        self.check(m, "threshold.read_stage",
                   ~tags[rs - 1] | (Array(memory.data for memory in memories)[scale]
                                    == line[rs - 1]),
                   "the memories deliver the watched position's threshold word as read")
        thr1 = Array(Cat(*[lane["thr1"] for lane in lanes]) for lanes in by_scale)[scale]
        self.check(m, "threshold.compare_stage", ~tags[rs] | (thr1 == line[rs]),
                   "the tail's first stage holds the watched position's threshold word")
        self.check(m, "threshold.timing", ~w.watched | (thr2 == seen),
                   "a position compares against the threshold written last before the "
                   "edge after accepting beat p + threshold_lag")

    def _delayed(self, m: Module, s: int, i: int, lane: dict[str, Value],
                 advance: Value) -> tuple[Signal, Signal]:
        """``(p_total, p_acc)``: lane ``i`` of scale ``s``'s total and accumulator one
        advance earlier, what the write-back cycle (e1) compares against."""
        total, wa = lane["total"], self.contract.accumulator_bits
        p_total = Signal.like(total, name=f"p_total_s{s}_l{i}")
        acc = Signal(signed(wa), name=f"acc_s{s}_l{i}")  # with total
        p_acc = Signal(signed(wa), name=f"p_acc_s{s}_l{i}")
        with m.If(advance):
            m.d.sync += [p_total.eq(total), acc.eq(lane["acc"]), p_acc.eq(acc)]
        return p_total, p_acc

    def _state(self, m: Module, w: Watch,
               delayed: list[list[tuple[Signal, Signal]]]) -> None:
        """``state.*``: the accumulator each position adds to (0 in a fresh frame, else
        what the previous frame wrote back to the watched word)."""
        wa = self.contract.accumulator_bits
        acc_shadow = Signal(self.geometry.lanes * wa, name="acc_shadow")
        after = Array(Cat(*[lane["after"].as_unsigned()[:wa] for lane in lanes])
                      for lanes in w.probes.lanes)[w.scale]
        with m.If(w.watched):
            m.d.sync += acc_shadow.eq(after)
        for s, lanes in enumerate(delayed):
            for i, (_, p_acc) in enumerate(lanes):
                previous = acc_shadow[i * wa:(i + 1) * wa].as_signed()
                self.check(m, "state.fresh_after_clear", ~w.e1 | ~w.e1_first | (p_acc == 0),
                           "in the first frame after a clear every accumulator reads as 0")
                self.check(m, "state.read_back",
                           ~(w.watched & (w.scale == s)) | w.e1_first | (p_acc == previous),
                           "after the first frame a position adds to exactly what the "
                           "previous frame wrote back to its word")

    def _tail(self, m: Module, w: Watch,
              delayed: list[list[tuple[Signal, Signal]]]) -> list[Value]:
        """``saturation.*``, ``fire.*``, ``reset.*`` and the tail's covers, per lane in the
        cycle its position is written back (e1). Returns per lane "its total is below the
        low rail now"."""
        c = self.contract
        lo, hi = signed_range(c.accumulator_bits)
        e1, below = w.e1, []
        for lanes, delays in zip(w.probes.lanes, delayed, strict=True):
            for lane, (p_total, _) in zip(lanes, delays, strict=True):
                thr, sat = lane["thr2"], lane["sat"]
                pos, neg, after = lane["pos"], lane["neg"], lane["after"]
                clamped = Mux(p_total > hi, hi, Mux(p_total < lo, lo, p_total))
                self.check(m, "saturation.clamps", ~e1 | (sat == clamped),
                           "the saturated total is the total clamped to the rails (never "
                           "wraps)")
                fired_ok = ~pos | (p_total >= thr)
                fired_ok &= ~neg | ((p_total <= -thr) & ~pos) if c.signed else ~neg
                self.check(m, "fire.spike_implies_threshold", ~e1 | fired_ok,
                           "a +1 spike only when the pre-saturation total reached the "
                           "threshold, a -1 only when it reached minus the threshold, never "
                           "both")
                # (the converse for -1, a total at or below minus the threshold fires -1,
                # made this check take minutes instead of seconds: the equivalence check
                # covers it)
                self.check(m, "fire.threshold_implies_spike", ~e1 | (p_total < thr) | pos,
                           "a total at or above the threshold fires +1")
                if c.reset == "zero":
                    expected = Mux(pos | neg, 0, sat)
                else:
                    expected = Mux(pos, sat - thr, Mux(neg, sat + thr, sat))
                self.check(m, f"reset.{c.reset}",
                           ~e1 | (after.as_unsigned()[:c.accumulator_bits]
                                  == expected.as_unsigned()[:c.accumulator_bits]),
                           f"the word written back is what reset mode {c.reset!r} leaves")
                self.check(m, "cover.spike_pos", e1 & pos,
                           "a +1 spike on every scale and lane", "cover")
                if c.signed:
                    self.check(m, "cover.spike_neg", e1 & neg,
                               "a -1 spike on every scale and lane", "cover")
                self.check(m, "cover.saturate_high", e1 & (p_total > hi),
                           "a total above the high rail (every scale and lane)", "cover")
                below.append(e1 & (p_total < lo))
        return below


def stream_check(group: str):
    """The factory of check ``group`` (:data:`PROPERTY_GROUPS`) of
    :data:`~rvsm.rtl.stream.STREAM`: ``factory(contract, mutation=None, lanes=1)``."""
    if group not in PROPERTY_GROUPS:
        raise ValueError(f"unknown property group {group!r}")

    def factory(contract: ArrayContract, mutation: str | None = None, lanes: int = 1,
                **options: int) -> StreamProperties:
        require_spike_sensor(contract, "the formal properties")
        return StreamProperties(contract, lanes, mutation, groups=(group,))

    factory.__name__ = f"stream_{group}"
    factory.__doc__ = f"The ``{group!r}`` properties of the streaming array."
    return factory


def stream_equivalence(contract: ArrayContract, mutation: str | None = None,
                       lanes: int = 1, **options: int) -> StreamEquivalence:
    """The ``"equivalence"`` harness factory of :data:`~rvsm.rtl.stream.STREAM`."""
    require_spike_sensor(contract, "the formal properties")
    return StreamEquivalence(contract, lanes, mutation)
