"""The streaming array's state: :class:`StateStage` (threshold bus, state memories).

Per scale one threshold memory (word = P thresholds of W-1 bits, every threshold at the
top rail ``2**(W-1)-1`` at configuration) and one accumulator memory (word = P signed
W-bit accumulators), depth ``H*G``, address ``y*G + g``, each a
:class:`~rvsm.rtl.stream.banked_memory.BankedMemory` with ``READ_STAGES`` advance edges
from the read address (the position pipeline's ``read`` tap) to ``words`` (stage Q).
The accumulator read-modify-write needs no forwarding: each address is read and written
once per frame, ``rmw_depth`` beats apart, and the read is gated by a cheaper superset
of the collisions (``valid`` of the write-back and ``rmw_guard_bits`` low address bits).

Shared thresholds (``threshold.storage = "shared"``, :attr:`StreamGeometry.shared_thresholds`):
no threshold memory; per scale one register of W-1 bits, configured to the contract's
nominal threshold (so the array spikes right with no threshold load; ``rst`` leaves it,
as it leaves the memories) and written through the same bus (``addr = s``, ``data`` one
threshold) with the same timing as a memory word: a write accepted at edge ``e`` lands
at ``e + 1``, and a read (an ``advance`` edge) from ``e + 1`` on sees it.

Threshold writes (the bus ``thr``) pass a register (``thr_*_r``) and land one edge after
the bus accepts them, so a read at the bus' edge does not see them; a read meeting the
registered write at the next edge gets its data forwarded after the bank registers (a
registered hit flag per scale, two registers of write data shared by the scales). The
write's address match against the read address is itself registered, computed one edge
ahead from the values both take at that edge, once for each value the read address may
take (``thr_rd_match_adv``, ``thr_rd_match_hold``, chosen after the edge by the
registered ``advance``): no comparator between the read address and the forwarding, and
no path from the beat advance into the comparator.

:class:`StateModel` is the numpy model (the memories as arrays, cycle by cycle).
"""

from __future__ import annotations

import numpy as np
from amaranth.hdl import Cat, Module, Mux, Signal, Value, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from rvsm.rtl.stream.banked_memory import BankedMemory
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.input_stage import control_signature
from rvsm.rtl.stream.memory_target import GENERIC_MEMORY, MemoryTarget
from rvsm.rtl.stream.position_stage import read_tap_signature, write_tap_signature
from rvsm.rtl.stream.signatures import threshold_word_bits, top_threshold_word

__all__ = ["StateModel", "StateStage", "state_words_layout", "write_back_layout"]


def state_words_layout(num_scales: int, lanes: int, accumulator_bits: int
                       ) -> data.StructLayout:
    """What the state memories deliver at stage Q: per scale ``acc[s]`` (P accumulators
    of W bits, lane ``i`` at ``[i*W +: W]``) and ``thr[s]`` (P thresholds of W-1 bits)."""
    wa, tw = accumulator_bits, accumulator_bits - 1
    return data.StructLayout({"acc": data.ArrayLayout(unsigned(lanes * wa), num_scales),
                              "thr": data.ArrayLayout(unsigned(lanes * tw), num_scales)})


def write_back_layout(num_scales: int, lanes: int, accumulator_bits: int) -> data.ArrayLayout:
    """The words written back to the accumulator memories, one per scale."""
    return data.ArrayLayout(unsigned(lanes * accumulator_bits), num_scales)


class StateStage(wiring.Component):
    """``ctl`` In(:func:`~rvsm.rtl.stream.input_stage.control_signature`), ``read``
    In(:func:`~rvsm.rtl.stream.position_stage.read_tap_signature`), ``write``
    In(:func:`~rvsm.rtl.stream.position_stage.write_tap_signature`), ``write_data``
    In(:func:`write_back_layout`), ``thr`` In(the threshold-write bus) -> ``words``
    Out(:func:`state_words_layout`, stage Q). After elaboration
    :attr:`threshold_memories` and :attr:`accumulator_memories` hold the memories.

    ``target``: the memories' banks (:class:`~rvsm.rtl.stream.memory_target.MemoryTarget`;
    with ``held_write``, the accumulators write where their own registered copy of the
    write-back's ``valid`` holds: a stalled write repeats the same word to the same
    address, and the write of a clear edge lands in a word the fresh frame after the
    clear reads as zero or captures, and overwrites). ``mutation``
    ``"stream.no_threshold_forwarding"`` (:mod:`rvsm.rtl.mutations`)."""

    def __init__(self, geometry: StreamGeometry, target: MemoryTarget = GENERIC_MEMORY,
                 mutation: str | None = None):
        self.geometry, self.target, self.mutation = geometry, target, mutation
        c, geo = geometry.contract, geometry
        #: Per scale the threshold / accumulator memory, set by :meth:`elaborate`.
        self.threshold_memories: list[BankedMemory] = []
        self.accumulator_memories: list[BankedMemory] = []
        s, p, wa = c.num_scales, geo.lanes, c.accumulator_bits
        super().__init__({
            "ctl": In(control_signature()),
            "read": In(read_tap_signature(geo.beats_per_frame)),
            "write": In(write_tap_signature(c.height, geo.groups)),
            "write_data": In(write_back_layout(s, p, wa)),
            "thr": In(geo.threshold_bus),
            "words": Out(state_words_layout(s, p, wa)),
        })

    def elaborate(self, platform: object) -> Module:
        m = Module()
        c, geo = self.geometry.contract, self.geometry
        p, words, wa = geo.lanes, geo.beats_per_frame, c.accumulator_bits
        advance, read, write = self.ctl.advance, self.read, self.write
        bus = self.thr
        bus_we = Signal(name="thr_we_r", reset_less=True)
        bus_addr = Signal.like(bus.addr, name="thr_addr_r", reset_less=True)
        bus_data = Signal.like(bus.data, name="thr_data_r", reset_less=True)
        m.d.sync += [bus_we.eq(bus.we), bus_addr.eq(bus.addr), bus_data.eq(bus.data)]
        self.threshold_memories, self.accumulator_memories = [], []
        self.threshold_registers = []
        if geo.shared_thresholds:
            self._shared_thresholds(m, bus_we, bus_addr, bus_data)
        else:
            self._threshold_memories(m, bus_we, bus_addr, bus_data)
        memory = {"bank_words": geo.bank_words, "read_stages": geo.READ_STAGES,
                  "target": self.target}
        for s in range(c.num_scales):
            held = self.target.held_write
            acc_mem = BankedMemory(p * wa, words, guard_bits=geo.rmw_guard_bits,
                                   held_write=held, **memory)
            m.submodules[f"acc_s{s}"] = acc_mem
            self.accumulator_memories.append(acc_mem)
            m.d.comb += [acc_mem.advance.eq(advance), acc_mem.read_addr.eq(read.addr),
                         acc_mem.read_bank.eq(read.bank), acc_mem.write_en.eq(write.en),
                         acc_mem.write_addr.eq(write.addr),
                         acc_mem.write_data.eq(self.write_data[s]),
                         acc_mem.may_write.eq(write.valid),
                         acc_mem.advance_next.eq(self.ctl.advance_next),
                         self.words.acc[s].eq(acc_mem.data)]
            if held:
                m.d.comb += acc_mem.write_en_next.eq(write.valid_next)
        return m

    def _shared_thresholds(self, m: Module, bus_we: Value, bus_addr: Value,
                           bus_data: Value) -> None:
        """Per scale one ``W-1``-bit register (configuration value: the contract's
        nominal threshold, no reset), written where the registered write lands; the
        value a read at an ``advance`` edge takes (the landing write included) goes
        through ``READ_STAGES`` advance-loaded registers, so it reaches ``words`` with
        the accumulators read at that edge: the threshold memories' timing."""
        c, geo, advance = self.geometry.contract, self.geometry, self.ctl.advance
        tw = c.threshold_bits
        for s, nominal in enumerate(c.shared_thresholds):
            reg = Signal(unsigned(tw), name=f"thr_s{s}", init=nominal, reset_less=True)
            landing = bus_we & (bus_addr == s)
            with m.If(landing):
                m.d.sync += reg.eq(bus_data)
            read = [Signal(unsigned(tw), name=f"thr_s{s}_q{k}", init=nominal,
                           reset_less=True) for k in range(geo.READ_STAGES)]
            with m.If(advance):
                m.d.sync += [read[0].eq(Mux(landing, bus_data, reg)),
                             *(b.eq(a) for a, b in zip(read, read[1:], strict=False))]
            m.d.comb += self.words.thr[s].eq(Cat(*([read[-1]] * geo.lanes)))
            self.threshold_registers.append(reg)

    def _threshold_memories(self, m: Module, bus_we: Value, bus_addr: Value,
                            bus_data: Value) -> None:
        """Per scale a threshold memory, writes forwarded to a read of their word
        (module docstring)."""
        c, geo = self.geometry.contract, self.geometry
        p, words, tw = geo.lanes, geo.beats_per_frame, c.threshold_bits
        advance, read, bus = self.ctl.advance, self.read, self.thr
        word_bits = threshold_word_bits(words)
        bus_word = bus_addr[:word_bits]
        bus_scale = bus_addr[word_bits:]
        # bus_addr == read.addr, registered (module docstring)
        matches = [Signal(name=f"thr_rd_match_{case}", init=1, reset_less=True)
                   for case in ("adv", "hold")]
        advanced = Signal(name="advanced", reset_less=True)
        m.d.sync += [*(match.eq(bus.addr[:word_bits] == addr) for match, addr in
                       zip(matches, (read.addr_next_adv, read.addr_next_hold), strict=True)),
                     advanced.eq(advance)]
        rd_match = Mux(advanced, *matches)
        fwd_data = [Signal.like(bus.data, name=f"thr_fwd{k}_data", reset_less=True)
                    for k in (1, 2)]  # shared by the scales
        with m.If(advance):
            m.d.sync += [fwd_data[0].eq(bus_data), fwd_data[1].eq(fwd_data[0])]
        memory = {"bank_words": geo.bank_words, "read_stages": geo.READ_STAGES,
                  "target": self.target}
        for s in range(c.num_scales):
            thr_mem = BankedMemory(p * tw, words, forward=True,
                                   init_word=top_threshold_word(tw, p), **memory)
            m.submodules[f"thr_s{s}"] = thr_mem
            self.threshold_memories.append(thr_mem)
            hit = bus_we & (bus_scale == s) & rd_match
            m.d.comb += [thr_mem.advance.eq(advance), thr_mem.read_addr.eq(read.addr),
                         thr_mem.read_bank.eq(read.bank),
                         thr_mem.write_en.eq(bus_we & (bus_scale == s)),
                         thr_mem.write_addr.eq(bus_word), thr_mem.write_data.eq(bus_data),
                         thr_mem.advance_next.eq(self.ctl.advance_next),
                         thr_mem.forward_hit.eq(
                             hit if self.mutation != "stream.no_threshold_forwarding" else 0),
                         thr_mem.forward_data.eq(fwd_data[1]),
                         self.words.thr[s].eq(thr_mem.data)]


class StateModel:
    """The numpy model of :class:`StateStage`, one clock edge per :meth:`edge`.

    ``thr (S, H*G, P)`` and ``acc (S, H*G, P)`` are the memories (thresholds at the top
    rail, accumulators undefined: -1 until written). A threshold write accepted by the
    bus at edge ``e`` lands at edge ``e + 1``, and a read at that edge sees it (the
    forwarding). An accumulator read at an edge where the write-back may collide with it
    (the write-back valid, the same bank and ``rmw_guard_bits`` low address bits) is
    undefined (-1), as is one of a word never written. A read at an ``advance`` edge is
    delivered at ``words`` after ``READ_STAGES`` advance edges in all (:attr:`words`:
    ``(acc (S, P), thr (S, P))``, ``None`` before the first)."""

    def __init__(self, geometry: StreamGeometry):
        c, geo = geometry.contract, geometry
        self.geometry = geo
        shape = (c.num_scales, geo.beats_per_frame, geo.lanes)
        self.thr = np.full(shape, (1 << c.threshold_bits) - 1, dtype=np.int64)
        if geo.shared_thresholds:  # every word of a scale holds its one register
            self.thr[:] = np.array(c.shared_thresholds, dtype=np.int64)[:, None, None]
        self.acc = np.full(shape, -1, dtype=np.int64)
        self._bus: tuple[int, int, np.ndarray] | None = None  # the registered write
        self._reads: list[tuple[np.ndarray, np.ndarray]] = []  # in flight, oldest first
        self.words: tuple[np.ndarray, np.ndarray] | None = None

    def edge(self, advance: bool, read_addr: int, write_en: bool, write_valid: bool,
             write_addr: int, write_data: np.ndarray,
             bus: tuple[int, int, np.ndarray] | None) -> None:
        """One rising edge: ``read_addr`` (sampled where ``advance``), the write-back
        (``write_en``, ``write_valid``, ``write_addr``, ``write_data (S, P)``) and the
        threshold bus this edge accepts (``(scale, word, thresholds (P,))`` or ``None``;
        with shared thresholds ``(scale, word, threshold)``, ``word`` unused: the write
        sets the scale's register, which every word of the model mirrors)."""
        geo = self.geometry
        if self._bus is not None:  # the registered write lands now
            s, word, values = self._bus
            if s < len(self.thr):
                self.thr[s, slice(None) if geo.shared_thresholds else word] = values
        self._bus = bus
        if advance:
            acc = self.acc[:, read_addr].copy()
            banked = len(geo.bank_sizes) > 1
            offset_bits = (geo.bank_words - 1 if banked else geo.beats_per_frame - 1
                           ).bit_length()
            k = min(geo.rmw_guard_bits, offset_bits)
            same_bank = not banked or (write_addr >> offset_bits) == (read_addr >> offset_bits)
            if write_valid and same_bank and (write_addr ^ read_addr) % (1 << k) == 0:
                acc[:] = -1
            self._reads.append((acc, self.thr[:, read_addr].copy()))
            if len(self._reads) == geo.READ_STAGES:
                self.words = self._reads.pop(0)
        if write_en:
            self.acc[:, write_addr] = write_data
