"""Verilog generation, port map, Verilator lint and yosys statistics on a tiny array."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.rtl.parallel.array import RvsmArray
from rvsm.rtl.verilog import write_outputs


@pytest.fixture(scope="module")
def generated(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, object]:
    tmp = tmp_path_factory.mktemp("verilog")
    point = default_design_point().with_size(2, 3)
    from dataclasses import replace

    point = replace(point, model="fsm")
    write_outputs(point.contract(), tmp / "out", "parallel")
    return tmp / "out", point


def test_files_ports_and_no_src(generated: tuple[Path, object]) -> None:
    out, point = generated
    text = (out / "rvsm_array.v").read_text()
    header = re.search(r"module rvsm_array\((.*?)\);", text).group(1)
    ports = {p.strip() for p in header.split(",")}
    assert ports == {"clk", "rst", "codes", "strobe", "clear", "cfg_we", "cfg_addr",
                     "cfg_data", "spike_pos", "spike_neg", "valid"}
    assert "src =" not in text
    meta = json.loads((out / "rvsm_array.ports.json").read_text())
    assert meta["latency"] == RvsmArray.LATENCY
    widths = {p["name"]: p["width"] for p in meta["ports"]}
    c = point.contract()
    assert widths["codes"] == 2 * 3 * c.adc_bits
    assert widths["spike_pos"] == c.num_scales * 6
    assert (out / "rvsm_array.ports.md").read_text().startswith("# `rvsm_array` port map")


def test_verilator_lint_clean(generated: tuple[Path, object]) -> None:
    from rvsm.rtl.verilog import verilator_lint

    out, _ = generated
    verilator_lint(out / "rvsm_array.v")


@pytest.mark.skipif(shutil.which("yosys") is None, reason="apt-get install yosys")
def test_yosys_stats(generated: tuple[Path, object], capsys: pytest.CaptureFixture) -> None:
    from rvsm.rtl.verilog import yosys_stats

    out, point = generated
    c = point.contract()
    st = yosys_stats(out / "rvsm_array.v")
    # per pixel at least the accumulator and threshold registers survive synthesis
    assert st["flip_flops"] >= 6 * (c.accumulator_bits + c.threshold_bits)
    assert st["cells"] > st["flip_flops"]
