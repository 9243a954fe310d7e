"""Event counters: :class:`EventCounters`, one wrapping counter per named event.

Counter ``k`` adds 1 at each rising edge with ``events[k]`` high and returns to 0 at an
edge with ``reset`` high (the reset wins), modulo ``2**width``. The IP counts its input
handshakes, output handshakes and dropped beats (``IN_BEATS``, ``OUT_BEATS``,
``DROPPED``; ``CONTROL.counters_reset``); a board front end can count its own events
the same way. :meth:`EventCounters.model` is the model.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from amaranth.hdl import Module, Value, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

__all__ = ["EventCounters"]


class EventCounters(wiring.Component):
    """``events`` In(one bit per name, in ``names`` order), ``reset`` In ->
    ``counts`` Out(an array of ``width``-bit counts); :meth:`count` by name."""

    def __init__(self, names: Sequence[str], width: int = 32):
        self.names, self.width = tuple(names), width
        super().__init__({"events": In(len(self.names)), "reset": In(1),
                          "counts": Out(data.ArrayLayout(unsigned(width), len(self.names)))})

    def count(self, name: str) -> Value:
        """The count of event ``name``."""
        return self.counts[self.names.index(name)]

    def elaborate(self, platform: object) -> Module:
        m = Module()
        for k in range(len(self.names)):
            count = self.counts[k]
            with m.If(self.reset):
                m.d.sync += count.eq(0)
            with m.Elif(self.events[k]):
                m.d.sync += count.eq(count + 1)
        return m

    def model(self, events: np.ndarray, reset: np.ndarray) -> np.ndarray:
        """Counts ``(T, len(names))`` before each cycle's edge, from reset, for
        ``events (T, len(names))`` and ``reset (T,)`` booleans."""
        events, reset = np.asarray(events, dtype=bool), np.asarray(reset, dtype=bool)
        counts = np.zeros((len(events), len(self.names)), dtype=np.int64)
        now = np.zeros(len(self.names), dtype=np.int64)
        for c in range(len(events)):
            counts[c] = now
            now = np.where(reset[c], 0, (now + events[c]) % (1 << self.width))
        return counts
