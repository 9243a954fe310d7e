"""Formal checks of the link's word alignment and deskew (rtl/board/harnesses.py, run by
the project's sby flow, ``run_sby``), a deliberately broken aligner that must give a
counterexample, and a property-based test of the receiver's clock crossing (hypothesis
over core clock periods, link start phases and sink stalls, ``amaranth.sim``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from amaranth.hdl import Cat, Module, Signal
from hypothesis import HealthCheck, Phase, example, given, settings
from hypothesis import strategies as st

from rvsm.rtl.board.aligner import GOOD_WORDS, WordAligner
from rvsm.rtl.board.drive import HALF_BIT_S, beat_ints, drive_link
from rvsm.rtl.board.harnesses import AlignerProperties, DeskewProperties
from rvsm.rtl.board.model import (
    GEAR_BITS,
    MARK,
    TRAIN,
    WORD_BITS,
    LinkFormat,
    beat_words,
    idle_words,
    serialise,
    training_words,
)
from rvsm.rtl.board.receiver import FIFO_DEPTH
from rvsm.rtl.formal_harness import FormalHarness, property_at
from rvsm.sim.formal.sby import SbyResult, run_sby


def _prove(harness: FormalHarness, workdir: Path, mode: str = "bmc",
           depth: int | None = None) -> tuple[SbyResult, list[str]]:
    """sby verdict and the names of the failing properties (or unreached covers)."""
    props = harness.statements()
    run_depth = depth or (harness.cover_depth if mode == "cover" else harness.depth)
    result = run_sby(harness, workdir, mode=mode, depth=run_depth, name="formal")
    names = [p.name for p in (property_at(props, loc) for loc in result.failed) if p]
    return result, names


def test_aligner_finds_every_slip_and_keeps_the_sent_words(tmp_path: Path) -> None:
    result, failed = _prove(AlignerProperties("training"), tmp_path)
    assert result.status == "PASS", failed


def test_aligner_reaches_alignment_at_every_slip(tmp_path: Path) -> None:
    result, unreached = _prove(AlignerProperties("training"), tmp_path, mode="cover")
    assert result.status == "PASS", unreached


def test_aligner_never_aligns_without_train(tmp_path: Path) -> None:
    result, failed = _prove(AlignerProperties("no_train"), tmp_path)
    assert result.status == "PASS", failed


@pytest.mark.parametrize("pairs", [2, pytest.param(3, marks=pytest.mark.slow)])
def test_deskew_lines_up_every_lane_on_one_transmit_cycle(tmp_path: Path,
                                                          pairs: int) -> None:
    result, failed = _prove(DeskewProperties(pairs), tmp_path)
    assert result.status == "PASS", failed


def test_deskew_covers_full_skew_and_retry(tmp_path: Path) -> None:
    result, unreached = _prove(DeskewProperties(3), tmp_path, mode="cover")
    assert result.status == "PASS", unreached


class _OffByOneWord(WordAligner):
    """The aligner with a bug: it searches on the window at ``slip`` but registers the
    word one bit further on (an off-by-one slip between search and output)."""

    def elaborate(self, platform: object) -> Module:
        m = Module()
        hist = Signal(4 * GEAR_BITS)
        good = Signal(range(GOOD_WORDS))
        m.d.sync += hist.eq(Cat(hist[GEAR_BITS:], self.gear))
        m.d.comb += self.window.eq(hist.bit_select(self.slip, WORD_BITS))
        with m.If(self.strobe):
            m.d.sync += self.word.eq(hist.bit_select(self.slip + 1, WORD_BITS))
        with m.If(self.strobe & self.search & ~self.aligned):
            with m.If(self.window == TRAIN):
                m.d.sync += good.eq(good + 1)
                with m.If(good == GOOD_WORDS - 1):
                    m.d.sync += self.aligned.eq(1)
            with m.Elif(self.window != MARK):
                m.d.sync += [good.eq(0), self.slip.eq(self.slip + 1)]
        return m


def test_an_off_by_one_aligner_gives_a_counterexample(tmp_path: Path) -> None:
    result, failed = _prove(AlignerProperties("training", aligner=_OffByOneWord), tmp_path)
    assert result.status == "FAIL"
    assert failed == ["align.word"]
    assert result.trace is not None and result.trace.is_file()


# the clock crossing: property-based, in simulation --------------------------------

FMT = LinkFormat(8)  # one data pair and the framing lane
BEATS = 24


async def _stalling_sink(ctx, dut, stalls: list[bool], out: list[int],  # noqa: ANN001
                         cycles: int) -> None:
    for cyc in range(cycles + 2 * FIFO_DEPTH):  # then drain, never stalling
        ready = cyc >= cycles or not stalls[cyc % len(stalls)]
        ctx.set(dut.beats.ready, ready)
        if ctx.get(dut.beats.valid) and ready:  # taken at this edge
            out.append(ctx.get(dut.beats.payload.as_value()))
        await ctx.tick()
    out.append(-1 - ctx.get(dut.status.overflow))  # the flag, after the last beat


def _receive(core_period: float, phase: float, stalls: list[bool]) -> tuple[list[int], int]:
    """Beats a :class:`LinkReceiver` hands over (sink stalling on ``stalls``, cyclic)
    and its overflow flag; beats numbered 0.. in their payload so that loss,
    duplication and order show."""
    from amaranth.sim import Simulator

    from rvsm.rtl.board.receiver import LinkReceiver

    payload = np.array([[(k >> b) & 1 for b in range(8)] for k in range(BEATS)], np.uint8)
    flags = np.zeros(BEATS, bool)
    words = np.concatenate([training_words(FMT, 48), beat_words(FMT, payload, flags, flags),
                            idle_words(FMT, 8)])
    bits = serialise(words)
    dut = LinkReceiver(FMT)
    sim = Simulator(dut)
    sim.add_clock(core_period, domain="sync")
    cycles = int((bits.shape[1] * 2 * HALF_BIT_S + phase + 800e-9) / core_period)
    got: list[int] = []

    async def link(ctx) -> None:  # noqa: ANN001
        await ctx.delay(200e-9 + phase)
        await drive_link(ctx, dut.clock, dut.pins, bits, HALF_BIT_S)

    async def sink(ctx) -> None:  # noqa: ANN001
        await _stalling_sink(ctx, dut, stalls, got, cycles)

    sim.add_process(link)
    sim.add_testbench(sink)
    sim.run()
    return got[:-1], -1 - got[-1]


@settings(max_examples=12, deadline=None, derandomize=True,
          phases=[Phase.explicit, Phase.generate],  # no shrinking: each run is seconds
          suppress_health_check=[HealthCheck.too_slow])
@given(core_period=st.floats(1.7e-9, 16e-9), phase=st.floats(0, 5e-9),
       stalls=st.lists(st.booleans(), min_size=1, max_size=7))
@example(core_period=16e-9, phase=0.0, stalls=[True, True, False])  # must overflow
def test_clock_crossing_loses_no_beat_unflagged(core_period: float, phase: float,
                                                stalls: list[bool]) -> None:
    got, overflow = _receive(core_period, phase, stalls)
    sent = beat_ints(np.array([[(k >> b) & 1 for b in range(8)] for k in range(BEATS)],
                              np.uint8), np.zeros(BEATS, bool), np.zeros(BEATS, bool))
    assert got == sorted(set(got)), "a beat duplicated or out of order"
    assert set(got) <= set(sent)
    assert (got != sent) == bool(overflow), (len(got), overflow)
    if (core_period, stalls) == (16e-9, [True, True, False]):
        assert overflow
