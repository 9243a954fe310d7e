"""Timing diagrams of the streaming array's native interface, recorded from ``amaranth.sim``.

Each :data:`SCENARIOS` entry drives a small :class:`RvsmStreamArray` (``dog1``, 3x4,
``P = 2``, 6 beats a frame: small enough to read; each foot note gives its ``lag``) cycle
by cycle and records its ports in a :class:`~rvsm.rtl.wavejson.CycleTable`, so every
diagram in ``docs/integration.md`` is what the RTL did, not a drawing. Recording also
checks the documented rules: output position ``p`` is presented in the second period
after input beat ``p + lag`` is accepted, in raster order, with ``last`` on a frame's
last position, and every output released before a ``clear`` comes out (the rest of
that stream never does).

Labels: ``codes.payload`` shows ``b<k>`` for input beat ``k`` (counted from the last
clear; ``f`` marks a flush beat, any codes), ``spikes.payload`` ``p<k> (<row>,<group>)``
for output position ``k``; ``thr.addr`` ``s<scale> w<word>``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.weights import model_contract
from rvsm.rtl.amaranth_sim import run_simulation
from rvsm.rtl.stream.array import RvsmStreamArray
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.drive import threshold_writes
from rvsm.rtl.stream.signatures import threshold_word_bits
from rvsm.rtl.wavejson import CycleTable

__all__ = ["SCENARIOS", "Cycle", "diagram_contract", "record_scenario", "scenario_wavejson"]

#: Lanes of the diagrams' array.
DIAGRAM_LANES = 2


def diagram_contract() -> ArrayContract:
    """The diagrams' contract: ``dog1`` 3x4, 4-bit codes, 10-bit accumulators."""
    return model_contract("dog1", 3, 4)


@dataclass(frozen=True)
class Cycle:
    """The inputs of one period: ``beat`` offered on ``codes`` (``None``: ``valid``
    low; ``"f"``: a flush beat), ``clear``, and a threshold write ``(scale, word)``."""

    beat: int | str | None = None
    clear: bool = False
    write: tuple[int, int] | None = None


def _stream(beats: int, stall_after: int = -1, stall: int = 0) -> list[Cycle]:
    out: list[Cycle] = []
    for k in range(beats):
        out.append(Cycle(beat=k))
        if k == stall_after:
            out += [Cycle()] * stall
    return out


def _flush(n: int) -> list[Cycle]:
    return [Cycle(beat="f")] * n


@dataclass(frozen=True)
class Scenario:
    """A diagram: its title, cycles (from the geometry), window and foot note (``{lag}``
    and ``{pause}``, the beats before a frame-1 threshold write, filled in)."""

    title: str
    cycles: Callable[[int, int, int], list[Cycle]]  # (lag, threshold_lag, beats/frame)
    foot: str
    start: int = 0


def _input_and_lag(lag: int, _thr_lag: int, _n: int) -> list[Cycle]:
    return _stream(lag + 4, stall_after=2, stall=2) + [Cycle()] * 3


def _flush_and_clear(lag: int, _thr_lag: int, n: int) -> list[Cycle]:
    return (_stream(n) + _flush(lag) + [Cycle(), Cycle(clear=True)]
            + _stream(3) + [Cycle()])


def _clear_mid_frame(lag: int, _thr_lag: int, n: int) -> list[Cycle]:
    return (_stream(lag + 3) + [Cycle(beat="c", clear=True), Cycle(beat="c", clear=True)]
            + _stream(lag + 2) + [Cycle()])


def _threshold_write(lag: int, thr_lag: int, n: int) -> list[Cycle]:
    pause = n + thr_lag  # thresholds written here apply from frame 1 on
    writes = [Cycle(write=(0, w)) for w in range(n)]
    return _stream(pause) + writes + [Cycle(beat=pause + k) for k in range(4)] + [Cycle()]


SCENARIOS: dict[str, Scenario] = {
    "stream-input": Scenario(
        "input beats, a stall, and the lag", _input_and_lag,
        "output p is presented in the 2nd period after input beat p + lag is accepted "
        "(lag = {lag} here); a stall holds everything in flight"),
    "stream-flush-clear": Scenario(
        "end of a stream: lag flush beats, then clear", _flush_and_clear,
        "the frame's last positions come out only as lag flush beats (any codes) go in; "
        "clear restarts at b0 = frame 0, row 0, group 0", start=4),
    "stream-clear-mid-frame": Scenario(
        "clear in mid-frame", _clear_mid_frame,
        "ready is low while clear is high (the offered beat c is refused); outputs "
        "released before the clear still come out, the rest are dropped; the next beat "
        "is b0 again", start=6),
    "stream-threshold-write": Scenario(
        "threshold writes at a frame boundary", _threshold_write,
        "paused after H*G + threshold_lag = {pause} beats, the writes apply from frame 1 on "
        "(StreamSchedule.threshold_pause_beat)", start=6),
}


def record_scenario(name: str, mutation: str | None = None) -> CycleTable:
    """Drive scenario ``name`` in ``amaranth.sim`` and record its ports, checking the
    documented output schedule (``AssertionError`` naming the period if the RTL breaks
    it; ``mutation`` builds a deliberately broken array, :mod:`rvsm.rtl.mutations`)."""
    scenario = SCENARIOS[name]
    contract = diagram_contract()
    dut = RvsmStreamArray(contract, DIAGRAM_LANES, mutation=mutation)
    geo = dut.geometry
    lag, n = geo.lag, geo.schedule.beats_per_frame
    cycles = scenario.cycles(lag, geo.threshold_lag, n)
    thresholds = np.full((contract.num_scales, contract.height, contract.width), 5)
    loads = threshold_writes(geo, thresholds)
    word_bits = threshold_word_bits(n)
    layout = geo.spike_layout
    table = CycleTable()
    streams: list[_Stream] = [_Stream(0)]

    async def bench(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        for addr, word in loads:
            ctx.set(dut.thr.we, 1)
            ctx.set(dut.thr.addr, addr)
            ctx.set(dut.thr.data, word)
            await ctx.tick()
        ctx.set(dut.thr.we, 0)
        ctx.set(dut.clear, 1)
        await ctx.tick()
        ctx.set(dut.clear, 0)
        for period, cyc in enumerate(cycles):
            if cyc.clear and period and not cycles[period - 1].clear:
                streams.append(_Stream(period))
            ctx.set(dut.codes.valid, cyc.beat is not None)
            ctx.set(dut.codes.payload.as_value(), period % 13)
            ctx.set(dut.clear, cyc.clear)
            s, w = cyc.write or (0, 0)
            ctx.set(dut.thr.we, cyc.write is not None)
            ctx.set(dut.thr.addr, (s << word_bits) | w)
            ctx.set(dut.thr.data, loads[w][1])
            valid, ready = ctx.get(dut.codes.valid), ctx.get(dut.codes.ready)
            out_valid = ctx.get(dut.spikes.valid)
            word = ctx.get(dut.spikes.payload.as_value())
            row, group, last = ((word >> layout[k].offset) & ((1 << layout[k].width) - 1)
                                for k in ("row", "group", "last"))
            out_label = None
            if out_valid:  # released by the beat accepted two periods ago
                stream = next(x for x in reversed(streams) if x.start <= period - 2)
                k = len(stream.presented)
                stream.presented.append(period)
                stream.check(name, k, period, row, group, last, lag, n, geo.groups)
                out_label = f"p{k} ({row},{group})"
            if valid and ready and not cyc.clear:
                streams[-1].accepted.append(period)
            label = None
            if cyc.beat is not None:
                label = cyc.beat if isinstance(cyc.beat, str) else f"b{cyc.beat}"
            table.record({
                "codes.valid": valid, "codes.ready": ready, "codes.payload": label,
                "clear": cyc.clear,
                "thr.we": cyc.write is not None,
                "thr.addr": f"s{s} w{w}" if cyc.write is not None else None,
                "spikes.valid": out_valid, "spikes.payload": out_label,
                "spikes.last": bool(out_valid and last),
            })
            await ctx.tick()

    run_simulation(dut, bench)
    for stream in streams:  # everything released before a clear came out
        released = max(0, len(stream.accepted) - lag)
        if len(stream.presented) < released and stream is not streams[-1]:
            raise AssertionError(f"{name}: {released} outputs released in the stream "
                                 f"from period {stream.start}, "
                                 f"{len(stream.presented)} presented")
    return table


@dataclass
class _Stream:
    """One stream between clears: its first period, the periods of its accepted beats
    and of its presented outputs."""

    start: int
    accepted: list[int] = field(default_factory=list)
    presented: list[int] = field(default_factory=list)

    def check(self, name: str, k: int, period: int, row: int, group: int, last: int,
              lag: int, beats_per_frame: int, groups: int) -> None:
        """Output ``k`` of this stream, presented in ``period``, is where the documented
        schedule puts it (``AssertionError`` otherwise)."""
        release = k + lag
        expect = self.accepted[release] + 2 if release < len(self.accepted) else None
        pos = k % beats_per_frame
        want = (expect, pos // groups, pos % groups, int(pos == beats_per_frame - 1))
        if (period, row, group, last) != want:
            raise AssertionError(
                f"{name}: output {k} presented in period {period} at row {row} group "
                f"{group} last {last}; the schedule says period {want[0]}, row "
                f"{want[1]}, group {want[2]}, last {want[3]}")


def scenario_wavejson(name: str) -> dict:
    """The WaveJSON diagram of scenario ``name`` (recorded and checked)."""
    scenario = SCENARIOS[name]
    table = record_scenario(name)
    groups = {"in": ("codes.valid", "codes.ready", "codes.payload", "clear")}
    if any(table.columns["thr.we"]):
        groups["thr"] = ("thr.we", "thr.addr")
    groups["out"] = ("spikes.valid", "spikes.payload", "spikes.last")
    geo = StreamGeometry(diagram_contract(), DIAGRAM_LANES)
    foot = scenario.foot.format(lag=geo.lag,
                                pause=geo.schedule.threshold_pause_beat(1))
    diagram = table.wavejson(f"{name}: {scenario.title}", start=scenario.start,
                             foot=foot, groups=groups)
    diagram["config"] = {"hscale": 2}
    return diagram
