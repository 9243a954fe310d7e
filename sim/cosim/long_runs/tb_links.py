"""cocotb testbench of the link loopback in the long-run harness: frames through both
links, the simulator doing every bit.

Reads ``RVSM_LINKS`` (an ``.npz`` written by :mod:`rvsm.sim.cosim.links_run`: input
``beats`` ``(K, P)`` codes (the frames, then the flush beats), ``adc_bits``,
``in_bits``, ``out_bits``, ``thr_count`` (thresholds in ``thresholds.hex``, 0: none),
``chunk`` (beats per harness chunk), ``clock_outside``) and writes the output beats'
``payload`` bits to ``RVSM_OUT`` (``.npy``, ``(K, out_bits) uint8``) and a JSON summary
to ``RVSM_RESULT``: ``cycles`` (bit-clock cycles), ``chunks``, ``stray``, ``overflow``,
``simulate_seconds``. The harness (:mod:`rvsm.sim.cosim.builds.chunk_harness`) presents
each chunk's beats and stores the spikes; Python wakes a few times per chunk.
"""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import cocotb
import numpy as np
from cocotb.clock import Clock
from cocotb.simtime import get_sim_time
from cocotb.triggers import FallingEdge, RisingEdge

from rvsm.sim.cosim.long_runs.chunk_files import decode_output_beats, encode_input_beats
from rvsm.sim.cosim.testbenches.tb_common import CLOCK_NS

RESET_CYCLES = 32  # bit clocks: several core cycles of the loopback


@cocotb.test()
async def links_chunks(dut) -> None:  # noqa: ANN001
    """Reset, thresholds, then every chunk of beats through the harness."""
    setup = np.load(os.environ["RVSM_LINKS"])
    beats, chunk = setup["beats"], int(setup["chunk"])
    adc_bits, in_bits, out_bits = (int(setup[k]) for k in ("adc_bits", "in_bits", "out_bits"))
    clk = dut.clk
    if int(setup["clock_outside"]):
        cocotb.start_soon(Clock(clk, CLOCK_NS, unit="ns").start())
    dut.rst.value = 1
    for name in ("clear", "thr_we", "thr_addr", "thr_data", "thr_load", "thr_count",
                 "start", "count", "state_load", "state_dump"):
        getattr(dut, name).value = 0
    for _ in range(RESET_CYCLES):
        await FallingEdge(clk)
    dut.rst.value = 0
    t0 = time.perf_counter()
    if int(setup["thr_count"]):
        dut.thr_count.value = int(setup["thr_count"])
        dut.thr_load.value = 1
        await FallingEdge(clk)
        dut.thr_load.value = 0
        await RisingEdge(dut.done)
        await FallingEdge(clk)
    cwd = Path.cwd()
    in_file, out_file = cwd / "chunk_in.hex", cwd / "chunk_out.hex"
    outs, chunks = [], 0
    for start in range(0, len(beats), chunk):
        part = beats[start:start + chunk]
        in_file.unlink(missing_ok=True)
        in_file.write_bytes(encode_input_beats(part, adc_bits, in_bits))
        out_file.unlink(missing_ok=True)
        dut.count.value = len(part)
        dut.start.value = 1
        await FallingEdge(clk)
        dut.start.value = 0
        await RisingEdge(dut.done)
        await FallingEdge(clk)
        if int(dut.out_count.value):
            bits, unknown = decode_output_beats(out_file.read_bytes(), out_bits)
            if unknown.any():
                raise AssertionError(f"chunk {chunks}: X/Z in an output beat")
            outs.append(bits)
        chunks += 1
    out = np.concatenate(outs) if outs else np.zeros((0, out_bits), np.uint8)
    np.save(os.environ["RVSM_OUT"], out)
    result = {"cycles": int(get_sim_time("ns") // CLOCK_NS),
              "chunks": chunks, "stray": int(dut.stray.value),
              "overflow": int(dut.overflow.value), "beats_out": int(len(out)),
              "simulate_seconds": time.perf_counter() - t0}
    Path(os.environ["RVSM_RESULT"]).write_text(json.dumps(result))
