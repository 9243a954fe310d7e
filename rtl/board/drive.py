"""Drive the board links in ``amaranth.sim``: bit streams onto pins, pins into bits.

The behavioural gearing (:mod:`rvsm.rtl.board.gearing`) takes a *bit clock*: one rising
edge per bit. :func:`drive_link` toggles a link's clock and sets its pins (at the
falling edge, half a bit before the rising edge that samples them) from bit streams
``(pairs, B)`` (:func:`rvsm.rtl.board.model.serialise`), with optional pauses (the
clock stopped: a lost lock). :func:`capture_link` records a transmitter's pins at each
rising edge of its forwarded clock. Used by the tests and the front end's driver.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

__all__ = ["capture_link", "drive_link"]


async def drive_link(ctx, clock, pins, bits: np.ndarray, half_period: float,  # noqa: ANN001
                     pauses: Mapping[int, float] | None = None) -> None:
    """Send bit streams ``(pairs, B)`` on ``pins`` with a bit clock on ``clock`` of
    ``2 * half_period`` seconds a bit; ``pauses[b] = t`` stops the clock for ``t``
    seconds before bit ``b``. Leaves the clock low after the last bit."""
    b = np.asarray(bits, dtype=np.uint8)
    words = [int.from_bytes(np.packbits(b[:, k], bitorder="little").tobytes(), "little")
             for k in range(b.shape[1])]
    pauses = dict(pauses or {})
    for k, word in enumerate(words):
        if k in pauses:
            await ctx.delay(pauses[k])
        ctx.set(pins, word)
        await ctx.delay(half_period)
        ctx.set(clock, 1)
        await ctx.delay(half_period)
        ctx.set(clock, 0)


async def capture_link(ctx, clock, pins, pairs: int, out: list[int]) -> None:  # noqa: ANN001
    """Append ``pins`` (an int of ``pairs`` bits) to ``out`` at every rising edge of
    ``clock`` (a transmitter's forwarded bit clock), forever (run it as a process)."""
    async for _edge, value in ctx.posedge(clock).sample(pins):
        out.append(int(value))


def sensor_bits(fmt, codes: np.ndarray, lanes: int, adc_bits: int,  # noqa: ANN001
                extra_beats: int, training: int = 64, idle_every: int = 0) -> np.ndarray:
    """The sensor's link for codes ``(T, H, W)``: ``training`` training words, the frames'
    beats plus ``extra_beats`` zero-code beats (the array's flush), an idle word after
    every ``idle_every``-th beat (0: none) and 8 idle words; as bit streams ``(pairs, B)``."""
    from rvsm.rtl.board.model import (
        beat_words,
        idle_words,
        pixel_beats,
        serialise,
        training_words,
    )
    c = np.asarray(codes)
    payload, sof, eol = pixel_beats(c, lanes, adc_bits)
    g = c.shape[2] // lanes
    k = np.arange(len(payload), len(payload) + extra_beats) % (c.shape[1] * g)
    payload = np.concatenate([payload, np.zeros((extra_beats, payload.shape[1]), np.uint8)])
    sof, eol = np.concatenate([sof, k == 0]), np.concatenate([eol, k % g == g - 1])
    words = beat_words(fmt, payload, sof, eol)
    if idle_every:
        parts = [words[i:i + idle_every] for i in range(0, len(words), idle_every)]
        words = np.concatenate([np.concatenate([p, idle_words(fmt, 1)]) for p in parts])
    return serialise(np.concatenate([training_words(fmt, training), words,
                                     idle_words(fmt, 8)]))


#: Half a bit period of the simulated links (s): 1.2 ns a bit, 833 Mbit/s.
HALF_BIT_S = 0.6e-9


def simulate_receiver(fmt, bits: np.ndarray, core_period: float,  # noqa: ANN001
                      pauses: Mapping[int, float] | None = None, train_at: float | None = None,
                      ) -> dict:
    """Run a :class:`~rvsm.rtl.board.receiver.LinkReceiver` on bit streams ``(pairs, B)``
    (behavioural gearing, the sink always ready) with a core clock of ``core_period``
    seconds; ``pauses`` stop the link clock (:func:`drive_link`); ``train_at`` raises
    ``control.train`` for 40 core cycles at that time (s). Returns ``beats`` (ints:
    payload, then ``sof`` and ``eol`` above it), ``locked`` (its value after every core
    cycle), the final ``lane_errors``, ``lock_losses`` and ``overflow``."""
    from amaranth.sim import Simulator

    from rvsm.rtl.board.receiver import LinkReceiver

    dut = LinkReceiver(fmt)
    out: dict = {"beats": [], "locked": []}
    sim = Simulator(dut)
    sim.add_clock(core_period, domain="sync")
    stop = bits.shape[1] * 2 * HALF_BIT_S + sum((pauses or {}).values()) + 800e-9
    cycles = int(stop / core_period)
    train_cycle = -10**9 if train_at is None else int(train_at / core_period)

    async def link(ctx) -> None:  # noqa: ANN001
        await ctx.delay(200e-9)
        await drive_link(ctx, dut.clock, dut.pins, bits, HALF_BIT_S, pauses)

    async def bench(ctx) -> None:  # noqa: ANN001
        ctx.set(dut.beats.ready, 1)
        for cyc in range(cycles):
            ctx.set(dut.control.train, train_cycle <= cyc < train_cycle + 40)
            await ctx.tick()
            if ctx.get(dut.beats.valid):
                out["beats"].append(ctx.get(dut.beats.payload.as_value()))
            out["locked"].append(ctx.get(dut.status.locked))
        out["lane_errors"] = [ctx.get(dut.status.lane_errors[i]) for i in range(fmt.pairs)]
        out["lock_losses"] = ctx.get(dut.status.lock_losses)
        out["overflow"] = ctx.get(dut.status.overflow)

    sim.add_process(link)
    sim.add_testbench(bench)
    sim.run()
    return out


def beat_ints(payload: np.ndarray, sof: np.ndarray, eol: np.ndarray) -> list[int]:
    """Beats as the receiver's stream words: payload bits, then ``sof``, ``eol`` above."""
    bits = payload.shape[1]
    return [int.from_bytes(np.packbits(p, bitorder="little").tobytes(), "little")
            | int(s) << bits | int(e) << (bits + 1)
            for p, s, e in zip(payload, sof, eol, strict=True)]
