"""The streaming array's tail: :class:`OutputStage` (add, compare, reset, output register).

At stage Q the sums, the state words and the position meet. Per scale and lane, the
sensor's output rule (:data:`OUTPUT_TAILS`, keyed by the sensor kind's output: the spike
camera's :class:`SpikeTail`, the event sensor's :class:`EventTail`) fills the same two
registered stages (``total``, ``thr1``, then ``sat``, ``thr2``, ``pos``, ``neg``) and
gives the word written back to the accumulator memory (``write_data``, at the write-back
edge) and the spikes; the output register then holds the position (``row``, ``group``,
``last``) and the ``S*P`` spikes, ``spikes.valid`` high for the cycle after the edge
that writes the position back. The accumulator reads as zero in a fresh frame (the first
after a clear; the event sensor captures its references there instead). Everything
loads on ``ctl.advance``; registers are reset-less.

Each rule's ``model`` is its numpy model (one step of one accumulator per element).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from amaranth.hdl import Cat, Const, Module, Mux, Signal, Value, signed, unsigned
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.widths import signed_range
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kinds.sensor_kind import Output
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.input_stage import control_signature
from rvsm.rtl.stream.memory_target import GENERIC_MEMORY, MemoryTarget
from rvsm.rtl.stream.position_stage import write_tap_signature
from rvsm.rtl.stream.signatures import spike_beat_signature
from rvsm.rtl.stream.state_stage import state_words_layout, write_back_layout
from rvsm.rtl.stream.sum_stage import sums_layout

__all__ = ["OUTPUT_TAILS", "EventTail", "LaneRegisters", "OutputStage", "SpikeTail",
           "output_tail"]


@dataclass(frozen=True)
class LaneRegisters:
    """The two registered stages of one lane's tail: ``total`` and ``thr1`` (stage 1),
    ``sat``, ``thr2``, ``pos`` and ``neg`` (stage 2)."""

    total: Signal
    thr1: Signal
    sat: Signal
    thr2: Signal
    pos: Signal
    neg: Signal


class SpikeTail:
    """The spike camera's rule (SPEC section 5): stage 1 ``total = acc + shifted``, the
    threshold and the threshold less one; stage 2 the saturated total, ``pos = total >=
    thr``, ``neg = total <= -thr`` (signed contracts; the register holds the compare
    alone, the output is ``neg & ~pos``: two independent carry chains) and the threshold
    kept for the reset; the word written back is what the reset mode leaves.

    ``mutation`` (:mod:`rvsm.rtl.mutations`): ``"stream.threshold_off_by_one"``,
    ``"stream.stale_threshold"``, ``"stream.no_negative_spikes"``,
    ``"stream.no_saturation"``, ``"stream.no_reset_on_spike"``,
    ``"stream.zero_instead_of_subtract"``."""

    def __init__(self, contract: ArrayContract, mutation: str | None = None):
        self.contract, self.mutation = contract, mutation

    def lane(self, acc: Value, ref: Value, fresh: Value, shifted: Value, thr: Value,
             r: LaneRegisters) -> tuple[list, Value, Value, Value]:
        """``(statements, pos, neg, after)`` of one lane: ``acc`` is the accumulator (0
        in a fresh frame), ``shifted`` the shifted sum, ``thr`` the threshold read."""
        c, mutation = self.contract, self.mutation
        wa = c.accumulator_bits
        lo, hi = signed_range(wa)
        # Both compares are the sign of one subtraction (one carry chain each, no
        # sign-extension logic after it): total >= thr is ~sign(total - thr), and
        # total <= -thr is sign(total + (thr - 1)), thr - 1 registered beside thr.
        fire_pos = ~(r.total - r.thr1)[-1]
        if mutation == "stream.threshold_off_by_one":
            fire_pos = r.total > r.thr1
        elif mutation == "stream.stale_threshold":
            fire_pos = r.total >= r.thr2  # the previous position's threshold
        thr1_m1 = Signal(signed(len(thr) + 1), name=f"{r.thr1.name}_m1", reset_less=True)
        fire_neg = (r.total + thr1_m1)[-1] if c.signed else Const(0)
        if mutation == "stream.no_negative_spikes":
            fire_neg = Const(0)
        stmts = [
            r.total.eq(acc + shifted),
            r.thr1.eq(thr),
            *([thr1_m1.eq(thr.as_unsigned() - 1)] if c.signed else []),
            r.sat.eq(r.total[:wa].as_signed()
                     if mutation == "stream.no_saturation"  # wraps around
                     else Mux(r.total > hi, hi, Mux(r.total < lo, lo, r.total))),
            r.pos.eq(fire_pos), r.neg.eq(fire_neg), r.thr2.eq(r.thr1),
        ]
        pos, neg = r.pos, r.neg & ~r.pos  # the register holds the compare alone
        if mutation == "stream.no_reset_on_spike":
            after = r.sat
        elif c.reset == "zero" or mutation == "stream.zero_instead_of_subtract":
            after = Mux(pos | neg, 0, r.sat)
        else:
            after = Mux(pos, r.sat - r.thr2, Mux(neg, r.sat + r.thr2, r.sat))
        return stmts, pos, neg, after

    def model(self, acc: np.ndarray, fresh: np.ndarray, shifted: np.ndarray,
              thr: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(pos, neg, after)`` (bool, bool, int64) for accumulators ``acc``, fresh-frame
        flags, shifted sums and thresholds (arrays of one shape)."""
        c = self.contract
        lo, hi = signed_range(c.accumulator_bits)
        total = np.where(fresh, 0, acc).astype(np.int64) + shifted
        sat = np.clip(total, lo, hi)
        pos = total >= thr
        neg = (total <= -thr) & ~pos if c.signed else np.zeros_like(pos)
        if c.reset == "zero":
            after = np.where(pos | neg, 0, sat)
        else:
            after = sat - thr * pos + thr * neg
        return pos, neg, after


class EventTail:
    """The event sensor's rule (SPEC section 7): the same registers, ``total`` holding
    ``d = shifted - ref`` and ``sat`` the new reference (written back).

    Stage 1, in parallel: ``d`` (exact), the threshold, the capture flag (a fresh frame:
    the first after a clear), ``clamp(shifted)``, ``ref + thr`` and ``ref - thr`` with
    their overflow bits (``ref`` and ``thr`` fit W bits, so a W+1-bit sum leaves the
    range exactly when its top two bits differ). Stage 2: ``up = d >= thr``, ``down = d
    <= -thr``, ``pos = ~cap & up``, ``neg = ~cap & ~up & down`` and the new reference, a
    4-way choice of stage-1 values: one compare and a multiplexer, the short path ``rvsm
    fpga`` measured (``docs/events.md``)."""

    def __init__(self, contract: ArrayContract, mutation: str | None = None):
        self.contract, self.mutation = contract, mutation

    def lane(self, acc: Value, ref: Value, fresh: Value, shifted: Value, thr: Value,
             r: LaneRegisters) -> tuple[list, Value, Value, Value]:
        """``(statements, pos, neg, after)`` of one lane: ``ref`` is the reference read,
        ``fresh`` the capture flag, ``shifted`` the shifted sum, ``thr`` the threshold."""
        wa = self.contract.accumulator_bits
        lo, hi = signed_range(wa)
        data = {"reset_less": True}
        name = r.total.name.removeprefix("total")  # "_s<s>_l<i>"
        cap1 = Signal(name=f"cap1{name}", **data)
        sum1 = Signal(signed(wa), name=f"sum1{name}", **data)
        ref1 = Signal(signed(wa), name=f"ref1{name}", **data)
        up1 = Signal(signed(wa + 1), name=f"up1{name}", **data)
        down1 = Signal(signed(wa + 1), name=f"down1{name}", **data)
        up_over = up1[wa] ^ up1[wa - 1]
        down_over = down1[wa] ^ down1[wa - 1]
        up, down = r.total >= r.thr1, r.total <= -r.thr1
        moved = Mux(up, Mux(up_over, hi, up1), Mux(down, Mux(down_over, lo, down1), ref1))
        stmts = [
            r.total.eq(shifted - ref), r.thr1.eq(thr), cap1.eq(fresh),
            sum1.eq(Mux(shifted > hi, hi, Mux(shifted < lo, lo, shifted))),
            ref1.eq(ref), up1.eq(ref + thr), down1.eq(ref - thr),
            r.pos.eq(~cap1 & up), r.neg.eq(~cap1 & ~up & down), r.thr2.eq(r.thr1),
            r.sat.eq(Mux(cap1, sum1, moved)),
        ]
        return stmts, r.pos, r.neg, r.sat  # the moved, saturated reference

    def model(self, ref: np.ndarray, fresh: np.ndarray, shifted: np.ndarray,
              thr: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(pos, neg, after)`` (bool, bool, int64) for references ``ref``, capture flags
        ``fresh``, shifted sums and thresholds (arrays of one shape)."""
        lo, hi = signed_range(self.contract.accumulator_bits)
        ref, shifted = np.asarray(ref, dtype=np.int64), np.asarray(shifted, dtype=np.int64)
        fresh = np.asarray(fresh, dtype=bool)
        d = shifted - ref
        up, down = d >= thr, d <= -thr
        pos, neg = ~fresh & up, ~fresh & ~up & down
        moved = np.clip(np.where(up, ref + thr, np.where(down, ref - thr, ref)), lo, hi)
        return pos, neg, np.where(fresh, np.clip(shifted, lo, hi), moved)


#: The tail of each output rule (``ArrayContract.kind.output``, the sensor kind's
#: :class:`~rvsm.model.kinds.sensor_kind.Output`); :func:`output_tail` is the one place it
#: is looked up.
OUTPUT_TAILS: dict[Output, type[SpikeTail] | type[EventTail]] = {Output.SPIKES: SpikeTail,
                                                                Output.EVENTS: EventTail}


def output_tail(contract: ArrayContract, mutation: str | None = None
                ) -> SpikeTail | EventTail:
    """The output rule of ``contract``'s sensor (:data:`OUTPUT_TAILS`)."""
    rule = OUTPUT_TAILS.get(contract.kind.output)
    if rule is None:
        raise RvsmError(f"no streaming-array tail for the {contract.sensor!r} sensor's "
                        f"output rule {contract.kind.output.name}")
    return rule(contract, mutation)


class OutputStage(wiring.Component):
    """``ctl`` In(:func:`~rvsm.rtl.stream.input_stage.control_signature`), ``sums``
    In(:func:`~rvsm.rtl.stream.sum_stage.sums_layout`), ``words``
    In(:func:`~rvsm.rtl.stream.state_stage.state_words_layout`), ``fresh`` and
    ``fresh_ahead`` In(1) (stage Q, Q-1), ``position``
    In(:func:`~rvsm.rtl.stream.position_stage.write_tap_signature`) -> ``write_data``
    Out(:func:`~rvsm.rtl.stream.state_stage.write_back_layout`), ``spikes``
    Out(:func:`~rvsm.rtl.stream.signatures.spike_beat_signature`). After elaboration
    :attr:`lanes` holds per scale and lane the tail's values (``acc``, ``total``,
    ``thr1``, ``sat``, ``thr2``, ``pos``, ``neg``, ``after``).

    ``target``: each scale and lane gets the fresh-frame flag through
    :meth:`~rvsm.rtl.stream.memory_target.MemoryTarget.flag_copy` (a device target: a
    register of its own, no net from one register to the zero multiplexers of every
    accumulator-adder input). ``mutation``: the rules' and ``"stream.clear_forgets_scale0"``,
    ``"stream.shift_off_by_one"``, ``"stream.swapped_lanes"`` (:mod:`rvsm.rtl.mutations`)."""

    def __init__(self, geometry: StreamGeometry, target: MemoryTarget = GENERIC_MEMORY,
                 mutation: str | None = None):
        self.geometry, self.target, self.mutation = geometry, target, mutation
        c, geo = geometry.contract, geometry
        s, p, wa = c.num_scales, geo.lanes, c.accumulator_bits
        #: Per scale and lane the tail's values, set by :meth:`elaborate`.
        self.lanes: list[list[dict[str, Value]]] = []
        super().__init__({
            "ctl": In(control_signature()),
            "sums": In(sums_layout(geo)),
            "words": In(state_words_layout(s, p, wa)),
            "fresh": In(1), "fresh_ahead": In(1),
            "position": In(write_tap_signature(c.height, geo.groups)),
            "write_data": Out(write_back_layout(s, p, wa)),
            "spikes": Out(spike_beat_signature(s, p, c.height, geo.groups)),
        })

    def elaborate(self, platform: object) -> Module:
        m = Module()
        c, geo, mutation = self.geometry.contract, self.geometry, self.mutation
        p, wa, tw = geo.lanes, c.accumulator_bits, c.threshold_bits
        advance = self.ctl.advance
        rule = output_tail(c, mutation)
        stmts, pos_bits, neg_bits = [], [], []
        self.lanes = []
        for s in range(c.num_scales):
            after_lanes = []
            self.lanes.append([])
            for i in range(p):
                fresh = self.target.flag_copy(m, self.fresh_ahead, self.fresh,
                                              f"fresh_s{s}_l{i}", en=advance)
                if mutation == "stream.clear_forgets_scale0" and s == 0:
                    fresh = 0  # the first frame after a clear reads scale 0's old state
                ref = self.words.acc[s][i * wa:(i + 1) * wa].as_signed()
                acc = Mux(fresh, 0, ref)
                extra = 1 if mutation == "stream.shift_off_by_one" else 0
                shifted = self.sums[i][f"s{s}"].as_signed() >> (c.shift + extra)
                data = {"reset_less": True}
                regs = LaneRegisters(
                    Signal(signed(max(wa, len(shifted)) + 1), name=f"total_s{s}_l{i}", **data),
                    Signal(unsigned(tw), name=f"thr1_s{s}_l{i}", **data),
                    Signal(signed(wa), name=f"sat_s{s}_l{i}", **data),
                    Signal(unsigned(tw), name=f"thr2_s{s}_l{i}", **data),
                    Signal(name=f"pos_s{s}_l{i}", **data),
                    Signal(name=f"neg_s{s}_l{i}", **data))
                lane, pos, neg, after = rule.lane(acc, ref, fresh, shifted,
                                                  self.words.thr[s][i * tw:(i + 1) * tw], regs)
                stmts += lane
                after_lanes.append(after.as_unsigned()[:wa])
                self.lanes[s].append({"acc": acc, "total": regs.total, "thr1": regs.thr1,
                                      "sat": regs.sat, "thr2": regs.thr2, "pos": pos,
                                      "neg": neg, "after": after})
                pos_bits.append(pos)
                neg_bits.append(neg)
            m.d.comb += self.write_data[s].eq(Cat(*after_lanes))
        out, position = self.spikes.payload, self.position
        if mutation == "stream.swapped_lanes" and p > 1:
            for bits in (pos_bits, neg_bits):  # lanes 0 and 1 of every scale swapped
                for s in range(c.num_scales):
                    bits[s * p], bits[s * p + 1] = bits[s * p + 1], bits[s * p]
        stmts += [out.row.eq(position.row), out.group.eq(position.group),
                  out.last.eq(position.last), out.pos.eq(Cat(*pos_bits)),
                  out.neg.eq(Cat(*neg_bits))]
        with m.If(advance):
            m.d.sync += stmts
        m.d.sync += self.spikes.valid.eq(position.en)
        return m
