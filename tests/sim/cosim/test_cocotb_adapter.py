"""The cocotb adapter: cocotb's public runner in a child process, failures named, the
parent's environment untouched, a safe PYTHONPATH, Verilator's top-level-only VPI."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

from rvsm.model.infra.errors import RvsmError, ToolError
from rvsm.rtl.toolchain import ToolFailure
from rvsm.sim.cosim.builds.cocotb_adapter import build_args, cocotb_build, public_ports_control
from rvsm.sim.cosim.builds.cocotb_job import safe_path

TWO_LEVELS = """
module sub(input clk, input [3:0] a, output reg [3:0] q);
  reg [3:0] inner;
  always @(posedge clk) begin inner <= a + 1; q <= inner; end
endmodule
module top(input clk, input [3:0] a, output [3:0] q);
  sub u(.clk(clk), .a(a), .q(q));
endmodule
"""
PORTS = ("clk", "a", "q")


def test_safe_path_drops_relative_and_current_folder_entries(tmp_path: Path,
                                                             monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert safe_path(["", ".", "rel/dir", str(tmp_path), "/abs/lib"]) == ["/abs/lib"]


def test_icarus_build_and_its_failure(tmp_path: Path) -> None:
    """A build runs; a compiler error is a ToolFailure naming the command and the log,
    and the parent's environment is the same afterwards."""
    if shutil.which("iverilog") is None:
        pytest.skip("Icarus Verilog not installed")
    environ = dict(os.environ)
    good = tmp_path / "top.v"
    good.write_text(TWO_LEVELS)
    cocotb_build("icarus", good, "top", PORTS, tmp_path / "ok" / "sim_build", True,
                 tmp_path / "ok.log")
    assert (tmp_path / "ok" / "sim_build" / "sim.vvp").is_file()
    bad = tmp_path / "bad.v"
    bad.write_text("module top(input clk);\n  syntax error here\nendmodule\n")
    log = tmp_path / "bad.log"
    with pytest.raises(ToolFailure, match=r"^icarus build \(iverilog\) exited with status "
                       r"\d+; log: ") as info:
        cocotb_build("icarus", bad, "top", ["clk"], tmp_path / "bad" / "sim_build", True,
                     log)
    assert info.value.log == log and "syntax error" in log.read_text()
    assert dict(os.environ) == environ


def test_a_missing_simulator_is_a_tool_error(tmp_path: Path, monkeypatch) -> None:
    (tmp_path / "top.v").write_text(TWO_LEVELS)
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    with pytest.raises(ToolError, match="icarus build failed: .*iverilog"):
        cocotb_build("icarus", tmp_path / "top.v", "top", PORTS,
                     tmp_path / "b" / "sim_build", True, tmp_path / "b.log")


def test_verilator_exposes_only_the_top_level_ports(tmp_path: Path) -> None:
    """cocotb's ``--public-flat-rw``, then our build arguments and control file (cocotb's
    order): the named top-level ports, and nothing else, are registered for VPI."""
    from rvsm.rtl.architectures.verilog import verilator_env

    try:
        env = verilator_env()
    except ToolError:
        pytest.skip("Verilator not installed")
    (tmp_path / "t.v").write_text(TWO_LEVELS.replace("output [3:0] q);",
                                                     "output [3:0] q);\n  wire [3:0] w = a;"))
    (tmp_path / "public.vlt").write_text(public_ports_control("top", PORTS))
    inserted = {}
    for name, flags in (("flat", []), ("ours", [*build_args("verilator", False),
                                                str(tmp_path / "public.vlt")])):
        out = tmp_path / name
        subprocess.run(["verilator", "--cc", "--vpi", "-Mdir", str(out), "--top-module",
                        "top", "--public-flat-rw", *flags, str(tmp_path / "t.v")],
                       env=env, check=True, capture_output=True)
        inserted[name] = sorted(set(re.findall(
            r'varInsert\("(\w+)"', "".join(p.read_text() for p in out.glob("*.cpp")))))
    assert inserted["flat"] == ["a", "clk", "inner", "q", "w"]
    assert inserted["ours"] == sorted(PORTS)
    with pytest.raises(RvsmError, match="Verilog identifier"):
        public_ports_control("top", ['a" -var "*'])
