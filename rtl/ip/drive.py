"""Drive :class:`~rvsm.rtl.ip.wrapper.RvsmAxisIp` in ``amaranth.sim``: an AXI4-Lite
master, an AXI4-Stream source and sink with per-cycle patterns, threshold loads.

:class:`Cycler` advances the clock and records every handshake on both streams, so the
AXI4-Lite helpers (:func:`axil_write`, :func:`axil_read`, :func:`load_thresholds`) and
the stream source run in one bench while the sink keeps its pattern. :func:`simulate_ip`
is a whole run: wait for the threshold initialisation, load thresholds, set the policy,
stream the frames (and ``lag`` flush beats, sent by the source or inserted by
``CONTROL.flush``), drain, read every register. Compare its result with
:func:`~rvsm.rtl.ip.model.run_stream_model` and the twin's beats.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.rtl.amaranth_sim import run_simulation
from rvsm.rtl.ip.axis import spike_tdata_layout, video_lane_bits
from rvsm.rtl.ip.register_map import RegisterMap
from rvsm.rtl.ip.wrapper import RvsmAxisIp
from rvsm.rtl.stream.drive import threshold_writes
from rvsm.rtl.stream.schedule import OutputBeats, StreamSchedule, pack_lanes

__all__ = ["Cycler", "IpRun", "axil_read", "axil_write", "decode_output", "input_stream",
           "load_thresholds", "read_register", "run_bench", "simulate_ip", "stream_beats",
           "threshold_chunks", "wait_idle"]


def input_stream(schedule: StreamSchedule, codes: np.ndarray, adc_bits: int,
                 flush: bool) -> tuple[list[int], list[int], list[int]]:
    """``(tdata, tuser, tlast)`` of the frames ``codes (T, H, W)`` (lanes padded to a
    byte, :func:`video_lane_bits`), followed by ``lag`` zero flush beats when ``flush``;
    tuser/tlast follow the beat's position (flush beats are the next frame's)."""
    beats = schedule.input_beats(codes) if flush else schedule.frame_beats(codes)
    words = pack_lanes(np.asarray(beats, dtype=np.int64), video_lane_bits(adc_bits))
    k = np.arange(len(words)) % schedule.beats_per_frame
    tuser = (k == 0).astype(int).tolist()
    tlast = (k % schedule.groups == schedule.groups - 1).astype(int).tolist()
    return words, tuser, tlast


def threshold_chunks(regmap: RegisterMap, word: int) -> list[int]:
    """A threshold word as its THR_DATA chunk values (32 bits each, chunk 0 first)."""
    return [(word >> (32 * k)) & 0xFFFFFFFF for k in range(regmap.thr_chunks)]


@dataclass
class Cycler:
    """The clock of a bench: :meth:`tick` sets the sink's ``tready`` from ``ready``
    (always ready beyond it) and records the cycle's handshakes: ``accepted`` (cycles
    of input handshakes), ``out`` (``(cycle, tdata, tuser, tlast)`` per output
    handshake). ``cycle`` counts from the bench's start; ``mark`` the stream's cycle 0."""

    ctx: object
    dut: RvsmAxisIp
    ready: Sequence[bool] = ()
    cycle: int = 0
    mark: int = 0
    accepted: list[int] = field(default_factory=list)
    out: list[tuple[int, int, int, int]] = field(default_factory=list)

    async def tick(self) -> None:
        """One clock cycle."""
        ctx, d = self.ctx, self.dut
        c = self.cycle - self.mark
        ctx.set(d.m_axis.tready, bool(self.ready[c]) if 0 <= c < len(self.ready) else True)
        if ctx.get(d.s_axis.tvalid) and ctx.get(d.s_axis.tready):
            self.accepted.append(c)
        if ctx.get(d.m_axis.tvalid) and ctx.get(d.m_axis.tready):
            self.out.append((c, ctx.get(d.m_axis.tdata), ctx.get(d.m_axis.tuser),
                             ctx.get(d.m_axis.tlast)))
        await ctx.tick()
        self.cycle += 1


async def axil_write(cy: Cycler, addr: int, data: int, strb: int = 0xF) -> int:
    """One AXI4-Lite write (AW and W together); returns ``bresp``."""
    ctx, bus = cy.ctx, cy.dut.s_axil
    ctx.set(bus.awaddr, addr)
    ctx.set(bus.wdata, data)
    ctx.set(bus.wstrb, strb)
    ctx.set(bus.awvalid, 1)
    ctx.set(bus.wvalid, 1)
    ctx.set(bus.bready, 1)
    aw = w = False
    while not (aw and w):
        aw_now = ctx.get(bus.awready) and not aw
        w_now = ctx.get(bus.wready) and not w
        await cy.tick()
        aw, w = aw or aw_now, w or w_now
        ctx.set(bus.awvalid, not aw)
        ctx.set(bus.wvalid, not w)
    while not ctx.get(bus.bvalid):
        await cy.tick()
    resp = ctx.get(bus.bresp)
    await cy.tick()
    ctx.set(bus.bready, 0)
    return resp


async def axil_read(cy: Cycler, addr: int) -> tuple[int, int]:
    """One AXI4-Lite read; returns ``(rdata, rresp)``."""
    ctx, bus = cy.ctx, cy.dut.s_axil
    ctx.set(bus.araddr, addr)
    ctx.set(bus.arvalid, 1)
    ctx.set(bus.rready, 1)
    while not ctx.get(bus.arready):
        await cy.tick()
    await cy.tick()
    ctx.set(bus.arvalid, 0)
    while not ctx.get(bus.rvalid):
        await cy.tick()
    data, resp = ctx.get(bus.rdata), ctx.get(bus.rresp)
    await cy.tick()
    ctx.set(bus.rready, 0)
    return data, resp


async def read_register(cy: Cycler, name: str) -> int:
    """A register's value by name (``OKAY`` checked)."""
    data, resp = await axil_read(cy, cy.dut.regmap[name].offset)
    if resp:
        raise AssertionError(f"read of {name} answered {resp:#x}")
    return data


async def wait_idle(cy: Cycler, limit: int = 1 << 20) -> None:
    """Poll STATUS until ``busy`` is low."""
    busy = cy.dut.regmap.field("STATUS", "busy").mask
    for _ in range(limit):
        if not (await read_register(cy, "STATUS")) & busy:
            return
    raise AssertionError("the IP stayed busy")


async def load_thresholds(cy: Cycler, thresholds: np.ndarray) -> list[int]:
    """Write every threshold word through THR_ADDR (once, at 0: it auto-increments) and
    the THR_DATA chunks; returns the responses (0: OKAY)."""
    rm = cy.dut.regmap
    resps = [await axil_write(cy, rm["THR_ADDR"].offset, 0)]
    for _, word in threshold_writes(cy.dut.geometry, thresholds):
        for reg, value in zip(rm.thr_data_registers(), threshold_chunks(rm, word),
                              strict=True):
            resps.append(await axil_write(cy, reg.offset, value))
    return resps


@dataclass(frozen=True)
class IpRun:
    """A run of :func:`simulate_ip` on ``dut``: ``accepted`` input cycles and ``out`` handshakes
    (``(cycle, tdata, tuser, tlast)``, cycles from the stream's start), the register
    values read at the end (``registers``), and the bench's threshold-load responses."""

    dut: RvsmAxisIp
    accepted: list[int]
    out: list[tuple[int, int, int, int]]
    registers: dict[str, int]
    load_responses: list[int]


async def stream_beats(cy: Cycler, words: Sequence[int], tuser: Sequence[int],
                       tlast: Sequence[int], valid: Sequence[bool]) -> None:
    """Offer the beats in order; in stream cycle ``c`` the source is idle unless
    ``valid[c]`` (always valid beyond it). Returns once the last beat is accepted."""
    ctx, s = cy.ctx, cy.dut.s_axis
    k = 0
    while k < len(words):
        c = cy.cycle - cy.mark
        offer = bool(valid[c]) if c < len(valid) else True
        ctx.set(s.tvalid, offer)
        ctx.set(s.tdata, words[k])
        ctx.set(s.tuser, tuser[k])
        ctx.set(s.tlast, tlast[k])
        took = offer and ctx.get(s.tready)
        await cy.tick()
        k += took
    ctx.set(s.tvalid, 0)


def decode_output(dut: RvsmAxisIp, out: Sequence[tuple[int, int, int, int]]
                  ) -> tuple[OutputBeats, np.ndarray, np.ndarray, np.ndarray]:
    """Output handshakes ``(cycle, tdata, tuser, tlast)`` as ``(beats, tuser, tlast,
    eof)``: the beats' positions and spikes (:class:`OutputBeats`, ``last`` = the
    ``eof`` bit) and the framing bits."""
    c, geo = dut.contract, dut.geometry
    layout = spike_tdata_layout(c.num_scales, geo.lanes, c.height, geo.groups)

    def col(name: str) -> list[int]:
        f = layout[name]
        return [(o[1] >> f.offset) & ((1 << f.shape.width) - 1) for o in out]

    beats = OutputBeats.from_words(col("row"), col("group"), col("eof"), col("pos"),
                                   col("neg"), c.num_scales, geo.lanes)
    return (beats, np.array([o[2] for o in out], dtype=bool),
            np.array([o[3] for o in out], dtype=bool), beats.last)


def run_bench(dut: RvsmAxisIp, bench: Callable[[Cycler], Awaitable[None]],
              vcd_path: str | None = None) -> Cycler:
    """Run ``bench(cycler)`` on ``dut`` (sink always ready unless the bench sets
    ``cycler.ready``); returns the :class:`Cycler` with its records."""
    box: list[Cycler] = []

    async def top(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        cy = Cycler(ctx, dut)
        box.append(cy)
        ctx.set(dut.m_axis.tready, 1)
        await bench(cy)

    run_simulation(dut, top, vcd_path)
    return box[0]


def simulate_ip(contract: ArrayContract, lanes: int, codes: np.ndarray,
                thresholds: np.ndarray, fifo_depth: int = RvsmAxisIp.FIFO_DEPTH,
                drop: bool = False, valid: Sequence[bool] = (), ready: Sequence[bool] = (),
                flush: str = "source", drain: int = 64, vcd_path: str | None = None,
                clear_before: Sequence[int] = ()) -> IpRun:
    """Run the IP on frames ``codes (T, H, W)`` with ``thresholds (S, H, W)``.

    ``flush``: ``"source"`` sends the ``lag`` flush beats as ordinary input beats (the
    stream the model :func:`run_stream_model` takes), ``"control"`` writes
    ``CONTROL = flush | clear`` after the frames, and after every segment between
    ``clear_before`` steps (:meth:`StreamSchedule.segments`; ``"control"`` only: the
    segments restart at frame 0 as :meth:`ArrayContract.run` does). The sink follows
    ``ready`` from the stream's first cycle; the bench then drains ``drain`` cycles with
    the sink ready and reads every register."""
    dut = RvsmAxisIp(contract, lanes, fifo_depth)
    sched = dut.geometry.schedule
    rm = dut.regmap
    codes = np.asarray(codes, dtype=np.int64)
    if clear_before and flush != "control":
        raise ValueError("clear_before needs flush='control'")
    streams = [input_stream(sched, codes[a:b], contract.adc_bits, flush == "source")
               for a, b in sched.segments(len(codes), clear_before)]
    result: dict[str, object] = {}

    async def bench(cy: Cycler) -> None:
        await wait_idle(cy)
        result["load"] = await load_thresholds(cy, thresholds)
        policy = rm.field("CONTROL", "drop").mask if drop else 0
        await axil_write(cy, rm["CONTROL"].offset,
                         rm.field("CONTROL", "counters_reset").mask | policy)
        for _ in range(4):
            await cy.tick()
        cy.mark, cy.ready = cy.cycle, ready
        for words, tuser, tlast in streams:
            await stream_beats(cy, words, tuser, tlast, valid)
            if flush == "control":
                bits = rm.field("CONTROL", "flush").mask | rm.field("CONTROL", "clear").mask
                await axil_write(cy, rm["CONTROL"].offset, bits | policy)
        while cy.cycle - cy.mark < len(ready):
            await cy.tick()
        cy.ready = ()
        for _ in range(drain):
            await cy.tick()
        result["registers"] = {r.name: await read_register(cy, r.name)
                               for r in rm.registers}

    cy = run_bench(dut, bench, vcd_path)
    out = [o for o in cy.out if o[0] >= 0]
    return IpRun(dut, [a for a in cy.accepted if a >= 0], out, result["registers"],
                 result["load"])
