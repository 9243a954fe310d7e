"""Protocol runs: the streaming array driven by a protocol script on Icarus or Verilator.

:func:`check_script_rtl` builds (cached) the streaming array with the per-cycle build
and runs :mod:`.tb_stream_protocol` on a :class:`~rvsm.rtl.stream.protocol.ProtocolScript`
(stalls, clears at any position of a frame, threshold writes colliding with reads);
:func:`protocol_verify` makes the seeded script of ``rvsm verify --protocol SEED``. A
failing run without ``waves`` is simulated again with waves on into ``failure/`` (a
script is short: its whole trace is the window).
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.registry import get_architecture
from rvsm.rtl.stream.protocol import ProtocolScript, random_script, save_script, script_coverage
from rvsm.sim.cosim.builds.build_cache import build, new_run_dir
from rvsm.sim.cosim.builds.cocotb_adapter import check_simulator
from rvsm.sim.cosim.testbench_run import run_cocotb

__all__ = ["PROTOCOL_TESTBENCH", "check_script_rtl", "protocol_verify"]

#: The cocotb testbench module of protocol runs.
PROTOCOL_TESTBENCH = "rvsm.sim.cosim.testbenches.tb_stream_protocol"
DEFAULT_WORK = Path("build") / "verify"


def check_script_rtl(script: ProtocolScript, sim: str = "icarus", waves: bool = False,
                     work_dir: str | os.PathLike = DEFAULT_WORK, name: str = "protocol",
                     build_root: str | os.PathLike | None = None) -> dict:
    """Run ``script`` on the streaming array's RTL; the testbench's checked result
    (``compared``, ``mismatches``, ``first_mismatch`` with its ``cycle``,
    ``first_mismatch_time_ns``, ``waves``, ``run_dir``, ``build_seconds``...)."""
    check_simulator(sim)
    arch = get_architecture("stream")
    options = arch.resolve({"lanes": script.lanes})
    arch.check(script.contract, **options)
    work = Path(work_dir)
    root = work / "builds" if build_root is None else Path(build_root)
    sb = build(script.contract, sim, root, waves=waves, arch=arch, **options)
    run_dir = new_run_dir(work, f"{name}-{sim}")
    try:
        path = run_dir / "script.npz"
        save_script(path, script)
        inputs = {"RVSM_SCRIPT": str(path.resolve())}
        result = run_cocotb(sb, inputs, run_dir, waves=waves, test_module=PROTOCOL_TESTBENCH)
        if result["mismatches"] and not result["waves"]:
            sbw = build(script.contract, sim, root, waves=True, arch=arch, **options)
            again = run_dir / "failure"
            result["waves"] = run_cocotb(sbw, inputs, again, waves=True,
                                         test_module=PROTOCOL_TESTBENCH)["waves"]
    except KeyboardInterrupt:
        shutil.rmtree(run_dir, ignore_errors=True)
        raise
    result.update(build_seconds=sb.build_seconds, generate_seconds=sb.generate_seconds,
                  build_cached=sb.cached, verilog=str(sb.verilog), run_dir=str(run_dir),
                  arch="stream", options=options, lanes=script.lanes,
                  coverage=script_coverage(script))
    return result


def protocol_verify(fixed: str | os.PathLike, seed: int, steps: int, sim: str = "icarus",
                    waves: bool = False, size: tuple[int, int] | None = None,
                    work_dir: str | os.PathLike = DEFAULT_WORK, lanes: int | None = None,
                    ) -> dict:
    """Verify the streaming array of design point ``fixed`` (TOML) on the seeded protocol
    script :func:`~rvsm.rtl.stream.protocol.random_script` over ``steps`` steps. Returns
    :func:`check_script_rtl`'s result plus ``seed``, ``point``, ``height``, ``width`` and
    ``coverage`` (per scale, :data:`~rvsm.rtl.stream.protocol.PROTOCOL_BINS`)."""
    from rvsm.model.fixed.point_toml import load_design_point

    check_simulator(sim)
    if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
        raise RvsmError(f"--steps must be a positive integer, got {steps!r}")
    point = load_design_point(fixed)
    if size is not None:
        point = point.with_size(*size)
    contract = point.contract()
    arch = get_architecture("stream")
    options = arch.resolve({"lanes": lanes})
    arch.check(contract, **options)
    script = random_script(contract, options["lanes"], steps, seed)
    result = check_script_rtl(script, sim, waves=waves, work_dir=work_dir,
                              name=f"protocol{seed}")
    result.update(seed=seed, point=str(fixed), height=point.height, width=point.width)
    return result
