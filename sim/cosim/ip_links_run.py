"""Co-simulate the AXI IP on a board through its links in cocotb (Icarus), registers
over SPI, with the link faults a board meets.

:func:`ip_links_verify` builds :class:`~rvsm.rtl.board.loopback.LinkLoopback` around
:class:`~rvsm.rtl.board.ip_front_end.IpBoardFrontEnd` (``front_end="ip"``, ``faults``:
skew between the receive pairs and a bit slip always; a further bit slip on pair 0 and a
stopped forwarded clock on command), runs :mod:`rvsm.sim.cosim.testbenches.tb_links_ip`
(frames, the faults, frames; the link registers read over SPI) and returns every spike
compared with the fixed twin (:meth:`ArrayContract.run` with the clear between the two
parts, :func:`check_beats`) and the registers it read.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
from amaranth.back import verilog as amaranth_verilog
from amaranth.hdl import Shape
from amaranth.lib.wiring import In

from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.infra.errors import ToolError
from rvsm.rtl.architectures.registry import get_architecture
from rvsm.rtl.board.loopback import CORE_BITS, LinkLoopback
from rvsm.rtl.ports import verilog_ports
from rvsm.sim.cosim.builds.cocotb_adapter import check_simulator, cocotb_build, cocotb_test
from rvsm.sim.cosim.builds.icarus_netlist import write_icarus_netlist

#: The streaming array's beats (the front end's array): their checker and type.
_BEATS = get_architecture().beats

__all__ = ["TOP", "ip_links_verify"]

TOP = "rvsm_ip_link_loopback"
#: The simulation's top: the loopback and its bit clock, made in Verilog (no wakeup
#: into Python per clock edge).
BENCH_TOP = "rvsm_ip_links_bench"
TESTBENCH = "rvsm.sim.cosim.testbenches.tb_links_ip"
#: The bit clock (ps): 800 Mbit/s a pair.
CLOCK_PS = 1250
#: SPI half period in core cycles (at least MIN_PHASE_CYCLES = 5).
SPI_HALF_CYCLES = 7.3


def _bench_top(lb: LinkLoopback, period_ps: int) -> str:
    """Verilog of :data:`BENCH_TOP`: ``clk`` made inside (rising edges from time 0 every
    ``period_ps``), every other port of the loopback passed through."""
    rows = [("_".join(map(str, path)), m.flow == In, Shape.cast(m.shape).width)
            for path, m in lb.signature.members.flatten() if m.is_port]
    ports = ["  input wire rst"] + [
        f"  {'input' if inp else 'output'} wire [{w - 1}:0] {n}" for n, inp, w in rows]
    conns = ", ".join([".clk(clk)", ".rst(rst)", *(f".{n}({n})" for n, _, _ in rows)])
    return (f"`timescale 1ns/1ps\nmodule {BENCH_TOP} (\n" + ",\n".join(ports) + "\n);\n"
            f"  reg clk;\n  initial begin\n    #0 clk = 1'b1;\n"
            f"    forever #{period_ps / 2000:.4f} clk = ~clk;\n  end\n"
            f"  {TOP} dut ({conns});\nendmodule\n")


def _beat_ints(codes: np.ndarray, lanes: int, bits: int) -> np.ndarray:
    """Code beats ``(T*H*G,)`` ints, lane ``i`` at bits ``[i*bits +: bits]``."""
    flat = codes.reshape(-1, lanes).astype(object)
    return np.array([sum(int(v) << (i * bits) for i, v in enumerate(row)) for row in flat],
                    dtype=object)


def ip_links_verify(point: DesignPoint, lanes: int, steps: int, work_dir: str | Path,
                    seed: int = 0, fault_bits: int = 3) -> dict:
    """Build and run the IP's links co-simulation in ``work_dir``: ``steps`` random
    frames, half before the faults and half after. Returns ``compared``, ``spikes``,
    ``mismatches``, ``first_mismatch``, ``registers`` (label -> value read over SPI),
    ``delays`` and the loopback's ``tx_link_errors``, ``out_framing_errors``,
    ``overflow``. :class:`ToolError` when the simulator writes no result."""
    check_simulator("icarus")
    work = Path(work_dir).resolve()
    shutil.rmtree(work / "run", ignore_errors=True)
    (work / "run").mkdir(parents=True)
    c = point.contract()
    lb = LinkLoopback(c, lanes, "ip", faults=True, fault_bits=fault_bits)
    verilog = work / f"{TOP}.v"
    verilog.write_text(amaranth_verilog.convert(lb, name=TOP, ports=verilog_ports(lb),
                                                emit_src=False))
    netlist = work / f"{TOP}.icarus.v"
    write_icarus_netlist(verilog, TOP, netlist, work / "yosys.log")
    bench = work / f"{BENCH_TOP}.v"
    bench.write_text(_bench_top(lb, CLOCK_PS))
    cocotb_build("icarus", [netlist, bench], BENCH_TOP, [], work / "build", False,
                 work / "build.log")
    geo = lb.geometry
    rng = np.random.default_rng(seed)
    codes = rng.integers(0, 1 << c.adc_bits, (steps, c.height, c.width), dtype=np.int64)
    cut = steps // 2
    expected = c.run(codes, point.integer_thresholds(), (cut,))
    stim = work / "run" / "links_ip.npz"
    beats = _beat_ints(codes, geo.lanes, c.adc_bits)
    split = cut * geo.beats_per_frame
    flush = np.zeros(lb.lag, dtype=np.int64)  # the lag beats that release the last outputs
    np.savez(stim, beats_a=np.concatenate([beats[:split].astype(np.int64), flush]),
             beats_b=np.concatenate([beats[split:].astype(np.int64), flush]),
             frames_a=split, clock_ps=CLOCK_PS, core_bits=CORE_BITS,
             spi_half_ns=SPI_HALF_CYCLES * CORE_BITS * CLOCK_PS / 1000)
    run = work / "run"
    result_path = run / "result.json"
    cocotb_test("icarus", work / "build", BENCH_TOP, TESTBENCH, run,
                {"RVSM_LINKS_IP": str(stim), "RVSM_RESULT": str(result_path)}, False, [],
                run / "results.xml", run / "sim.log")
    try:
        result = json.loads(result_path.read_text())
    except (OSError, ValueError):
        raise ToolError(f"the IP links testbench wrote no result; log: {run / 'sim.log'}") \
            from None
    fields = {name: (f.offset, f.width) for name, f in geo.spike_layout}

    def field(name: str) -> list[int]:
        off, width = fields[name]
        return [(w >> off) & ((1 << width) - 1) for w in result["beats"]]

    got = _BEATS.output_beats.from_words(field("row"), field("group"), field("last"),
                                 field("pos"), field("neg"), c.num_scales, geo.lanes)
    check = _BEATS.check_beats(geo.schedule, expected, got)
    return {"compared": int(check["compared"]), "spikes": int(np.count_nonzero(expected)),
            "mismatches": int(check["mismatches"]),
            "first_mismatch": check.get("first_mismatch"),
            "beats_out": len(result["beats"]), "delays": list(lb.delays),
            "registers": {label: value for label, _addr, value in result["reads"]},
            "tx_link_errors": result["tx_link_errors"],
            "out_framing_errors": result["out_framing_errors"],
            "overflow": result["overflow"], "seconds": result["seconds"]}
