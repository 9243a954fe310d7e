"""The IP's input gate (``rtl/ip/input_gate.py``) against its cycle model: random
valids, policies, FIFO levels, flush and clear requests and threshold initialisation."""

from __future__ import annotations

import numpy as np

from rvsm.rtl.ip.input_gate import InputGate


def _inputs(cycles: int, seed: int, depth: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    init = np.zeros(cycles, dtype=int)
    init[:20] = 1  # the threshold walk after reset
    return {"tvalid": rng.random(cycles) < 0.7,
            "tdata": rng.integers(0, 1 << 16, cycles),
            "init": init,
            "drop": np.repeat(rng.random(cycles // 50 + 1) < 0.4, 50)[:cycles],
            "flush": rng.random(cycles) < 0.02, "clear": rng.random(cycles) < 0.02,
            "fifo_level": rng.integers(0, depth + 1, cycles),
            "out_valid": rng.random(cycles) < 0.5}


def test_input_gate_follows_its_model(amaranth_sim) -> None:
    dut = InputGate(adc_bits=5, lanes=2, lag=6, fifo_depth=5)
    cycles = 600
    x = _inputs(cycles, 3, dut.fifo_depth)
    want = dut.model(x)
    ports = {"tvalid": dut.s_axis.tvalid, "tdata": dut.s_axis.tdata, "init": dut.ctl.init,
             "drop": dut.ctl.drop, "flush": dut.ctl.flush, "clear": dut.ctl.clear,
             "fifo_level": dut.fifo_level, "out_valid": dut.out_valid}
    outs = {"tready": dut.s_axis.tready, "busy": dut.busy, "flushing": dut.flushing,
            "accepted": dut.accepted, "restart": dut.restart, "codes_valid": dut.codes.valid,
            "codes": dut.codes.payload.as_value(), "clear": dut.clear}
    got: dict[str, list[int]] = {k: [] for k in outs}

    async def bench(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        for c in range(cycles):
            for k, sig in ports.items():
                ctx.set(sig, int(x[k][c]))
            for k, sig in outs.items():
                got[k].append(ctx.get(sig))
            await ctx.tick()

    amaranth_sim.run(dut, bench)
    for k in outs:
        assert got[k] == want[k], k
    # the pattern reached every rule: stalls for credit, flush beats, clears
    flushing, tready = np.array(want["flushing"]), np.array(want["tready"])
    assert flushing.sum() > 6 * 3 and sum(want["restart"]) > 3
    stalled = ~tready.astype(bool) & ~np.array(want["busy"], dtype=bool)
    assert stalled.any() and sum(want["accepted"]) > 100
    flush_beats = np.array(want["codes_valid"][1:], bool) & ~np.array(want["accepted"][:-1],
                                                                      bool)
    assert flush_beats.any() and all(want["codes"][1:][i] == 0
                                     for i in np.flatnonzero(flush_beats))
