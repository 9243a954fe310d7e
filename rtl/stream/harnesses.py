"""Formal checks of the streaming array (``rvsm formal --arch stream``).

Five checks, each one sby run of a harness driving
:class:`~rvsm.rtl.stream.array.RvsmStreamArray` from free inputs (``AnySeq``: codes,
``codes.valid``, ``clear``, threshold writes; no domain reset, which does what ``clear``
does), checked by bounded model checking to :attr:`_StreamHarness.depth` = two frames
plus the lag plus two cycles (``2*H*G + lag + 2``): every input sequence of that many
clock cycles.

:class:`StreamProperties` states the protocol and the tail's arithmetic from the
harness's own bookkeeping (beats counted at the ports, shadows of one symbolic word of
the memories: an ``AnyConst`` word and scale, so the checks hold for every word; the
accumulator memories start with any contents, as RAM at power-up), observing the array's
internal :class:`~rvsm.rtl.stream.array.StreamProbes`. Stalls,
clears and threshold writes are free at every cycle. Its properties come in four groups
(:data:`PROPERTY_GROUPS`), each its own check so that sby keeps only that group's cone of
logic:

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

:class:`StreamEquivalence` (check ``"equivalence"``) is a miter: the same symbolic codes
and thresholds drive the streaming array and the fully parallel
:class:`~rvsm.rtl.parallel.array.RvsmArray` (itself proven against the contract's integer
rules by :mod:`rvsm.rtl.parallel.harnesses`), which gets each frame at once when its last
beat is accepted. Every accumulator the stream writes back and every spike it outputs
must equal the parallel array's for the same frame and position
(``equivalence.accumulators``, ``equivalence.spikes``; ``..._early`` for positions the
stream finishes before the parallel array has their frame, when ``lag < H*G``).
Thresholds are written (free scale, word, lane and value) while no beat has been
accepted since the start. The stream runs back to back (``codes.valid`` high, no clear):
with free stalls the solver must relate every alignment of beats to cycles and the
check does not finish in minutes; stalls and clears are the protocol, state and
threshold checks' subject, and :attr:`StreamEquivalence.inputs` allows them for a longer
run.
"""

from __future__ import annotations

from amaranth.asserts import AnyConst, AnySeq
from amaranth.hdl import Array, Cat, Module, Mux, ResetSignal, Signal, Value, signed

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.widths import signed_range
from rvsm.rtl.capabilities import require_spike_sensor
from rvsm.rtl.formal_harness import ElaborateAfter, FormalHarness
from rvsm.rtl.mutations import check_mutation
from rvsm.rtl.parallel.array import RvsmArray
from rvsm.rtl.stream.array import RvsmStreamArray, StreamProbes
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.signatures import threshold_word_bits, top_threshold_word

__all__ = ["PROPERTY_GROUPS", "StreamEquivalence", "StreamProperties", "stream_check",
           "stream_equivalence"]


class _StreamHarness(FormalHarness):
    """What both harnesses share: the array, its free inputs and the beat bookkeeping."""

    provable = False

    def __init__(self, contract: ArrayContract, lanes: int = 1,
                 mutation: str | None = None) -> None:
        super().__init__()
        self.contract = contract
        self.geometry = StreamGeometry(contract, lanes)
        self.mutation = check_mutation(mutation, "stream")
        #: The most cycles with a stall (``codes.valid`` low) and with ``clear`` high
        #: within the bound (``"stalls"``, ``"clears"``; a missing key: any number).
        self.inputs: dict[str, int] = {}
        geo = self.geometry
        #: Two frames plus the lag, plus the two cycles from acceptance to output.
        self.depth = 2 * geo.beats_per_frame + geo.lag + 2
        self.cover_depth = self.depth

    def _array(self, m: Module) -> RvsmStreamArray:
        dut = RvsmStreamArray(self.contract, self.geometry.lanes, mutation=self.mutation)
        m.submodules.dut = dut
        self.check(m, "assume.no_domain_reset", ~ResetSignal("sync"),
                   "the domain reset is not used (it restarts the stream like clear)",
                   "assume")
        valid, clear = AnySeq(1), AnySeq(1)
        m.d.comb += [dut.codes.payload.eq(AnySeq(len(dut.codes.payload.as_value()))),
                     dut.codes.valid.eq(valid), dut.clear.eq(clear)]
        for name, event in (("stalls", ~valid), ("clears", clear)):
            limit = self.inputs.get(name)
            if limit is None:
                continue
            count = Signal(range(limit + 2), name=f"{name}_so_far")
            with m.If(event & (count <= limit)):
                m.d.sync += count.eq(count + 1)
            self.check(m, f"assume.{name}", ~event | (count < limit),
                       f"at most {limit} cycles with {name[:-1]} in the bound", "assume")
        return dut

    def _counter(self, m: Module, name: str, clear: Value, step: Value,
                 modulo: int) -> Signal:
        """A counter of ``step`` s modulo ``modulo``, 0 after ``clear``."""
        count = Signal(range(modulo), name=name)
        with m.If(clear):
            m.d.sync += count.eq(0)
        with m.Elif(step):
            m.d.sync += count.eq(Mux(count == modulo - 1, 0, count + 1))
        return count

    def _beats(self, m: Module, dut: RvsmStreamArray, lag: int) -> Value:
        """``accepted beats since the last clear >= lag`` (a counter saturating at lag)."""
        seen = Signal(range(lag + 1), name=f"beats_to_{lag}")
        taken = dut.codes.valid & dut.codes.ready
        with m.If(dut.clear):
            m.d.sync += seen.eq(0)
        with m.Elif(taken & (seen < lag)):
            m.d.sync += seen.eq(seen + 1)
        return seen >= lag


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


class StreamProperties(_StreamHarness):
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
    power_up_memories = ("dut.state.acc_s*",)

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
        tw, p = c.threshold_bits, geo.lanes
        words = geo.beats_per_frame
        wb = threshold_word_bits(words)
        m.d.comb += [dut.thr.we.eq(AnySeq(1)), dut.thr.addr.eq(AnySeq(len(dut.thr.addr))),
                     dut.thr.data.eq(AnySeq(len(dut.thr.data)))]
        in_range = Cat(*[dut.thr.data[i * tw:(i + 1) * tw] != 0 for i in range(p)]).all()
        self.check(m, "assume.threshold_write", ~dut.thr.we | (
            in_range & (dut.thr.addr[:wb] < words) & (dut.thr.addr[wb:] < c.num_scales)),
            "a threshold write holds thresholds in 1 .. 2**(W-1)-1 at an existing word "
            "and scale", "assume")
        m.submodules.properties = ElaborateAfter(lambda platform: self._properties(dut))
        return m

    def _properties(self, dut: RvsmStreamArray) -> Module:
        m = Module()
        c, geo = self.contract, self.geometry
        probes: StreamProbes = dut.probes
        p, words, wa, tw = geo.lanes, geo.beats_per_frame, c.accumulator_bits, \
            c.threshold_bits
        wb = threshold_word_bits(words)
        lo, hi = signed_range(wa)
        taken = dut.codes.valid & dut.codes.ready
        clear = dut.clear

        self.check(m, "handshake.ready", dut.codes.ready == ~clear,
                   "codes.ready is low exactly while clear is high")

        # Output beats: accepted beat b >= lag releases position (b - lag) mod H*G at
        # the next edge (the write-back, e1) and presents it one cycle later (e2).
        releases = taken & self._beats(m, dut, geo.lag)
        out_pos = self._counter(m, "out_pos", clear, releases, words)
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
        self.check(m, "output.one_per_beat",
                   (dut.spikes.valid == e2) & (probes.acc_write_en == e1),
                   "an output beat (and its write-back) for each accepted beat from the "
                   "lag-th after a clear on, two cycles after its acceptance")
        out = dut.spikes.payload
        self.check(m, "output.raster_order",
                   ~dut.spikes.valid | ((out.row * geo.groups + out.group == e2_pos)
                                        & (out.last == (e2_pos == words - 1))),
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

        # Memories: one symbolic word and scale (``AnyConst``: the checks hold for
        # every word) is shadowed: thresholds as written (top rail at start) and, per
        # position, the word it must have read (at the edge after accepting beat
        # p + threshold_lag); accumulators as written back.
        watch = Signal(range(words), name="watch_word")
        m.d.comb += watch.eq(AnyConst(len(watch)))
        self.check(m, "assume.watch_word", watch < words,
                   "the watched word exists", "assume")
        top_word = top_threshold_word(tw, p)
        bus = dut.thr
        reads = taken & self._beats(m, dut, geo.threshold_lag)
        read_pos = self._counter(m, "thr_read_pos", clear, reads, words)
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
        mid = clear & (out_pos != 0)
        self.check(m, "cover.clear_mid_frame", mid,
                   "a clear after some positions of a frame were output", "cover")

        # ... and one symbolic scale: a shadow word of each kind in all.
        scale = Signal(range(max(2, c.num_scales)), name="watch_scale")
        m.d.comb += scale.eq(AnyConst(len(scale)))
        self.check(m, "assume.watch_scale", scale < c.num_scales,
                   "the watched scale exists", "assume")
        watched = e1 & (e1_pos == watch)
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
        by_scale = [probes.lanes[s] for s in range(c.num_scales)]
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
        self.check(m, "threshold.timing", ~watched | (thr2 == seen),
                   "a position compares against the threshold written last before the "
                   "edge after accepting beat p + threshold_lag")
        acc_shadow = Signal(p * wa, name="acc_shadow")
        after = Array(Cat(*[lane["after"].as_unsigned()[:wa] for lane in lanes])
                      for lanes in by_scale)[scale]
        with m.If(watched):
            m.d.sync += acc_shadow.eq(after)
        below = [self._lane(m, s, i, lane, probes, e1, e1_first, watched & (scale == s),
                            acc_shadow[i * wa:(i + 1) * wa].as_signed(), lo, hi)
                 for s, lanes in enumerate(by_scale) for i, lane in enumerate(lanes)]
        if c.signed:
            # from a cleared accumulator the low rail takes a surround's large negative
            # sums: within two frames some scales (dog2's centre) cannot reach it
            self.check(m, "cover.saturate_low", Cat(*below).any(),
                       "a total below the low rail (some scale and lane)", "cover")
        return m

    def _lane(self, m: Module, s: int, i: int, lane: dict[str, Value],
              probes: StreamProbes, e1: Signal, e1_first: Signal, watched: Value,
              previous: Value, lo: int, hi: int) -> Value:
        """One lane's tail properties in the cycle its position is written back (e1):
        ``p_total`` / ``p_acc`` are the total and accumulator one advance earlier.
        Returns "this lane's total is below the low rail now"."""
        c = self.contract
        total, thr, sat = lane["total"], lane["thr2"], lane["sat"]
        pos, neg, after = lane["pos"], lane["neg"], lane["after"]
        p_total = Signal.like(total, name=f"p_total_s{s}_l{i}")
        acc = Signal(signed(c.accumulator_bits), name=f"acc_s{s}_l{i}")  # with total
        p_acc = Signal(signed(c.accumulator_bits), name=f"p_acc_s{s}_l{i}")
        with m.If(probes.advance):
            m.d.sync += [p_total.eq(total), acc.eq(lane["acc"]), p_acc.eq(acc)]
        self.check(m, "state.fresh_after_clear", ~e1 | ~e1_first | (p_acc == 0),
                   "in the first frame after a clear every accumulator reads as 0")
        self.check(m, "state.read_back", ~watched | e1_first | (p_acc == previous),
                   "after the first frame a position adds to exactly what the previous "
                   "frame wrote back to its word")
        clamped = Mux(p_total > hi, hi, Mux(p_total < lo, lo, p_total))
        self.check(m, "saturation.clamps", ~e1 | (sat == clamped),
                   "the saturated total is the total clamped to the rails (never wraps)")
        fired_ok = ~pos | (p_total >= thr)
        fired_ok &= ~neg | ((p_total <= -thr) & ~pos) if c.signed else ~neg
        self.check(m, "fire.spike_implies_threshold", ~e1 | fired_ok,
                   "a +1 spike only when the pre-saturation total reached the threshold, "
                   "a -1 only when it reached minus the threshold, never both")
        # (the converse for -1, a total at or below minus the threshold fires -1, made
        # this check take minutes instead of seconds: the equivalence check covers it)
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
        return e1 & (p_total < lo)


class StreamEquivalence(_StreamHarness):
    """The miter of the streaming and the parallel array (module docstring): a
    back-to-back stream (``codes.valid`` high, no ``clear`` after the start) unless
    ``inputs`` allows stalls and clears."""

    def __init__(self, contract: ArrayContract, lanes: int = 1,
                 mutation: str | None = None,
                 inputs: dict[str, int] | None = None) -> None:
        super().__init__(contract, lanes, mutation)
        self.inputs = {"stalls": 0, "clears": 0} if inputs is None else dict(inputs)

    def elaborate(self, platform: object) -> Module:
        m = Module()
        dut = self._array(m)
        c, geo = self.contract, self.geometry
        p, n, tw = geo.lanes, c.adc_bits, c.threshold_bits
        words, hw = geo.beats_per_frame, c.height * c.width
        wb = threshold_word_bits(words)
        ref = RvsmArray(c)
        m.submodules.ref = ref
        taken = dut.codes.valid & dut.codes.ready
        clear = dut.clear
        m.d.comb += ref.clear.eq(clear)

        # Threshold writes: one threshold (scale, word, lane, value) while loading.
        loading = ~self._beats(m, dut, 1)
        we = AnySeq(1)
        scale, word = AnySeq(max(1, (c.num_scales - 1).bit_length())), AnySeq(wb)
        lane, value = AnySeq(max(1, (p - 1).bit_length())), AnySeq(tw)
        self.check(m, "assume.threshold_write",
                   ~we | (loading & ~taken & (value != 0) & (scale < c.num_scales)
                          & (word < words) & (lane < p)),
                   "thresholds (1 .. 2**(W-1)-1) are written only while no beat was "
                   "accepted since the last clear", "assume")
        shadow = [Array(Signal(p * tw, init=top_threshold_word(tw, p),
                               name=f"thr_shadow_s{s}_w{w}") for w in range(words))
                  for s in range(c.num_scales)]
        word_now = Signal(p * tw, name="thr_word_now")
        m.d.comb += word_now.eq(Array(shadow)[scale][word])
        data = Cat(*[Mux(lane == i, value, word_now[i * tw:(i + 1) * tw])
                     for i in range(p)])
        m.d.comb += [dut.thr.we.eq(we), dut.thr.addr.eq(Cat(word, scale) if c.num_scales > 1
                                                         else word),
                     dut.thr.data.eq(data),
                     ref.cfg.we.eq(we), ref.cfg.addr.eq(scale * hw + word * p + lane),
                     ref.cfg.data.eq(value)]
        for s in range(c.num_scales):
            with m.If(we & (scale == s)):
                m.d.sync += shadow[s][word].eq(data)

        # The reference gets a frame when its last beat is accepted.
        in_pos = self._counter(m, "in_pos", clear, taken, words)
        frame = [Signal(p * n, name=f"frame_w{w}") for w in range(words)]
        beat = dut.codes.payload.as_value()
        for w in range(words):
            with m.If(taken & (in_pos == w)):
                m.d.sync += frame[w].eq(beat)
        m.d.comb += [ref.codes.eq(Cat(*frame[:-1], beat)),
                     ref.strobe.eq(taken & (in_pos == words - 1))]

        m.submodules.compare = ElaborateAfter(lambda platform: self._compare(dut, ref))
        return m

    def _compare(self, dut: RvsmStreamArray, ref: RvsmArray) -> Module:
        """The comparison, once both arrays are elaborated (the cells, the probes)."""
        m = Module()
        c, geo = self.contract, self.geometry
        p, words, hw = geo.lanes, geo.beats_per_frame, c.height * c.width
        clear = dut.clear
        # Reference frames (spikes and the accumulators after them) wait in a ring
        # until the stream outputs the same frame.
        depth = geo.lag // words + 2
        n_acc = c.num_scales * hw
        wa = c.accumulator_bits
        cells = [ref.cells[k] for k in range(n_acc)]
        record = Cat(ref.spike_pos, ref.spike_neg, *[cell.acc for cell in cells])
        ring = Array(Signal(len(record), name=f"ref_frame{k}") for k in range(depth))
        head = Signal(range(depth), name="ref_head")   # next frame the reference gives
        with m.If(ref.valid):
            m.d.sync += [ring[head].eq(record),
                         head.eq(Mux(head == depth - 1, 0, head + 1))]

        def fields(frame: Value, w: int) -> tuple[Value, Value, Value]:
            """(pos, neg, accumulators) of position ``w`` in a ring entry, in the
            stream's order: scale-major, then lane."""
            ks = [s * hw + w * p + i for s in range(c.num_scales) for i in range(p)]
            return (Cat(*[frame[k] for k in ks]), Cat(*[frame[n_acc + k] for k in ks]),
                    Cat(*[frame[2 * n_acc + k * wa:2 * n_acc + (k + 1) * wa] for k in ks]))

        # Write-back (probes, the cycle before the output) and output: each has a
        # pointer to the ring entry of the frame it is in and a count of frames the
        # reference has given and it has not finished.
        out = dut.spikes.payload
        probes: StreamProbes = dut.probes
        wr_pos = Signal(range(words), name="wr_pos")
        m.d.comb += wr_pos.eq(probes.acc_write_addr)
        after = Cat(*[lane["after"].as_unsigned()[:wa]
                      for lanes in probes.lanes for lane in lanes])
        spikes = Cat(out.pos, out.neg)
        clear_d = Signal(name="clear_d")
        m.d.sync += clear_d.eq(clear)
        compared = Signal(range(3), name="frames_compared")
        for kind, (event, position, value) in {
                "accumulators": (probes.acc_write_en, wr_pos, after),
                "spikes": (dut.spikes.valid, out.row * geo.groups + out.group,
                           spikes)}.items():
            part = 2 if kind == "accumulators" else slice(0, 2)

            def reference(frame: Value, w: int, part=part) -> Value:
                return Cat(*fields(frame, w)[part]) if isinstance(part, slice) \
                    else fields(frame, w)[part]

            tail = Signal(range(depth), name=f"{kind}_frame")
            ready = Signal(range(depth + 1), name=f"{kind}_ready")
            # compared at the event when the reference has the frame (lag >= H*G) ...
            here = Array(reference(ring[tail], w) for w in range(words))[position]
            what = ("every spike the stream outputs" if kind == "spikes" else
                    "every accumulator the stream writes back")
            description = (f"{what} equals the parallel array's for the same frame and "
                           "position (same codes and thresholds)")
            same = ~event | (ready == 0) | (value == here)
            if kind == "spikes":  # one statement per source line: sby names lines
                self.check(m, "equivalence.spikes", same, description)
            else:
                self.check(m, "equivalence.accumulators", same, description)
            # ... else kept until the reference gives the frame (lag < H*G)
            got = [Signal(len(value), name=f"{kind}_got_w{w}") for w in range(words)]
            emitted = Signal(words, name=f"{kind}_emitted")
            early = event & (ready == 0)
            for w in range(words):
                with m.If(early & (position == w)):
                    m.d.sync += [got[w].eq(value), emitted[w].eq(1)]
            late = ref.valid & (ready == 0)
            now_ok = ~event | (value == Array(reference(record, w)
                                              for w in range(words))[position])
            same = ~late | (now_ok & Cat(*[
                ~emitted[w] | (got[w] == reference(record, w)) for w in range(words)
            ]).all())
            description += (", for positions the stream finished before the parallel "
                            "array had their frame (lag < H*G): compared when it has")
            if kind == "spikes":
                self.check(m, "equivalence.spikes_early", same, description)
            else:
                self.check(m, "equivalence.accumulators_early", same, description)
            done = event & (position == words - 1)
            with m.If(clear_d):
                # a clear drops the frames in flight: realign one cycle later (beats
                # accepted before it are still output in the cycle after the clear)
                m.d.sync += [tail.eq(head), ready.eq(ref.valid), emitted.eq(0)]
            with m.Else():
                with m.If(done):
                    m.d.sync += [tail.eq(Mux(tail == depth - 1, 0, tail + 1)),
                                 emitted.eq(0)]
                m.d.sync += ready.eq(ready + ref.valid - done)
            if kind == "spikes":
                with m.If(done & (compared != 2)):
                    m.d.sync += compared.eq(compared + 1)
                self.check(m, "cover.two_frames_compared", done & (compared == 1),
                           "the bound reaches the end of a second frame's comparison",
                           "cover")
        return m


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
