"""The lane-parallel streaming RVSM pixel array, built from one :class:`ArrayContract`.

Where :class:`~rvsm.rtl.parallel.array.RvsmArray` builds an adder network and an accumulator per
(scale, pixel), this array streams the frame through ``P`` lanes: the datapath is
O(P), and only the state memories grow with the sensor. One clock domain ``sync``
(synchronous reset ``rst``), composed of one component per pipeline stage::

    codes (P ADC codes per beat, raster order, valid/ready)
      -> InputStage: input register; advance = an accepted beat, a cycle later
      -> WindowStage: line buffer (one memory, depth W/P, word 2L rows x P
         codes), window register of 2E+1 column-group slabs of 2L+1 rows
         and the centre position                                     [stage 0]
         zero padding by registered row/column masks                 [stage 1]
      -> SumStage: per lane 8-fold symmetric orbit sums, shared by all
         scales; per scale a constant CSD shift-and-add tree,
         registered every LEVELS_PER_STAGE adder levels              [stage Q]
      -> StateStage: threshold and accumulator memories (banked, bank
         outputs registered), read at Q - READ_STAGES              [at stage Q]
      -> OutputStage: acc (0 in the first frame after clear) + (sum >> shift)
                                                                      [Q+1]
         compare (on the pre-saturation total) and saturate           [Q+2]
         fire / reset -> write back to the accumulator memory;
         spikes + position registered on the output stream            [Q+3]
    PositionStage: the position and valid bits beside the datapath, tapped
    by the state (read, write-back) and output stages

Each stage is a ``wiring.Component`` with its own signature and numpy model
(:mod:`.input_stage`, :mod:`.window_stage`, :mod:`.sum_stage`, :mod:`.position_stage`,
:mod:`.state_stage`, :mod:`.output_stage`); this module wires them.

L is the kernel radius (:func:`~rvsm.model.kernels.geometry.kernel_radius`), E =
``ceil(L / P)`` the column groups a window reaches either side, G = ``W / P``.

**State.** Per scale one accumulator memory (word = P signed W-bit accumulators) and one
threshold memory (word = P thresholds of W-1 bits), depth ``H*G``, address ``y*G + g``,
each a :class:`~rvsm.rtl.stream.banked_memory.BankedMemory` split into banks of at most
:attr:`StreamGeometry.bank_words` words (a power of two, 1024 by default) whose read
data is registered before the bank multiplexer (block-RAM timing); the banks come from
the memory target (:mod:`rvsm.rtl.stream.memory_target`: a parameter of the array, or
the platform's, e.g. the FPGA flow's block RAMs; generic Amaranth memories otherwise).
Each address is read and written once per frame, :attr:`StreamGeometry.rmw_depth` beats
apart, so the read-modify-write needs no forwarding as long as ``H*G > rmw_depth``
(checked). A bank's read is disabled when its write port writes the same address at
that edge (no read-first bypass multiplexer after the block RAM); threshold writes are
registered and forwarded after the bank registers to a read meeting them, so the rule
below holds.

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
  With shared thresholds (``threshold.storage = "shared"``) there is no threshold
  memory: ``addr`` is the scale, ``data`` one threshold, written to that scale's
  register with the same timing; the registers start at the contract's nominal
  thresholds (:class:`~rvsm.rtl.stream.state_stage.StateStage`).

The bit-accurate model is :meth:`ArrayContract.run`, rearranged into beats by
:class:`~rvsm.rtl.stream.schedule.StreamSchedule`; the component is driven in
``amaranth.sim`` by :mod:`rvsm.rtl.stream.drive`.
"""

from __future__ import annotations

from dataclasses import dataclass

from amaranth.hdl import Module, Signal, Value
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from rvsm.model.fixed.contract import ArrayContract
from rvsm.rtl.mutations import check_mutation
from rvsm.rtl.stream.banked_memory import BankedMemory
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.input_stage import InputStage
from rvsm.rtl.stream.memory_target import MemoryTarget, memory_target
from rvsm.rtl.stream.output_stage import OutputStage
from rvsm.rtl.stream.position_stage import PositionStage
from rvsm.rtl.stream.schedule import StreamSchedule
from rvsm.rtl.stream.signatures import (
    code_beat_signature,
    spike_beat_signature,
    threshold_word_bits,
)
from rvsm.rtl.stream.state_stage import StateStage
from rvsm.rtl.stream.sum_stage import SumStage
from rvsm.rtl.stream.window_stage import WindowStage

__all__ = ["RvsmStreamArray", "StreamProbes"]


@dataclass
class StreamProbes:
    """Internal signals a formal harness observes (:mod:`rvsm.rtl.stream.harnesses`),
    gathered from the stages once the array is elaborated: ``advance`` (the pipeline
    steps at this edge), ``clear`` (the registered clear that flushes it), the
    accumulator memories' read (``acc_read_addr`` sampled at an ``advance`` edge where
    ``acc_read_valid``) and write-back (``acc_write_en``, ``acc_write_addr``), and per
    scale and lane the tail's registers (``lanes[s][i]``: ``acc`` (the accumulator read,
    0 in a fresh frame; the value ``total`` is loaded from), ``total``, ``thr1``, ``sat``,
    ``thr2``, ``pos``, ``neg``, ``after``: the pre-saturation total, the threshold read,
    the saturated total, that threshold one stage on, the spikes and the value written
    back), valid in a cycle where ``acc_write_en`` is high; ``threshold_memories``: per
    scale the threshold :class:`BankedMemory` (its formal-only ``probe_addr`` /
    ``probe_data``); ``window`` (cell ``(d, j)`` of the masked window, stage 1, valid
    where ``window_valid``) and ``sums[s][i]`` (stage Q, valid where ``sum_valid``)."""

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


def _shared_threshold_docs(contract: ArrayContract) -> dict[str, str]:
    """The threshold ports of an array with one threshold register per scale."""
    c = contract
    return {"thr_we": "threshold write enable (one scale's register per rising edge)",
            "thr_addr": f"scale s, 0..{c.num_scales - 1} (threshold.storage = shared)",
            "thr_data": f"the scale's threshold, 1..{(1 << c.threshold_bits) - 1} "
                        f"(configured to {', '.join(map(str, c.shared_thresholds))})"}


class RvsmStreamArray(wiring.Component):
    """``S x H x W`` accumulators fed by a ``lanes``-wide raster stream of ADC codes.

    Members: ``codes`` In(:func:`code_beat_signature`), ``spikes``
    Out(:func:`spike_beat_signature`), ``thr`` In(:func:`threshold_write_signature`),
    ``clear`` In(1); Verilog ports ``codes_payload``, ``codes_valid``, ``codes_ready``,
    ``spikes_payload``, ``spikes_valid``, ``thr_we``, ``thr_addr``, ``thr_data``,
    ``clear`` (:mod:`rvsm.rtl.ports`, described by :meth:`port_docs`). See the module
    docstring for the schedule and the controls; sizes and the named timing properties
    are in :attr:`geometry` (:class:`StreamGeometry`). ``memory``: the state memories'
    target (:class:`~rvsm.rtl.stream.memory_target.MemoryTarget`); ``None``: the one of
    the platform the array is elaborated for (:func:`memory_target`).
    """

    def __init__(self, contract: ArrayContract, lanes: int = 1,
                 bank_words: int = StreamGeometry.BANK_WORDS, mutation: str | None = None,
                 memory: MemoryTarget | None = None):
        geo = StreamGeometry(contract, lanes, bank_words)
        #: A deliberate bug (:mod:`rvsm.rtl.mutations`) or None (the shipped logic).
        self.mutation = check_mutation(mutation, "stream")
        self.geometry = geo
        self.contract = contract
        self.lanes = geo.lanes
        self.groups = geo.groups
        self.memory = memory
        self._stages: dict[str, wiring.Component] | None = None
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
            "thr": In(geo.threshold_bus),
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
            **(_shared_threshold_docs(c) if geo.shared_thresholds else {
                "thr_we": "threshold write enable (one memory word per rising edge)",
                "thr_addr": f"(scale s << {wb}) | (y*{g} + g)",
                "thr_data": f"{p} thresholds, lane i at bits [i*{c.threshold_bits} +: "
                            f"{c.threshold_bits}], each 1..{(1 << c.threshold_bits) - 1}"}),
            "clear": "synchronous restart of the stream: positions in flight dropped, "
                     "accumulators zero in the next frame, thresholds kept",
        }

    @property
    def latency(self) -> int:
        """:attr:`StreamGeometry.latency` (clock cycles, back-to-back beats)."""
        return self.geometry.latency

    @property
    def pixel_to_spike(self) -> int:
        """:attr:`StreamGeometry.pixel_to_spike` (clock cycles, back-to-back beats)."""
        return self.geometry.pixel_to_spike

    @property
    def lag(self) -> int:
        """:attr:`StreamGeometry.lag` (beats)."""
        return self.geometry.lag

    @property
    def schedule(self) -> StreamSchedule:
        """:attr:`StreamGeometry.schedule`."""
        return self.geometry.schedule

    def elaborate(self, platform: object) -> Module:
        """The stages, wired in datapath order (module docstring)."""
        m = Module()
        geo, mutation = self.geometry, self.mutation
        target = self.memory if self.memory is not None else memory_target(platform)
        stages = {  # submodule names: the stages' module names (dut.state_stage.acc_s0, ...)
            "input_stage": InputStage(self.contract.adc_bits, geo.lanes, mutation),
            "window_stage": WindowStage(geo, mutation),
            "sum_stage": SumStage(geo),
            "position_stage": PositionStage(geo),
            "state_stage": StateStage(geo, target, mutation),
            "output_stage": OutputStage(geo, target, mutation),
        }
        for name, stage in stages.items():
            m.submodules[name] = stage
        self._stages = stages
        inp, win, sums, pos, state, out = stages.values()
        wiring.connect(m, wiring.flipped(self.codes), inp.codes)
        wiring.connect(m, wiring.flipped(self.thr), state.thr)
        wiring.connect(m, inp.ctl, win.ctl, sums.ctl, pos.ctl, state.ctl, out.ctl)
        wiring.connect(m, pos.read, state.read)
        wiring.connect(m, win.centre, pos.centre)
        wiring.connect(m, pos.write, state.write, out.position)
        wiring.connect(m, out.spikes, wiring.flipped(self.spikes))
        m.d.comb += [
            inp.clear.eq(self.clear), win.beat.eq(inp.beat),
            sums.window.eq(win.window),
            pos.centre_next_addr.eq(win.next_addr), state.write_data.eq(out.write_data),
            out.sums.eq(sums.sums), out.words.eq(state.words),
            out.fresh.eq(pos.fresh), out.fresh_ahead.eq(pos.fresh_ahead),
        ]
        return m

    @property
    def probes(self) -> StreamProbes:
        """Internal signals for formal harnesses (:class:`StreamProbes`), once the array
        and its stages are elaborated (an ``ElaborateAfter`` beside it)."""
        if self._stages is None:
            raise RuntimeError("the stream array's probes exist once it is elaborated")
        inp, win, sums, pos, state, out = self._stages.values()
        ctl = inp.ctl
        c, geo = self.contract, self.geometry
        return StreamProbes(
            ctl.advance, ctl.clear, pos.read.addr, ctl.advance & pos.read.valid,
            pos.write.en, pos.write.addr, out.lanes, state.threshold_memories,
            {cell: win.window[k] for k, cell in enumerate(geo.window_cells())},
            pos.valid_at[1],
            [[sums.sums[i][f"s{s}"] for i in range(geo.lanes)] for s in range(c.num_scales)],
            pos.valid_at[geo.sum_stage])
