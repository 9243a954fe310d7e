"""The composed AXI IP against golden traces recorded from the one-method IP it replaced.

``RvsmAxisIp`` was one 104-line ``elaborate`` until issue 39; it is now joined from the
input gate, framing check, threshold port, output packer and event counters. Its cycle
behaviour must not have changed: the traces in ``tests/data/ip_traces/`` were recorded
from the old IP (main at cc098cb) with :func:`record_trace`, driving every input port
of the IP (AXI4-Stream data, valid, ready, framing bits, and every AXI4-Lite channel
with random valids, addresses, data and strobes, plus a reset mid-way) from a seeded
pattern, and sampling every output port and the public observables (``init``,
``flush_req``, ``clear_req``, ``drop``, the FIFO's level) every cycle. The test replays
the same pattern on today's IP and asserts every sample equal.

Reads of ``DIGEST_RTL`` are left out of the pattern (the RTL digest hashes the sources,
so it changes with any edit under ``rtl/``); everything else is compared.

Re-record deliberately, only when the IP's behaviour is meant to change:
``python -m tests.rtl.ip.test_composition`` rewrites the traces from today's IP.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from amaranth.hdl import ClockDomain, Module

from rvsm.model.fixed.contract import ArrayContract
from rvsm.rtl.amaranth_sim import run_simulation
from rvsm.rtl.ip.wrapper import RvsmAxisIp
from tests.conftest import model_contract

TRACES = Path(__file__).parents[2] / "data" / "ip_traces"

#: name -> (model, height, width, lanes, fifo depth, shared thresholds or None, cycles)
POINTS = {
    "dog4_p2_fifo4": ("dog4", 4, 8, 2, 4, None, 2500),
    "dog2_p2_shared_fifo7": ("dog2", 4, 8, 2, 7, (9, 40), 2500),
    "fsm_p1_fifo5": ("fsm", 3, 4, 1, 5, None, 2000),
}

#: Outputs sampled every cycle: the IP's output ports and the public observables.
OUTPUTS = ("s_axis.tready", "m_axis.tdata", "m_axis.tvalid", "m_axis.tuser",
           "m_axis.tlast", "s_axil.awready", "s_axil.wready", "s_axil.bresp",
           "s_axil.bvalid", "s_axil.arready", "s_axil.rdata", "s_axil.rresp",
           "s_axil.rvalid", "init", "flush_req", "clear_req", "drop", "fifo.level")


def _contract(name: str) -> tuple[ArrayContract, int, int, int]:
    model, h, w, lanes, depth, shared, cycles = POINTS[name]
    c = model_contract(model, h, w)
    if shared is not None:
        c = dataclasses.replace(c, shared_thresholds=shared)
    return c, lanes, depth, cycles


def _member(dut: RvsmAxisIp, path: str) -> object:
    obj: object = dut
    for part in path.split("."):
        obj = getattr(obj, part)
    return obj


def stimulus(dut: RvsmAxisIp, cycles: int, seed: int) -> dict[str, np.ndarray]:
    """Every input port's value per cycle (``rst`` high for two cycles mid-way)."""
    rng = np.random.default_rng(seed)
    rm, geo = dut.regmap, dut.geometry
    offsets = [r.offset for r in rm.registers]
    readable = [o for o in offsets if o != rm["DIGEST_RTL"].offset] + [0x44, 0xFFC]
    writes = offsets + [0x44]
    control = rm["CONTROL"].offset

    def bits(p: float) -> np.ndarray:
        return (rng.random(cycles) < p).astype(np.int64)

    awaddr = rng.choice(writes, cycles)
    awaddr[rng.random(cycles) < 0.15] = control  # flush, clear, policy, counter resets
    small = rng.integers(0, 16, cycles)
    wide = rng.integers(0, 1 << 32, cycles, dtype=np.int64)
    s = {
        "s_axis.tvalid": bits(0.75),
        "s_axis.tdata": rng.integers(0, 1 << len(dut.s_axis.tdata), cycles, dtype=np.int64),
        "s_axis.tuser": bits(1 / geo.beats_per_frame),
        "s_axis.tlast": bits(1 / geo.groups),
        "m_axis.tready": np.repeat(bits(0.6)[: cycles // 4 + 1], 4)[:cycles],
        "s_axil.awaddr": awaddr, "s_axil.awvalid": bits(0.35),
        "s_axil.wdata": np.where(rng.random(cycles) < 0.8, small, wide),
        "s_axil.wstrb": np.where(rng.random(cycles) < 0.9, 0xF, rng.integers(0, 16, cycles)),
        "s_axil.wvalid": bits(0.35), "s_axil.bready": bits(0.7),
        "s_axil.araddr": rng.choice(readable, cycles), "s_axil.arvalid": bits(0.35),
        "s_axil.rready": bits(0.7),
        "rst": np.zeros(cycles, dtype=np.int64),
    }
    s["rst"][cycles // 2: cycles // 2 + 2] = 1
    return s


def record_trace(dut: RvsmAxisIp, cycles: int, seed: int) -> dict[str, np.ndarray]:
    """Drive ``dut`` with :func:`stimulus` and sample :data:`OUTPUTS` each cycle (after
    the cycle's inputs are set, before its rising edge)."""
    stim = stimulus(dut, cycles, seed)
    top = Module()
    top.domains.sync = cd = ClockDomain()
    top.submodules.dut = dut
    ports = {k: (cd.rst if k == "rst" else _member(dut, k)) for k in stim}
    outs = {k: _member(dut, k) for k in OUTPUTS}
    trace = {k: np.zeros(cycles, dtype=np.uint64) for k in OUTPUTS}

    async def bench(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        for c in range(cycles):
            for k, sig in ports.items():
                ctx.set(sig, int(stim[k][c]))
            for k, sig in outs.items():
                trace[k][c] = ctx.get(sig)
            await ctx.tick()

    run_simulation(top, bench)
    return trace


def _trace_of(name: str) -> dict[str, np.ndarray]:
    c, lanes, depth, cycles = _contract(name)
    return record_trace(RvsmAxisIp(c, lanes, depth), cycles, seed=sum(map(ord, name)))


@pytest.mark.parametrize("name", list(POINTS))
def test_the_composed_ip_is_cycle_identical_to_the_recorded_one(name: str) -> None:
    golden = np.load(TRACES / f"{name}.npz")
    trace = _trace_of(name)
    assert set(golden.files) == set(OUTPUTS)
    for k in OUTPUTS:
        diff = np.flatnonzero(golden[k] != trace[k])
        assert diff.size == 0, (f"{k} differs first at cycle {diff[0]}: recorded "
                                f"{golden[k][diff[0]]}, now {trace[k][diff[0]]}")
    # the pattern exercised what the IP does: beats both ways, register responses,
    # flush and clear requests, drops, the reset walk twice
    for k in ("m_axis.tvalid", "s_axil.bvalid", "s_axil.rvalid", "flush_req",
              "clear_req", "drop"):
        assert trace[k].any(), k
    assert (np.diff(trace["init"].astype(int)) == 1).sum() == 1  # rst restarted the walk
    assert (golden["s_axil.bresp"][golden["s_axil.bvalid"] == 1] == 0).any()


if __name__ == "__main__":
    TRACES.mkdir(parents=True, exist_ok=True)
    for point in POINTS:
        np.savez_compressed(TRACES / f"{point}.npz", **_trace_of(point))
        print("recorded", point)
