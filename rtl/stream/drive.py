"""Drive the streaming array in ``amaranth.sim``: threshold loads, beats, output capture.

:func:`threshold_writes` (address and data of every threshold word),
:class:`BeatCollector` (records each presented output beat and the input beat that
released it) and :func:`simulate` (a whole run: thresholds, segments between clears,
flush, optional pauses and threshold updates) are shared by the ``amaranth.sim`` tests
and anything else that drives :class:`~rvsm.rtl.stream.array.RvsmStreamArray`. Compare
the beats with :func:`~rvsm.rtl.stream.schedule.check_beats`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.rtl.amaranth_sim import run_simulation
from rvsm.rtl.stream.array import RvsmStreamArray
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.protocol_script import ProtocolScript
from rvsm.rtl.stream.schedule import OutputBeats, pack_lanes

__all__ = ["BeatCollector", "colliding_threshold_writes", "simulate", "simulate_script",
           "simulate_with_threshold_writes", "threshold_writes", "write_thresholds"]

#: Payload fields of an output beat, in :meth:`OutputBeats.from_words` order.
FIELDS = ("row", "group", "last", "pos", "neg")


def threshold_writes(geometry: StreamGeometry, thresholds: np.ndarray
                     ) -> list[tuple[int, int]]:
    """``(addr, data)`` of every threshold write for thresholds ``(S, H, W)``
    (:meth:`StreamGeometry.threshold_writes`: scale by scale, word ``y*G + g`` in order,
    ``addr = (s << word_bits) | word``; shared thresholds: ``(s, threshold)``)."""
    return geometry.threshold_writes(thresholds)


async def write_thresholds(ctx, dut: RvsmStreamArray,  # noqa: ANN001 - SimulatorContext
                           thresholds: np.ndarray) -> None:
    """Write every threshold word through ``dut.thr``, one per clock; ``we`` low after."""
    for addr, word in threshold_writes(dut.geometry, thresholds):
        ctx.set(dut.thr.we, 1)
        ctx.set(dut.thr.addr, addr)
        ctx.set(dut.thr.data, word)
        await ctx.tick()
    ctx.set(dut.thr.we, 0)


class BeatCollector:
    """Records the output beats of ``dut``: call :meth:`after_edge` after every clock
    edge with the index of the input beat accepted at it (-1: none)."""

    def __init__(self, dut: RvsmStreamArray):
        self.dut = dut
        layout = dut.geometry.spike_layout
        self.fields = {name: (layout[name].offset, layout[name].width) for name in FIELDS}
        self.got: dict[str, list[int]] = {k: [] for k in (*FIELDS, "accepted")}
        self._accepted = [-1, -1]  # beats accepted at the previous and the latest edge

    def after_edge(self, ctx, beat: int) -> None:  # noqa: ANN001 - SimulatorContext
        """Record the output presented after an edge that accepted ``beat``."""
        self._accepted[:] = [self._accepted[1], beat]
        if ctx.get(self.dut.spikes.valid):
            word = ctx.get(self.dut.spikes.payload.as_value())
            for k, (off, width) in self.fields.items():
                self.got[k].append((word >> off) & ((1 << width) - 1))
            self.got["accepted"].append(self._accepted[0])

    def beats(self) -> OutputBeats:
        """The beats recorded so far; ``accepted`` the input beat that released each."""
        c, geo = self.dut.contract, self.dut.geometry
        return OutputBeats.from_words(*(self.got[k] for k in FIELDS), c.num_scales,
                                      geo.lanes, self.got["accepted"])


def simulate(
    contract: ArrayContract,
    codes: np.ndarray,
    thresholds: np.ndarray,
    lanes: int = 1,
    clear_before: Sequence[int] = (),
    threshold_updates: Mapping[int, np.ndarray] | None = None,
    idle_every: int = 0,
    bank_words: int = StreamGeometry.BANK_WORDS,
    vcd_path: str | None = None,
    mutation: str | None = None,
) -> OutputBeats:
    """Run :class:`RvsmStreamArray` in ``amaranth.sim``; return every output beat.

    Thresholds ``(S, H, W)`` are written through ``thr``; each segment between
    ``clear_before`` steps is streamed back to back, flushed with ``lag`` beats and
    followed by a one-cycle ``clear``. ``threshold_updates`` maps a frame ``t`` (of the
    first segment) to thresholds written while the stream is paused at
    :meth:`StreamSchedule.threshold_pause_beat` ``(t)``. ``idle_every = k > 0`` drops
    ``valid`` for one cycle after every ``k``-th beat (a paused stream); ``mutation``
    builds a deliberately broken array (:mod:`rvsm.rtl.mutations`). Compare the
    result with :func:`~rvsm.rtl.stream.schedule.check_beats`; its ``accepted`` holds,
    per output beat, the index (within its segment) of the input beat accepted two
    cycles before it was presented, the beat that released it.
    """
    c = contract
    codes = np.asarray(codes, dtype=np.int64)
    dut = RvsmStreamArray(c, lanes, bank_words, mutation=mutation)
    sched = dut.schedule
    updates = dict(threshold_updates or {})
    out = BeatCollector(dut)

    async def bench(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        await write_thresholds(ctx, dut, thresholds)
        for seg, (a, b) in enumerate(sched.segments(len(codes), clear_before)):
            if seg:
                ctx.set(dut.clear, 1)
                await ctx.tick()
                out.after_edge(ctx, -1)
                ctx.set(dut.clear, 0)
            beats = pack_lanes(sched.input_beats(codes[a:b]), c.adc_bits)
            pauses = {sched.threshold_pause_beat(t): thr for t, thr in updates.items()} \
                if seg == 0 else {}
            for k, word in enumerate(beats):
                if k in pauses:
                    ctx.set(dut.codes.valid, 0)
                    await ctx.tick()
                    out.after_edge(ctx, -1)
                    await write_thresholds(ctx, dut, pauses[k])
                ctx.set(dut.codes.payload.as_value(), word)
                ctx.set(dut.codes.valid, 1)
                await ctx.tick()
                out.after_edge(ctx, k)
                if idle_every and (k + 1) % idle_every == 0:
                    ctx.set(dut.codes.valid, 0)
                    await ctx.tick()
                    out.after_edge(ctx, -1)
            ctx.set(dut.codes.valid, 0)
            for _ in range(2):
                await ctx.tick()
                out.after_edge(ctx, -1)

    run_simulation(dut, bench, vcd_path)
    return out.beats()


def simulate_with_threshold_writes(
    contract: ArrayContract, lanes: int, codes: np.ndarray, thresholds: np.ndarray,
    writes: Mapping[int, tuple[int, int, int]],
    bank_words: int = StreamGeometry.BANK_WORDS, mutation: str | None = None,
) -> OutputBeats:
    """Load ``thresholds``, stream ``codes`` back to back (then ``lag`` flush beats) and,
    at the edge accepting beat ``k``, write ``writes[k] = (s, addr, word)`` on ``thr``
    (threshold writes while the stream runs, :func:`colliding_threshold_writes`)."""
    c = contract
    dut = RvsmStreamArray(c, lanes, bank_words, mutation=mutation)
    sched = dut.schedule
    beats = pack_lanes(sched.input_beats(np.asarray(codes, dtype=np.int64)), c.adc_bits)
    out = BeatCollector(dut)

    async def bench(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        for addr, word in threshold_writes(dut.geometry, thresholds):
            ctx.set(dut.thr.we, 1)
            ctx.set(dut.thr.addr, addr)
            ctx.set(dut.thr.data, word)
            await ctx.tick()
        for k, beat in enumerate([*beats, None, None]):
            ctx.set(dut.codes.valid, beat is not None)
            ctx.set(dut.codes.payload.as_value(), beat or 0)
            s, a, w = writes.get(k, (0, 0, 0))
            ctx.set(dut.thr.we, k in writes)
            ctx.set(dut.thr.addr, dut.geometry.threshold_address(s, a))
            ctx.set(dut.thr.data, w)
            await ctx.tick()
            out.after_edge(ctx, k if beat is not None else -1)

    run_simulation(dut, bench)
    return out.beats()


def simulate_script(script: ProtocolScript, bank_words: int = StreamGeometry.BANK_WORDS,
                    mutation: str | None = None, vcd_path: str | None = None,
                    ) -> tuple[OutputBeats, list[int]]:
    """Drive a :class:`~rvsm.rtl.stream.protocol_script.ProtocolScript` cycle by cycle; return
    the output beats and the edge after which each was presented (compare both with
    :func:`~rvsm.rtl.stream.protocol.check_script`)."""
    dut = RvsmStreamArray(script.contract, script.lanes, bank_words, mutation=mutation)
    out = BeatCollector(dut)
    cycles: list[int] = []
    payload, addr, data = script.payload_words(), script.thr_addresses(), script.thr_words()

    async def bench(ctx) -> None:  # noqa: ANN001 - SimulatorContext
        for cyc in range(script.num_cycles):
            ctx.set(dut.codes.valid, bool(script.valid[cyc]))
            ctx.set(dut.codes.payload.as_value(), payload[cyc])
            ctx.set(dut.clear, bool(script.clear[cyc]))
            ctx.set(dut.thr.we, bool(script.thr_we[cyc]))
            ctx.set(dut.thr.addr, addr[cyc])
            ctx.set(dut.thr.data, data[cyc])
            await ctx.tick()
            before = len(out.got["row"])
            out.after_edge(ctx, -1)
            if len(out.got["row"]) > before:
                cycles.append(cyc)

    run_simulation(dut, bench, vcd_path)
    return out.beats(), cycles


def colliding_threshold_writes(
    geometry: StreamGeometry, thresholds: np.ndarray, steps: int, seed: int,
    thr_hi: int,
) -> tuple[dict[int, tuple[int, int, int]], list[np.ndarray], list[np.ndarray], int]:
    """Threshold writes while ``steps`` frames stream back to back, many at the very edge
    that reads the same word (not seen by that read) or one edge earlier (seen).

    Returns ``(writes, frames, frames_late, collisions)``: the writes for
    :func:`simulate_with_threshold_writes`, the threshold words ``(S, H*G, P)`` each frame
    reads under the documented rule, the same if a write were seen at its own edge (a
    wrong rule), and how many writes meet their own read."""
    c, schedule = geometry.contract, geometry.schedule
    lanes, hg, lag = schedule.lanes, schedule.beats_per_frame, schedule.threshold_lag
    rng = np.random.default_rng(seed)
    state = schedule.threshold_words(np.asarray(thresholds, dtype=np.int64)).copy()
    seen_late = state.copy()
    frames: list[np.ndarray] = []
    frames_late: list[np.ndarray] = []
    writes: dict[int, tuple[int, int, int]] = {}
    collisions = 0
    # back to back, position p reads at the edge accepting beat p + threshold_lag + 1
    for p in range(steps * hg):
        k = p + lag + 1
        s, lanes_thr = int(rng.integers(c.num_scales)), rng.integers(1, thr_hi, lanes)
        if geometry.shared_thresholds:  # one register per scale: one value
            lanes_thr[:] = lanes_thr[0]
        kind = rng.integers(4)  # 0: p's own word, 1: p+1's word, 2: any word, 3: none
        a = [p % hg, (p + 1) % hg, int(rng.integers(hg)), None][kind]
        if a is not None:
            writes[k] = (s, a, geometry.threshold_data(lanes_thr))
            collisions += kind == 0
        if p % hg == 0:
            frames.append(np.empty_like(state))
            frames_late.append(np.empty_like(state))
        frames[-1][:, p % hg] = state[:, p % hg]
        if a is not None:
            seen_late[s, geometry.words_written(a)] = lanes_thr
        frames_late[-1][:, p % hg] = seen_late[:, p % hg]
        if a is not None:
            state[s, geometry.words_written(a)] = lanes_thr
    return writes, frames, frames_late, collisions
