"""Event counters (``rtl/ip/event_counters.py``) against their model: random events and
resets, and the wrap modulo ``2**width``."""

from __future__ import annotations

import numpy as np

from rvsm.rtl.ip.event_counters import EventCounters


def test_event_counters_follow_their_model(amaranth_sim) -> None:
    dut = EventCounters(("A", "B", "C"), width=4)
    rng = np.random.default_rng(11)
    cycles = 200
    events = rng.random((cycles, 3)) < (0.9, 0.5, 0.1)
    reset = rng.random(cycles) < 0.02
    want = dut.model(events, reset)
    got = np.zeros_like(want)

    async def bench(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        for c in range(cycles):
            ctx.set(dut.events, int(sum(int(b) << k for k, b in enumerate(events[c]))))
            ctx.set(dut.reset, int(reset[c]))
            got[c] = [ctx.get(dut.count(n)) for n in dut.names]
            await ctx.tick()

    amaranth_sim.run(dut, bench)
    assert np.array_equal(got, want)
    assert (np.diff(want[:, 0]) < 0).sum() > reset.sum()  # wrapped past 15, not only reset
