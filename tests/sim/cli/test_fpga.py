"""``rvsm fpga``: JSON output, progress on stderr, exit 3 for tool failures, 2 for bad input."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rvsm.model.fixed.point_toml import save_design_point
from rvsm.model.infra.errors import ToolError
from rvsm.rtl.fpga.fpga_run import run_fpga
from rvsm.sim.cli import main

TINY = (2, 2)


def test_cli_synth_only_json(tmp_path: Path, capsys: pytest.CaptureFixture,
                             fsm_point) -> None:
    save_design_point(tmp_path / "p.toml", fsm_point)
    code = main(["fpga", str(tmp_path / "p.toml"), "--size", "2x2", "--arch", "parallel",
                 "--synth-only", "--json", "--rtlil", "-o", str(tmp_path / "w")])
    out, err = capsys.readouterr()
    assert code == 0, err
    d = json.loads(out)
    assert d["mode"] == "synthesis-only" and d["lanes"] == 4 and d["fmax_mhz"] is None
    assert d["sensor_height"] == 250 and d["height"] == 2
    assert "synthesis (yosys): done" in err  # progress on stderr
    assert d["netlist"] == "rtlil" and (tmp_path / "w" / "top.il").is_file()


def test_failing_tool_is_a_tool_error_and_exit_3(tmp_path: Path, capsys: pytest.CaptureFixture,
                                                 monkeypatch: pytest.MonkeyPatch,
                                                 fsm_point, fake_tool) -> None:
    fake = fake_tool(tmp_path / "fake-yosys", "echo 'ERROR: something broke'\nexit 1\n")
    monkeypatch.setenv("RVSM_YOSYS", str(fake))
    with pytest.raises(ToolError, match="exit 1.*something broke"):
        run_fpga(fsm_point, tmp_path / "a", arch="parallel", size=TINY, synth_only=True)
    save_design_point(tmp_path / "p.toml", fsm_point)
    code = main(["fpga", str(tmp_path / "p.toml"), "--size", "2x2", "--arch", "parallel",
                 "--synth-only", "--quiet", "-o", str(tmp_path / "b")])
    _, err = capsys.readouterr()
    assert code == 3
    assert err.count("\n") == 1 and err.startswith("rvsm: error:") and "yosys.out" in err
    monkeypatch.setenv("RVSM_YOSYS", str(tmp_path / "missing"))
    assert main(["fpga", str(tmp_path / "p.toml"), "--size", "2x2", "--arch", "parallel",
                 "--synth-only", "--quiet", "-o", str(tmp_path / "c")]) == 3


def test_bad_input_is_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture, fsm_point) -> None:
    save_design_point(tmp_path / "p.toml", fsm_point)
    assert main(["fpga", str(tmp_path / "p.toml"), "--lanes", "0", "--arch", "parallel"]) == 2
    assert main(["fpga", str(tmp_path / "p.toml"), "--arch", "stream", "--size", "2x2",
                 "--lanes", "3", "--synth-only", "-o", str(tmp_path / "w")]) == 2


def test_interface_axis_places_the_ip(tmp_path: Path, capsys: pytest.CaptureFixture,
                                      monkeypatch: pytest.MonkeyPatch, fsm_point,
                                      fake_tool) -> None:
    """``--interface axis`` hands the flow the AXI IP around the array (the netlist has
    its AXI ports; yosys here is a stand-in that fails after the Verilog is written)."""
    save_design_point(tmp_path / "p.toml", fsm_point)
    point = str(tmp_path / "p.toml")
    monkeypatch.setenv("RVSM_YOSYS", str(fake_tool(tmp_path / "y", "exit 1\n")))
    assert main(["fpga", point, "--size", "4x8", "--lanes", "2", "--interface", "axis",
                 "--fifo-depth", "6", "--synth-only", "--quiet", "-o",
                 str(tmp_path / "w")]) == 3
    top = (tmp_path / "w" / "top.v").read_text()
    assert "s_axil__awvalid" in top and "m_axis__tvalid" in top  # the AXI ports
    assert "module \\rvsm_fpga_top.dut.fifo" in top  # and the output FIFO
    capsys.readouterr()
    assert main(["fpga", point, "--size", "4x8", "--lanes", "2", "--fifo-depth", "6",
                 "--synth-only", "-o", str(tmp_path / "n")]) == 2
    assert "--fifo-depth applies to --interface axis only" in capsys.readouterr().err
    assert main(["fpga", point, "--size", "2x2", "--arch", "parallel", "--interface",
                 "axis", "--synth-only", "-o", str(tmp_path / "p")]) == 2
    assert "wraps the streaming array" in capsys.readouterr().err


def test_board_options_refused_in_bad_combinations(tmp_path: Path,
                                                   capsys: pytest.CaptureFixture,
                                                   fsm_point) -> None:
    save_design_point(tmp_path / "p.toml", fsm_point)
    base = ["fpga", str(tmp_path / "p.toml"), "--size", "2x4", "--lanes", "1", "--quiet",
            "-o", str(tmp_path / "w")]
    assert main([*base, "--package", "CABGA554"]) == 2
    assert "--package goes with --board" in capsys.readouterr().err
    assert main([*base, "--board", "--synth-only"]) == 2
    assert "does not go with --synth-only" in capsys.readouterr().err
    assert main([*base, "--board", "--freq", "125"]) == 2  # 500 MHz edge clock: VCO 800
    assert "integer VCO / edge clock" in capsys.readouterr().err
    assert not (tmp_path / "w" / "report.json").exists()
