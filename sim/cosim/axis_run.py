"""Co-simulation of the AXI IP (``rvsm verilog --interface axis``) with cocotbext-axi.

:func:`axis_verify` builds the IP (the registry's ``axis`` wrapper of the streaming
array, ``rtl/ip/architecture.py``) through the shared build cache
(:func:`~.build_cache.build`), writes the stimulus into a fresh run folder and runs the
wrapper's testbench (:mod:`.tb_axis`) through the one cocotb runner
(:func:`~.testbench_run.run_cocotb`): the policy, the seed of the pause generators and
the idle/back-pressure probabilities go in as ``RVSM_AXIS``. :func:`register_map_check`
runs the register-map testbench (:mod:`.tb_register_map`) on the same build: a seeded
random sequence of AXI4-Lite writes and reads against the Python register model.
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.stimulus import Stimulus, save_stimulus
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.architectures.registry import DEFAULT_ARCHITECTURE, get_architecture
from rvsm.rtl.capabilities import Architecture
from rvsm.sim.cosim.builds.build_cache import build, new_run_dir
from rvsm.sim.cosim.builds.testbench_run import run_cocotb
from rvsm.sim.cosim.verify import DEFAULT_WORK

__all__ = ["AXIS_POLICIES", "axis_verify", "register_map_check"]

#: The output policies of the IP (CONTROL.drop = 0 / 1).
AXIS_POLICIES = ("stall", "drop")


def axis_verify(stim: Stimulus, sim: str = "icarus", policy: str = "stall", seed: int = 0,
                idle_in: float = 0.3, idle_out: float = 0.3, lanes: int = 1,
                fifo_depth: int | None = None, work_dir: str | os.PathLike = DEFAULT_WORK,
                waves: bool = False, arch: str | Architecture | None = None) -> dict:
    """Drive the IP of ``stim.contract`` with ``stim`` under ``policy``, the source idle
    with probability ``idle_in`` per cycle and the sink stalling with ``idle_out``
    (seeded by ``seed``); returns the testbench's result (``mismatches`` 0 when every
    beat, counter and register checked out; ``dropped``, ``counters``, ``cycles``...)
    with the build's timings and ``run_dir``. ``arch`` is the wrapper (default the
    streaming array's ``axis`` one), ``lanes`` and ``fifo_depth`` its options."""
    if policy not in AXIS_POLICIES:
        raise RvsmError(f"unknown policy {policy!r}; choose one of {AXIS_POLICIES}")
    for name, p in (("idle_in", idle_in), ("idle_out", idle_out)):
        if not 0 <= p < 1:
            raise RvsmError(f"{name} must be a probability in [0, 1), got {p}")
    if policy == "drop" and stim.clear_before:
        raise RvsmError("the drop-policy check takes a stimulus without clears")
    contract = stim.contract
    wrapper = get_architecture(DEFAULT_ARCHITECTURE, "axis") if arch is None \
        else get_architecture(arch)
    options = wrapper.resolve({"lanes": lanes, "fifo_depth": fifo_depth})
    wrapper.check(contract, **options)
    work = Path(work_dir)
    sb = build(contract, sim, work / "builds", waves=waves, arch=wrapper, **options)
    run_dir = new_run_dir(work, f"axis-{policy}-{sim}")
    try:
        path = run_dir / "stimulus.npz"
        save_stimulus(path, stim)
        cfg = {"policy": policy, "seed": int(seed), "idle_in": float(idle_in),
               "idle_out": float(idle_out)}
        result = run_cocotb(sb, {"RVSM_STIMULUS": str(path.resolve()),
                                 "RVSM_AXIS": json.dumps(cfg)}, run_dir, waves=waves)
    except KeyboardInterrupt:
        shutil.rmtree(run_dir, ignore_errors=True)
        raise
    result.update(build_seconds=sb.build_seconds, generate_seconds=sb.generate_seconds,
                  build_cached=sb.cached, verilog=str(sb.verilog), run_dir=str(run_dir),
                  arch=wrapper.name, options=options)
    return result


def register_map_check(contract: ArrayContract, sim: str = "icarus", seed: int = 0,
                       count: int = 200, lanes: int = 1, fifo_depth: int | None = None,
                       work_dir: str | os.PathLike = DEFAULT_WORK) -> dict:
    """Drive the IP of ``contract`` with ``count`` random AXI4-Lite writes and reads
    (seeded by ``seed``) and check each response and read-back against
    :class:`~rvsm.rtl.ip.register_model.RegisterFileModel`; returns the testbench's result
    (``mismatches`` 0 when all agree; ``responses``: per kind, the count of each
    response code) with ``run_dir``."""
    wrapper = get_architecture(DEFAULT_ARCHITECTURE, "axis")
    options = wrapper.resolve({"lanes": lanes, "fifo_depth": fifo_depth})
    wrapper.check(contract, **options)
    work = Path(work_dir)
    sb = build(contract, sim, work / "builds", arch=wrapper, **options)
    run_dir = new_run_dir(work, f"regmap-{sim}")
    try:
        path = run_dir / "stimulus.npz"
        codes = np.zeros((1, contract.height, contract.width), np.int64)
        thresholds = np.ones((contract.num_scales, contract.height, contract.width), np.int64)
        save_stimulus(path, Stimulus(codes, thresholds, contract.run(codes, thresholds)
                                     .astype(np.int8), contract))
        result = run_cocotb(sb, {"RVSM_STIMULUS": str(path.resolve()),
                                 "RVSM_REGMAP": json.dumps({"seed": int(seed),
                                                            "count": int(count)})},
                            run_dir, test_module=wrapper.register_testbench)
    except KeyboardInterrupt:
        shutil.rmtree(run_dir, ignore_errors=True)
        raise
    result.update(run_dir=str(run_dir), options=options)
    return result
