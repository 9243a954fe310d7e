"""The bounded equivalence of the streaming and the parallel array (``rvsm formal --arch
stream --check equivalence``).

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

from amaranth.asserts import AnySeq
from amaranth.hdl import Array, Cat, Module, Mux, Signal, Value

from rvsm.model.fixed.contract import ArrayContract
from rvsm.rtl.formal_harness import ElaborateAfter
from rvsm.rtl.parallel.array import RvsmArray
from rvsm.rtl.stream.array import RvsmStreamArray, StreamProbes
from rvsm.rtl.stream.harness_base import StreamHarness
from rvsm.rtl.stream.signatures import threshold_word_bits, top_threshold_word

__all__ = ["StreamEquivalence"]


class StreamEquivalence(StreamHarness):
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
        p, tw = geo.lanes, c.threshold_bits
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
        if geo.shared_thresholds:  # one register per scale on both arrays
            scale, value = AnySeq(max(1, (c.num_scales - 1).bit_length())), AnySeq(tw)
            self.check(m, "assume.threshold_write",
                       ~we | (loading & ~taken & (value != 0) & (scale < c.num_scales)),
                       "thresholds (1 .. 2**(W-1)-1) are written only while no beat was "
                       "accepted since the last clear", "assume")
            m.d.comb += [dut.thr.we.eq(we), dut.thr.addr.eq(scale), dut.thr.data.eq(value),
                         ref.cfg.we.eq(we), ref.cfg.addr.eq(scale), ref.cfg.data.eq(value)]
            return self._reference_frames(m, dut, ref, taken, clear)
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
        return self._reference_frames(m, dut, ref, taken, clear)

    def _reference_frames(self, m: Module, dut: RvsmStreamArray, ref: RvsmArray,
                          taken: Value, clear: Value) -> Module:
        """The reference strobed with each whole frame, then the comparison."""
        c, geo = self.contract, self.geometry
        p, n, words = geo.lanes, c.adc_bits, geo.beats_per_frame
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
