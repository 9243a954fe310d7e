"""Verilog of the streaming array: ports from the signature, no zero initialisers, lint."""

from __future__ import annotations

import json
import re
import time
from dataclasses import replace
from pathlib import Path

import pytest

from rvsm.model.fixed.design_point import DesignPoint, default_design_point
from rvsm.model.fixed.point_toml import save_design_point
from rvsm.rtl.architectures import get_architecture
from rvsm.rtl.stream.geometry import StreamGeometry
from rvsm.rtl.verilog import strip_zero_memory_init, write_outputs
from rvsm.sim.cli import main

STREAM_TOP = get_architecture("stream").default_top


@pytest.fixture(scope="module")
def generated(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, DesignPoint]:
    tmp = tmp_path_factory.mktemp("stream_verilog")
    point = replace(default_design_point().with_size(6, 8), model="dog2")
    save_design_point(tmp / "p.toml", point)
    assert main(["verilog", str(tmp / "p.toml"), "--arch", "stream", "--lanes", "2",
                 "-o", str(tmp / "out")]) == 0
    return tmp / "out", point


def test_ports_follow_the_signature(generated: tuple[Path, DesignPoint]) -> None:
    out, point = generated
    text = (out / f"{STREAM_TOP}.v").read_text()
    header = re.search(rf"module {STREAM_TOP}\((.*?)\);", text).group(1)
    ports = {p.strip() for p in header.split(",")}
    meta = json.loads((out / f"{STREAM_TOP}.ports.json").read_text())
    assert ports == {p["name"] for p in meta["ports"]}
    assert ports == {"clk", "rst", "codes_payload", "codes_valid", "codes_ready",
                     "spikes_payload", "spikes_valid", "thr_we", "thr_addr", "thr_data",
                     "clear"}
    c = point.contract()
    widths = {p["name"]: p["width"] for p in meta["ports"]}
    assert widths["codes_payload"] == 2 * c.adc_bits
    fields = {f["name"]: f for f in next(p for p in meta["ports"]
                                         if p["name"] == "spikes_payload")["fields"]}
    assert fields["pos"]["width"] == c.num_scales * 2
    assert sum(f["width"] for f in fields.values()) == widths["spikes_payload"]
    assert meta["timing"] == StreamGeometry(c, 2).timing()
    assert "src =" not in text
    # the only initialisers left: the threshold memories at the top rail (2 lanes)
    tw = c.accumulator_bits - 1
    top = f"{2 * tw}'h{(1 << (2 * tw)) - 1:x}"
    blocks = re.findall(r"initial begin\n(.*?)\n\s*end\n", text, re.S)
    assert blocks and {v for b in blocks for v in re.findall(r"= (\S+);", b)} == {top}
    md = (out / f"{STREAM_TOP}.ports.md").read_text()
    assert md.startswith(f"# `{STREAM_TOP}` port map") and "`spikes_payload`" in md


def test_verilator_lint_clean(generated: tuple[Path, DesignPoint]) -> None:
    from rvsm.rtl.verilog import verilator_lint

    out, _ = generated
    verilator_lint(out / f"{STREAM_TOP}.v", STREAM_TOP)


def test_strip_keeps_nonzero_initialisers() -> None:
    text = ("  reg [3:0] m [1:0];\n  initial begin\n    m[0] = 4'h0;\n    m[1] = 4'h0;\n"
            "  end\n  initial begin\n    k[0] = 4'h3;\n  end\n")
    stripped, n = strip_zero_memory_init(text)
    assert n == 1
    assert "4'h3" in stripped and "m[0]" not in stripped


def test_cli_rejects_lanes_not_dividing(tmp_path: Path,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    save_design_point(tmp_path / "p.toml", default_design_point().with_size(6, 8))
    assert main(["verilog", str(tmp_path / "p.toml"), "--arch", "stream", "--lanes", "3",
                 "-o", str(tmp_path / "o")]) == 2
    assert "divisor" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.parametrize("lanes", [20, 40])
def test_full_sensor_verilog(tmp_path: Path, lanes: int) -> None:
    """250x400 dog4 default point: figures printed (target < 60 s, < 10 MB)."""
    from rvsm.rtl.verilog import verilator_lint

    t0 = time.perf_counter()
    paths, gen = write_outputs(DesignPoint().contract(), tmp_path, "stream", lanes=lanes)
    size = paths["verilog"].stat().st_size
    print(f"P={lanes}: generated in {gen.seconds:.1f} s ({time.perf_counter() - t0:.1f} s "
          f"with port map), {size / 1e6:.2f} MB")
    assert size < 10e6
    verilator_lint(paths["verilog"], STREAM_TOP)
