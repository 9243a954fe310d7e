"""The lane-parallel streaming RVSM pixel array, built from one :class:`ArrayContract`.

Where :class:`~rvsm.rtl.array.RvsmArray` builds an adder network and an accumulator per
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

L is the kernel radius (:func:`~rvsm.rtl.pipelined_sum.kernel_radius`), E =
``ceil(L / P)`` the column groups a window reaches either side, G = ``W / P``.

**State.** Per scale one accumulator memory (word = P signed W-bit accumulators) and one
threshold memory (word = P thresholds of W-1 bits), depth ``H*G``, address ``y*G + g``,
split into banks of at most :attr:`StreamGeometry.bank_words` words (a power of two,
1024 by default) whose read data is registered before the bank multiplexer (ECP5
block-RAM timing). Each address is read and written once per frame,
:attr:`StreamGeometry.rmw_depth` beats apart, so the
read-modify-write needs no forwarding as long as ``H*G > rmw_depth`` (checked). A bank's
read is disabled when its write port writes the same address at that edge (no read-first
bypass multiplexer after the block RAM); threshold writes are registered and forwarded
after the bank registers to a read meeting them, so the rule below holds.

**Streams.** ``codes`` (:func:`code_beat_signature`): ``payload`` lane ``i`` = pixel
``(y, g*P + i)``; a beat is accepted at a rising edge with ``valid & ready``; ``ready``
is low only while ``clear`` is high. Accepted beats and ``clear`` pass an input
register (no combinational path from the ports into the datapath), and the whole
pipeline advances once per accepted beat, at the edge after its acceptance (a clock
enable), so a paused input holds everything in flight. ``spikes``
(:func:`spike_beat_signature`, no back-pressure): ``valid`` is high for the one cycle
after the edge that releases a position; ``payload.row``/``group`` is the position,
``last`` marks the frame's last beat, bit ``s*P + i`` of ``pos``/``neg`` the +1/-1
spike of accumulator ``(s, y, g*P + i)``. The output of position ``p`` (beats counted
from the last clear) is released by input beat ``p + lag``: it is presented in the
second cycle after that beat's acceptance. To drain a stream, send ``lag`` more beats
(any codes) and wait one more cycle. :mod:`rvsm.rtl.stream_schedule` is the numpy model
of this schedule.

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
  memories are not initialised: load every threshold before streaming.

The bit-accurate model is :meth:`ArrayContract.run`, rearranged into beats by
:class:`~rvsm.rtl.stream_schedule.StreamSchedule`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from amaranth.hdl import Cat, Const, Module, Mux, Signal, Value, signed, unsigned
from amaranth.lib import data, stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from rvsm.model.fixed.core import ArrayContract
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.interfaces import ThresholdWriteSignature
from rvsm.rtl.pipelined_sum import Pipeline, Timed, kernel_orbits, kernel_radius, orbit_terms
from rvsm.rtl.receptive_sum import sum_width
from rvsm.rtl.stream_schedule import OutputBeats, StreamSchedule, pack_lanes

__all__ = [
    "RvsmStreamArray",
    "StreamGeometry",
    "code_beat_signature",
    "simulate",
    "spike_beat_layout",
    "spike_beat_signature",
    "threshold_word_bits",
    "threshold_write_signature",
]


def _bits(max_value: int) -> int:
    """Bits of an unsigned field holding ``0 .. max_value`` (at least 1)."""
    return max(1, int(max_value).bit_length())


def code_beat_signature(adc_bits: int, lanes: int) -> stream.Signature:
    """Input stream: ``payload`` = ``lanes`` unsigned ADC codes, ``valid``, ``ready``."""
    return stream.Signature(data.ArrayLayout(unsigned(adc_bits), lanes))


def spike_beat_layout(num_scales: int, lanes: int, height: int,
                      groups: int) -> data.StructLayout:
    """Output payload: ``row``, ``group``, ``last``, ``pos`` and ``neg`` (``S*P`` bits)."""
    return data.StructLayout({
        "row": unsigned(_bits(height - 1)),
        "group": unsigned(_bits(groups - 1)),
        "last": unsigned(1),
        "pos": unsigned(num_scales * lanes),
        "neg": unsigned(num_scales * lanes),
    })


def spike_beat_signature(num_scales: int, lanes: int, height: int,
                         groups: int) -> wiring.Signature:
    """Output stream of :func:`spike_beat_layout` beats: ``payload`` and ``valid``, no
    ``ready`` (a sensor cannot be stopped: there is no back-pressure)."""
    return wiring.Signature({
        "payload": Out(spike_beat_layout(num_scales, lanes, height, groups)),
        "valid": Out(1),
    })


def threshold_word_bits(words: int) -> int:
    """Bits of the word part (``y*G + g``) of a threshold write address."""
    return _bits(words - 1)


def threshold_write_signature(num_scales: int, words: int, lanes: int,
                              threshold_bits: int) -> ThresholdWriteSignature:
    """The shared threshold-write bus with one memory word (P thresholds) per write:
    ``data`` lane ``i`` at ``[i*(W-1) +: W-1]``, ``addr = (s << word_bits) | (y*G + g)``
    (:func:`threshold_word_bits`)."""
    return ThresholdWriteSignature(lanes * threshold_bits,
                                   _bits(num_scales - 1) + threshold_word_bits(words))


class StreamGeometry:
    """Sizes and timing of a stream array: pure Python, nothing to elaborate.

    ``RvsmStreamArray(contract, lanes).geometry``, or build one directly when only the
    schedule or the named timing properties are needed (e.g. by a testbench).
    """

    #: Adder levels between pipeline registers in the receptive-sum trees.
    LEVELS_PER_STAGE = 2
    #: Default largest number of words in one bank of a state memory (one ECP5 DP16KD
    #: holds 1024 words of up to 18 bits; wider words use several in parallel).
    BANK_WORDS = 1024
    #: Stages from the sums' register to the output register: add, compare, reset.
    TAIL_STAGES = 3
    #: Registers between the input ports and the datapath (accepted beat, clear).
    INPUT_STAGES = 1

    def __init__(self, contract: ArrayContract, lanes: int = 1,
                 bank_words: int = BANK_WORDS):
        c = contract
        if bank_words < 1 or bank_words & (bank_words - 1):
            raise RvsmError(f"bank_words must be a power of two, got {bank_words}")
        self.bank_words = int(bank_words)
        if isinstance(lanes, bool) or not isinstance(lanes, (int, np.integer)) \
                or lanes < 1 or c.width % lanes:
            raise RvsmError(f"lanes must be a positive divisor of the width {c.width}, "
                            f"got {lanes}")
        self.contract = c
        self.lanes = int(lanes)
        self.groups = c.width // self.lanes
        self.radius = kernel_radius(c.weights)
        self.edge_groups = -(-self.radius // self.lanes)
        self.orbits = kernel_orbits(c.weights)
        self.beats_per_frame = c.height * self.groups
        self.sum_stage = self.build_sums(Pipeline(None), None)[1]
        if self.beats_per_frame <= self.rmw_depth:
            raise RvsmError(
                f"the stream array needs more than {self.rmw_depth} beats per frame (its "
                f"read-modify-write depth); {c.height}x{c.width} at {lanes} lane(s) has "
                f"{self.beats_per_frame}: use fewer lanes")

    @property
    def window_lag(self) -> int:
        """Input beats after position ``p`` until its window is complete: ``L*G + E``."""
        return self.radius * self.groups + self.edge_groups

    @property
    def pipeline_depth(self) -> int:
        """Registered stages from the window register to the output register."""
        return self.sum_stage + self.TAIL_STAGES

    @property
    def latency(self) -> int:
        """Clock cycles from the edge accepting beat ``p + window_lag`` to the edge
        presenting ``p``'s output, when beats are back to back."""
        return self.INPUT_STAGES + self.pipeline_depth

    @property
    def lag(self) -> int:
        """Output ``p`` is released by input beat ``p + lag`` (presented in the second
        cycle after that beat's acceptance)."""
        return self.window_lag + self.pipeline_depth

    @property
    def rmw_depth(self) -> int:
        """Beats from an accumulator read (address sampled) to its write-back."""
        return self.TAIL_STAGES + 1

    @property
    def rmw_guard_bits(self) -> int:
        """Low address bits that tell an accumulator read from the write at its edge.

        The read of position ``p`` meets the write-back of ``p - rmw_depth``, so the
        addresses differ by ``rmw_depth`` or ``rmw_depth - beats_per_frame``: the
        smallest ``k`` for which ``2**k`` divides neither (all address bits at most).
        """
        def twos(v: int) -> int:
            return (v & -v).bit_length() - 1

        d, n = self.rmw_depth, self.beats_per_frame
        return min(1 + max(twos(d), twos(n - d)), max(1, (n - 1).bit_length()))

    @property
    def threshold_lag(self) -> int:
        """Position ``p`` reads its thresholds at the edge after the one accepting input
        beat ``p + threshold_lag``."""
        return self.window_lag + self.sum_stage - 1

    @property
    def bank_sizes(self) -> list[int]:
        """Words per bank of each state memory (every bank but the last is full)."""
        n, b = self.beats_per_frame, self.bank_words
        return [min(b, n - i) for i in range(0, n, b)]

    @property
    def state_bits(self) -> dict[str, int]:
        """Memory bits: ``accumulators``, ``thresholds``, ``line_buffer``."""
        c = self.contract
        acc = c.num_scales * c.height * c.width * c.accumulator_bits
        thr = c.num_scales * c.height * c.width * c.threshold_bits
        return {"accumulators": acc, "thresholds": thr,
                "line_buffer": 2 * self.radius * c.width * c.adc_bits}

    @property
    def schedule(self) -> StreamSchedule:
        """The numpy model of this array's beat schedule."""
        c = self.contract
        return StreamSchedule(c.height, c.width, self.lanes, self.lag, self.threshold_lag)

    @property
    def spike_layout(self) -> data.StructLayout:
        """Layout of the output payload (:func:`spike_beat_layout`)."""
        c = self.contract
        return spike_beat_layout(c.num_scales, self.lanes, c.height, self.groups)

    def timing(self) -> dict[str, int]:
        """The named timing properties, as a dict (for port maps and reports)."""
        return {k: getattr(self, k) for k in (
            "lanes", "groups", "radius", "window_lag", "pipeline_depth", "latency", "lag",
            "rmw_depth", "threshold_lag", "beats_per_frame")}

    def sum_bits(self, scale: int) -> int:
        """Signed width of scale ``scale``'s exact weighted sum."""
        return sum_width(*self.contract.sum_range(scale))

    def window_cells(self) -> list[tuple[int, int]]:
        """Window cells ``(d, j)`` (row 0..2L, column 0..P+2L-1) some tap reads."""
        r = self.radius
        return sorted({(r + dy, r + i + dx) for i in range(self.lanes)
                       for o in self.orbits for dy, dx in o.offsets})

    def build_sums(self, pipe: Pipeline, window: Mapping[tuple[int, int], Timed] | None
                   ) -> tuple[list[list[Timed]], int]:
        """Per lane, per scale the weighted sum; and the stage they are all registered at.

        ``window`` maps cells to stage-1 values; ``None`` plans (stage numbers only).
        """
        c, r, n = self.contract, self.radius, self.contract.adc_bits
        if window is None:
            window = {cell: pipe.timed(None, 1) for cell in self.window_cells()}
        sums = []
        for i in range(self.lanes):
            orbit_sums = []
            for o in self.orbits:
                terms = [(1, window[(r + dy, r + i + dx)], 0) for dy, dx in o.offsets]
                width = n + (len(terms) - 1).bit_length()
                orbit_sums.append(pipe.settle(pipe.sum(terms, width)))
            sums.append([pipe.settle(pipe.sum(orbit_terms(orbit_sums, self.orbits, s),
                                              self.sum_bits(s)))
                         for s in range(c.num_scales)])
        stage = max([2] + [t.stage for lane in sums for t in lane])
        return sums, stage


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
                 bank_words: int = StreamGeometry.BANK_WORDS):
        geo = StreamGeometry(contract, lanes, bank_words)
        self.geometry = geo
        self.contract = contract
        self.lanes = geo.lanes
        self.groups = geo.groups
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

    def _banked(self, m: Module, name: str, width: int, advance: Value,
                read_addr: Value, read_bank: Value,
                writes: Sequence[tuple[Value, Value, Value]],
                forward: tuple[Value, Value] | None = None,
                guard: tuple[Value, int] | None = None) -> Value:
        """A banked memory of ``width``-bit words; returns the registered read data.

        The read address is sampled at an ``advance`` edge; the data is registered per
        bank at the next ``advance`` edge and multiplexed by ``read_bank`` (which must be
        the bank of that address, delayed alike). ``writes`` is one ``(en, addr, data)``
        port description per write port. A bank's read is disabled at an edge where a
        write port writes its address: the read data is then undefined (yosys needs no
        read-first bypass multiplexer after the block RAM), so either such collisions
        never meet a valid read, or ``forward = (hit, data)`` replaces the read data by
        ``data`` after the bank registers where ``hit`` was set (``hit`` is sampled with
        the read address; ``data`` must be the forwarded word delayed alike, two
        ``advance`` edges). ``guard = (may_write, k)`` (one write port whose enable is
        ``advance & may_write``) gates the read where ``may_write`` holds and the low
        ``k`` address bits match: a cheaper superset of the collisions, for a memory
        whose valid reads and writes never match in those bits.
        """
        sizes = self.geometry.bank_sizes
        banked = len(sizes) > 1
        offset_bits = (self.geometry.bank_words - 1).bit_length()
        outs = []
        for b, depth in enumerate(sizes):
            mem = Memory(shape=unsigned(width), depth=depth, init=[])
            m.submodules[f"{name}_b{b}"] = mem
            for en, addr, wdata in writes:
                wp = mem.write_port()
                hit = (addr >> offset_bits) == b if banked else Const(1)
                m.d.comb += [wp.addr.eq(addr[:offset_bits] if banked else addr),
                             wp.data.eq(wdata), wp.en.eq(en & hit)]
            rp = mem.read_port()
            m.d.comb += rp.addr.eq(read_addr[:offset_bits] if banked else read_addr)
            collide = Const(0)
            for (_, addr, _), wp in zip(writes, mem.write_ports, strict=True):
                if guard is None:
                    collide = collide | (wp.en & (wp.addr == rp.addr))
                else:
                    hit = (addr >> offset_bits) == b if banked else Const(1)
                    k = min(guard[1], len(rp.addr))
                    collide = collide | (guard[0] & hit & (wp.addr[:k] == rp.addr[:k]))
            m.d.comb += rp.en.eq(advance & ~collide)
            reg = Signal(unsigned(width), name=f"{name}_b{b}_q", reset_less=True)
            with m.If(advance):
                m.d.sync += reg.eq(rp.data)
            outs.append(reg)
        out = outs[-1]
        for b in range(len(outs) - 2, -1, -1):
            out = Mux(read_bank == b, outs[b], out)
        if forward is not None:
            hit, data = forward
            hit1 = Signal(name=f"{name}_fwd1", reset_less=True)
            hit2 = Signal(name=f"{name}_fwd2", reset_less=True)
            with m.If(advance):
                m.d.sync += [hit1.eq(hit), hit2.eq(hit1)]
            out = Mux(hit2, data, out)
        return out

    def elaborate(self, platform: object) -> Module:
        """Line buffer, window, masks, sums, state memories, output register."""
        m = Module()
        c, geo = self.contract, self.geometry
        h, n, p, g_count = c.height, c.adc_bits, geo.lanes, geo.groups
        r, e = geo.radius, geo.edge_groups
        words = geo.beats_per_frame
        wa = c.accumulator_bits

        # Input register: an accepted beat (and clear) acts one cycle later, so no
        # combinational path runs from the ports into the datapath. Datapath registers
        # are reset-less (only control state and valid bits are reset): less reset
        # fan-out, and no next-state logic of the datapath depends on the ``rst`` port.
        m.d.comb += self.codes.ready.eq(~self.clear)
        advance = Signal(name="advance")
        clear = Signal(name="clear_r")
        codes_in = Signal(unsigned(p * n), name="codes_r", reset_less=True)
        m.d.sync += [advance.eq(self.codes.valid & ~self.clear), clear.eq(self.clear)]
        with m.If(self.codes.valid & ~self.clear):
            m.d.sync += codes_in.eq(self.codes.payload.as_value())

        # -- line buffer: word = 2L rows of P codes, row 0 the most recent -----------------
        row_bits = p * n
        g_in = Signal(range(g_count), name="in_group")
        g_in_next = Mux(g_in == g_count - 1, 0, g_in + 1)
        with m.If(clear):
            m.d.sync += g_in.eq(0)
        with m.Elif(advance):
            m.d.sync += g_in.eq(g_in_next)
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

        # -- window centre position (stage 0) and registered padding masks ----------------
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
        row_ok = Signal(2 * r + 1, name="row_mask")
        col_ok = Signal(p + 2 * r, name="col_mask")
        row_next = [(ny >= r - d) if d < r else (ny <= h - 1 - (d - r)) if d > r else Const(1)
                    for d in range(2 * r + 1)]
        col_next = []
        for j in range(p + 2 * r):
            if j < r:
                col_next.append(ng >= -(-(r - j) // p))
            elif j >= p + r:
                col_next.append(ng <= -(-(c.width + r - j) // p) - 1)
            else:
                col_next.append(Const(1))
        m.d.sync += [row_ok.eq(Cat(*row_next)), col_ok.eq(Cat(*col_next))]

        # -- masked window (stage 1) and pipelined sums (stage Q) -------------------------
        pipe = Pipeline(m, advance, geo.LEVELS_PER_STAGE, name="sum")
        window = {}
        for d, j in geo.window_cells():
            q = e * p - r + j
            src = slabs[2 * e - q // p]
            lane = q % p
            code = src[(d * p + lane) * n:(d * p + lane + 1) * n]
            keep = row_ok[d] & col_ok[j] if (j < r or j >= p + r) else row_ok[d]
            window[(d, j)] = pipe.register(pipe.timed(Mux(keep, code, 0), 0),
                                           name=f"win_r{d}_c{j}")
        sums, stage_q = geo.build_sums(pipe, window)
        if stage_q != geo.sum_stage:
            raise AssertionError("planned and built sum stages differ")
        sums = [[pipe.at(t, stage_q) for t in lane] for lane in sums]

        # -- position pipeline -------------------------------------------------------------
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
        rd_addr = pipe.at(addr0, stage_q - 2).value
        bank_q = pipe.at(addr0, stage_q).value >> (geo.bank_words - 1).bit_length()
        fresh_q = pipe.at(fresh_t, stage_q).value
        tail = stage_q + geo.TAIL_STAGES - 1  # the stage that writes back
        wr_addr = pipe.at(addr0, tail).value
        out_row, out_group = pipe.at(row_t, tail).value, pipe.at(group_t, tail).value
        out_last = pipe.at(last_t, tail).value
        wr_en = advance & valid[tail]

        # -- state memories and the tail: add, compare/saturate, fire/reset ---------------
        lo, hi = -(1 << (wa - 1)), (1 << (wa - 1)) - 1
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
        fwd_data = [Signal.like(bus.data, name=f"thr_fwd{k}_data", reset_less=True)
                    for k in (1, 2)]  # shared by the scales
        with m.If(advance):
            m.d.sync += [fwd_data[0].eq(bus_data), fwd_data[1].eq(fwd_data[0])]
        tail_stmts = []
        pos_bits, neg_bits = [], []
        for s in range(c.num_scales):
            after_lanes = []
            thr_q = self._banked(
                m, f"thr_s{s}", p * tw, advance, rd_addr, bank_q,
                [(bus_we & (bus_scale == s), bus_word, bus_data)],
                forward=(bus_we & (bus_scale == s) & (bus_word == rd_addr), fwd_data[1]))
            after_flat = Signal(unsigned(p * wa), name=f"acc_s{s}_wdata")
            acc_q = self._banked(m, f"acc_s{s}", p * wa, advance, rd_addr, bank_q,
                                 [(wr_en, wr_addr, after_flat)],
                                 guard=(valid[tail], geo.rmw_guard_bits))
            for i in range(p):
                acc = Mux(fresh_q, 0, acc_q[i * wa:(i + 1) * wa].as_signed())
                shifted = sums[i][s].value.as_signed() >> c.shift
                data = {"reset_less": True}
                total = Signal(signed(max(wa, len(shifted)) + 1), name=f"total_s{s}_l{i}",
                               **data)
                thr1 = Signal(unsigned(tw), name=f"thr1_s{s}_l{i}", **data)
                sat = Signal(signed(wa), name=f"sat_s{s}_l{i}", **data)
                thr2 = Signal(unsigned(tw), name=f"thr2_s{s}_l{i}", **data)
                pos = Signal(name=f"pos_s{s}_l{i}", **data)
                neg = Signal(name=f"neg_s{s}_l{i}", **data)
                fire_pos = total >= thr1
                fire_neg = (~fire_pos & (total <= -thr1)) if c.signed else Const(0)
                tail_stmts += [
                    total.eq(acc + shifted),
                    thr1.eq(thr_q[i * tw:(i + 1) * tw]),
                    sat.eq(Mux(total > hi, hi, Mux(total < lo, lo, total))),
                    pos.eq(fire_pos), neg.eq(fire_neg), thr2.eq(thr1),
                ]
                if c.reset == "zero":
                    after = Mux(pos | neg, 0, sat)
                else:
                    after = Mux(pos, sat - thr2, Mux(neg, sat + thr2, sat))
                after_lanes.append(after.as_unsigned()[:wa])
                pos_bits.append(pos)
                neg_bits.append(neg)
            m.d.comb += after_flat.eq(Cat(*after_lanes))
        out = self.spikes.payload
        tail_stmts += [out.row.eq(out_row), out.group.eq(out_group), out.last.eq(out_last),
                       out.pos.eq(Cat(*pos_bits)), out.neg.eq(Cat(*neg_bits))]
        with m.If(advance):
            m.d.sync += tail_stmts
        m.d.sync += self.spikes.valid.eq(wr_en)
        pipe.emit()
        return m


def simulate(
    contract: ArrayContract,
    codes: np.ndarray,
    thresholds: np.ndarray,
    lanes: int = 1,
    clear_before: Sequence[int] = (),
    threshold_updates: Mapping[int, np.ndarray] | None = None,
    idle_every: int = 0,
    bank_words: int = StreamGeometry.BANK_WORDS,
) -> OutputBeats:
    """Run :class:`RvsmStreamArray` in ``amaranth.sim``; return every output beat.

    Thresholds ``(S, H, W)`` are written through ``thr``; each segment between
    ``clear_before`` steps is streamed back to back, flushed with ``lag`` beats and
    followed by a one-cycle ``clear``. ``threshold_updates`` maps a frame ``t`` (of the
    first segment) to thresholds written while the stream is paused at
    :meth:`StreamSchedule.threshold_pause_beat` ``(t)``. ``idle_every = k > 0`` drops
    ``valid`` for one cycle after every ``k``-th beat (a paused stream). Compare the
    result with :func:`~rvsm.rtl.stream_schedule.check_beats`; its ``accepted`` holds,
    per output beat, the index (within its segment) of the input beat accepted two
    cycles before it was presented, the beat that released it.
    """
    from amaranth.sim import Simulator

    c = contract
    codes = np.asarray(codes, dtype=np.int64)
    StreamGeometry(c, lanes, bank_words)  # validate before building a component
    dut = RvsmStreamArray(c, lanes, bank_words)
    sched = dut.schedule
    layout = dut.geometry.spike_layout
    word_bits = threshold_word_bits(sched.beats_per_frame)
    fields = {name: (layout[name].offset, layout[name].width)
              for name in ("row", "group", "last", "pos", "neg")}
    updates = dict(threshold_updates or {})
    got: dict[str, list[int]] = {k: [] for k in (*fields, "accepted")}

    def thr_words(thr: np.ndarray) -> list[tuple[int, int, int]]:
        w = sched.threshold_words(np.asarray(thr, dtype=np.int64))
        packed = pack_lanes(w.reshape(-1, lanes), c.threshold_bits)
        return [(s, a, packed[s * sched.beats_per_frame + a])
                for s in range(c.num_scales) for a in range(sched.beats_per_frame)]

    async def write_thresholds(ctx, thr: np.ndarray) -> None:  # noqa: ANN001
        for s, a, word in thr_words(thr):
            ctx.set(dut.thr.we, 1)
            ctx.set(dut.thr.addr, (s << word_bits) | a)
            ctx.set(dut.thr.data, word)
            await ctx.tick()
        ctx.set(dut.thr.we, 0)

    accepted = [-1, -1]  # beats accepted at the previous and at the latest edge

    def collect(ctx, beat: int) -> None:  # noqa: ANN001
        """After an edge that accepted ``beat`` (-1: none), record a presented output."""
        accepted[:] = [accepted[1], beat]
        if ctx.get(dut.spikes.valid):
            word = ctx.get(dut.spikes.payload.as_value())
            for k, (off, width) in fields.items():
                got[k].append((word >> off) & ((1 << width) - 1))
            got["accepted"].append(accepted[0])

    async def bench(ctx) -> None:  # noqa: ANN001
        await write_thresholds(ctx, thresholds)
        for seg, (a, b) in enumerate(sched.segments(len(codes), clear_before)):
            if seg:
                ctx.set(dut.clear, 1)
                await ctx.tick()
                collect(ctx, -1)
                ctx.set(dut.clear, 0)
            beats = pack_lanes(sched.input_beats(codes[a:b]), c.adc_bits)
            pauses = {sched.threshold_pause_beat(t): thr for t, thr in updates.items()} \
                if seg == 0 else {}
            for k, word in enumerate(beats):
                if k in pauses:
                    ctx.set(dut.codes.valid, 0)
                    await ctx.tick()
                    collect(ctx, -1)
                    await write_thresholds(ctx, pauses[k])
                ctx.set(dut.codes.payload.as_value(), word)
                ctx.set(dut.codes.valid, 1)
                await ctx.tick()
                collect(ctx, k)
                if idle_every and (k + 1) % idle_every == 0:
                    ctx.set(dut.codes.valid, 0)
                    await ctx.tick()
                    collect(ctx, -1)
            ctx.set(dut.codes.valid, 0)
            for _ in range(2):
                await ctx.tick()
                collect(ctx, -1)

    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    return OutputBeats.from_words(got["row"], got["group"], got["last"], got["pos"],
                                  got["neg"], c.num_scales, lanes, got["accepted"])
