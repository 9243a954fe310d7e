"""The IP's input gate: :class:`InputGate`, credits or drops, flush beats, clears, and the
input register in front of the array.

``s_axis_tready = ~busy & (drop | credit_r)`` (``busy = init | flushing | clearing``).
Under the stall policy (``drop`` low) the credit is registered:
``credit_r <= level + r1 + r2 + v + 1 < fifo_depth`` (``level`` the FIFO's beats, ``r1``
and ``r2`` the beats in the IP's and the array's input registers, ``v`` the array's
output this cycle, ``+ 1`` the beat accepted meanwhile), so every beat in flight finds
room in the FIFO and no path runs from the FIFO's level to ``tready``.

``flush`` (a one-cycle request) inserts ``lag`` zero beats, one per cycle with credit;
``clear`` (a request) lets one clear through once no flush is pending, so
``flush | clear`` drains, then restarts. Neither acts while ``init``. What the gate lets
through (an accepted beat, a flush beat, a clear) passes one register (``codes``,
``clear``), so no path runs from the gate's control state into the array.
:meth:`InputGate.model` is the cycle model.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from amaranth.hdl import Cat, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from rvsm.rtl.ip.axis import AxiStreamSignature, video_lane_bits
from rvsm.rtl.stream.signatures import code_beat_signature

__all__ = ["InputGate", "gate_control_signature"]


def gate_control_signature() -> wiring.Signature:
    """What drives the gate (the controller's view, every member ``Out``): ``init``
    (thresholds being set: closed), ``drop`` (the policy), one-cycle ``flush`` and
    ``clear`` requests."""
    return wiring.Signature({"init": Out(1), "drop": Out(1), "flush": Out(1),
                             "clear": Out(1)})


class InputGate(wiring.Component):
    """``s_axis`` In(:class:`AxiStreamSignature`; ``tdata``, ``tvalid``, ``tready``), ``ctl``
    In(:func:`gate_control_signature`), ``fifo_level`` In (beats) and ``out_valid`` In
    (the array's output this cycle) -> ``codes`` Out(:func:`code_beat_signature`, the
    input register; its ``ready`` is not used: the array takes every beat) and ``clear``
    Out (registered clear, to the array); ``busy``, ``flushing``, ``accepted`` (an
    ``s_axis`` handshake this cycle) and ``restart`` (a clear let through this cycle).

    ``flush_req``, ``clear_req``: the pending requests (registers, for benches)."""

    #: Registers a beat passes in the gate: the IP's input register (cycles).
    REGISTERS = 1

    def __init__(self, adc_bits: int, lanes: int, lag: int, fifo_depth: int):
        self.adc_bits, self.lanes, self.lag, self.fifo_depth = adc_bits, lanes, lag, fifo_depth
        self.flush_req = Signal(name="flush_req")
        self.clear_req = Signal(name="clear_req")
        super().__init__({
            "s_axis": In(AxiStreamSignature(lanes * video_lane_bits(adc_bits))),
            "ctl": In(gate_control_signature()),
            "fifo_level": In(range(fifo_depth + 1)),
            "out_valid": In(1),
            "codes": Out(code_beat_signature(adc_bits, lanes)),
            "clear": Out(1),
            "busy": Out(1), "flushing": Out(1), "accepted": Out(1), "restart": Out(1),
        })

    def elaborate(self, platform: object) -> Module:
        m = Module()
        ctl, s_in, n = self.ctl, self.s_axis, self.adc_bits
        flush_req, clear_req = self.flush_req, self.clear_req
        flush_left = Signal(range(self.lag + 1), name="flush_left")
        busy = ctl.init | flush_req | clear_req
        r1 = Signal(name="accepted_r1")  # the beat in the IP's input register
        r2 = Signal(name="accepted_r2")  # the beat in the array's input register
        # room next cycle for every beat then in flight: registered (timing), with one
        # more beat of margin for the beat this cycle may accept
        credit_r = Signal(init=1, name="credit_r")
        m.d.sync += credit_r.eq(self.fifo_level + r1 + r2 + self.out_valid + 1
                                < self.fifo_depth)
        credit = ctl.drop | credit_r
        m.d.comb += s_in.tready.eq(~busy & credit)
        fire = s_in.tvalid & s_in.tready
        inject = ~ctl.init & flush_req & credit
        clear_now = ~ctl.init & ~flush_req & clear_req
        lane_bits = video_lane_bits(n)
        codes = Cat(*(s_in.tdata[i * lane_bits:i * lane_bits + n] for i in range(self.lanes)))
        # the input register: r1 is its valid bit
        in_codes = Signal(len(codes), name="in_codes_r", reset_less=True)
        in_clear = Signal(name="in_clear_r")
        m.d.sync += [r1.eq(fire | inject), r2.eq(r1), in_clear.eq(clear_now),
                     in_codes.eq(Mux(inject, 0, codes))]
        m.d.comb += [self.codes.valid.eq(r1), self.codes.payload.as_value().eq(in_codes),
                     self.clear.eq(in_clear), self.busy.eq(busy),
                     self.flushing.eq(flush_req), self.accepted.eq(fire),
                     self.restart.eq(clear_now)]
        # flush and clear requests (one-cycle pulses)
        with m.If(ctl.flush & ~flush_req):
            m.d.sync += [flush_req.eq(1), flush_left.eq(self.lag)]
        with m.If(inject):
            m.d.sync += flush_left.eq(flush_left - 1)
            with m.If(flush_left == 1):
                m.d.sync += flush_req.eq(0)
        with m.If(ctl.clear):
            m.d.sync += clear_req.eq(1)
        with m.If(clear_now):
            m.d.sync += clear_req.eq(0)
        return m

    def model(self, inputs: Mapping[str, Sequence[int]]) -> dict[str, list[int]]:
        """Per cycle, from reset, for ``inputs`` (per cycle: ``tvalid``, ``tdata``,
        ``init``, ``drop``, ``flush``, ``clear``, ``fifo_level``, ``out_valid``): the
        outputs sampled before the cycle's edge, ``tready``, ``busy``, ``flushing``,
        ``accepted``, ``restart``, ``codes_valid``, ``codes`` (the lanes' codes packed,
        lane ``i`` at ``[i*N +: N]``; 0 for a flush beat) and ``clear``."""
        n, lane_bits = self.adc_bits, video_lane_bits(self.adc_bits)
        mask = (1 << n) - 1
        flush_req = clear_req = r1 = r2 = in_clear = in_codes = flush_left = 0
        credit_r = 1
        out: dict[str, list[int]] = {k: [] for k in (
            "tready", "busy", "flushing", "accepted", "restart", "codes_valid", "codes",
            "clear")}
        for c in range(len(inputs["tvalid"])):
            x = {k: int(v[c]) for k, v in inputs.items()}
            busy = x["init"] | flush_req | clear_req
            credit = x["drop"] | credit_r
            tready = int(not busy and credit)
            fire = x["tvalid"] & tready
            inject = int(not x["init"] and flush_req and credit)
            clear_now = int(not x["init"] and not flush_req and clear_req)
            for k, v in (("tready", tready), ("busy", busy), ("flushing", flush_req),
                         ("accepted", fire), ("restart", clear_now), ("codes_valid", r1),
                         ("codes", in_codes), ("clear", in_clear)):
                out[k].append(v)
            codes = sum(((x["tdata"] >> (i * lane_bits)) & mask) << (i * n)
                        for i in range(self.lanes))
            credit_r = int(x["fifo_level"] + r1 + r2 + x["out_valid"] + 1 < self.fifo_depth)
            r1, r2, in_clear = fire | inject, r1, clear_now
            in_codes = 0 if inject else codes
            new_flush, new_left = flush_req, flush_left
            if x["flush"] and not flush_req:
                new_flush, new_left = 1, self.lag
            if inject:
                new_left = flush_left - 1
                if flush_left == 1:
                    new_flush = 0
            flush_req, flush_left = new_flush, new_left
            clear_req = 0 if clear_now else (1 if x["clear"] else clear_req)
        return out
