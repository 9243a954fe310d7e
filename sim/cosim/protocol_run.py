"""Protocol runs: an array driven by a protocol script on Icarus or Verilator.

:func:`check_script_rtl` builds (cached) the array with the per-cycle build and runs its
protocol testbench (the architecture's :class:`~rvsm.rtl.capabilities.ProtocolScripts`:
the streaming array's scripts of ``rtl/stream/protocol.py``, stalls, clears at any
position of a frame, threshold writes colliding with reads, played by
:mod:`.tb_stream_protocol`); :func:`protocol_verify` makes the seeded script of ``rvsm
verify --protocol SEED``. A failing run without ``waves`` is simulated again with waves
on into ``failure/`` (a script is short: its whole trace is the window).
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import Any

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.architectures.registry import (
    DEFAULT_ARCHITECTURE,
    architectures_with,
    get_architecture,
)
from rvsm.rtl.capabilities import Architecture, ProtocolScripts
from rvsm.sim.cosim.builds.build_cache import build, new_run_dir
from rvsm.sim.cosim.builds.cocotb_adapter import check_simulator
from rvsm.sim.cosim.builds.testbench_run import run_cocotb
from rvsm.sim.cosim.run_point import RunPoint

__all__ = ["check_script_rtl", "protocol_scripts", "protocol_verify"]

DEFAULT_WORK = Path("build") / "verify"


def protocol_scripts(arch: Architecture) -> ProtocolScripts:
    """``arch``'s protocol scripts; :class:`RvsmError` for an architecture without."""
    if arch.protocol is None:
        names = ", ".join(f"--arch {n}" for n in architectures_with(lambda a: a.protocol))
        raise RvsmError(f"--protocol drives {names} only, not --arch {arch.name}")
    return arch.protocol


def check_script_rtl(script: Any, sim: str = "icarus", waves: bool = False,
                     work_dir: str | os.PathLike = DEFAULT_WORK, name: str = "protocol",
                     build_root: str | os.PathLike | None = None,
                     arch: str | Architecture = DEFAULT_ARCHITECTURE) -> dict:
    """Run ``script`` (one of ``arch``'s protocol scripts) on ``arch``'s RTL; the
    testbench's checked result (``compared``, ``mismatches``, ``first_mismatch`` with its
    ``cycle``, ``first_mismatch_time_ns``, ``waves``, ``run_dir``, ``build_seconds``...)."""
    check_simulator(sim)
    a = get_architecture(arch)
    scripts = protocol_scripts(a)
    options = a.resolve({"lanes": script.lanes})
    a.check(script.contract, **options)
    work = Path(work_dir)
    root = work / "builds" if build_root is None else Path(build_root)
    sb = build(script.contract, sim, root, waves=waves, arch=a, **options)
    run_dir = new_run_dir(work, f"{name}-{sim}")
    try:
        path = run_dir / "script.npz"
        scripts.save(path, script)
        inputs = {"RVSM_SCRIPT": str(path.resolve())}
        result = run_cocotb(sb, inputs, run_dir, waves=waves, test_module=scripts.testbench)
        if result["mismatches"] and not result["waves"]:
            sbw = build(script.contract, sim, root, waves=True, arch=a, **options)
            again = run_dir / "failure"
            result["waves"] = run_cocotb(sbw, inputs, again, waves=True,
                                         test_module=scripts.testbench)["waves"]
    except KeyboardInterrupt:
        shutil.rmtree(run_dir, ignore_errors=True)
        raise
    result.update(build_seconds=sb.build_seconds, generate_seconds=sb.generate_seconds,
                  build_cached=sb.cached, verilog=str(sb.verilog), run_dir=str(run_dir),
                  arch=a.name, options=options, lanes=script.lanes,
                  coverage=scripts.coverage(script))
    return result


def protocol_verify(point: RunPoint | str | os.PathLike, seed: int, steps: int,
                    sim: str = "icarus", waves: bool = False,
                    size: tuple[int, int] | None = None,
                    work_dir: str | os.PathLike = DEFAULT_WORK, lanes: int | None = None,
                    arch: str | Architecture = DEFAULT_ARCHITECTURE) -> dict:
    """Verify ``arch`` (default the streaming array) of design ``point`` (a
    :class:`~.run_point.RunPoint`, or its TOML path; ``size`` resizes it) on its seeded
    protocol script over ``steps`` steps (``random_script``). Returns
    :func:`check_script_rtl`'s result plus ``seed``, ``point``, ``height``, ``width`` and
    ``coverage`` (per scale, the script's protocol bins)."""
    check_simulator(sim)
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise RvsmError(f"--steps must be a positive integer, got {steps!r}")
    a = get_architecture(arch)
    scripts = protocol_scripts(a)
    run = RunPoint.coerce(point, size)
    options = a.resolve({"lanes": lanes})
    a.check(run.contract, **options)
    script = scripts.random_script(run.contract, options["lanes"], steps, seed)
    result = check_script_rtl(script, sim, waves=waves, work_dir=work_dir,
                              name=f"protocol{seed}", arch=a)
    h, w = run.shape
    result.update(seed=seed, point=run.source, height=h, width=w)
    return result
