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

import json
import time

import cocotb
import numpy as np
from cocotb.simtime import get_sim_time
from cocotb.triggers import FallingEdge

from rvsm.rtl.architectures.registry import get_architecture
from rvsm.rtl.ports import load_ports_json
from rvsm.sim.cosim.testbenches.tb_common import (
    CLOCK_NS,
    beat_stream,
    clock_and_reset,
    logic_bits,
    stream_geometry,
    testbench_arg,
)


@cocotb.test()
async def stream_follows_protocol_script(dut: object) -> None:
    """Drive every cycle of the script; compare every output beat and its cycle."""
    ports = load_ports_json(testbench_arg("ports"))
    scripts = get_architecture(ports["arch"]).protocol
    if scripts is None:
        raise RuntimeError(f"the {ports['arch']} architecture has no protocol scripts")
    script = scripts.load(testbench_arg("script"))
    result_path = testbench_arg("result")
    c = script.contract
    geo = stream_geometry(c, ports)
    if geo.lanes != script.lanes:
        raise RuntimeError(f"the build has {geo.lanes} lanes, the script {script.lanes}")
    by_name = {p["name"]: p for p in ports["ports"]}
    fields = {f["name"]: (f["offset"], f["width"])
              for f in by_name["spikes_payload"]["fields"]}
    clk = dut.clk  # type: ignore[attr-defined]
    inputs = ("codes_valid", "codes_payload", "clear", "thr_we", "thr_addr", "thr_data")
    handles = [getattr(dut, name) for name in inputs]
    out_valid, out_payload = dut.spikes_valid, dut.spikes_payload  # type: ignore[attr-defined]
    await clock_and_reset(dut, inputs)
    columns = [[int(v) for v in script.valid], script.payload_words(),
               [int(v) for v in script.clear], [int(v) for v in script.thr_we],
               script.thr_addresses(), script.thr_words()]
    last = [0] * len(handles)
    got: dict[str, list[int]] = {k: [] for k in fields}
    cycles: list[int] = []
    x_beats: list[int] = []
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
            value, xmask = logic_bits(out_payload.value)
            if xmask:
                x_beats.append(len(cycles))
            for name, (off, width) in fields.items():
                got[name].append((value >> off) & ((1 << width) - 1))
            cycles.append(cyc)
    seconds = time.perf_counter() - t0
    beats = beat_stream(ports).output_beats.from_words(
        got["row"], got["group"], got["last"], got["pos"], got["neg"], c.num_scales,
        geo.lanes)
    result = scripts.check(script, beats, cycles)
    if x_beats:
        result["mismatches"] += len(x_beats)
        result["mismatch_list"].insert(0, {"beat": x_beats[0], "cycle": cycles[x_beats[0]],
                                           "error": f"X/Z in {len(x_beats)} output beat(s)"})
        result["first_mismatch"] = result["mismatch_list"][0]
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
    with open(result_path, "w", encoding="utf-8") as f:
        json.dump(result, f)
    assert result["mismatches"] == 0, \
        f"{result['mismatches']} mismatches; first {result['first_mismatch']}"
