"""The streaming array as AXI IP: :class:`RvsmAxisIp` (docs/ip.md).

One clock domain ``sync`` (synchronous reset ``rst``)::

    s_axis (video: P codes/beat, tuser = start of frame, tlast = end of line)
      -> input gate: tready = ~busy & (drop policy | credit_r)   [framing check]
      -> input register (the beat or a flush beat, and clear)
      -> RvsmStreamArray (codes, clear, thr)  <- threshold writes
      -> spikes beat (+ tuser, tlast) -> SyncFIFOBuffered(fifo_depth) -> m_axis
    s_axil -> AxiLiteRegisters(ip_register_map) <-> control, status, counters, THR_*

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

from amaranth.hdl import Cat, Const, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.fifo import SyncFIFOBuffered
from amaranth.lib.wiring import In, Out

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.versions import rvsm_version
from rvsm.rtl.flow_files import design_point_digest
from rvsm.rtl.ip.axi_lite import AxiLiteRegisters, AxiLiteSignature
from rvsm.rtl.ip.axis import AxiStreamSignature, spike_tdata_layout, video_lane_bits
from rvsm.rtl.ip.register_map import ADDR_BITS, RegisterMap, ip_register_map
from rvsm.rtl.rtl_digest import rtl_digest
from rvsm.rtl.stream.array import RvsmStreamArray
from rvsm.rtl.stream.dimensions import StreamGeometry

__all__ = ["IP_ARCH", "RvsmAxisIp", "ip_regmap"]

#: The architecture name of the IP in provenance, digests and ``ports.json``.
IP_ARCH = "stream_axis"


class RvsmAxisIp(wiring.Component):
    """The streaming array behind AXI4-Stream video in, AXI4-Stream spikes out and
    AXI4-Lite registers (see the module docstring).

    Members: ``s_axis`` In(:class:`AxiStreamSignature`), ``m_axis``
    Out(:class:`AxiStreamSignature`), ``s_axil`` In(:class:`AxiLiteSignature`); Verilog
    ports ``s_axis_tdata`` ... ``s_axil_rready`` plus ``clk`` and ``rst``. ``regmap`` is
    the register map (:func:`ip_register_map`); timing in :attr:`geometry` and the
    properties below.
    """

    #: Registers from the input gate to the FIFO's write: the IP's input register and
    #: the array's input and output registers (cycles; beats in flight).
    IN_FLIGHT = 3
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
                 fifo_depth: int = FIFO_DEPTH):
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
        self.options = {"lanes": self.lanes, "fifo_depth": fifo_depth}
        self.rtl_digest = rtl_digest(contract, IP_ARCH, self.options)
        self.regmap: RegisterMap = ip_regmap(contract, self.lanes, fifo_depth)
        #: The register file (:class:`AxiLiteRegisters`) and the output FIFO: submodules,
        #: attributes so that a bench can observe them.
        self.regs = AxiLiteRegisters(self.regmap)
        layout = spike_tdata_layout(contract.num_scales, self.lanes, contract.height,
                                    self.geometry.groups)
        self.fifo = SyncFIFOBuffered(width=layout.size + 2, depth=fifo_depth)
        #: Control state (threshold initialisation, flush and clear requests) and the
        #: drop strobe, for benches and diagrams.
        self.init = Signal(init=1, name="init")
        self.flush_req = Signal(name="flush_req")
        self.clear_req = Signal(name="clear_req")
        self.drop = Signal(name="drop")
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
        m = Module()
        c, geo, arr = self.contract, self.geometry, self.array
        p, n = geo.lanes, c.adc_bits
        m.submodules.array = arr
        m.submodules.regs = regs = self.regs
        wiring.connect(m, wiring.flipped(self.s_axil), regs.bus)
        layout = spike_tdata_layout(c.num_scales, p, c.height, geo.groups)
        m.submodules.fifo = fifo = self.fifo

        init, flush_req, clear_req = self.init, self.flush_req, self.clear_req
        flush_left = Signal(range(self.lag + 1), name="flush_left")
        drop_policy = regs.value["CONTROL.drop"]
        busy = init | flush_req | clear_req
        if self.IN_FLIGHT != 3:
            raise AssertionError("IN_FLIGHT counts the registers built here")
        r1 = Signal(name="accepted_r1")  # the beat in the IP's input register
        r2 = Signal(name="accepted_r2")  # the beat in the array's input register
        # room next cycle for every beat then in flight: registered (timing), with one
        # more beat of margin for the beat this cycle may accept
        credit_r = Signal(init=1, name="credit_r")
        m.d.sync += credit_r.eq(fifo.level + r1 + r2 + arr.spikes.valid + 1
                                < self.fifo_depth)
        credit = drop_policy | credit_r
        s_in = self.s_axis
        m.d.comb += s_in.tready.eq(~busy & credit)
        fire = s_in.tvalid & s_in.tready
        inject = ~init & flush_req & credit
        clear_now = ~init & ~flush_req & clear_req
        lane_bits = video_lane_bits(n)
        codes = Cat(*(s_in.tdata[i * lane_bits:i * lane_bits + n] for i in range(p)))
        # the input register (module docstring): r1 is its valid bit
        in_codes = Signal(len(codes), name="in_codes_r", reset_less=True)
        in_clear = Signal(name="in_clear_r")
        m.d.sync += [r1.eq(fire | inject), r2.eq(r1), in_clear.eq(clear_now),
                     in_codes.eq(Mux(inject, 0, codes))]
        m.d.comb += [arr.codes.valid.eq(r1), arr.codes.payload.as_value().eq(in_codes),
                     arr.clear.eq(in_clear)]

        # flush and clear requests (CONTROL pulses, the cycle after the write)
        with m.If(regs.pulse["CONTROL.flush"] & ~flush_req):
            m.d.sync += [flush_req.eq(1), flush_left.eq(self.lag)]
        with m.If(inject):
            m.d.sync += flush_left.eq(flush_left - 1)
            with m.If(flush_left == 1):
                m.d.sync += flush_req.eq(0)
        with m.If(regs.pulse["CONTROL.clear"]):
            m.d.sync += clear_req.eq(1)
        with m.If(clear_now):
            m.d.sync += clear_req.eq(0)

        # input position: framing check of tuser (start of frame) and tlast (end of line),
        # one cycle after the beat (its handshake registered: no path from the input gate
        # into the position counters); the counters hold the position of the beat in r1
        in_g = Signal(range(geo.groups), name="in_group")
        in_y = Signal(range(c.height), name="in_row")
        fire_r = Signal(name="fire_r")
        tuser_r, tlast_r = Signal(name="tuser_r"), Signal(name="tlast_r")
        m.d.sync += [fire_r.eq(fire), tuser_r.eq(s_in.tuser), tlast_r.eq(s_in.tlast)]
        g_end = in_g == geo.groups - 1
        with m.If(clear_now):
            m.d.sync += [in_g.eq(0), in_y.eq(0)]
        with m.Elif(r1):
            m.d.sync += [in_g.eq(Mux(g_end, 0, in_g + 1)),
                         in_y.eq(Mux(g_end, Mux(in_y == c.height - 1, 0, in_y + 1), in_y))]
        sof = (in_g == 0) & (in_y == 0)
        m.d.comb += regs.set["STATUS.framing"].eq(
            fire_r & ((tuser_r != sof) | (tlast_r != g_end)))

        self._thresholds(m, regs, init)

        # output: spikes beat -> FIFO -> m_axis
        sp = arr.spikes.payload
        beat = Signal(layout, name="out_beat")
        m.d.comb += [beat.pos.eq(sp.pos), beat.neg.eq(sp.neg), beat.row.eq(sp.row),
                     beat.group.eq(sp.group), beat.eof.eq(sp.last)]
        out_sof = (sp.row == 0) & (sp.group == 0)
        out_eol = sp.group == geo.groups - 1
        drop = self.drop
        m.d.comb += drop.eq(arr.spikes.valid & ~fifo.w_rdy)
        m.d.comb += [fifo.w_en.eq(arr.spikes.valid),
                     fifo.w_data.eq(Cat(beat.as_value(), out_sof, out_eol)),
                     self.m_axis.tvalid.eq(fifo.r_rdy),
                     self.m_axis.tdata.eq(fifo.r_data[:layout.size]),
                     self.m_axis.tuser.eq(fifo.r_data[layout.size]),
                     self.m_axis.tlast.eq(fifo.r_data[layout.size + 1]),
                     fifo.r_en.eq(self.m_axis.tready),
                     regs.set["STATUS.overflow"].eq(drop)]

        # counters and status
        sent = self.m_axis.tvalid & self.m_axis.tready
        for name, event in (("IN_BEATS", fire), ("OUT_BEATS", sent), ("DROPPED", drop)):
            count = regs.value[f"{name}.count"]
            with m.If(regs.pulse["CONTROL.counters_reset"]):
                m.d.sync += count.eq(0)
            with m.Elif(event):
                m.d.sync += count.eq(count + 1)
        # status as registers (one cycle behind): the register read multiplexer starts
        # at flip-flops
        m.d.sync += [regs.value["STATUS.init"].eq(init),
                     regs.value["STATUS.flushing"].eq(flush_req),
                     regs.value["STATUS.busy"].eq(busy),
                     regs.value["STATUS.fifo_level"].eq(fifo.level)]
        return m

    def _thresholds(self, m: Module, regs: AxiLiteRegisters, init: Signal) -> None:
        """THR_ADDR (auto-incrementing), the commit of THR_DATA chunks, and the walk
        that sets every threshold word to the top rail after reset."""
        c, geo, arr, rm = self.contract, self.geometry, self.array, self.regmap
        shared = geo.shared_thresholds  # THR_ADDR without a word: one register per scale
        word = None if shared else regs.value["THR_ADDR.word"]
        scale = regs.value["THR_ADDR.scale"]
        last_word = Const(1) if shared else word == geo.threshold_words - 1
        last_scale = scale == c.num_scales - 1
        reset_data = Const(geo.threshold_reset_data(0), len(arr.thr.data))
        for s in range(1, c.num_scales if shared else 1):  # what rst restores, per scale
            reset_data = Mux(scale == s, geo.threshold_reset_data(s), reset_data)
        chunks = [regs.value[f"{r.name}.data"] for r in rm.thr_data_registers()]
        commit = regs.written[rm.thr_data_registers()[-1].name]
        for name in ("THR_ADDR", rm.thr_data_registers()[-1].name):
            m.d.comb += regs.refuse[name].eq(init)
        step = init | commit
        m.d.comb += [arr.thr.we.eq(step),
                     arr.thr.addr.eq(scale if shared else Cat(word, scale)),
                     arr.thr.data.eq(Mux(init, reset_data,
                                         Cat(*chunks)[:len(arr.thr.data)]))]
        with m.If(step):
            m.d.sync += scale.eq(Mux(last_word, Mux(last_scale, 0, scale + 1), scale))
            if not shared:
                m.d.sync += word.eq(Mux(last_word, 0, word + 1))
            with m.If(last_word & last_scale):
                m.d.sync += init.eq(0)
        with m.Elif(regs.written["THR_ADDR"]):
            m.d.sync += scale.eq(regs.wdata[16:16 + len(scale)])
            if not shared:
                m.d.sync += word.eq(regs.wdata[:len(word)])


def ip_regmap(contract: ArrayContract, lanes: int, fifo_depth: int) -> RegisterMap:
    """The register map of the IP built with ``lanes`` and ``fifo_depth`` (its identity
    registers hold this build's digests), without building the IP."""
    options = {"lanes": lanes, "fifo_depth": fifo_depth}
    return ip_register_map(contract, lanes, fifo_depth,
                           rtl_digest(contract, IP_ARCH, options),
                           design_point_digest(contract), rvsm_version())
