"""ECP5 block RAMs with the output register (``rtl/fpga/ecp5_memory.py``): the
INITVAL layout, and the array built with them equals the generic array cycle by cycle
in Icarus (``dp16kd_model.v``: yosys ships DP16KD as a black box only)."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest
from amaranth.back import verilog

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.ecp5_memory import (
    ECP5_BLOCK_RAMS,
    ECP5_PLATFORM,
    Ecp5BlockRam,
    dp16kd_count,
    initval,
)
from rvsm.rtl.ports import verilog_ports
from rvsm.rtl.stream.architecture import stream_port_map
from rvsm.rtl.stream.array import RvsmStreamArray
from rvsm.rtl.stream.memory_target import memory_target

MODEL = Path(__file__).with_name("dp16kd_model.v")
FF_MODEL = Path(__file__).with_name("trellis_ff_model.v")


def test_initval_puts_16_words_in_20_bit_slots() -> None:
    params = initval([0x3FFFF, 1, 2] + [0] * 13 + [5])
    assert len(params) == 64 and all(len(v) == 320 for v in params.values())
    assert params["INITVAL_00"].value == 0x3FFFF | (1 << 20) | (2 << 40)
    assert params["INITVAL_01"].value == 5 and params["INITVAL_3F"].value == 0
    with pytest.raises(RvsmError, match="1024 words"):
        initval([0] * 1025)


def test_a_bank_is_one_primitive_per_18_bits_and_at_most_1024_words() -> None:
    assert [dp16kd_count(w) for w in (1, 18, 19, 72, 144)] == [1, 1, 2, 4, 8]
    with pytest.raises(RvsmError, match="1..1024 words"):
        Ecp5BlockRam(18, 2048)


def test_the_ecp5_build_instantiates_outreg_block_rams_only(small_contract) -> None:
    c = small_contract("dog2", 6, 8)
    text = verilog.convert(RvsmStreamArray(c, 2, bank_words=8), name="fpga",
                           platform=ECP5_PLATFORM, emit_src=False)
    # 2 scales x 3 banks x (thresholds 18 bits: 1 primitive, accumulators 20 bits: 2)
    assert text.count("DP16KD #(") == 2 * 3 * (1 + 2)
    assert text.count('.REGMODE_B("OUTREG")') == 18
    # the only memory array left in the fabric: the line buffer (distributed RAM)
    assert re.findall(r"reg \[\d+:0\] (\w+) \[", text) == ["line_buffer"]
    generic = verilog.convert(RvsmStreamArray(c, 2, bank_words=8), name="gen",
                              emit_src=False)
    assert "DP16KD" not in generic


def test_the_array_takes_the_block_rams_as_a_parameter_or_from_the_platform(
        small_contract) -> None:
    """``rtl/stream`` knows no device: the ECP5 block RAMs are a memory target, given to
    the array or carried by the platform the flow converts with; either way the same
    netlist."""
    assert memory_target(ECP5_PLATFORM) is ECP5_BLOCK_RAMS and ECP5_BLOCK_RAMS.held_write
    c = small_contract("dog2", 6, 8)
    given = verilog.convert(RvsmStreamArray(c, 2, bank_words=8, memory=ECP5_BLOCK_RAMS),
                            name="fpga", emit_src=False)
    carried = verilog.convert(RvsmStreamArray(c, 2, bank_words=8), name="fpga",
                              platform=ECP5_PLATFORM, emit_src=False)
    assert given == carried and given.count("DP16KD #(") == 18


def _verilog(dut: RvsmStreamArray, name: str, platform: object | None) -> str:
    return verilog.convert(dut, name=name, platform=platform, emit_src=False,
                           ports=verilog_ports(dut))


def _testbench(contract, lanes: int, cycles: int, seed: int) -> str:
    ports = {p["name"]: p for p in stream_port_map(contract, lanes)}
    w = {name: p["width"] for name, p in ports.items()}
    fields = {f["name"]: f for f in ports["spikes_payload"]["fields"]}
    spikes = sum(((1 << f["width"]) - 1) << f["offset"] for n, f in fields.items()
                 if n in ("pos", "neg"))
    tw = contract.threshold_bits
    conn = ", ".join(f".{n}({n}_{{s}})" if p["dir"] == "out" else f".{n}({n})"
                     for n, p in ports.items())
    outs = "\n".join(f"  wire [{w[n] - 1}:0] {n}_gen, {n}_fpga;" for n, p in ports.items()
                     if p["dir"] == "out")
    ins = "\n".join(f"  reg [{w[n] - 1}:0] {n} = 0;" for n, p in ports.items()
                    if p["dir"] == "in" and n != "clk")
    return f"""`timescale 1ns / 1ps
module tb;
  reg clk = 0;
{ins}
{outs}
  gen g({conn.format(s="gen")});
  fpga f({conn.format(s="fpga")});
  always #5 clk = ~clk;
  integer cycle, i, errors = 0, valid = 0, fired = 0, seed = {seed};
  initial begin
    rst = 1;
    for (cycle = 0; cycle < {cycles}; cycle = cycle + 1) begin
      @(negedge clk);
      if (codes_ready_gen !== codes_ready_fpga || spikes_valid_gen !== spikes_valid_fpga
          || (spikes_valid_gen && spikes_payload_gen !== spikes_payload_fpga)
          || (spikes_valid_gen && ^spikes_payload_fpga === 1'bx)) begin
        if (errors < 5) $display("MISMATCH cycle %0d: %h %h", cycle, spikes_payload_gen,
                                 spikes_payload_fpga);
        errors = errors + 1;
      end
      if (spikes_valid_gen) begin
        valid = valid + 1;
        if ((spikes_payload_gen & {w['spikes_payload']}'d{spikes}) != 0) fired = fired + 1;
      end
      rst = cycle < 2;
      codes_valid = ($random(seed) & 7) != 0;
      codes_payload = $random(seed);
      clear = ($random(seed) % 150) == 0;
      thr_we = ($random(seed) & 3) == 0;
      thr_addr = $random(seed);
      for (i = 0; i < {lanes}; i = i + 1)
        thr_data[i * {tw} +: {tw}] = 1 + (($random(seed) & 32'h7fffffff) % 12);
    end
    $display("RESULT errors=%0d valid=%0d fired=%0d", errors, valid, fired);
    $finish;
  end
endmodule
"""


def _run(tmp_path: Path, generic: str, fpga: str, tb: str) -> dict[str, int]:
    (tmp_path / "gen.v").write_text(generic)
    (tmp_path / "fpga.v").write_text(fpga)
    (tmp_path / "tb.v").write_text(tb)
    subprocess.run(["iverilog", "-g2012", "-s", "tb", "-o", "tb.vvp", "tb.v", "gen.v", "fpga.v",
                    str(MODEL), str(FF_MODEL)], cwd=tmp_path, check=True,
                   capture_output=True, text=True)
    out = subprocess.run(["vvp", "-n", "tb.vvp"], cwd=tmp_path, check=True,
                         capture_output=True, text=True, timeout=120).stdout
    found = re.search(r"RESULT errors=(\d+) valid=(\d+) fired=(\d+)", out)
    assert found, out
    return {**dict(zip(("errors", "valid", "fired"), map(int, found.groups()), strict=True)),
            "collisions": out.count("COLLISION")}


@pytest.mark.skipif(shutil.which("iverilog") is None, reason="needs Icarus Verilog")
def test_the_ecp5_array_equals_the_generic_array_cycle_by_cycle(small_contract,
                                                               tmp_path: Path) -> None:
    """dog2 6x8, 2 lanes, banks of 8 words (3 banks; 20-bit accumulator words: two
    primitives side by side; thresholds start at the top rail from INITVAL): 1500 cycles
    of random codes, stalls, clears and threshold writes at random addresses (reads
    meeting writes included: not gated in the ECP5 build, X in the model); every output
    cycle equal, no X. Then the same bench with the output register off (``NOREG``: the
    data one beat early) must disagree, and so must an ECP5 build without the threshold
    forwarding, and one whose accumulator block RAMs never write (their write enable is
    the registered copy of ``valid``: the held write through stalls and at clear edges
    is what the equal run checks; writing at every edge would agree too, since invalid
    positions only occur in a fresh frame, whose words are read as zero and rewritten)."""
    c = small_contract("dog2", 6, 8)
    generic, fpga = (_verilog(RvsmStreamArray(c, 2, bank_words=8), name, platform)
                     for name, platform in (("gen", None), ("fpga", ECP5_PLATFORM)))
    tb = _testbench(c, 2, 1500, seed=7)
    r = _run(tmp_path, generic, fpga, tb)
    assert r["errors"] == 0 and r["valid"] > 800 and r["fired"] > 100, r
    # reads meeting writes happened (the ECP5 build does not gate them: their data is
    # X in the model), and no X reached a valid output (checked by the bench)
    assert r["collisions"] > 0
    broken = fpga.replace('.REGMODE_B("OUTREG")', '.REGMODE_B("NOREG")')
    assert _run(tmp_path, generic, broken, tb)["errors"] > 0
    # the threshold forwarding (which replaces a read meeting the registered write) off
    # in the ECP5 build: the X of such a read reaches the output
    unforwarded = _verilog(RvsmStreamArray(c, 2, bank_words=8,
                                           mutation="stream.no_threshold_forwarding"),
                           "fpga", ECP5_PLATFORM)
    assert _run(tmp_path, generic, unforwarded, tb)["errors"] > 0
    assert fpga.count(".DI(write_en_next)") == 12  # 2 scales x 3 banks x 2 primitives
    never = fpga.replace(".DI(write_en_next)", ".DI(1'h0)")
    assert _run(tmp_path, generic, never, tb)["errors"] > 0
