"""cocotb 2.x testbench: the AXI IP (:class:`~rvsm.rtl.ip.wrapper.RvsmAxisIp`) driven by
cocotbext-axi, checked against the fixed twin and the IP's cycle model.

Inputs (environment, or ``+rvsm_<name>=`` plusargs): ``RVSM_STIMULUS`` (a stimulus
file: codes, thresholds, expected spikes, contract, ``clear_before``), ``RVSM_PORTS``
(the build's ``<top>.ports.json``: lanes, FIFO depth, provenance), ``RVSM_AXIS`` (JSON:
``policy`` ``"stall"`` or ``"drop"``, ``seed``, ``idle_in`` and ``idle_out``: the
probability of an idle cycle of the source and of back-pressure from the sink, drawn
by the pause generators; default stall without pauses), ``RVSM_RESULT``.

The bench: reset; every register read through ``AxiLiteMaster`` (constants against the
register map rebuilt from the port map's provenance); wait for the threshold
initialisation; every threshold word written (THR_ADDR once, then the THR_DATA chunks);
the policy set; the frames sent line by line by ``AxiStreamSource`` (tuser = start of
frame, tlast = end of line) with random idle cycles, the sink (``AxiStreamSink``) under
random back-pressure. *Stall*: each segment between clears ends with ``CONTROL = flush
| clear``; every output beat must equal the twin's (:func:`check_beats`: none lost,
none duplicated). *Drop* (one segment): the flush beats are sent as whole zero lines, the
source's ``tvalid`` and the sink's ``tready`` are recorded every cycle and replayed
through :func:`~rvsm.rtl.ip.model.run_stream_model`: the accepted cycles, the delivered
positions (each beat whole, equal to the twin's) and the drop count must be the model's,
and ``DROPPED`` too. Finally the counters and STATUS are read back.
"""

from __future__ import annotations

import json
import random
import time

import cocotb
import numpy as np
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, FallingEdge
from cocotbext.axi import (
    AxiLiteBus,
    AxiLiteMaster,
    AxiStreamBus,
    AxiStreamFrame,
    AxiStreamSink,
    AxiStreamSource,
)

from rvsm.model.fixed.stimulus import load_stimulus
from rvsm.rtl.ip.axis import spike_tdata_layout, video_lane_bits
from rvsm.rtl.ip.drive import input_stream, threshold_chunks
from rvsm.rtl.ip.model import run_stream_model
from rvsm.rtl.ip.register_map import ip_register_map
from rvsm.sim.cosim.testbenches.tb_common import (
    CLOCK_NS,
    beat_stream,
    build_ports,
    testbench_arg,
)


def _pauses(rng: random.Random, idle: float):  # noqa: ANN202 - a generator
    while True:
        yield rng.random() < idle


class _Trace:
    """Per-cycle samples (at the falling edge) of both streams while ``on``."""

    def __init__(self, dut: object, out_bits: int):
        self.dut, self.on = dut, False
        self.valid: list[bool] = []
        self.ready: list[bool] = []
        self.accepted: list[int] = []
        self.out: list[tuple[int, int, int, int]] = []

    async def run(self) -> None:
        d = self.dut
        while True:
            await FallingEdge(d.clk)
            if not self.on:
                continue
            c = len(self.valid)
            sv, sr = int(d.s_axis_tvalid.value), int(d.s_axis_tready.value)
            mv, mr = int(d.m_axis_tvalid.value), int(d.m_axis_tready.value)
            self.valid.append(bool(sv))
            self.ready.append(bool(mr))
            if sv and sr:
                self.accepted.append(c)
            if mv and mr:
                self.out.append((c, int(d.m_axis_tdata.value), int(d.m_axis_tuser.value),
                                 int(d.m_axis_tlast.value)))


def _frames(words: list[int], tuser: list[int], tlast: list[int], lane_bytes: int
            ) -> list[AxiStreamFrame]:
    """Beats as AXI4-Stream frames ending at each tlast (one video line each); tuser per
    byte lane, as cocotbext-axi takes it."""
    frames, data, user = [], bytearray(), []
    for w, u, last in zip(words, tuser, tlast, strict=True):
        data += int(w).to_bytes(lane_bytes, "little")
        user += [u] * lane_bytes
        if last:
            frames.append(AxiStreamFrame(bytes(data), tuser=user))
            data, user = bytearray(), []
    if data:
        raise ValueError("a stream must end at the end of a line")
    return frames


@cocotb.test()
async def axis_ip_matches_fixed_twin(dut: object) -> None:
    """Registers, thresholds, frames under random idles and back-pressure; every beat."""
    stim = load_stimulus(testbench_arg("stimulus"))
    ports = build_ports()
    try:
        cfg = json.loads(testbench_arg("axis"))
    except RuntimeError:  # not given (e.g. `rvsm verify` of the IP): stall, no pauses
        cfg = {"policy": "stall", "seed": 0, "idle_in": 0.0, "idle_out": 0.0}
    result_path = testbench_arg("result")
    c, timing, prov = stim.contract, ports["timing"], ports["provenance"]
    stream = beat_stream(ports)  # the streaming array's beats, inside the IP
    geo = stream.geometry(c, int(timing["lanes"]))
    sched, depth = geo.schedule, int(timing["fifo_depth"])
    rm = ip_register_map(c, geo.lanes, depth, prov["rtl_digest"],
                         prov["design_point_digest"], prov["rvsm_version"])
    drop = cfg["policy"] == "drop"
    rng = random.Random(int(cfg["seed"]))
    problems: list[dict] = []

    cocotb.start_soon(Clock(dut.clk, CLOCK_NS, unit="ns").start())
    axil = AxiLiteMaster(AxiLiteBus.from_prefix(dut, "s_axil"), dut.clk, dut.rst)
    src = AxiStreamSource(AxiStreamBus.from_prefix(dut, "s_axis"), dut.clk, dut.rst)
    sink = AxiStreamSink(AxiStreamBus.from_prefix(dut, "m_axis"), dut.clk, dut.rst)
    layout = spike_tdata_layout(c.num_scales, geo.lanes, c.height, geo.groups)
    trace = _Trace(dut, layout.size)
    cocotb.start_soon(trace.run())
    dut.rst.value = 1
    await ClockCycles(dut.clk, 3)
    dut.rst.value = 0
    t0 = time.perf_counter()

    async def read(name: str) -> int:
        return int(await axil.read_dword(rm[name].offset))

    async def write(name: str, value: int) -> None:
        await axil.write_dword(rm[name].offset, value)

    # every register reads back; the constants equal the register map's
    for r in rm.registers:
        got = await read(r.name)
        constant = all(f.access == "RO" and not f.live for f in r.fields)
        if constant and got != r.reset:
            problems.append({"beat": -1, "error": f"register {r.name} reads {got:#x}, "
                             f"expected {r.reset:#x}"})
    busy = rm.field("STATUS", "busy").mask
    while await read("STATUS") & busy:
        await ClockCycles(dut.clk, 8)
    await write("THR_ADDR", 0)
    words = stream.threshold_writes(geo, stim.thresholds)
    for _, word in words:
        for reg, value in zip(rm.thr_data_registers(), threshold_chunks(rm, word),
                              strict=True):
            await axil.write_dword(reg.offset, value)
    last_chunk = threshold_chunks(rm, words[-1][1])[-1]
    for name, want in (("THR_ADDR", 0), (rm.thr_data_registers()[-1].name, last_chunk)):
        if (got := await read(name)) != want:
            problems.append({"beat": -1, "error": f"{name} reads {got:#x}, expected "
                             f"{want:#x} after the threshold load"})
    policy = rm.field("CONTROL", "drop").mask if drop else 0
    await write("CONTROL", policy | rm.field("CONTROL", "counters_reset").mask)
    if await read("CONTROL") != policy:
        problems.append({"beat": -1, "error": "CONTROL does not read back its policy"})

    src.set_pause_generator(_pauses(rng, float(cfg["idle_in"])))
    sink.set_pause_generator(_pauses(rng, float(cfg["idle_out"])))
    lane_bytes = geo.lanes * video_lane_bits(c.adc_bits) // 8
    codes = np.asarray(stim.codes, dtype=np.int64)
    segments = sched.segments(len(codes), stim.clear_before)
    if drop and len(segments) > 1:
        raise RuntimeError("the drop-policy bench takes a stimulus without clears")
    trace.on = True
    n_in = 0
    expected = stim.spikes
    for a, b in segments:
        seg = codes[a:b]
        if drop:  # flush with whole zero lines: the twin sees zero frames after the last
            lines = -(-geo.lag // geo.groups)
            extra = -(-lines * geo.groups // geo.beats_per_frame)
            seg = np.concatenate([seg, np.zeros((extra, c.height, c.width), np.int64)])
            expected = c.run(seg, stim.thresholds)
            w, u, last = input_stream(sched, seg, c.adc_bits, False)
            n = len(codes[a:b]) * geo.beats_per_frame + lines * geo.groups
            w, u, last = w[:n], u[:n], last[:n]
        else:
            w, u, last = input_stream(sched, seg, c.adc_bits, False)
        n_in += len(w)
        for frame in _frames(w, u, last, lane_bytes):
            await src.send(frame)
        await src.wait()
        if not drop:
            await write("CONTROL", policy | rm.field("CONTROL", "flush").mask
                        | rm.field("CONTROL", "clear").mask)
    # drain: until nothing is in flight and the FIFO is empty
    level = rm.field("STATUS", "fifo_level").mask
    while True:
        await ClockCycles(dut.clk, 2 * geo.lag + 16)
        status = await read("STATUS")
        if not status & (busy | level):
            break
    sink.clear_pause_generator()
    await ClockCycles(dut.clk, 8)
    trace.on = False
    stream_seconds = time.perf_counter() - t0

    out = trace.out
    fields = {name: (f.offset, f.shape.width) for name, f in layout}

    def col(name: str) -> list[int]:
        off, width = fields[name]
        return [(o[1] >> off) & ((1 << width) - 1) for o in out]

    beats = stream.output_beats.from_words(col("row"), col("group"), col("eof"), col("pos"),
                                   col("neg"), c.num_scales, geo.lanes)
    counters = {name: await read(name) for name in ("IN_BEATS", "OUT_BEATS", "DROPPED")}
    status = await read("STATUS")
    overflow = bool(status & rm.field("STATUS", "overflow").mask)
    framing = bool(status & rm.field("STATUS", "framing").mask)
    all_exp = sched.expected_beats(expected)
    if drop:
        start = trace.valid.index(True)
        model = run_stream_model(n_in, geo.lag, depth, True, trace.valid[start:],
                                 trace.ready[start:])
        pos = model.delivered
        result = {"compared": int(all_exp[pos].size), "mismatches": 0, "beats": len(out)}
        listed = []
        if [a - start for a in trace.accepted] != model.accepted.tolist():
            listed.append({"beat": -1, "error": "input beats accepted in other cycles "
                           "than the cycle model's"})
        if [o[0] - start for o in out] != model.sent.tolist():
            listed.append({"beat": -1, "error": "output beats sent in other cycles than "
                           "the cycle model's"})
        rows, groups = sched.positions(len(all_exp))
        if len(out) != len(pos):
            listed.append({"beat": len(out), "error": f"{len(out)} beats delivered, the "
                           f"model delivers {len(pos)}"})
        else:
            bad = np.flatnonzero((beats.rows != rows[pos]) | (beats.groups != groups[pos])
                                 | np.any(beats.spikes != all_exp[pos], axis=(1, 2)))
            listed += [{"beat": int(k), "error": f"delivered beat {k} is not the twin's "
                        f"position {int(pos[k])}"} for k in bad[:20]]
        for name, want in (("DROPPED", len(model.dropped)), ("OUT_BEATS", len(pos)),
                           ("IN_BEATS", n_in)):
            if counters[name] != want:
                listed.append({"beat": -1, "error": f"{name} = {counters[name]}, the model "
                               f"says {want}"})
        if overflow != bool(len(model.dropped)):
            listed.append({"beat": -1, "error": f"STATUS.overflow = {overflow} with "
                           f"{len(model.dropped)} beats dropped"})
        result["mismatches"] = len(listed)
        result["mismatch_list"] = listed
        result["first_mismatch"] = listed[0] if listed else None
        result["dropped"] = len(model.dropped)
    else:
        result = stream.check_beats(sched, expected, beats)
        result["dropped"] = counters["DROPPED"]
        for name, want in (("DROPPED", 0), ("OUT_BEATS", len(all_exp)),
                           ("IN_BEATS", n_in)):
            if counters[name] != want:
                problems.append({"beat": -1, "error": f"{name} = {counters[name]}, "
                                 f"expected {want}"})
        if overflow:
            problems.append({"beat": -1, "error": "STATUS.overflow under the stall policy"})
    if framing:
        problems.append({"beat": -1, "error": "STATUS.framing set by a well-framed stream"})
    tuser = np.array([o[2] for o in out], dtype=bool)
    tlast = np.array([o[3] for o in out], dtype=bool)
    if not np.array_equal(tuser, (beats.rows == 0) & (beats.groups == 0)) or \
            not np.array_equal(tlast, beats.groups == geo.groups - 1):
        problems.append({"beat": -1, "error": "m_axis tuser/tlast disagree with the "
                         "beats' positions"})
    if problems:
        result["mismatches"] += len(problems)
        result["mismatch_list"] = problems + result["mismatch_list"]
        result["first_mismatch"] = result["mismatch_list"][0]
    result.update({
        "policy": cfg["policy"], "input_beats": n_in, "output_beats": len(out),
        "counters": counters, "cycles": len(trace.valid),
        "cycles_per_second": len(trace.valid) / stream_seconds if stream_seconds else None,
        "stream_seconds": stream_seconds, "steps": int(codes.shape[0]),
        "expected_spikes": int(np.count_nonzero(stim.spikes)),
    })
    with open(result_path, "w", encoding="utf-8") as f:
        json.dump(result, f)
    assert result["mismatches"] == 0, \
        f"{result['mismatches']} mismatches; first {result['first_mismatch']}"
