"""cocotb 2.x testbench: the streaming array driven by a protocol script, cycle by cycle.

Inputs (environment, or ``+rvsm_<name>=`` plusargs): ``RVSM_SCRIPT`` -- a protocol
script (the architecture's :class:`~rvsm.rtl.capabilities.ProtocolScripts`,
``rtl/stream/protocol.py``: per cycle ``codes`` valid and payload,
``clear``, a threshold write; the expected output beats and the cycle of each);
``RVSM_PORTS`` -- the build's ``<top>.ports.json``; ``RVSM_RESULT`` -- where the JSON
result goes.

After reset, every cycle of the script is driven on the falling edge before its rising
edge (handles written only when their value changes); after each rising edge a
``spikes_valid`` cycle records one output beat and the edge it followed.
The scripts' ``check`` then compares count, order, positions,
``last``, spikes and the cycle of every beat: stalls, clears at any position of a frame
and threshold writes colliding with reads are checked against the documented rules,
not only the spikes of a plain stream.
"""

from __future__ import annotations

import time

import cocotb
import numpy as np
from cocotb.simtime import get_sim_time
from cocotb.triggers import FallingEdge

from rvsm.rtl.architectures.registry import get_architecture
from rvsm.sim.cosim.testbenches.tb_common import (
    CLOCK_NS,
    OutputBeats,
    beat_stream,
    build_ports,
    clock_and_reset,
    stream_geometry,
    testbench_arg,
    write_result,
)


@cocotb.test()
async def stream_follows_protocol_script(dut: object) -> None:
    """Drive every cycle of the script; compare every output beat and its cycle."""
    ports = build_ports()
    scripts = get_architecture(ports["arch"]).protocol
    if scripts is None:
        raise RuntimeError(f"the {ports['arch']} architecture has no protocol scripts")
    script = scripts.load(testbench_arg("script"))
    result_path = testbench_arg("result")
    c = script.contract
    geo = stream_geometry(c, ports)
    if geo.lanes != script.lanes:
        raise RuntimeError(f"the build has {geo.lanes} lanes, the script {script.lanes}")
    clk = dut.clk  # type: ignore[attr-defined]
    inputs = ("codes_valid", "codes_payload", "clear", "thr_we", "thr_addr", "thr_data")
    handles = [getattr(dut, name) for name in inputs]
    out_valid, out_payload = dut.spikes_valid, dut.spikes_payload  # type: ignore[attr-defined]
    await clock_and_reset(dut, inputs)
    columns = [[int(v) for v in script.valid], script.payload_words(),
               [int(v) for v in script.clear], [int(v) for v in script.thr_we],
               script.thr_addresses(), script.thr_words()]
    last = [0] * len(handles)
    got = OutputBeats(ports)
    cycles: list[int] = []
    t0 = time.perf_counter()
    start_ns = int(get_sim_time("ns"))  # the falling edge before cycle 0's rising edge
    for cyc in range(script.num_cycles):
        for k, handle in enumerate(handles):
            v = columns[k][cyc]
            if v != last[k]:
                handle.value = v
                last[k] = v
        await FallingEdge(clk)
        if str(out_valid.value) == "1":
            got.read(out_payload.value)
            cycles.append(cyc)
    seconds = time.perf_counter() - t0
    result = scripts.check(script, got.decoded(beat_stream(ports), c.num_scales, geo.lanes),
                           cycles)
    got.count_x(result, cycles)
    first = result["first_mismatch"]
    at = None
    if first is not None:
        # the falling edge after the rising edge of the beat's cycle
        at = start_ns + (int(first.get("cycle", script.num_cycles - 1)) + 1) * CLOCK_NS
    result.update({
        "first_mismatch_time_ns": at,
        "steps": int(script.expected_steps.max() + 1) if len(script.expected_steps) else 0,
        "cycles": script.num_cycles,
        "lanes": geo.lanes,
        "expected_spikes": int(np.count_nonzero(script.expected.spikes)),
        "cycles_per_second": script.num_cycles / seconds if seconds else None,
        "stream_seconds": seconds,
        "sim_time_ns": int(get_sim_time("ns")),
    })
    write_result(result, result_path)
