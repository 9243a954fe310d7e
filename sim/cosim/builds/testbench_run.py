"""One testbench run on a cached build: a stimulus in, the checked result out.

The testbench (:mod:`.tb_parallel`, :mod:`.tb_stream`) reads the stimulus ``.npz`` named by
``RVSM_STIMULUS`` and the port map ``RVSM_PORTS``, drives the build, and writes its JSON
result to ``RVSM_RESULT``; cocotb's verdict (``results.xml``) must agree with it.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

from rvsm.model.infra.errors import RvsmError, ToolError
from rvsm.sim.cosim.builds.build_cache import SimBuild
from rvsm.sim.cosim.builds.cocotb_adapter import cocotb_test

__all__ = ["run_cocotb", "run_testbench"]


def run_testbench(
    sb: SimBuild, stimulus: str | os.PathLike, test_dir: str | os.PathLike,
    waves: bool = False, test_module: str | None = None,
) -> dict:
    """Run the testbench ``test_module`` (default: the build's, ``sb.test_module``) on one
    stimulus ``.npz``; return its JSON result.

    ``test_dir`` (the simulator's current folder) should be a fresh folder
    (:func:`~rvsm.sim.cosim.builds.build_cache.new_run_dir`). The result has ``compared``,
    ``mismatches``, ``first_mismatch`` (or None), ``stream_seconds`` and ``simulator``;
    ``waves`` the FST path when kept. Raises :class:`~rvsm.rtl.toolchain.ToolFailure`
    when the simulator fails or is killed, :class:`ToolError` when the testbench ends
    without a result or its cocotb verdict contradicts the result (both: exit status 3).
    """
    return run_cocotb(sb, {"RVSM_STIMULUS": str(Path(stimulus).resolve())}, test_dir,
                      waves=waves, test_module=test_module)


def run_cocotb(
    sb: SimBuild, inputs: Mapping[str, str], test_dir: str | os.PathLike,
    waves: bool = False, test_module: str | None = None, plusargs: Sequence[str] = (),
    hdl_dumps: bool = False,
) -> dict:
    """Run a testbench on ``sb`` with ``inputs`` (``RVSM_*`` variables, besides
    ``RVSM_RESULT`` and ``RVSM_PORTS`` which this sets) and ``plusargs``; the checked
    result as :func:`run_testbench`. ``hdl_dumps`` lets the design's own ``$dumpvars``
    write (cocotb runs Icarus with its dumps suppressed unless it keeps waves itself);
    ``waves`` keeps cocotb's whole-run waveform."""
    from cocotb_tools.check_results import get_results

    if waves and not sb.waves:
        raise RvsmError("this build has no wave support; build it with waves=True")
    test_dir = Path(test_dir).resolve()
    test_dir.mkdir(parents=True, exist_ok=True)
    result_path = test_dir / "result.json"
    result_path.unlink(missing_ok=True)
    wave_path = test_dir / ("waves.fst" if sb.sim == "icarus" else "dump.fst")
    plusargs = [*plusargs, *([f"+dumpfile_path={wave_path}"]
                             if (waves and sb.sim == "icarus") else [])]
    log = test_dir / "sim.log"
    results_xml = test_dir / "results.xml"
    extra = {**inputs, "RVSM_RESULT": str(result_path),
             "RVSM_PORTS": str(sb.ports_json.resolve())}
    test_module = test_module or sb.test_module
    t0 = time.perf_counter()
    cocotb_test(sb.sim, sb.build_dir, sb.hdl_top, test_module, test_dir, extra,
                waves or hdl_dumps, plusargs, results_xml, log)
    wall = time.perf_counter() - t0
    tb = test_module.rsplit(".", 1)[-1]
    try:
        tests, failed = get_results(results_xml)
    except (RuntimeError, OSError):
        raise ToolError(f"testbench {tb} on {sb.sim} wrote no cocotb results "
                        f"({results_xml.name}); log: {log}") from None
    try:
        result = json.loads(result_path.read_text())
        mismatches = int(result["mismatches"])
    except (OSError, ValueError, KeyError, TypeError):
        raise ToolError(f"testbench {tb} on {sb.sim} crashed before writing its result "
                        f"({failed} of {tests} cocotb test(s) failed); log: {log}") from None
    if tests < 1 or bool(failed) != bool(mismatches):
        raise ToolError(f"testbench {tb} on {sb.sim}: cocotb reports {failed} of {tests} "
                        f"test(s) failed but the result has {mismatches} mismatches; "
                        f"log: {log}")
    result["simulator"] = sb.sim
    result["sim_wall_seconds"] = wall
    result["waves"] = str(wave_path) if waves and wave_path.exists() else None
    result["cocotb_tests"], result["cocotb_failed"] = tests, failed
    result["log"] = str(log)
    return result
