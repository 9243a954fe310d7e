"""The streaming array as AXI IP: :class:`RvsmAxisIp` (docs/ip.md).

One clock domain ``sync`` (synchronous reset ``rst``), joined from one component per
concern, each with its own signature and cycle model::

    s_axis (video: P codes/beat, tuser = start of frame, tlast = end of line)
      -> InputGate: tready = ~busy & (drop | credit_r); flush beats, clear; the
         input register                                  (input_gate.py)
         FramingCheck beside it: tuser/tlast against the position  (framing_check.py)
      -> RvsmStreamArray (codes, clear, thr)
         <- ThresholdPort: THR_ADDR/THR_DATA commits, the reset walk (threshold_port.py)
      -> OutputPacker: spike beat -> tdata + tuser + tlast, drop  (output_packer.py)
      -> SyncFIFOBuffered(fifo_depth) (w_stream) -> m_axis
    s_axil -> AxiLiteRegisters(ip_register_map) <-> controls, STATUS, THR_*,
              EventCounters: IN_BEATS, OUT_BEATS, DROPPED   (event_counters.py)

Submodules: ``array``, ``regs``, ``fifo``, ``gate``, ``framing``, ``threshold_port``,
``packer``, ``counters``. A wrapper adds its own registers with ``extra_registers``
(:meth:`~rvsm.rtl.ip.register_map.RegisterMap.extended`, offsets in
:data:`~rvsm.rtl.ip.register_map.EXTRA_WINDOW`) and drives or reads their fields
through :attr:`RvsmAxisIp.regs` (``value``, ``set``, ``pulse``, ``written``).

**Input register.** What the gate lets through (an accepted beat, a flush beat, a
clear) passes one register before the array's own input register: no path runs from
the gate's control state (flush and clear requests, credit) to the array, whose input
register may sit far from it (the IP's critical path at 150 MHz on the ECP5). It costs
one cycle of release latency (:attr:`RvsmAxisIp.RELEASE_CYCLES`).

**Policies** (``CONTROL.drop``). *Stall* (0, the reset value; replay from memory): the
array has no output back-pressure and an output beat reaches the FIFO
:attr:`RvsmAxisIp.IN_FLIGHT` cycles after the gate accepts the input beat that releases
it, so the input is gated by credits, never by the FIFO's fullness: ``tready`` is high
only in a cycle after one with ``level + r1 + r2 + v + 1 < fifo_depth`` (``level`` the
FIFO's beats, ``r1`` and ``r2`` beats accepted one and two cycles before, in the input
registers, ``v`` the array's output that cycle; the credit is registered, so no path
runs from the FIFO's level or ``m_axis_tready`` to ``s_axis_tready`` or the array, and
the ``+ 1`` covers the beat accepted meanwhile). Every beat in flight then finds room:
no beat is lost, whatever the sink does. *Drop* (1; a live sensor, which cannot
stall): ``tready`` stays high (except
while busy); an output beat that reaches the FIFO while it is full (``w_rdy`` low: the
FIFO holds ``fifo_depth`` beats) is dropped whole, ``STATUS.overflow`` is set and
``DROPPED`` counts it. The cycle model :mod:`rvsm.rtl.ip.model` gives the exact drops
for an input-valid and output-ready pattern.

**Reset.** After ``rst`` the IP writes the top rail ``2**(W-1)-1`` into every threshold
word, one word per cycle (``S*H*G`` cycles, ``STATUS.init`` and ``busy`` high, input
``tready`` low, threshold commits refused): the thresholds then have the same defined
value after every reset as after configuration, on any memory technology (a block
RAM's initial contents are an FPGA feature; an ASIC SRAM has none). Load the thresholds
after ``STATUS.init`` falls. With shared thresholds (``threshold.storage = "shared"``:
one register per scale, ``THR_ADDR`` a scale only, ``THR_DATA`` one threshold) the walk
takes ``S`` cycles and restores each scale's nominal threshold: the IP spikes correctly
with no threshold load.

**Flush and clear.** ``CONTROL.flush`` inserts ``lag`` zero beats (input ``tready``
low meanwhile), so every accepted beat's output comes out; ``CONTROL.clear`` restarts
the stream at frame 0 (accumulators zero in the next frame, thresholds kept). Written
together, the flush comes first: ``CONTROL = flush | clear`` ends a stream and starts
the next. Flush beats count as the next frame's beats, so clear after a flush before
sending a new frame.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict

from amaranth.hdl import Cat, Module, Signal
from amaranth.lib import wiring
from amaranth.lib.data import View
from amaranth.lib.fifo import SyncFIFOBuffered
from amaranth.lib.wiring import In, Out

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.versions import rvsm_version
from rvsm.rtl.flow_files import design_point_digest
from rvsm.rtl.ip.axi_lite import AxiLiteRegisters, AxiLiteSignature
from rvsm.rtl.ip.axis import AxiStreamSignature, spike_tdata_layout, video_lane_bits
from rvsm.rtl.ip.event_counters import EventCounters
from rvsm.rtl.ip.framing_check import FramingCheck
from rvsm.rtl.ip.input_gate import InputGate
from rvsm.rtl.ip.output_packer import OutputPacker
from rvsm.rtl.ip.register_map import ADDR_BITS, Register, RegisterMap, ip_register_map
from rvsm.rtl.ip.threshold_port import ThresholdPort
from rvsm.rtl.rtl_digest import rtl_digest
from rvsm.rtl.stream.array import RvsmStreamArray
from rvsm.rtl.stream.dimensions import StreamGeometry

__all__ = ["COUNTERS", "IP_ARCH", "RvsmAxisIp", "ip_options", "ip_regmap"]

#: The architecture name of the IP in provenance, digests and ``ports.json``.
IP_ARCH = "stream_axis"
#: The beat counters, in the order of :class:`EventCounters`' events: input handshakes,
#: output handshakes, dropped output beats (registers of the same names).
COUNTERS = ("IN_BEATS", "OUT_BEATS", "DROPPED")


class RvsmAxisIp(wiring.Component):
    """The streaming array behind AXI4-Stream video in, AXI4-Stream spikes out and
    AXI4-Lite registers (see the module docstring).

    Members: ``s_axis`` In(:class:`AxiStreamSignature`), ``m_axis``
    Out(:class:`AxiStreamSignature`), ``s_axil`` In(:class:`AxiLiteSignature`); Verilog
    ports ``s_axis_tdata`` ... ``s_axil_rready`` plus ``clk`` and ``rst``. ``regmap`` is
    the register map (:func:`ip_register_map`, plus ``extra_registers``); timing in
    :attr:`geometry` and the properties below.
    """

    #: Registers from the input gate to the FIFO's write: the IP's input register and
    #: the array's input and output registers (cycles; beats in flight).
    IN_FLIGHT = InputGate.REGISTERS + 2
    #: Smallest output FIFO (beats) accepted.
    MIN_FIFO_DEPTH = 4
    #: Smallest output FIFO that takes a beat every cycle while the sink is always ready
    #: (two beats in the FIFO, IN_FLIGHT in flight, one accepted while the registered
    #: credit is formed).
    FULL_RATE_DEPTH = IN_FLIGHT + 4
    #: Default output FIFO depth (beats).
    FIFO_DEPTH = 16
    #: Cycles from the edge accepting a releasing input beat to the cycle its output is
    #: offered on ``m_axis`` (FIFO empty): the IP's input register and the array's input
    #: and output registers (IN_FLIGHT), the FIFO write (1) and the FIFO's output
    #: register (1).
    RELEASE_CYCLES = IN_FLIGHT + 2

    def __init__(self, contract: ArrayContract, lanes: int = 1,
                 fifo_depth: int = FIFO_DEPTH, extra_registers: Sequence[Register] = ()):
        if not isinstance(fifo_depth, int) or not \
                self.MIN_FIFO_DEPTH <= fifo_depth < 1 << 16:
            raise RvsmError(f"fifo_depth must be an integer from {self.MIN_FIFO_DEPTH} to "
                            f"65535, got {fifo_depth!r}")
        self.array = RvsmStreamArray(contract, lanes)
        self.contract = contract
        self.geometry: StreamGeometry = self.array.geometry
        self.lanes = self.geometry.lanes
        self.fifo_depth = fifo_depth
        #: The options that build this IP (provenance, digest).
        self.options = ip_options(self.lanes, fifo_depth, extra_registers)
        self.rtl_digest = rtl_digest(contract, IP_ARCH, self.options)
        self.regmap: RegisterMap = ip_regmap(contract, self.lanes, fifo_depth,
                                             extra_registers)
        #: The parts (submodules; attributes so that a bench can observe them): the
        #: register file, the input gate, the framing check, the threshold port, the
        #: output packer, the output FIFO and the beat counters.
        self.regs = AxiLiteRegisters(self.regmap)
        self.gate = InputGate(contract.adc_bits, self.lanes, self.lag, fifo_depth)
        self.framing = FramingCheck(contract.height, self.geometry.groups)
        self.threshold_port = ThresholdPort(self.geometry, self.regmap)
        self.packer = OutputPacker(self.geometry)
        self.fifo = SyncFIFOBuffered(width=self.packer.word.size, depth=fifo_depth)
        self.counters = EventCounters(COUNTERS)
        #: Control state (threshold initialisation, flush and clear requests) and the
        #: drop strobe, for benches and diagrams.
        self.init: Signal = self.threshold_port.init
        self.flush_req: Signal = self.gate.flush_req
        self.clear_req: Signal = self.gate.clear_req
        self.drop: Signal = self.packer.drop
        super().__init__(self.interface(contract, self.lanes))

    @staticmethod
    def interface(contract: ArrayContract, lanes: int) -> wiring.Signature:
        """The IP's signature for ``contract`` and ``lanes``."""
        c, geo = contract, StreamGeometry(contract, lanes)
        out = spike_tdata_layout(c.num_scales, geo.lanes, c.height, geo.groups)
        return wiring.Signature({
            "s_axis": In(AxiStreamSignature(geo.lanes * video_lane_bits(c.adc_bits))),
            "m_axis": Out(AxiStreamSignature(out.size)),
            "s_axil": In(AxiLiteSignature(ADDR_BITS)),
        })

    @property
    def lag(self) -> int:
        """Output ``p`` is released by input beat ``p + lag`` (beats; the array's)."""
        return self.geometry.lag

    @property
    def latency(self) -> int:
        """Cycles from the edge accepting beat ``p + window_lag`` to ``p``'s output on
        ``m_axis`` (beats back to back, FIFO empty): the array's latency plus the IP's
        input register and the FIFO's two cycles."""
        return self.geometry.latency + self.RELEASE_CYCLES - 2

    @property
    def pixel_to_spike(self) -> int:
        """Cycles from the edge accepting a pixel's beat on ``s_axis`` to its spikes on
        ``m_axis`` (beats back to back, FIFO empty): ``lag + RELEASE_CYCLES``, one more
        than ``window_lag + latency`` (the input register before the array)."""
        return self.lag + self.RELEASE_CYCLES

    @property
    def init_cycles(self) -> int:
        """Cycles after ``rst`` during which the thresholds are set (``S*H*G``; ``S`` with
        shared thresholds)."""
        return self.contract.num_scales * self.geometry.threshold_words

    def elaborate(self, platform: object) -> Module:
        """The parts (module docstring), joined: streams with ``wiring.connect``, the
        register file's fields by name."""
        m = Module()
        regs, gate, thr, fifo, arr = self.regs, self.gate, self.threshold_port, self.fifo, \
            self.array
        for name, part in (("array", arr), ("regs", regs), ("fifo", fifo), ("gate", gate),
                           ("framing", self.framing), ("threshold_port", thr),
                           ("packer", self.packer), ("counters", self.counters)):
            m.submodules[name] = part
        # the datapath: s_axis -> gate -> array -> packer -> FIFO -> m_axis
        wiring.connect(m, wiring.flipped(self.s_axis), gate.s_axis)
        wiring.connect(m, gate.codes, arr.codes)
        wiring.connect(m, thr.thr, arr.thr)
        wiring.connect(m, arr.spikes, self.packer.spikes)
        wiring.connect(m, self.packer.beats, fifo.w_stream)
        wiring.connect(m, wiring.flipped(self.s_axil), regs.bus)
        out = View(self.packer.word, fifo.r_data)
        sent = self.m_axis.tvalid & self.m_axis.tready
        m.d.comb += [arr.clear.eq(gate.clear), gate.out_valid.eq(arr.spikes.valid),
                     gate.fifo_level.eq(fifo.level),
                     self.m_axis.tvalid.eq(fifo.r_rdy), self.m_axis.tdata.eq(out.tdata),
                     self.m_axis.tuser.eq(out.tuser), self.m_axis.tlast.eq(out.tlast),
                     fifo.r_en.eq(self.m_axis.tready)]
        # the framing check beside the gate
        framing = self.framing
        m.d.comb += [framing.accepted.eq(gate.accepted), framing.tuser.eq(self.s_axis.tuser),
                     framing.tlast.eq(self.s_axis.tlast), framing.advance.eq(gate.codes.valid),
                     framing.restart.eq(gate.restart)]
        # the register file: controls in, status and counts out
        thr_data = self.regmap.thr_data_registers()
        m.d.comb += [gate.ctl.init.eq(thr.init), gate.ctl.drop.eq(regs.value["CONTROL.drop"]),
                     gate.ctl.flush.eq(regs.pulse["CONTROL.flush"]),
                     gate.ctl.clear.eq(regs.pulse["CONTROL.clear"]),
                     thr.data.eq(Cat(*(regs.value[f"{r.name}.data"] for r in thr_data))),
                     thr.commit.eq(regs.written[thr_data[-1].name]),
                     thr.address_written.eq(regs.written["THR_ADDR"]),
                     thr.wdata.eq(regs.wdata),
                     regs.value["THR_ADDR.scale"].eq(thr.scale),
                     regs.refuse["THR_ADDR"].eq(thr.init),
                     regs.refuse[thr_data[-1].name].eq(thr.init),
                     regs.set["STATUS.framing"].eq(framing.error),
                     regs.set["STATUS.overflow"].eq(self.drop),
                     self.counters.events.eq(Cat(gate.accepted, sent, self.drop)),
                     self.counters.reset.eq(regs.pulse["CONTROL.counters_reset"])]
        if not self.geometry.shared_thresholds:
            m.d.comb += regs.value["THR_ADDR.word"].eq(thr.word)
        for name in self.counters.names:
            m.d.comb += regs.value[f"{name}.count"].eq(self.counters.count(name))
        # status as registers (one cycle behind): the register read multiplexer starts
        # at flip-flops
        m.d.sync += [regs.value["STATUS.init"].eq(thr.init),
                     regs.value["STATUS.flushing"].eq(gate.flushing),
                     regs.value["STATUS.busy"].eq(gate.busy),
                     regs.value["STATUS.fifo_level"].eq(fifo.level)]
        return m


def ip_options(lanes: int, fifo_depth: int,
               extra_registers: Sequence[Register] = ()) -> dict[str, object]:
    """The options that build the IP (JSON values; the RTL digest's): ``lanes``,
    ``fifo_depth`` and, when there are any, the ``extra_registers`` declared."""
    options: dict[str, object] = {"lanes": lanes, "fifo_depth": fifo_depth}
    if extra_registers:
        options["extra_registers"] = [asdict(r) for r in extra_registers]
    return options


def ip_regmap(contract: ArrayContract, lanes: int, fifo_depth: int,
              extra_registers: Sequence[Register] = ()) -> RegisterMap:
    """The register map of the IP built with ``lanes``, ``fifo_depth`` and
    ``extra_registers`` (its identity registers hold this build's digests), without
    building the IP."""
    options = ip_options(lanes, fifo_depth, extra_registers)
    regmap = ip_register_map(contract, lanes, fifo_depth,
                             rtl_digest(contract, IP_ARCH, options),
                             design_point_digest(contract), rvsm_version())
    return regmap.extended(extra_registers)
