"""One RVSM accumulator: threshold register, W-bit saturating add, compare, fire, reset.

The cell is independent of how its input sum is produced; the fully parallel
:class:`~rvsm.rtl.parallel.array.RvsmArray` builds one per (scale, pixel). (The streaming
array keeps its accumulators in memories and has its own tail.)
Per strobe it implements steps 2..5 of the contract (:mod:`rvsm.model.fixed.contract`)::

    shifted = sum_in >>> shift                         (arithmetic, floor)
    sat     = clamp(acc + shifted, -2**(W-1), 2**(W-1)-1)
    pos     = sat >= thr;  neg = signed and not pos and sat <= -thr
    acc    <= 0 | sat - thr*pos + thr*neg | sat         (reset "zero" / "subtract" / none)
    spike_pos, spike_neg <= pos, neg                    (registered; LATENCY = 1)

Control, all synchronous: ``clear`` (priority) zeroes the accumulator and the spike
outputs and keeps the threshold; ``thr.we`` loads ``thr.data`` into the threshold
register (any time; it takes effect from the next strobe). ``thr`` is the threshold-write
bus (:class:`~rvsm.rtl.interfaces.ThresholdWriteSignature`, without address). The domain
reset returns the threshold to its ``init`` value ``2**(W-1) - 1``. A cell of an array with
shared thresholds has no threshold register: it compares with its scale's
(``threshold_in``).
"""

from __future__ import annotations

from amaranth.hdl import Module, Mux, Signal, Value, signed, unsigned
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from rvsm.model.fixed.widths import signed_range
from rvsm.model.kinds.sensor_kind import Output
from rvsm.rtl.interfaces import ThresholdWriteSignature

__all__ = ["PixelCell"]


class PixelCell(wiring.Component):
    """The accumulator of one (scale, pixel).

    Parameters: ``sum_bits`` (signed width of ``sum_in``), ``shift``, ``accumulator_bits``
    (W), ``signed_model`` (fire -1 spikes), ``reset`` (``"zero"`` or ``"subtract"``),
    ``output``: the output rule (:class:`~rvsm.model.kinds.sensor_kind.Output`, a
    contract's ``kind.output``): ``SPIKES``, or ``EVENTS`` for the event sensor's cell
    (``acc`` is then the reference, captured as ``clamp(shifted)`` at the first strobe
    after a clear or reset with no event; afterwards ``d = shifted - ref``, ``d >= thr``
    ON and ``ref = clamp(ref + thr)``, else ``d <= -thr`` OFF and ``ref = clamp(ref -
    thr)``). The next-state logic of each rule is a method, chosen through a table keyed
    by the rule in :meth:`elaborate`.

    Ports: ``sum_in`` In(signed(sum_bits)); ``strobe``, ``clear`` In(1); ``thr``
    In(ThresholdWriteSignature(W-1)): ``thr.we``, ``thr.data``; ``spike_pos``,
    ``spike_neg`` Out(1), registered, valid :attr:`LATENCY` cycles after the strobe;
    ``acc`` Out(signed(W)) and ``threshold`` Out(unsigned(W-1)) for observation (the
    formal harness :mod:`rvsm.rtl.parallel.harnesses`). ``mutation``: a deliberate bug of
    :mod:`rvsm.rtl.mutations` (``parallel.*``) or None. ``shared_threshold``
    (``threshold.storage = "shared"``): no threshold register of its own; ``thr`` is
    replaced by ``threshold_in`` In(unsigned(W-1)), its scale's register.
    """

    #: Clock cycles from the strobe edge that samples ``sum_in`` to valid spike outputs.
    LATENCY = 1

    def __init__(
        self,
        sum_bits: int,
        shift: int,
        accumulator_bits: int,
        signed_model: bool,
        reset: str = "zero",
        mutation: str | None = None,
        output: Output = Output.SPIKES,
        shared_threshold: bool = False,
    ):
        if not isinstance(output, Output):
            raise ValueError(f"output must be one of {[o.name for o in Output]}, got "
                             f"{output!r}")
        self.output = output
        if reset not in ("zero", "subtract"):
            raise ValueError(f"reset must be 'zero' or 'subtract', got {reset!r}")
        self.sum_bits = sum_bits
        self.shift = shift
        self.accumulator_bits = accumulator_bits
        self.signed_model = signed_model
        self.reset = reset
        #: A deliberate bug (:mod:`rvsm.rtl.mutations`) or None (the shipped logic).
        self.mutation = mutation
        self.shared_threshold = shared_threshold
        threshold_port = ({"threshold_in": In(unsigned(accumulator_bits - 1))}
                          if shared_threshold else
                          {"thr": In(ThresholdWriteSignature(accumulator_bits - 1))})
        super().__init__({
            "sum_in": In(signed(sum_bits)),
            "strobe": In(1),
            "clear": In(1),
            **threshold_port,
            "spike_pos": Out(1),
            "spike_neg": Out(1),
            "acc": Out(signed(accumulator_bits)),
            "threshold": Out(unsigned(accumulator_bits - 1)),
        })

    @property
    def acc_range(self) -> tuple[int, int]:
        """``(lo, hi)`` of the W-bit signed accumulator."""
        return signed_range(self.accumulator_bits)

    def elaborate(self, platform: object) -> Module:
        """Registers and next-state logic of the cell."""
        m = Module()
        lo, hi = self.acc_range
        w = self.accumulator_bits
        if self.shared_threshold:  # the scale's register, outside the cell
            thr = self.threshold_in
        else:
            thr = Signal(unsigned(w - 1), init=hi)
            with m.If(self.thr.we):
                m.d.sync += thr.eq(self.thr.data)
        acc = Signal(signed(w))
        m.d.comb += [self.acc.eq(acc), self.threshold.eq(thr)]

        shifted = self.sum_in >> self.shift if self.shift else self.sum_in
        total = Signal(signed(max(w, len(shifted)) + 1))
        m.d.comb += total.eq(acc + shifted)
        sat = Signal(signed(w))
        if self.mutation == "parallel.wrapping_accumulator":
            m.d.comb += sat.eq(total[:w].as_signed())  # no saturation: wraps around
        else:
            m.d.comb += sat.eq(Mux(total > hi, hi, Mux(total < lo, lo, total)))

        pos = Signal()
        neg = Signal()
        if self.mutation == "parallel.threshold_off_by_one":
            m.d.comb += pos.eq(sat > thr)
        else:
            m.d.comb += pos.eq(sat >= thr)
        if self.signed_model:
            m.d.comb += neg.eq(~pos & (sat <= -thr))

        if self.reset == "zero" or self.mutation == "parallel.zero_instead_of_subtract":
            after = Mux(pos | neg, 0, sat)
        else:
            after = Mux(pos, sat - thr, Mux(neg, sat + thr, sat))

        cells = {Output.SPIKES: lambda: self._spike_cell(m, thr, acc, pos, neg, after),
                 Output.EVENTS: lambda: self._event_cell(m, thr, acc, shifted)}
        return cells[self.output]()

    def _spike_cell(self, m: Module, thr: Value, acc: Signal, pos: Signal, neg: Signal,
                    after: Value) -> Module:
        """The spike camera's registers: clear, accumulate and fire."""
        clear = self.clear if self.mutation != "parallel.clear_ignored" else 0
        with m.If(clear):
            m.d.sync += [acc.eq(0), self.spike_pos.eq(0), self.spike_neg.eq(0)]
        with m.Elif(self.strobe):
            m.d.sync += [acc.eq(after), self.spike_pos.eq(pos), self.spike_neg.eq(neg)]
        return m

    def _event_cell(self, m: Module, thr: Value, ref: Signal, shifted: Value) -> Module:
        """The event sensor's next-state logic (class docstring): ``ref`` in ``acc``."""
        lo, hi = self.acc_range
        captured = Signal()
        d = Signal(signed(max(self.accumulator_bits, len(shifted)) + 1))
        m.d.comb += d.eq(shifted - ref)
        up, down = d >= thr, d <= -thr
        moved = Mux(up, ref + thr, Mux(down, ref - thr, ref))
        new = Mux(captured, moved, shifted)
        with m.If(self.clear):
            m.d.sync += [ref.eq(0), captured.eq(0), self.spike_pos.eq(0),
                         self.spike_neg.eq(0)]
        with m.Elif(self.strobe):
            m.d.sync += [ref.eq(Mux(new > hi, hi, Mux(new < lo, lo, new))),
                         captured.eq(1), self.spike_pos.eq(captured & up),
                         self.spike_neg.eq(captured & ~up & down)]
        return m
