"""The streaming array's input register: :class:`InputStage`, and the pipeline's control.

An accepted beat (``codes.valid & ~clear``; ``codes.ready`` is ``~clear``) and ``clear``
pass a register before they act, so no combinational path runs from the ports into the
datapath. The registered acceptance is ``advance``, the clock enable of every later
stage: the whole pipeline steps once per accepted beat, at the edge after its
acceptance. :func:`control_signature` carries it to the stages, with ``clear`` (the
registered clear, which flushes them) and ``advance_next`` (the value ``advance`` takes
at the next edge, for memory targets that register their enables; 0 in reset).
:meth:`InputStage.model` is the numpy model.
"""

from __future__ import annotations

import numpy as np
from amaranth.hdl import Module, Mux, ResetSignal, Signal, unsigned
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from rvsm.rtl.stream.signatures import code_beat_signature

__all__ = ["InputStage", "control_signature"]


def control_signature() -> wiring.Signature:
    """The pipeline's control, driven by :class:`InputStage` (module docstring):
    ``advance``, ``advance_next``, ``clear``."""
    return wiring.Signature({"advance": Out(1), "advance_next": Out(1), "clear": Out(1)})


class InputStage(wiring.Component):
    """``codes`` In(:func:`code_beat_signature`), ``clear`` In(1) -> ``ctl``
    Out(:func:`control_signature`), ``beat`` Out(P x N bits): the accepted beat, held
    until the next is accepted (reset-less: datapath registers load without reset).

    ``mutation`` ``"stream.advance_during_stall"`` (:mod:`rvsm.rtl.mutations`): a stalled
    cycle advances the pipeline too (the last beat repeated)."""

    def __init__(self, adc_bits: int, lanes: int, mutation: str | None = None):
        self.adc_bits, self.lanes, self.mutation = adc_bits, lanes, mutation
        super().__init__({
            "codes": In(code_beat_signature(adc_bits, lanes)),
            "clear": In(1),
            "ctl": Out(control_signature()),
            "beat": Out(unsigned(adc_bits * lanes)),
        })

    def elaborate(self, platform: object) -> Module:
        m = Module()
        m.d.comb += self.codes.ready.eq(~self.clear)
        taken = self.codes.valid & ~self.clear
        if self.mutation == "stream.advance_during_stall":
            taken = ~self.clear  # a stalled cycle repeats the last beat
        m.d.sync += [self.ctl.advance.eq(taken), self.ctl.clear.eq(self.clear)]
        m.d.comb += self.ctl.advance_next.eq(Mux(ResetSignal(), 0, taken))
        beat = Signal.like(self.beat, name="codes_r", reset_less=True)  # datapath
        with m.If(self.codes.valid & ~self.clear):
            m.d.sync += beat.eq(self.codes.payload.as_value())
        m.d.comb += self.beat.eq(beat)
        return m

    @staticmethod
    def model(valid: np.ndarray, clear: np.ndarray) -> dict[str, np.ndarray]:
        """Per cycle (after the edge ending it; the stage reset before cycle 0) for
        ``valid``, ``clear`` ``(T,) bool``: ``advance``, ``clear`` and ``loaded`` (the
        beat register took that cycle's payload), ``(T,) bool`` each."""
        valid, clear = np.asarray(valid, dtype=bool), np.asarray(clear, dtype=bool)
        taken = valid & ~clear
        return {"advance": taken, "clear": clear.copy(), "loaded": taken}
