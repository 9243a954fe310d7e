"""The cycle-level model of :class:`~rvsm.rtl.ip.wrapper.RvsmAxisIp`'s streams.

Given the input-valid pattern (the source offers its next beat in cycle ``c`` when
``valid[c]``), the output-ready pattern (``ready[c]``), the policy and the FIFO depth,
:func:`run_stream_model` gives, cycle by cycle, what the IP does from a quiet start
(FIFO empty, nothing in flight, no clear since the stream's first beat): the cycle each
input beat is accepted, the output beats delivered (by position, the twin's beat index)
with the cycle of their ``m_axis`` handshake, and the positions dropped. The
twin's spikes of each position come from :meth:`ArrayContract.run` through
:class:`~rvsm.rtl.stream.schedule.StreamSchedule`; the model only says which beats
arrive and when, so its invariants are simple: delivered positions are increasing and
disjoint from the dropped ones, delivered + dropped = released, and under the stall
policy nothing is dropped.

The rules it states (module docstring of :mod:`rvsm.rtl.ip.wrapper`): input beat ``k``
accepted at the edge ending cycle ``c`` releases position ``k - lag`` (if ``k >= lag``),
which reaches the FIFO in cycle ``c + in_flight`` (``RvsmAxisIp.IN_FLIGHT`` registers:
the IP's input register, the array's input and output registers); ``tready = drop or
credit`` with the registered ``credit`` of the cycle before, ``level + (beats in those
registers) + 1 < fifo_depth``; the FIFO
is Amaranth's ``SyncFIFOBuffered`` (``depth - 1`` words of
memory and an output register; ``w_rdy`` = memory not full; ``m_axis_tvalid`` = the
output register is full).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rvsm.rtl.ip.wrapper import RvsmAxisIp

__all__ = ["StreamOutcome", "pause_pattern", "run_stream_model"]


@dataclass(frozen=True)
class StreamOutcome:
    """What the IP does with a stream: ``accepted[k]`` the cycle input beat ``k`` was
    accepted in; ``delivered`` positions in output order and ``sent`` the cycle of each
    one's handshake; ``dropped`` positions; ``cycles`` until the last output left."""

    accepted: np.ndarray
    delivered: np.ndarray
    sent: np.ndarray
    dropped: np.ndarray
    cycles: int


def pause_pattern(cycles: int, busy: float, seed: int) -> np.ndarray:
    """``cycles`` booleans, each ``False`` (a pause) with probability ``busy``."""
    return np.random.default_rng(seed).random(cycles) >= busy


def run_stream_model(beats: int, lag: int, fifo_depth: int, drop: bool,
                     valid: Sequence[bool], ready: Sequence[bool],
                     max_cycles: int = 1 << 22,
                     in_flight: int = RvsmAxisIp.IN_FLIGHT) -> StreamOutcome:
    """Stream ``beats`` input beats (any flush beats included) through the IP.

    ``valid``/``ready`` give the source's and the sink's pattern per cycle (beyond
    their end: always valid, always ready); ``in_flight``: the registers from the input
    gate to the FIFO (``RvsmAxisIp.IN_FLIGHT``, the default). Runs until every input
    beat is accepted and every released output has been delivered or dropped.
    """
    def at(pattern: Sequence[bool], c: int) -> bool:
        return bool(pattern[c]) if c < len(pattern) else True

    inner: deque[int] = deque()  # the FIFO's memory (positions)
    out_reg: int | None = None  # the FIFO's output register
    # the registers from the gate to the FIFO, newest first: a beat's position (-1: it
    # releases none) or None; the last one is the array's output (v), valid beats only
    flight: list[int | None] = [None] * in_flight
    k = 0
    accepted, delivered, sent, dropped = [], [], [], []
    released = max(0, beats - lag)
    c = 0
    credit = True  # the registered credit: room for every beat in flight, with margin
    while k < beats or any(b is not None for b in flight) or inner or out_reg is not None:
        if c >= max_cycles:
            raise RuntimeError(f"the stream did not finish within {max_cycles} cycles")
        level = len(inner) + (out_reg is not None)
        tready = drop or credit
        credit = level + sum(b is not None for b in flight) + 1 < fifo_depth
        fire = k < beats and at(valid, c) and tready
        r_en = at(ready, c)
        w_rdy = len(inner) != fifo_depth - 1
        if out_reg is not None and r_en:
            delivered.append(out_reg)
            sent.append(c)
            out_reg = None
        # the edge: the FIFO's output register takes the memory's head when it is empty
        # or read in this cycle (using the memory's level before this cycle's write)
        take = bool(inner) and out_reg is None
        v = flight[-1]
        if v is not None:
            if w_rdy:
                inner.append(v)
            else:
                dropped.append(v)
        if take:
            out_reg = inner.popleft()
        new = None
        if fire:
            accepted.append(c)
            new = k - lag if k >= lag else -1
            k += 1
        flight = [new, *flight[:-1]]
        if flight[-1] is not None and flight[-1] < 0:
            flight[-1] = None  # a beat that releases no position: no output
        c += 1
    if len(delivered) + len(dropped) != released:
        raise AssertionError("model lost a beat")
    return StreamOutcome(np.asarray(accepted), np.asarray(delivered, dtype=np.int64),
                         np.asarray(sent), np.asarray(dropped, dtype=np.int64), c)
