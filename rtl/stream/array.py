"""The lane-parallel streaming RVSM pixel array, built from one :class:`ArrayContract`.

Where :class:`~rvsm.rtl.parallel.array.RvsmArray` builds an adder network and an accumulator per
(scale, pixel), this array streams the frame through ``P`` lanes: the datapath is
O(P), and only the state memories grow with the sensor. One clock domain ``sync``
(synchronous reset ``rst``)::

    codes (P ADC codes per beat, raster order, valid/ready)
      -> line buffer (one memory, depth W/P, word 2L rows x P codes)
      -> window register: 2E+1 column-group slabs of 2L+1 rows       [stage 0]
      -> zero padding by registered row/column masks                  [stage 1]
      -> per lane: 8-fold symmetric orbit sums, shared by all scales
      -> per scale: constant CSD shift-and-add tree, registered every
         LEVELS_PER_STAGE adder levels, equal depth for all scales    [stage Q]
      -> acc (+ >> shift) from the accumulator memory (banked, bank
         outputs registered; zero in the first frame after clear)    [Q+1]
      -> compare (on the pre-saturation total) and saturate           [Q+2]
      -> fire / reset -> write back to the accumulator memory;
         spikes + position registered on the output stream           [Q+3]

L is the kernel radius (:func:`~rvsm.model.kernels.geometry.kernel_radius`), E =
``ceil(L / P)`` the column groups a window reaches either side, G = ``W / P``.

**State.** Per scale one accumulator memory (word = P signed W-bit accumulators) and one
threshold memory (word = P thresholds of W-1 bits), depth ``H*G``, address ``y*G + g``,
each a :class:`~rvsm.rtl.stream.banked_memory.BankedMemory` split into banks of at most
:attr:`StreamGeometry.bank_words` words (a power of two, 1024 by default) whose read
data is registered before the bank multiplexer (ECP5 block-RAM timing). Each address is
read and written once per frame, :attr:`StreamGeometry.rmw_depth` beats apart, so the
read-modify-write needs no forwarding as long as ``H*G > rmw_depth`` (checked). A bank's
read is disabled when its write port writes the same address at that edge (no read-first
bypass multiplexer after the block RAM); threshold writes are registered and forwarded
after the bank registers to a read meeting them, so the rule below holds.

**Streams.** ``codes`` (:func:`~rvsm.rtl.stream.signatures.code_beat_signature`):
``payload`` lane ``i`` = pixel ``(y, g*P + i)``; a beat is accepted at a rising edge
with ``valid & ready``; ``ready`` is low only while ``clear`` is high. Accepted beats
and ``clear`` pass an input register (no combinational path from the ports into the
datapath), and the whole pipeline advances once per accepted beat, at the edge after its
acceptance (a clock enable), so a paused input holds everything in flight. ``spikes``
(:func:`spike_beat_signature`, no back-pressure): ``valid`` is high for the one cycle
after the edge that releases a position; ``payload.row``/``group`` is the position,
``last`` marks the frame's last beat, bit ``s*P + i`` of ``pos``/``neg`` the +1/-1 spike
of accumulator ``(s, y, g*P + i)``. The output of position ``p`` (beats counted from the
last clear) is released by input beat ``p + lag``: it is presented in the second cycle
after that beat's acceptance. To drain a stream, send ``lag`` more beats (any codes) and
wait one more cycle. :mod:`rvsm.rtl.stream.schedule` is the numpy model of this
schedule.

**Frame-boundary meaning of the controls.**

* ``clear`` (synchronous, any number of cycles): discards every position in flight and
  restarts the stream: the next accepted beat is frame 0, row 0, group 0, and every
  accumulator reads as zero during the first frame after it (the memories are not
  swept; that frame's read-modify-write overwrites each word). Thresholds are kept.
  The domain reset does the same. ``clear`` between frames, after draining, therefore
  equals :meth:`ArrayContract.run` restarted at that frame.
* ``thr`` (the shared :class:`~rvsm.rtl.interfaces.ThresholdWriteSignature`: ``we``,
  ``addr = (s << word_bits) | (y*G + g)``, ``data`` = P thresholds, lane ``i`` at
  ``[i*(W-1) +: W-1]``): writes one threshold word at the rising edge, at any
  time. Position ``p`` reads its thresholds at the edge after the one accepting input
  beat ``p + threshold_lag`` (a write at that same edge is not seen). So thresholds
  written while
  the stream is paused after ``t*H*G + threshold_lag`` accepted beats apply exactly from
  frame ``t`` on (:meth:`StreamSchedule.threshold_pause_beat`); written after a clear
  and before the first beat (as a loader does), they apply from frame 0. The threshold
  memories start (at configuration: block-RAM initial contents) with every threshold at
  the top rail ``2**(W-1)-1``, like the parallel array after its reset, so an array
  whose thresholds were never loaded fires only at saturation instead of reading
  undefined data; neither ``rst`` nor ``clear`` reloads them (a block RAM has no reset).

The bit-accurate model is :meth:`ArrayContract.run`, rearranged into beats by
:class:`~rvsm.rtl.stream.schedule.StreamSchedule`; the component is driven in
``amaranth.sim`` by :mod:`rvsm.rtl.stream.drive`.
"""

from __future__ import annotations

from dataclasses import dataclass

from amaranth.hdl import Cat, Const, Module, Mux, ResetSignal, Signal, Value, signed, unsigned
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from rvsm.model.fixed.contract import ArrayContract
from rvsm.rtl.fpga.ecp5_memory import ECP5_PLATFORM, kept_register
from rvsm.rtl.mutations import check_mutation
from rvsm.rtl.stream.banked_memory import BankedMemory
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.pipelined_sum import Pipeline, Timed
from rvsm.rtl.stream.schedule import StreamSchedule
from rvsm.rtl.stream.signatures import (
    code_beat_signature,
    spike_beat_signature,
    threshold_word_bits,
    threshold_write_signature,
    top_threshold_word,
)

__all__ = ["RvsmStreamArray"]


@dataclass(frozen=True)
class _Centre:
    """The window centre at stage 0: valid bit, row, column group, address, whether it is
    in the first frame after a clear, whether it is a frame's last position, and the
    registered padding masks (one bit per window row / column)."""

    valid0: Signal
    yc: Signal
    gc: Signal
    ac: Signal
    fresh0: Signal
    last0: Value
    row_ok: Signal
    col_ok: Signal
    next_addr: Value


@dataclass(frozen=True)
class _Tail:
    """What the state memories and the tail need from the position pipeline
    (``rd_addr_next``: the value ``rd_addr`` takes at the next edge if this cycle
    advances, and if it does not; ``fresh_prev``: ``fresh_q`` one stage before, for
    copies of it; ``wr_valid_next``: the value ``valid`` takes at the next edge)."""

    rd_addr: Value
    rd_addr_next: tuple[Value, Value]
    rd_valid: Value
    bank_q: Value
    fresh_q: Value
    fresh_prev: Value
    wr_addr: Value
    wr_en: Value
    wr_valid_next: Value
    valid: Signal
    row: Value
    group: Value
    last: Value
    valid_at: list[Signal]  # the valid bit of every stage (0 .. the tail)


@dataclass
class StreamProbes:
    """Internal signals a formal harness observes (:mod:`rvsm.rtl.stream.harnesses`), set
    when the array is elaborated: ``advance`` (the pipeline steps at this edge),
    ``clear`` (the registered clear that flushes it), the accumulator memories' read
    (``acc_read_addr`` sampled at an ``advance`` edge where ``acc_read_valid``) and
    write-back (``acc_write_en``, ``acc_write_addr``), and per scale and lane the tail's
    registers (``lanes[s][i]``: ``acc`` (the accumulator read, 0 in a fresh frame; the
    value ``total`` is loaded from), ``total``, ``thr1``, ``sat``, ``thr2``, ``pos``, ``neg``,
    ``after``: the pre-saturation total, the threshold read, the saturated total, that
    threshold one stage on, the spikes and the value written back), valid in a cycle
    where ``acc_write_en`` is high; ``threshold_memories``: per scale the threshold
    :class:`BankedMemory` (its formal-only ``probe_addr``/``probe_data``)."""

    advance: Signal
    clear: Signal
    acc_read_addr: Value
    acc_read_valid: Value
    acc_write_en: Value
    acc_write_addr: Value
    lanes: list[list[dict[str, Value]]]
    threshold_memories: list[BankedMemory]
    window: dict[tuple[int, int], Value]
    window_valid: Value
    sums: list[list[Value]]
    sum_valid: Value


class RvsmStreamArray(wiring.Component):
    """``S x H x W`` accumulators fed by a ``lanes``-wide raster stream of ADC codes.

    Members: ``codes`` In(:func:`code_beat_signature`), ``spikes``
    Out(:func:`spike_beat_signature`), ``thr`` In(:func:`threshold_write_signature`),
    ``clear`` In(1); Verilog ports ``codes_payload``, ``codes_valid``, ``codes_ready``,
    ``spikes_payload``, ``spikes_valid``, ``thr_we``, ``thr_addr``, ``thr_data``,
    ``clear`` (:mod:`rvsm.rtl.ports`, described by :meth:`port_docs`). See the module
    docstring for the schedule and the controls; sizes and the named timing properties
    are in :attr:`geometry` (:class:`StreamGeometry`).
    """

    def __init__(self, contract: ArrayContract, lanes: int = 1,
                 bank_words: int = StreamGeometry.BANK_WORDS, mutation: str | None = None):
        geo = StreamGeometry(contract, lanes, bank_words)
        #: A deliberate bug (:mod:`rvsm.rtl.mutations`) or None (the shipped logic).
        self.mutation = check_mutation(mutation, "stream")
        self.geometry = geo
        self.contract = contract
        self.lanes = geo.lanes
        self.groups = geo.groups
        #: Internal signals for formal harnesses (:class:`StreamProbes`), set by
        #: :meth:`elaborate`.
        self.probes: StreamProbes | None = None
        super().__init__(self.interface(contract, geo.lanes))

    @staticmethod
    def interface(contract: ArrayContract, lanes: int) -> wiring.Signature:
        """The array's signature for ``contract`` and ``lanes`` (no component needed)."""
        c = contract
        geo = StreamGeometry(c, lanes)
        return wiring.Signature({
            "codes": In(code_beat_signature(c.adc_bits, geo.lanes)),
            "spikes": Out(spike_beat_signature(c.num_scales, geo.lanes, c.height,
                                               geo.groups)),
            "thr": In(threshold_write_signature(c.num_scales, geo.beats_per_frame,
                                                geo.lanes, c.threshold_bits)),
            "clear": In(1),
        })

    @staticmethod
    def port_docs(contract: ArrayContract, lanes: int) -> dict[str, str]:
        """Meaning of every Verilog port (names as :func:`rvsm.rtl.ports.port_map`)."""
        c = contract
        geo = StreamGeometry(c, lanes)
        p, n, g = geo.lanes, c.adc_bits, geo.groups
        wb = threshold_word_bits(geo.beats_per_frame)
        return {
            "clk": "clock (rising edge)",
            "rst": "synchronous reset: the state after a clear (memories untouched)",
            "codes_payload": f"ADC codes of one beat: lane i = pixel (y, g*{p} + i) at bits "
                             f"[i*{n} +: {n}]; beats in raster order (frame, row y, group "
                             f"g = 0..{g - 1})",
            "codes_valid": "the input beat is valid",
            "codes_ready": "the array accepts a beat (low only while clear is high)",
            "spikes_payload": "one output beat (fields below): position and S*P spikes",
            "spikes_valid": "high for one cycle when a position is released",
            "thr_we": "threshold write enable (one memory word per rising edge)",
            "thr_addr": f"(scale s << {wb}) | (y*{g} + g)",
            "thr_data": f"{p} thresholds, lane i at bits [i*{c.threshold_bits} +: "
                        f"{c.threshold_bits}], each 1..{(1 << c.threshold_bits) - 1}",
            "clear": "synchronous restart of the stream: positions in flight dropped, "
                     "accumulators zero in the next frame, thresholds kept",
        }

    @property
    def latency(self) -> int:
        """:attr:`StreamGeometry.latency` (clock cycles, back-to-back beats)."""
        return self.geometry.latency

    @property
    def lag(self) -> int:
        """:attr:`StreamGeometry.lag` (beats)."""
        return self.geometry.lag

    @property
    def schedule(self) -> StreamSchedule:
        """:attr:`StreamGeometry.schedule`."""
        return self.geometry.schedule

    def elaborate(self, platform: object) -> Module:
        """Input register, line buffer, window, masks, sums, state memories, output
        register: one method per stage group, in datapath order."""
        m = Module()
        advance, advance_next, clear, codes_in = self._input_register(m)
        slabs = self._line_buffer(m, advance, clear, codes_in)
        centre = self._window_centre(m, advance, clear)
        pipe = Pipeline(m, advance, self.geometry.LEVELS_PER_STAGE, name="sum")
        window, sums, stage_q = self._window_sums(pipe, slabs, centre)
        tail = self._position_pipeline(m, pipe, advance, clear, centre, stage_q)
        lanes, thr_memories = self._state_and_output(m, advance, advance_next, sums, tail,
                                                     ecp5=platform == ECP5_PLATFORM)
        self.probes = StreamProbes(advance, clear, tail.rd_addr, advance & tail.rd_valid,
                                   tail.wr_en, tail.wr_addr, lanes, thr_memories,
                                   {cell: t.value for cell, t in window.items()},
                                   tail.valid_at[1],
                                   [[lane[s].value for lane in sums]
                                    for s in range(self.contract.num_scales)],
                                   tail.valid_at[stage_q])
        pipe.emit()
        return m

    def _input_register(self, m: Module) -> tuple[Signal, Value, Signal, Signal]:
        """``(advance, advance_next, clear_r, codes_r)``: an accepted beat (and clear)
        acts one cycle later, so no combinational path runs from the ports into the
        datapath (``advance_next``, the value ``advance`` takes at the next edge, feeds
        only the ECP5 block RAMs' own enable registers). Datapath
        registers are reset-less (only control state and valid bits are reset): less
        reset fan-out, and no next-state logic of the datapath depends on ``rst``."""
        p, n = self.geometry.lanes, self.contract.adc_bits
        m.d.comb += self.codes.ready.eq(~self.clear)
        advance = Signal(name="advance")
        clear = Signal(name="clear_r")
        codes_in = Signal(unsigned(p * n), name="codes_r", reset_less=True)
        taken = self.codes.valid & ~self.clear
        if self.mutation == "stream.advance_during_stall":
            taken = ~self.clear  # a stalled cycle repeats the last beat
        m.d.sync += [advance.eq(taken), clear.eq(self.clear)]
        with m.If(self.codes.valid & ~self.clear):
            m.d.sync += codes_in.eq(self.codes.payload.as_value())
        return advance, Mux(ResetSignal(), 0, taken), clear, codes_in

    def _line_buffer(self, m: Module, advance: Signal, clear: Signal, codes_in: Signal
                     ) -> list[Signal]:
        """The ``2E+1`` column-group slabs of ``2L+1`` rows (stage 0): a line buffer
        whose word is 2L rows of P codes (row 0 the most recent), then the window
        register."""
        c, geo = self.contract, self.geometry
        n, p, g_count = c.adc_bits, geo.lanes, geo.groups
        r, e = geo.radius, geo.edge_groups
        row_bits = p * n
        g_in = Signal(range(g_count), name="in_group")
        # g_in's successor, kept in its own register (the line buffer's read address):
        # no counter carry chain in front of the distributed RAM's read.
        g_in_next = Signal(range(g_count), name="in_group_next", init=1 % g_count)
        with m.If(clear):
            m.d.sync += [g_in.eq(0), g_in_next.eq(1 % g_count)]
        with m.Elif(advance):
            m.d.sync += [g_in.eq(g_in_next),
                         g_in_next.eq(Mux(g_in_next == g_count - 1, 0, g_in_next + 1))]
        if r == 0:
            stored = Const(0, 0)
        elif g_count == 1:
            stored = Signal(unsigned(2 * r * row_bits), name="line_buffer", reset_less=True)
            with m.If(advance):
                m.d.sync += stored.eq(Cat(codes_in, stored[:(2 * r - 1) * row_bits]))
        else:
            lb = Memory(shape=unsigned(2 * r * row_bits), depth=g_count, init=[])
            m.submodules.line_buffer = lb
            wp, rp = lb.write_port(), lb.read_port()
            stored = rp.data
            m.d.comb += [rp.addr.eq(Mux(clear, 0, g_in_next)),
                         rp.en.eq(advance | clear),
                         wp.addr.eq(g_in), wp.en.eq(advance),
                         wp.data.eq(Cat(codes_in, stored[:(2 * r - 1) * row_bits]))]
        # slab row d (0 = oldest, 2L = the input row): line-buffer row 2L-1-d
        slab = Cat(*[stored[(2 * r - 1 - d) * row_bits:(2 * r - d) * row_bits]
                     for d in range(2 * r)], codes_in)
        slabs = [Signal(unsigned(len(slab)), name=f"slab{k}", reset_less=True)
                 for k in range(2 * e + 1)]
        with m.If(advance):
            m.d.sync += slabs[0].eq(slab)
            m.d.sync += [slabs[k].eq(slabs[k - 1]) for k in range(1, len(slabs))]
        return slabs

    def _window_centre(self, m: Module, advance: Signal, clear: Signal) -> _Centre:
        """The window centre's position (stage 0) and the registered padding masks."""
        c, geo = self.contract, self.geometry
        h, p, g_count, r = c.height, geo.lanes, geo.groups, geo.radius
        words = geo.beats_per_frame
        lag = geo.window_lag
        prime = Signal(range(lag + 1), name="prime")
        primed = prime == lag
        valid0 = Signal(name="valid_s0")
        yc = Signal(range(h), name="centre_row")
        gc = Signal(range(g_count), name="centre_group")
        ac = Signal(range(words), name="centre_addr")
        fresh0 = Signal(init=1, name="fresh_s0")
        last0 = ac == words - 1
        # valid0 is set only at an advance edge where primed holds, and primed stays set
        # until a clear (which drops valid0 too): valid0 implies primed. So the position
        # steps on valid0 alone, which keeps the prime counter out of the next-position
        # logic (a critical path at 64x64, P = 8).
        step = advance & valid0
        g_end = gc == g_count - 1
        ny, ng, na = Signal.like(yc), Signal.like(gc), Signal.like(ac)
        with m.If(clear):
            m.d.comb += [ny.eq(0), ng.eq(0), na.eq(0)]
            m.d.sync += [prime.eq(0), valid0.eq(0), fresh0.eq(1)]
        with m.Else():
            with m.If(step):
                m.d.comb += [ng.eq(Mux(g_end, 0, gc + 1)),
                             ny.eq(Mux(g_end, Mux(yc == h - 1, 0, yc + 1), yc)),
                             na.eq(Mux(last0, 0, ac + 1))]
            with m.Else():
                m.d.comb += [ny.eq(yc), ng.eq(gc), na.eq(ac)]
            with m.If(advance):
                m.d.sync += valid0.eq(primed)
                if lag:
                    with m.If(~primed):
                        m.d.sync += prime.eq(prime + 1)
                with m.If(step & last0):
                    m.d.sync += fresh0.eq(0)
        m.d.sync += [yc.eq(ny), gc.eq(ng), ac.eq(na)]
        # The padding masks of the next position, from the current one: the masks of
        # row y + 1 (column group g + 1) are constant compares of y (g), so no
        # counter's carry chain precedes them. Held otherwise; reset to position (0, 0).
        top = 1 if self.mutation == "stream.top_padding_off_by_one" else 0
        right = 0 if self.mutation == "stream.right_padding_off_by_one" else 1

        def at_least(v: Value | int, k: int) -> Value | bool:
            return v >= k if isinstance(v, int) else (Const(1) if k <= 0 else v >= k)

        def at_most(v: Value | int, k: int) -> Value | bool:
            return v <= k if isinstance(v, int) else v <= k

        def rows(y: Value | int, plus: int) -> list:
            return [at_least(y, r - d - top - plus) if d < r
                    else at_most(y, h - 1 - (d - r) - plus) if d > r else 1
                    for d in range(2 * r + 1)]

        def cols(g: Value | int, plus: int) -> list:
            return [at_least(g, -(-(r - j) // p) - plus) if j < r
                    else at_most(g, -(-(c.width + r - j) // p) - right - plus)
                    if j >= p + r else 1 for j in range(p + 2 * r)]

        def bits(values: list) -> Value:
            return Cat(*[Const(int(v), 1) if isinstance(v, (bool, int)) else v
                         for v in values])

        def word(values: list) -> int:
            return sum(int(v) << i for i, v in enumerate(values))

        row_ok = Signal(2 * r + 1, name="row_mask", init=word(rows(0, 0)))
        col_ok = Signal(p + 2 * r, name="col_mask", init=word(cols(0, 0)))
        with m.If(clear):
            m.d.sync += [row_ok.eq(row_ok.init), col_ok.eq(col_ok.init)]
        with m.Elif(step):
            m.d.sync += col_ok.eq(Mux(g_end, col_ok.init, bits(cols(gc, 1))))
            with m.If(g_end):
                m.d.sync += row_ok.eq(Mux(yc == h - 1, row_ok.init, bits(rows(yc, 1))))
        return _Centre(valid0, yc, gc, ac, fresh0, last0, row_ok, col_ok, na)

    def _window_sums(self, pipe: Pipeline, slabs: list[Signal], centre: _Centre
                     ) -> tuple[dict[tuple[int, int], Timed], list[list[Timed]], int]:
        """The masked window (stage 1) and every lane's per-scale sums at stage Q:
        ``(window, sums[lane][scale], Q)``."""
        geo = self.geometry
        n, p, r, e = self.contract.adc_bits, geo.lanes, geo.radius, geo.edge_groups
        row_ok, col_ok = centre.row_ok, centre.col_ok
        window = {}
        for d, j in geo.window_cells():
            q = e * p - r + j
            src = slabs[2 * e - q // p]
            lane = q % p
            code = src[(d * p + lane) * n:(d * p + lane + 1) * n]
            keep = row_ok[d] & col_ok[j] if (j < r or j >= p + r) else row_ok[d]
            # an AND, not Mux(keep, code, 0): yosys maps the latter to the flip-flops'
            # synchronous reset, which on the ECP5 has priority over the clock enable,
            # so the reset became advance & ~keep, a path from the beat advance (64x64,
            # P = 8: 7.27 ns); the AND leaves advance on the clock enable alone
            window[(d, j)] = pipe.register(pipe.timed(code & keep.replicate(n), 0),
                                           name=f"win_r{d}_c{j}")
        sums, stage_q = geo.stage_q_sums(pipe, window)
        return window, sums, stage_q

    def _position_pipeline(self, m: Module, pipe: Pipeline, advance: Signal, clear: Signal,
                           centre: _Centre, stage_q: int) -> _Tail:
        """Valid bits and the position carried along the pipeline to the state-memory
        read (stage Q-2), the add (Q) and the write-back and output (the tail)."""
        geo = self.geometry
        valid0, ac, fresh0, yc, gc, last0 = (centre.valid0, centre.ac, centre.fresh0,
                                             centre.yc, centre.gc, centre.last0)
        valid = [valid0]
        for s in range(1, stage_q + geo.TAIL_STAGES):
            v = Signal(name=f"valid_s{s}")
            with m.If(clear):
                m.d.sync += v.eq(0)
            with m.Elif(advance):
                m.d.sync += v.eq(valid[-1])
            valid.append(v)
        addr0, fresh_t, row_t = pipe.timed(ac), pipe.timed(fresh0), pipe.timed(yc)
        group_t, last_t = pipe.timed(gc), pipe.timed(last0)
        read = geo.read_stage
        rd_addr = pipe.at(addr0, read).value
        # the value rd_addr takes at the next edge (for comparators registered ahead),
        # if this cycle advances and if not: neither depends on advance
        if read == 0:  # rd_addr is the centre address itself (reset to 0)
            same = Mux(ResetSignal(), 0, centre.next_addr)
            rd_addr_next = (same, same)
        else:
            rd_addr_next = (pipe.at(addr0, read - 1).value, rd_addr)
        # the banks' output registers hold the read two edges on: select among them there
        bank_q = pipe.at(addr0, read + 2).value >> (geo.bank_words - 1).bit_length()
        fresh_prev = pipe.at(fresh_t, stage_q - 1).value
        fresh_q = pipe.at(fresh_t, stage_q).value
        tail = stage_q + geo.TAIL_STAGES - 1  # the stage that writes back
        wr_addr = pipe.at(addr0, tail).value
        out_row, out_group = pipe.at(row_t, tail).value, pipe.at(group_t, tail).value
        out_last = pipe.at(last_t, tail).value
        wr_en = advance & valid[tail]
        # valid[tail] at the next edge (its reset, clear and advance above)
        wr_valid_next = Mux(ResetSignal() | clear, 0,
                            Mux(advance, valid[tail - 1], valid[tail]))
        return _Tail(rd_addr, rd_addr_next, valid[read], bank_q, fresh_q, fresh_prev,
                     wr_addr, wr_en, wr_valid_next, valid[tail], out_row, out_group,
                     out_last, valid)

    def _state_and_output(self, m: Module, advance: Signal, advance_next: Value,
                          sums: list[list[Timed]], tail: _Tail, ecp5: bool = False
                          ) -> tuple[list[list[dict[str, Value]]], list[BankedMemory]]:
        """Per scale the threshold and accumulator memories, then the tail: add,
        compare/saturate, fire/reset, write back; spikes and position on the output.
        Returns what :class:`StreamProbes` needs: the lanes' tail registers (per scale)
        and the threshold memories.

        ``ecp5`` (the ECP5 build): the accumulator block RAMs write where their own
        registered copy of ``valid`` holds (``held_write``: a stalled write repeats the
        same word to the same address, and the write of a clear edge lands in a word
        the fresh frame after the clear reads as zero or captures, and overwrites), and
        every scale and lane has its own copy of the fresh-frame flag (no net from one
        register to the zero multiplexers of every accumulator-adder input); both are
        :func:`~rvsm.rtl.fpga.ecp5_memory.kept_register` flip-flops."""
        c, geo = self.contract, self.geometry
        p, words, wa = geo.lanes, geo.beats_per_frame, c.accumulator_bits
        rd_addr, bank_q, fresh_q, wr_addr, wr_en = (tail.rd_addr, tail.bank_q, tail.fresh_q,
                                                    tail.wr_addr, tail.wr_en)
        tw = c.threshold_bits
        # Threshold writes land one edge after the bus accepts them (a registered bus),
        # so a read at the bus' edge does not see them; a read meeting the registered
        # write at the next edge gets its data forwarded after the bank registers.
        bus = self.thr
        word_bits = threshold_word_bits(words)
        bus_we = Signal(name="thr_we_r", reset_less=True)
        bus_addr = Signal.like(bus.addr, name="thr_addr_r", reset_less=True)
        bus_data = Signal.like(bus.data, name="thr_data_r", reset_less=True)
        m.d.sync += [bus_we.eq(bus.we), bus_addr.eq(bus.addr), bus_data.eq(bus.data)]
        bus_word = bus_addr[:word_bits]
        bus_scale = bus_addr[word_bits:]
        # bus_addr == rd_addr, registered: compared one edge ahead from the values both
        # take at that edge (the bus register loads every cycle), so no comparator sits
        # between the read address and the forwarding; compared for both values rd_addr
        # may take and chosen after the edge by advance, registered: no path from
        # advance (the clock enable of the whole pipeline) into the comparator.
        matches = [Signal(name=f"thr_rd_match_{case}", init=1, reset_less=True)
                   for case in ("adv", "hold")]
        advanced = Signal(name="advanced", reset_less=True)
        m.d.sync += [*(match.eq(bus.addr[:word_bits] == addr)
                       for match, addr in zip(matches, tail.rd_addr_next, strict=True)),
                     advanced.eq(advance)]
        rd_match = Mux(advanced, *matches)
        fwd_data = [Signal.like(bus.data, name=f"thr_fwd{k}_data", reset_less=True)
                    for k in (1, 2)]  # shared by the scales
        with m.If(advance):
            m.d.sync += [fwd_data[0].eq(bus_data), fwd_data[1].eq(fwd_data[0])]
        tail_stmts = []
        pos_bits, neg_bits = [], []
        probes: list[list[dict[str, Value]]] = []
        thr_memories: list[BankedMemory] = []
        for s in range(c.num_scales):
            after_lanes = []
            probes.append([])
            thr_mem = BankedMemory(p * tw, words, geo.bank_words, forward=True,
                                   init_word=top_threshold_word(tw, p),  # module docstring
                                   read_stages=geo.READ_STAGES)
            m.submodules[f"thr_s{s}"] = thr_mem
            thr_memories.append(thr_mem)
            m.d.comb += [thr_mem.advance.eq(advance), thr_mem.read_addr.eq(rd_addr),
                         thr_mem.read_bank.eq(bank_q),
                         thr_mem.write_en.eq(bus_we & (bus_scale == s)),
                         thr_mem.write_addr.eq(bus_word), thr_mem.write_data.eq(bus_data),
                         thr_mem.advance_next.eq(advance_next),
                         thr_mem.forward_hit.eq(
                             bus_we & (bus_scale == s) & rd_match
                             if self.mutation != "stream.no_threshold_forwarding" else 0),
                         thr_mem.forward_data.eq(fwd_data[1])]
            thr_q = thr_mem.data
            after_flat = Signal(unsigned(p * wa), name=f"acc_s{s}_wdata")
            acc_mem = BankedMemory(p * wa, words, geo.bank_words,
                                   guard_bits=geo.rmw_guard_bits, read_stages=geo.READ_STAGES,
                                   held_write=ecp5)
            m.submodules[f"acc_s{s}"] = acc_mem
            m.d.comb += [acc_mem.advance.eq(advance), acc_mem.read_addr.eq(rd_addr),
                         acc_mem.read_bank.eq(bank_q), acc_mem.write_en.eq(wr_en),
                         acc_mem.write_addr.eq(wr_addr), acc_mem.write_data.eq(after_flat),
                         acc_mem.may_write.eq(tail.valid),
                         acc_mem.advance_next.eq(advance_next)]
            if ecp5:
                m.d.comb += acc_mem.write_en_next.eq(tail.wr_valid_next)
            acc_q = acc_mem.data
            for i in range(p):
                fresh = (kept_register(m, tail.fresh_prev, f"fresh_s{s}_l{i}", en=advance)
                         if ecp5 else fresh_q)
                if self.mutation == "stream.clear_forgets_scale0" and s == 0:
                    fresh = 0  # the first frame after a clear reads scale 0's old state
                acc = Mux(fresh, 0, acc_q[i * wa:(i + 1) * wa].as_signed())
                extra = 1 if self.mutation == "stream.shift_off_by_one" else 0
                shifted = sums[i][s].value.as_signed() >> (c.shift + extra)
                data = {"reset_less": True}
                total = Signal(signed(max(wa, len(shifted)) + 1), name=f"total_s{s}_l{i}",
                               **data)
                thr1 = Signal(unsigned(tw), name=f"thr1_s{s}_l{i}", **data)
                sat = Signal(signed(wa), name=f"sat_s{s}_l{i}", **data)
                thr2 = Signal(unsigned(tw), name=f"thr2_s{s}_l{i}", **data)
                pos = Signal(name=f"pos_s{s}_l{i}", **data)
                neg = Signal(name=f"neg_s{s}_l{i}", **data)
                if c.sensor == "dvs":
                    tail_stmts += self._event_tail(m, s, i, acc_q[i * wa:(i + 1) * wa]
                                                   .as_signed(), fresh, shifted,
                                                   thr_q[i * tw:(i + 1) * tw], total, thr1,
                                                   sat, thr2, pos, neg)
                    after = sat  # the moved, saturated reference
                else:
                    tail_stmts += self._spike_tail(acc, shifted, thr_q[i * tw:(i + 1) * tw],
                                                   total, thr1, sat, thr2, pos, neg)
                    neg = neg & ~pos  # the register holds the compare alone (docstring)
                    if self.mutation == "stream.no_reset_on_spike":
                        after = sat
                    elif c.reset == "zero" or \
                            self.mutation == "stream.zero_instead_of_subtract":
                        after = Mux(pos | neg, 0, sat)
                    else:
                        after = Mux(pos, sat - thr2, Mux(neg, sat + thr2, sat))
                after_lanes.append(after.as_unsigned()[:wa])
                probes[s].append({"acc": acc, "total": total, "thr1": thr1, "sat": sat,
                                  "thr2": thr2, "pos": pos, "neg": neg, "after": after})
                pos_bits.append(pos)
                neg_bits.append(neg)
            m.d.comb += after_flat.eq(Cat(*after_lanes))
        out = self.spikes.payload
        if self.mutation == "stream.swapped_lanes" and p > 1:
            for bits in (pos_bits, neg_bits):  # lanes 0 and 1 of every scale swapped
                for s in range(c.num_scales):
                    bits[s * p], bits[s * p + 1] = bits[s * p + 1], bits[s * p]
        tail_stmts += [out.row.eq(tail.row), out.group.eq(tail.group), out.last.eq(tail.last),
                       out.pos.eq(Cat(*pos_bits)), out.neg.eq(Cat(*neg_bits))]
        with m.If(advance):
            m.d.sync += tail_stmts
        m.d.sync += self.spikes.valid.eq(wr_en)
        return probes, thr_memories

    def _spike_tail(self, acc: Value, shifted: Value, thr: Value, total: Signal,
                    thr1: Signal, sat: Signal, thr2: Signal, pos: Signal, neg: Signal
                    ) -> list:
        """The spike camera's tail for one lane and scale: stage 1 ``total = acc +
        shifted``, the threshold and the threshold less one; stage 2 saturation, ``pos = total >=
        thr``, ``neg = total <= -thr`` (the caller masks it with ``~pos``: the two compares
        are independent carry chains) and the threshold kept for the reset (the caller's
        ``after``)."""
        c = self.contract
        wa = c.accumulator_bits
        lo, hi = -(1 << (wa - 1)), (1 << (wa - 1)) - 1
        # Both compares are the sign of one subtraction (one carry chain each, no
        # sign-extension logic after it): total >= thr is ~sign(total - thr), and
        # total <= -thr is sign(total + (thr - 1)), thr - 1 registered beside thr. The
        # neg register holds that compare alone; the caller takes ~pos & neg.
        fire_pos = ~(total - thr1)[-1]
        if self.mutation == "stream.threshold_off_by_one":
            fire_pos = total > thr1
        elif self.mutation == "stream.stale_threshold":
            fire_pos = total >= thr2  # the previous position's threshold
        thr1_m1 = Signal(signed(len(thr) + 1), name=f"{thr1.name}_m1", reset_less=True)
        fire_neg = (total + thr1_m1)[-1] if c.signed else Const(0)
        if self.mutation == "stream.no_negative_spikes":
            fire_neg = Const(0)
        return [
            total.eq(acc + shifted),
            thr1.eq(thr),
            *([thr1_m1.eq(thr.as_unsigned() - 1)] if c.signed else []),
            sat.eq(total[:wa].as_signed()
                   if self.mutation == "stream.no_saturation"  # wraps around
                   else Mux(total > hi, hi, Mux(total < lo, lo, total))),
            pos.eq(fire_pos), neg.eq(fire_neg), thr2.eq(thr1),
        ]

    def _event_tail(self, m: Module, s: int, i: int, ref: Value, fresh: Value,
                    shifted: Value, thr: Value, total: Signal, thr1: Signal, sat: Signal,
                    thr2: Signal, pos: Signal, neg: Signal) -> list:
        """The event sensor's tail for lane ``i`` of scale ``s`` (``contract.sensor ==
        "dvs"``): the statements of its two registered stages, the same registers as the
        spike camera's (``total`` holds ``d = shifted - ref``, ``sat`` the new
        reference, written back).

        Stage 1, in parallel: ``d = shifted - ref`` (exact), the threshold, the capture
        flag (a fresh frame: the first after a clear), ``clamp(shifted)``, ``ref + thr``
        and ``ref - thr`` with their overflow bits (``ref`` and ``thr`` fit W bits, so a
        W+1-bit sum leaves the range exactly when its top two bits differ). Stage 2: ``up
        = d >= thr``, ``down = d <= -thr``, ``pos = ~cap & up``, ``neg = ~cap & ~up &
        down`` and the new reference, a 4-way choice of stage-1 values: one compare and
        a multiplexer, the short path ``rvsm fpga`` measured (``docs/events.md``).
        """
        wa = self.contract.accumulator_bits
        lo, hi = -(1 << (wa - 1)), (1 << (wa - 1)) - 1
        data = {"reset_less": True}
        cap1 = Signal(name=f"cap1_s{s}_l{i}", **data)
        sum1 = Signal(signed(wa), name=f"sum1_s{s}_l{i}", **data)
        ref1 = Signal(signed(wa), name=f"ref1_s{s}_l{i}", **data)
        up1 = Signal(signed(wa + 1), name=f"up1_s{s}_l{i}", **data)
        down1 = Signal(signed(wa + 1), name=f"down1_s{s}_l{i}", **data)
        up_over = up1[wa] ^ up1[wa - 1]
        down_over = down1[wa] ^ down1[wa - 1]
        up, down = total >= thr1, total <= -thr1
        moved = Mux(up, Mux(up_over, hi, up1), Mux(down, Mux(down_over, lo, down1), ref1))
        return [
            total.eq(shifted - ref), thr1.eq(thr), cap1.eq(fresh),
            sum1.eq(Mux(shifted > hi, hi, Mux(shifted < lo, lo, shifted))),
            ref1.eq(ref), up1.eq(ref + thr), down1.eq(ref - thr),
            pos.eq(~cap1 & up), neg.eq(~cap1 & ~up & down), thr2.eq(thr1),
            sat.eq(Mux(cap1, sum1, moved)),
        ]
