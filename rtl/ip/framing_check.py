"""The framing check of the IP's input: :class:`FramingCheck`.

An input beat's ``tuser`` (start of frame) and ``tlast`` (end of line, UG934) must
agree with its position, which the check counts itself: row ``y`` and column group
``g`` of the beat in the IP's input register, advanced by each beat that enters it
(``advance``, a user or flush beat) and zeroed by a clear let through (``restart``).
The handshake and both flags are registered first (no path from the input gate into
the counters); ``error`` is high in the cycle after a beat whose flags disagree (the
beat is still taken: the flags describe the stream, they do not steer it).
:meth:`FramingCheck.model` is the cycle model.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from amaranth.hdl import Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

__all__ = ["FramingCheck"]


class FramingCheck(wiring.Component):
    """``accepted``, ``tuser``, ``tlast`` (the ``s_axis`` handshake and its flags),
    ``advance`` (a beat in the input register), ``restart`` (a clear let through) In ->
    ``error`` Out (one cycle per beat with wrong flags), for ``height`` rows of
    ``groups`` beats."""

    def __init__(self, height: int, groups: int):
        self.height, self.groups = height, groups
        super().__init__({"accepted": In(1), "tuser": In(1), "tlast": In(1),
                          "advance": In(1), "restart": In(1), "error": Out(1)})

    def elaborate(self, platform: object) -> Module:
        m = Module()
        in_g = Signal(range(self.groups), name="in_group")
        in_y = Signal(range(self.height), name="in_row")
        fire_r = Signal(name="fire_r")
        tuser_r, tlast_r = Signal(name="tuser_r"), Signal(name="tlast_r")
        m.d.sync += [fire_r.eq(self.accepted), tuser_r.eq(self.tuser),
                     tlast_r.eq(self.tlast)]
        g_end = in_g == self.groups - 1
        with m.If(self.restart):
            m.d.sync += [in_g.eq(0), in_y.eq(0)]
        with m.Elif(self.advance):
            m.d.sync += [in_g.eq(Mux(g_end, 0, in_g + 1)),
                         in_y.eq(Mux(g_end, Mux(in_y == self.height - 1, 0, in_y + 1),
                                     in_y))]
        sof = (in_g == 0) & (in_y == 0)
        m.d.comb += self.error.eq(fire_r & ((tuser_r != sof) | (tlast_r != g_end)))
        return m

    def model(self, inputs: Mapping[str, Sequence[int]]) -> list[int]:
        """``error`` per cycle (before the cycle's edge, from reset) for ``inputs`` per
        cycle: ``accepted``, ``tuser``, ``tlast``, ``advance``, ``restart``."""
        g = y = fire_r = tuser_r = tlast_r = 0
        errors = []
        for c in range(len(inputs["accepted"])):
            x = {k: int(v[c]) for k, v in inputs.items()}
            g_end = g == self.groups - 1
            sof = g == 0 and y == 0
            errors.append(int(bool(fire_r) and (tuser_r != sof or tlast_r != g_end)))
            fire_r, tuser_r, tlast_r = x["accepted"], x["tuser"], x["tlast"]
            if x["restart"]:
                g = y = 0
            elif x["advance"]:
                y = (0 if y == self.height - 1 else y + 1) if g_end else y
                g = 0 if g_end else g + 1
        return errors
