#!/usr/bin/env python3
"""The Icarus long-run case's simulator alone: the same run replayed by plain ``vvp``,
no cocotb (``scripts/bench_rtl.py --only icarus`` prints it beside the whole run).

Given a long-run harness build for Icarus (its folder: ``rvsm_chunk_harness.v``, the
``.icarus.v`` netlist, the port map) and the run's source (the JSON of
``StimulusChunks.spec``), this writes every chunk's input beats as the testbench does
(chunks of 8 steps, then the ``lag`` flush), the threshold writes, and a Verilog driver
that resets the harness, has it write the thresholds (``thr_load``), then streams each
chunk (``start`` ... ``done``) exactly as the testbench does, and the same file names;
compiles it with ``iverilog`` and times ``vvp``. Output: one JSON line with ``cycles``,
``seconds`` (wall), ``user_seconds`` (vvp's CPU) and ``cycles_per_second``.

Usage: ``bench_icarus_plain.py BUILD_DIR SOURCE_JSON [--work DIR]``.
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from rvsm.model.fixed.stimulus_chunks import open_stimulus_chunks
from rvsm.rtl.ports import load_ports_json
from rvsm.rtl.stream.drive import threshold_writes
from rvsm.sim.cosim.builds.chunk_harness import HARNESS_TOP, HarnessLayout
from rvsm.sim.cosim.long_runs.chunk_files import encode_input_beats, encode_threshold_writes
from rvsm.sim.cosim.testbenches.tb_common import stream_geometry

CHUNK_STEPS = 8

DRIVER = """`timescale 1ns/1ps
module rvsm_plain_driver;
  reg rst = 1, clear = 0, thr_we = 0, thr_load = 0, start = 0;
  reg [31:0] thr_count = {nthr};
  reg [{ab}:0] thr_addr = 0;
  reg [{db}:0] thr_data = 0;
  reg [31:0] count = 0;
  wire clk, done, overflow;
  wire [31:0] out_count, stray;
  reg [31:0] counts [0:{nchunks}];
  reg [8*1024-1:0] name;
  integer k;
  {top} h (.clk(clk), .rst(rst), .clear(clear), .thr_we(thr_we), .thr_addr(thr_addr),
    .thr_data(thr_data), .thr_load(thr_load), .thr_count(thr_count), .start(start),
    .count(count), .done(done),
    .out_count(out_count), .stray(stray), .overflow(overflow));
  initial begin
    $readmemh("counts.hex", counts);
    @(negedge clk); @(negedge clk); rst = 0;
    thr_load = 1; @(negedge clk); thr_load = 0;
    @(posedge done); @(negedge clk);
    for (k = 0; k <= {nchunks}; k = k + 1) begin
      $sformat(name, "in_%0d.hex", k);
      h.in_file = name;
      count = counts[k]; start = 1; @(negedge clk); start = 0;
      @(posedge done); @(negedge clk);
    end
    $display("cycles %0d stray %0d overflow %0d", $time / 10, stray, overflow);
    $finish;
  end
endmodule
"""


def write_replay(build_dir: Path, source_json: str, work: Path) -> int:
    """Chunk files, thresholds, counts and the driver in ``work``; the number of parts."""
    source = open_stimulus_chunks(source_json)
    ports = load_ports_json(next(build_dir.glob("*.ports.json")))
    geo = stream_geometry(source.contract, ports)
    layout = HarnessLayout.from_ports(ports)
    c, sched = source.contract, geo.schedule
    counts = []

    def part(beats: np.ndarray) -> None:
        for k0 in range(0, beats.shape[0], layout.depth):
            b = beats[k0:k0 + layout.depth]
            (work / f"in_{len(counts)}.hex").write_bytes(
                encode_input_beats(b, c.adc_bits, layout.in_bits))
            counts.append(b.shape[0])

    for chunk in source.chunks(CHUNK_STEPS):
        if chunk.clear:
            raise SystemExit("bench_icarus_plain: runs with clears are not replayed")
        part(sched.frame_beats(chunk.codes))
    part(np.zeros((sched.lag, geo.lanes), dtype=np.uint16))
    ab, db = layout.widths["thr_addr"], layout.widths["thr_data"]
    writes = threshold_writes(geo, source.thresholds)
    (work / "thresholds.hex").write_bytes(encode_threshold_writes(writes, ab, db))
    (work / "counts.hex").write_text("".join(f"{n:08x}\n" for n in counts))
    (work / "driver.v").write_text(DRIVER.format(
        ab=ab - 1, db=db - 1, nthr=len(writes),
        nchunks=len(counts) - 1, top=HARNESS_TOP))
    return len(counts)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("build_dir", type=Path)
    parser.add_argument("source_json")
    parser.add_argument("--work", type=Path)
    args = parser.parse_args()
    work = args.work or Path(tempfile.mkdtemp(prefix="rvsm-plain-vvp-"))
    work.mkdir(parents=True, exist_ok=True)
    b = args.build_dir.resolve()
    write_replay(b, args.source_json, work)
    sources = [work / "driver.v", b / "rvsm_chunk_harness.v", *b.glob("*.icarus.v")]
    subprocess.run(["iverilog", "-g2012", "-o", str(work / "plain.vvp"), "-s",
                    "rvsm_plain_driver", *map(str, sources)], check=True)
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime
    t0 = time.perf_counter()
    out = subprocess.run(["vvp", "-n", "plain.vvp"], cwd=work, check=True,
                         capture_output=True, text=True).stdout
    wall = time.perf_counter() - t0
    user = resource.getrusage(resource.RUSAGE_CHILDREN).ru_utime - before
    line = next(ln for ln in out.splitlines() if ln.startswith("cycles "))
    cycles, stray, overflow = (int(x) for x in line.split()[1::2])
    print(json.dumps({"cycles": cycles, "seconds": wall, "user_seconds": user,
                      "cycles_per_second": cycles / wall, "stray": stray,
                      "overflow": overflow}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
