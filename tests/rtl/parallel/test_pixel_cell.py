"""amaranth.sim tests of one accumulator cell against the contract's integrator."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.model.fixed.contract import FixedIntegrator, arithmetic_shift
from rvsm.model.fixed.widths import signed_range
from rvsm.rtl.parallel.pixel_cell import PixelCell


def run_cell(
    amaranth_sim, sums: list[int], thr: int, bits: int, signed: bool, reset: str, shift: int = 0,
    sum_bits: int = 12, clear_at: tuple[int, ...] = (),
) -> list[int]:
    """Strobe ``sums`` through one cell; spikes per step (+1/-1/0)."""
    cell = PixelCell(sum_bits, shift, bits, signed, reset)
    out: list[int] = []

    async def bench(ctx) -> None:  # noqa: ANN001
        ctx.set(cell.thr.we, 1)
        ctx.set(cell.thr.data, thr)
        await ctx.tick()
        ctx.set(cell.thr.we, 0)
        for t, s in enumerate(sums):
            if t in clear_at:
                ctx.set(cell.clear, 1)
                await ctx.tick()
                ctx.set(cell.clear, 0)
                assert ctx.get(cell.acc) == 0
            ctx.set(cell.sum_in, s)
            ctx.set(cell.strobe, 1)
            await ctx.tick()
            ctx.set(cell.strobe, 0)
            for _ in range(cell.LATENCY - 1):
                await ctx.tick()
            out.append(ctx.get(cell.spike_pos) - ctx.get(cell.spike_neg))

    amaranth_sim.run(cell, bench)
    return out


def expected(sums: list[int], thr: int, bits: int, signed: bool, reset: str,
             shift: int = 0, clear_at: tuple[int, ...] = ()) -> list[int]:
    """The contract's :class:`FixedIntegrator` on one accumulator, cleared at ``clear_at``."""
    cuts = [0, *sorted(clear_at), len(sums)]
    out: list[int] = []
    for a, b in zip(cuts, cuts[1:], strict=False):
        integ = FixedIntegrator(np.full((1, 1, 1), thr), bits, signed, reset)
        for s in sums[a:b]:
            shifted = arithmetic_shift(np.full((1, 1, 1), s), shift)
            out.append(int(integ.step(shifted)[0, 0, 0]))
    return out


@pytest.mark.parametrize("signed", [True, False])
@pytest.mark.parametrize("reset", ["zero", "subtract"])
def test_random_sums_match_integrator(signed: bool, reset: str, amaranth_sim) -> None:
    rng = np.random.default_rng(7)
    lo = -2048 if signed else 0
    sums = [int(v) for v in rng.integers(lo, 2048, 200)]
    for shift in (0, 2):
        got = run_cell(amaranth_sim, sums, 300, 10, signed, reset, shift=shift)
        assert got == expected(sums, 300, 10, signed, reset, shift=shift)


def test_both_saturation_rails_and_exact_threshold(amaranth_sim) -> None:
    bits = 8
    lo, hi = signed_range(bits)
    # threshold at the top rail: only a saturated accumulator reaches it exactly
    sums = [100, 100, 100, -100, -100, -100, -100, 127, 0, 5]
    for thr in (hi, 127, 100, 1):
        got = run_cell(amaranth_sim, sums, thr, bits, True, "subtract")
        assert got == expected(sums, thr, bits, True, "subtract")
    assert lo == -128


def test_threshold_hit_exactly_fires(amaranth_sim) -> None:
    got = run_cell(amaranth_sim, [5, 5, 10, -20], 10, 8, True, "zero")
    assert got == [0, 1, 1, -1]


def test_clear_restarts_accumulator(amaranth_sim) -> None:
    sums = [7, 7, 7, 7, 7, 7]
    got = run_cell(amaranth_sim, sums, 20, 8, True, "zero", clear_at=(2, 4))
    assert got == expected(sums, 20, 8, True, "zero", clear_at=(2, 4))
    assert got == [0, 0, 0, 0, 0, 0]


def test_unsigned_model_never_fires_negative(amaranth_sim) -> None:
    got = run_cell(amaranth_sim, [-100] * 20, 5, 8, False, "zero")
    assert set(got) == {0}


def test_the_cell_takes_an_output_rule_not_a_name():
    """The cell's next-state logic is chosen by the contract's ``kind.output``; a sensor's
    name is refused."""
    from amaranth.hdl import Fragment

    from rvsm.model.kinds.sensor_kind import Output

    for output in Output:
        Fragment.get(PixelCell(12, 0, 8, True, output=output), None)
    with pytest.raises(ValueError, match="output must be one of"):
        PixelCell(12, 0, 8, True, output="dvs")  # type: ignore[arg-type]
