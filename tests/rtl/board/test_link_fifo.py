"""The links' clock-crossing FIFO: every word once and in order at unrelated clock
ratios and random enables, the registered side's rate, the full depth, the error type."""

from __future__ import annotations

import random

import pytest
from amaranth.hdl import ClockDomain, Module
from amaranth.sim import Simulator

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.board.link_fifo import LinkFifo

DEPTH = 8


def _run(link: str, w_period: float, r_period: float, seed: int, words: int = 60,
         stall_reads: int = 0) -> tuple[list[int], list[int], int, bool]:
    """Words written (taken at a ``w`` edge with ``w_en`` and ``w_rdy`` high), words read,
    the words written before the first read (reads held off for ``stall_reads``
    cycles), and whether the registered side ever allowed two accesses in a row."""
    rng = random.Random(seed)
    fifo = LinkFifo(8, DEPTH, "w", "r", link)
    m = Module()
    m.domains += [ClockDomain("w"), ClockDomain("r")]
    m.submodules.fifo = fifo
    sim = Simulator(m)
    sim.add_clock(w_period, domain="w")
    sim.add_clock(r_period, domain="r", phase=0.37 * r_period)
    sent: list[int] = []
    got: list[int] = []
    before_read: list[int] = []
    back_to_back = [False]

    async def writer(ctx) -> None:  # noqa: ANN001
        k, last = 0, False
        while k < words:
            en = rng.random() < 0.7
            ctx.set(fifo.w_en, en)
            ctx.set(fifo.w_data, k)
            took = en and bool(ctx.get(fifo.w_rdy))
            back_to_back[0] |= link == "w" and took and last
            await ctx.tick("w")
            if took:
                sent.append(k)
                k += 1
            last = took
        ctx.set(fifo.w_en, 0)

    async def reader(ctx) -> None:  # noqa: ANN001
        cyc, last = 0, False
        while len(got) < words and cyc < 40 * words:
            if cyc == stall_reads:
                before_read.append(len(sent))
            en = cyc >= stall_reads and rng.random() < 0.6
            ctx.set(fifo.r_en, en)
            took = en and bool(ctx.get(fifo.r_rdy))
            back_to_back[0] |= link == "r" and took and last
            data = ctx.get(fifo.r_data)
            await ctx.tick("r")
            if took:
                got.append(data)
            last = took
            cyc += 1

    sim.add_testbench(writer)
    sim.add_testbench(reader)
    sim.run()
    return sent, got, before_read[0], back_to_back[0]


@pytest.mark.parametrize("link", ["w", "r"])
@pytest.mark.parametrize(("w_period", "r_period"), [(5e-9, 10e-9), (10e-9, 5e-9),
                                                    (5e-9, 17e-9), (13e-9, 5e-9)])
def test_every_word_once_and_in_order(link: str, w_period: float, r_period: float) -> None:
    sent, got, _, back_to_back = _run(link, w_period, r_period,
                                      seed=int(w_period * 1e10 + r_period * 1e9))
    assert sent == list(range(60))
    assert got == sent
    assert not back_to_back  # the registered side takes a word at most every other cycle


@pytest.mark.parametrize("link", ["w", "r"])
def test_holds_depth_words_and_no_more(link: str) -> None:
    sent, got, before_read, _ = _run(link, 5e-9, 10e-9, seed=3, words=3 * DEPTH,
                                     stall_reads=20 * DEPTH)
    assert before_read == DEPTH
    assert got == sent == list(range(3 * DEPTH))


def test_bad_parameters_are_an_rvsm_error() -> None:
    with pytest.raises(RvsmError, match="power-of-2"):
        LinkFifo(8, 12, "w", "r", "w")
    with pytest.raises(RvsmError, match="link"):
        LinkFifo(8, 8, "w", "r", "both")
