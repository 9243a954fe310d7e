"""The generated Verilog in a vanilla flow (docs/rtl.md, "Using the Verilog in your flow"):
a timescale, plain ``verilator --lint-only -Wall`` clean with only the shipped waiver
file, Icarus ``-g2005``/``-g2012`` without warnings, a provenance header, byte-identical
output for the same inputs, a FuseSoC core whose lint target runs, an SDC template."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
from dataclasses import replace
from pathlib import Path

import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.fixed.point_toml import save_design_point
from rvsm.rtl.architectures.verilog import OUTPUT_SUFFIXES, verilator_env
from rvsm.rtl.flow_files import LINT_WAIVER_RULES, design_point_digest
from rvsm.sim.cli import main

#: name -> (size, model, rvsm verilog arguments, top): tiny streaming arrays at P = 1 and
#: P = 3, a tiny parallel array and the AXI IP around a tiny streaming array.
DESIGNS = {
    "stream1": ("6x8", "dog2", ["--arch", "stream", "--lanes", "1"], "rvsm_stream_array"),
    "stream3": ("6x9", "dog2", ["--arch", "stream", "--lanes", "3"], "rvsm_stream_array"),
    "parallel": ("2x3", "fsm", ["--arch", "parallel"], "rvsm_array"),
    "axis": ("6x8", "dog2", ["--arch", "stream", "--lanes", "2", "--interface", "axis"],
             "rvsm_axis_ip"),
}
#: The architecture each design's provenance names (default: its --arch).
ARCH_NAMES = {"axis": "stream_axis"}
#: Files beside the Verilog beyond OUTPUT_SUFFIXES, with the same provenance header.
EXTRA_SUFFIXES = {"axis": {"regs_md": ".regs.md", "regs_h": ".regs.h"}}


def _argv(root: Path, name: str) -> list[str]:
    size, _, args, _ = DESIGNS[name]
    return ["verilog", str(root / f"{name}.toml"), "--size", size, *args,
            "-o", str(root / name), "--force"]


@pytest.fixture(scope="module")
def generated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("vanilla")
    for name, (_, model, _, _) in DESIGNS.items():
        save_design_point(root / f"{name}.toml", replace(default_design_point(), model=model))
        assert main(_argv(root, name)) == 0
    return root


def _files(root: Path, name: str) -> dict[str, Path]:
    top = DESIGNS[name][3]
    suffixes = {**OUTPUT_SUFFIXES, **EXTRA_SUFFIXES.get(name, {})}
    return {k: root / name / f"{top}{ext}" for k, ext in suffixes.items()}


def _verilator(cwd: Path, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run(["verilator", "--lint-only", "-Wall", *args], cwd=cwd,
                          env=verilator_env(), capture_output=True, text=True, timeout=120)


@pytest.mark.parametrize("name", DESIGNS)
def test_timescale_first(generated: Path, name: str) -> None:
    text = _files(generated, name)["verilog"].read_text()
    assert "`timescale 1ns/1ps\n" in text
    assert text.index("`timescale 1ns/1ps") < text.index("module ")


@pytest.mark.parametrize("name", DESIGNS)
def test_plain_verilator_lint_with_the_shipped_waivers_only(generated: Path,
                                                            name: str) -> None:
    files = _files(generated, name)
    proc = _verilator(files["verilog"].parent, files["waivers"].name, files["verilog"].name)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "%Warning" not in proc.stdout + proc.stderr
    # without it, only the documented rules fire
    proc = _verilator(files["verilog"].parent, files["verilog"].name)
    kinds = set(re.findall(r"%Warning-([A-Z0-9]+)", proc.stderr))
    assert proc.returncode != 0 and kinds and kinds <= set(LINT_WAIVER_RULES)


@pytest.mark.skipif(shutil.which("iverilog") is None, reason="apt-get install iverilog")
@pytest.mark.parametrize("name", DESIGNS)
@pytest.mark.parametrize("gen", ["-g2005", "-g2012"])
def test_icarus_has_no_warnings(generated: Path, name: str, gen: str) -> None:
    verilog = _files(generated, name)["verilog"]
    proc = subprocess.run(["iverilog", gen, "-Wall", "-o", "/dev/null", verilog.name],
                          cwd=verilog.parent, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and proc.stdout + proc.stderr == ""


@pytest.mark.parametrize("name", DESIGNS)
def test_provenance_header_in_every_file(generated: Path, name: str) -> None:
    files = _files(generated, name)
    meta = json.loads(files["ports_json"].read_text())
    prov = meta["provenance"]
    assert prov["arch"] == ARCH_NAMES.get(name, DESIGNS[name][2][1])
    assert prov["top"] == DESIGNS[name][3]
    assert re.fullmatch(r"[0-9a-f]{16}", prov["rtl_digest"])
    assert re.fullmatch(r"[0-9a-f]{16}", prov["design_point_digest"])
    assert prov["command"].startswith("rvsm verilog ") and "--size" in prov["command"]
    point = default_design_point()
    size = tuple(int(v) for v in DESIGNS[name][0].split("x"))
    contract = replace(point, model=DESIGNS[name][1]).with_size(*size).contract()
    assert prov["design_point_digest"] == design_point_digest(contract)
    for key in ("verilog", "ports_md", "waivers", "core", "sdc",
                *EXTRA_SUFFIXES.get(name, {})):
        head = "\n".join(files[key].read_text().splitlines()[:8])
        assert f"Generated by rvsm {prov['rvsm_version']}" in head, key
        assert f"design point digest: {prov['design_point_digest']}" in head, key
        assert f"RTL digest: {prov['rtl_digest']}" in head, key
        assert f"command: {prov['command']}" in head, key
    assert "generation_seconds" not in meta  # nothing time-dependent


def test_same_inputs_give_byte_identical_files(generated: Path) -> None:
    before = {k: p.read_bytes() for k, p in _files(generated, "stream3").items()}
    assert main(_argv(generated, "stream3")) == 0
    after = {k: p.read_bytes() for k, p in _files(generated, "stream3").items()}
    assert before == after


def test_sdc_names_the_clock_and_every_port(generated: Path) -> None:
    files = _files(generated, "stream1")
    sdc = files["sdc"].read_text()
    assert "create_clock -name clk -period 6.667 [get_ports clk]" in sdc
    ports = json.loads(files["ports_json"].read_text())["ports"]
    for p in ports:
        if p["name"] != "clk":
            assert re.search(rf"[{{ ]{p['name']}(\[\*\])?[ }}\]]", sdc), p["name"]
    out = generated / "clock100"
    assert main([*_argv(generated, "stream1")[:-3], "-o", str(out), "--clock-mhz",
                 "100"]) == 0
    assert "-period 10.000 [get_ports clk]" in (out / "rvsm_stream_array.sdc").read_text()


def test_fusesoc_lint_target(generated: Path, tmp_path: Path) -> None:
    """``fusesoc run --target lint`` on the shipped core: plain Verilator -Wall with the
    waiver file; removing the waivers from the core makes it fail."""
    env = verilator_env()  # Verilator's bin/ and this Python's (fusesoc) on PATH
    fusesoc = shutil.which("fusesoc", path=env["PATH"])
    assert fusesoc, "fusesoc is a dev dependency: pip install -e '.[dev]'"
    core = _files(generated, "stream1")["core"]
    name = re.search(r"^name: (\S+)$", core.read_text(), re.M).group(1)

    def lint(cores: Path) -> subprocess.CompletedProcess:
        return subprocess.run([fusesoc, "--cores-root", str(cores), "run", "--build-root",
                               str(tmp_path / f"build-{cores.name}"), "--target", "lint",
                               name], cwd=tmp_path, env=env, capture_output=True,
                              text=True, timeout=120)

    proc = lint(core.parent)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    bare = tmp_path / "bare"
    shutil.copytree(core.parent, bare)
    bare_core = bare / core.name
    bare_core.write_text(bare_core.read_text().replace("filesets: [rtl, waivers]",
                                                       "filesets: [rtl]"))
    assert lint(bare).returncode != 0


def test_cli_lint_runs_verilator_and_icarus(generated: Path,
                                            capsys: pytest.CaptureFixture) -> None:
    assert main([*_argv(generated, "parallel"), "--lint"]) == 0
    out = capsys.readouterr().out
    assert "verilator --lint-only -Wall rvsm_array.vlt rvsm_array.v: clean" in out
    assert "iverilog -g2005 / -g2012 -Wall rvsm_array.v: clean" in out


@pytest.mark.parametrize("name", sorted(DESIGNS))
def test_sdc_comments_name_only_ports_the_top_has(generated: Path, name: str) -> None:
    """The notes of ``<top>.sdc`` name port families (``thr_*``, ``clear``...) that the top
    really has: the AXI IP has none of the bare array's control ports (issue 34)."""
    files = _files(generated, name)
    names = [p["name"] for p in json.loads(files["ports_json"].read_text())["ports"]]
    notes = [line for line in files["sdc"].read_text().splitlines()
             if line.startswith("# - ") and "control" in line]
    for family in re.findall(r"\b(\w+_)\*", "\n".join(notes)):
        assert any(n.startswith(family) for n in names), (name, family)
    if any(n == "clear" for n in names):
        assert any("clear" in line for line in notes), name
