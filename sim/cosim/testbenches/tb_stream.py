"""cocotb 2.x testbench: the streaming array against the fixed twin, beat for beat.

Inputs (environment, or ``+rvsm_<name>=`` plusargs): ``RVSM_STIMULUS`` -- a stimulus
file (:mod:`rvsm.model.fixed.stimulus`): codes, thresholds, expected spikes, the
contract and ``clear_before``; ``RVSM_PORTS`` -- the build's ``<top>.ports.json`` (its
lanes, timing properties and payload bit fields, derived from the component);
``RVSM_RESULT`` -- where the JSON result goes.

cocotb runs everything from Python, one clock cycle at a time (inputs driven on the
falling edge): reset; every threshold word through ``thr``; then per segment between
clears (:meth:`StreamSchedule.segments`) the frames as back-to-back beats, the ``lag``
flush beats, one idle cycle and one ``clear`` cycle. Every cycle with ``spikes_valid``
high records one output beat; at the end the beat stream's ``check_beats`` (the
schedule model's checker, :class:`~rvsm.rtl.capabilities.BeatStream` of the build's
architecture) compares positions and spikes with the expectation. The
per-cycle Python is a few handle accesses on vectors of a few hundred bits; the result
reports ``cycles_per_second`` to show whether it or the simulator dominates.
"""

from __future__ import annotations

import time

import cocotb
import numpy as np
from cocotb.simtime import get_sim_time
from cocotb.triggers import FallingEdge

from rvsm.model.fixed.stimulus import load_stimulus
from rvsm.sim.cosim.testbenches.tb_common import (
    OutputBeats,
    beat_stream,
    build_ports,
    clock_and_reset,
    stream_geometry,
    testbench_arg,
    write_result,
)


@cocotb.test()
async def stream_matches_fixed_twin(dut: object) -> None:
    """Stream every step, compare every output beat with the fixed twin's expectation."""
    stim = load_stimulus(testbench_arg("stimulus"))
    ports = build_ports()
    result_path = testbench_arg("result")
    c = stim.contract
    codes = stim.codes.astype(np.int64)
    expected = stim.spikes
    steps, scales, height, width = expected.shape
    stream = beat_stream(ports)
    geo = stream_geometry(c, ports)
    lanes = geo.lanes
    sched = geo.schedule

    clk = dut.clk  # type: ignore[attr-defined]
    d = {name: getattr(dut, name) for name in (
        "rst", "clear", "codes_valid", "codes_payload", "thr_we", "thr_addr", "thr_data",
        "spikes_valid", "spikes_payload")}
    await clock_and_reset(dut, ("clear", "codes_valid", "codes_payload", "thr_we",
                                "thr_addr", "thr_data"))

    t0 = time.perf_counter()
    cycles = 0
    d["thr_we"].value = 1
    for addr, word in stream.threshold_writes(geo, stim.thresholds):
        d["thr_addr"].value = addr
        d["thr_data"].value = word
        await FallingEdge(clk)
        cycles += 1
    d["thr_we"].value = 0

    got = OutputBeats(ports)
    beat_times: list[int] = []  # simulation time (ns) at which each output beat was read
    out_valid, out_payload = d["spikes_valid"], d["spikes_payload"]
    in_payload = d["codes_payload"]

    def record() -> None:
        """After a falling edge: record the output beat presented, if any."""
        if str(out_valid.value) == "1":
            beat_times.append(int(get_sim_time("ns")))
            got.read(out_payload.value)
    for seg, (a, b) in enumerate(sched.segments(steps, stim.clear_before)):
        if seg:
            d["clear"].value = 1
            await FallingEdge(clk)
            cycles += 1
            record()
            d["clear"].value = 0
        beats = stream.pack_lanes(sched.input_beats(codes[a:b]), c.adc_bits)
        d["codes_valid"].value = 1
        for word in beats:
            in_payload.value = word
            await FallingEdge(clk)
            cycles += 1
            record()
        d["codes_valid"].value = 0
        await FallingEdge(clk)  # the last released beat is presented one cycle later
        cycles += 1
        record()
    stream_seconds = time.perf_counter() - t0

    result = stream.check_beats(sched, expected, got.decoded(stream, scales, lanes))
    got.count_x(result)
    first = result["first_mismatch"]
    at = None
    if first is not None and beat_times:  # a missing beat: after the last one received
        at = beat_times[min(first["beat"], len(beat_times) - 1)]
    result.update({
        "first_mismatch_time_ns": at,
        "steps": steps,
        "accumulators": scales * height * width,
        "expected_spikes": int(np.count_nonzero(expected)),
        "lanes": lanes,
        "cycles": cycles,
        "cycles_per_second": cycles / stream_seconds if stream_seconds else None,
        "stream_seconds": stream_seconds,
        "sim_time_ns": int(get_sim_time("ns")),
    })
    write_result(result, result_path)
