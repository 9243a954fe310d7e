"""The IP's framing check (``rtl/ip/framing_check.py``) against its cycle model: flags
right and wrong, beats and clears at random."""

from __future__ import annotations

import numpy as np

from rvsm.rtl.ip.framing_check import FramingCheck


def _simulate(amaranth_sim, dut: FramingCheck, x: dict) -> list[int]:  # noqa: ANN001
    got: list[int] = []

    async def bench(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        for c in range(len(x["accepted"])):
            for name, v in x.items():
                ctx.set(getattr(dut, name), int(v[c]))
            got.append(ctx.get(dut.error))
            await ctx.tick()

    amaranth_sim.run(dut, bench)
    return got


def test_framing_check_follows_its_model(amaranth_sim) -> None:
    dut = FramingCheck(height=3, groups=4)
    rng = np.random.default_rng(5)
    cycles = 500
    accepted = rng.random(cycles) < 0.7
    advance = np.concatenate([[False], accepted[:-1]]) | (rng.random(cycles) < 0.05)
    restart = rng.random(cycles) < 0.01
    # mostly the right flags (the count of accepted beats), a few flipped
    k = np.cumsum(accepted) - accepted
    tuser = (k % 12 == 0) ^ (rng.random(cycles) < 0.03)
    tlast = (k % 4 == 3) ^ (rng.random(cycles) < 0.03)
    x = {"accepted": accepted, "tuser": tuser, "tlast": tlast, "advance": advance,
         "restart": restart}
    want = dut.model(x)
    assert _simulate(amaranth_sim, dut, x) == want
    assert 0 < sum(want) < sum(accepted)  # errors, and beats without one


def test_a_well_framed_stream_has_no_error(amaranth_sim) -> None:
    """Back-to-back beats (each in the input register a cycle after its handshake) with
    the right flags: no error; ``tlast`` one group early: an error for the beats at
    ``g = 1`` and ``g = 2`` (the last one's comes after the run)."""
    n = 30
    k = np.arange(n)
    x = {"accepted": np.ones(n), "tuser": k % 6 == 0, "tlast": k % 3 == 2,
         "advance": np.r_[0, np.ones(n - 1)], "restart": np.zeros(n)}
    dut = FramingCheck(height=2, groups=3)
    assert _simulate(amaranth_sim, dut, x) == dut.model(x) == [0] * n
    x["tlast"] = k % 3 == 1
    dut = FramingCheck(height=2, groups=3)
    assert _simulate(amaranth_sim, dut, x) == dut.model(x)
    assert sum(dut.model(x)) == 2 * n // 3 - 1
