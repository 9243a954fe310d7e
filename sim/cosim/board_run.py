"""Co-simulate the board front end through its links in cocotb (Icarus).

:func:`board_verify` builds :class:`~rvsm.rtl.board.front_end.BoardFrontEnd` (behavioural
gearing) for a design point, serialises the sensor's frames with the link model
(:mod:`rvsm.rtl.board.model`: training, framing, a skew per pair, a bit slip, the clock
stopped between two parts: a lost lock, then training again), runs the testbench
:mod:`rvsm.sim.cosim.testbenches.tb_board` through the cocotb adapter's build and test
calls on the Icarus netlist of :mod:`rvsm.sim.cosim.builds.icarus_netlist` (Amaranth's
Verilog has ``always @*`` processes whose inputs never change from their initial values,
e.g. a state machine's outputs in its first state; Icarus never runs them, so they stay
``x``; as netlist cells they do not), and returns its result: every spike out of the
transmitter compared with the fixed twin, and the link status the ports report.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.infra.errors import ToolError
from rvsm.rtl.board.drive import sensor_bits
from rvsm.rtl.board.front_end import BoardFrontEnd, front_end_verilog
from rvsm.rtl.board.model import skewed
from rvsm.sim.cosim.builds.cocotb_adapter import check_simulator, cocotb_build, cocotb_test
from rvsm.sim.cosim.builds.icarus_netlist import write_icarus_netlist

__all__ = ["TOP", "board_verify"]

#: The front end's module name in the co-simulation.
TOP = "rvsm_board"
#: The cocotb testbench module.
TESTBENCH = "rvsm.sim.cosim.testbenches.tb_board"


def board_stimulus(point: DesignPoint, lanes: int, steps: int, seed: int,
                   delays: tuple[int, ...], slip: int, pause_ns: int
                   ) -> tuple[BoardFrontEnd, dict[str, np.ndarray]]:
    """The front end and the testbench's inputs: ``steps`` random frames in two parts
    (the receive clock stops ``pause_ns`` between them), each pair delayed by
    ``slip + delays[i]`` bits."""
    c = point.contract()
    fe = BoardFrontEnd(c, lanes)
    rng = np.random.default_rng(seed)
    codes = rng.integers(0, 1 << c.adc_bits, (steps, c.height, c.width))
    thr = point.integer_thresholds()
    cut = steps // 2
    first = sensor_bits(fe.rx_format, codes[:cut], lanes, c.adc_bits, 0)
    second = sensor_bits(fe.rx_format, codes[cut:], lanes, c.adc_bits, fe.lag)
    bits = np.concatenate([first, second], axis=1)
    bits = skewed(bits, [slip + d for d in delays], fill=1)
    return fe, {"rx_bits": bits, "pause_bit": np.int64(first.shape[1]),
                "pause_ns": np.int64(pause_ns),
                "thr_writes": np.array(fe.threshold_writes(thr), dtype=object)
                .astype(np.int64).reshape(-1, 2),
                "expected": c.run(codes, thr), "lanes": np.int64(fe.geometry.lanes),
                "tx_payload_bits": np.int64(fe.tx_format.payload_bits)}


def board_verify(point: DesignPoint, lanes: int, steps: int, work_dir: str | Path,
                 seed: int = 0, delays: tuple[int, ...] | None = None, slip: int = 3,
                 pause_ns: int = 2000) -> dict:
    """Build and run the board co-simulation in ``work_dir`` (a fresh folder); return
    the testbench's result (``compared``, ``mismatches``, ``status``, ...). Raises
    :class:`ToolError` when the simulator writes no result."""
    from cocotb_tools.check_results import get_results

    check_simulator("icarus")
    work = Path(work_dir).resolve()
    work.mkdir(parents=True, exist_ok=True)
    fe, stim = board_stimulus(point, lanes, steps, seed,
                              delays if delays is not None else (0, 4), slip, pause_ns)
    verilog = work / f"{TOP}.v"
    verilog.write_text(front_end_verilog(fe, TOP))
    stim_path = work / "board.npz"
    np.savez(stim_path, **stim)
    netlist = work / f"{TOP}.icarus.v"  # processes as cells: no always @* left idle at 0
    write_icarus_netlist(verilog, TOP, netlist, work / "yosys.log")
    build_dir = work / "build"
    cocotb_build("icarus", netlist, TOP, [], build_dir, False, work / "build.log")
    run = work / "run"
    run.mkdir(exist_ok=True)
    result_path = run / "result.json"
    cocotb_test("icarus", build_dir, TOP, TESTBENCH, run,
                {"RVSM_BOARD": str(stim_path), "RVSM_RESULT": str(result_path)}, False, [],
                run / "results.xml", run / "sim.log")
    try:
        result = json.loads(result_path.read_text())
        tests, failed = get_results(run / "results.xml")
    except (OSError, ValueError, RuntimeError):
        raise ToolError(f"the board testbench wrote no result; log: {run / 'sim.log'}") \
            from None
    result["cocotb_tests"], result["cocotb_failed"] = tests, failed
    return result
