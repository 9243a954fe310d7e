"""Formal properties of the fully parallel array (``rvsm formal --arch parallel``).

:class:`ParallelProperties` drives an :class:`~rvsm.rtl.parallel.array.RvsmArray` with
free inputs every cycle (``AnySeq``: codes, strobe, clear, threshold writes and the domain
reset ``rst``; written thresholds assumed in the contract's range ``1 .. 2**(W-1)-1``)
and checks every accumulator cell against the contract's integer rules
(:mod:`rvsm.model.fixed.contract`, restated here from the SPEC, not taken from the cell):

* ``receptive.sum``: the cell's input is the exact weighted sum of the codes (zero
  padding), computed here by plain multiplication;
* ``saturation.high_rail`` / ``saturation.low_rail``: a total beyond a rail clamps to it
  (never wraps): the next accumulator and spikes are the contract's;
* ``fire.spike_implies_threshold``: a +1 spike only when the saturated total reached the
  threshold (a -1 only when it reached minus the threshold, signed models);
* ``fire.threshold_implies_spike``: a total at or above the threshold fires +1;
* ``reset.<zero|subtract>``: after a strobed step the accumulator is what the contract's
  reset mode leaves;
* ``hold.no_strobe``: without strobe, clear or reset nothing changes;
* ``clear.zeroes_state``: ``clear`` zeroes accumulators and spikes, keeps thresholds;
* ``reset.domain``: ``rst`` zeroes accumulators and spikes, thresholds to ``2**(W-1)-1``
  (shared thresholds: to the contract's nominal ones);
* ``threshold.write`` / ``threshold.kept``: a write to a cell's address loads it from the
  next cycle, any other cycle keeps it;
* ``valid.latency``: ``valid`` is high exactly one cycle after a strobe without clear;
* covers: a +1 and a -1 spike (signed models) in every cell of every scale, both
  saturation rails, a clear right after a spike.

Every property is 1-inductive (the harness remembers the previous cycle's inputs and
state), so k-induction closes at any size and a small depth (3):
:attr:`ParallelProperties.provable`.
"""

from __future__ import annotations

from dataclasses import dataclass

from amaranth.asserts import AnySeq
from amaranth.hdl import (
    Cat,
    ClockDomain,
    ClockSignal,
    Module,
    Mux,
    ResetSignal,
    Signal,
    Value,
    signed,
    unsigned,
)

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.widths import signed_range
from rvsm.rtl.capabilities import require_spike_sensor
from rvsm.rtl.formal_harness import ElaborateAfter, FormalHarness
from rvsm.rtl.mutations import check_mutation
from rvsm.rtl.parallel.array import RvsmArray, accumulator_index
from rvsm.rtl.parallel.pixel_cell import PixelCell

__all__ = ["ParallelProperties", "parallel_properties"]


@dataclass(frozen=True)
class _Past:
    """The previous cycle's inputs, as the harness's never-reset registers remember them
    (``started``: a previous cycle exists)."""

    started: Signal
    rst: Signal
    strobe: Signal
    clear: Signal
    we: Signal
    addr: Signal
    data: Signal

    @property
    def step(self) -> Value:
        """The previous cycle was a contract step: strobe without clear or reset."""
        return self.started & ~self.rst & ~self.clear & self.strobe

    @property
    def observed(self) -> Value:
        """A previous cycle exists and was not a domain reset."""
        return self.started & ~self.rst


class ParallelProperties(FormalHarness):
    """The properties of an ``H x W`` :class:`RvsmArray` for ``contract`` (tiny sizes:
    every cell gets every property). ``mutation``: a ``parallel.*`` deliberate bug."""

    depth = 3
    #: Steps the covers need (a rail is reached after about 2**(W-1) / max|sum| steps).
    cover_depth = 12
    provable = True

    def __init__(self, contract: ArrayContract, mutation: str | None = None) -> None:
        super().__init__()
        self.contract = contract
        self.mutation = check_mutation(mutation, "parallel")

    def elaborate(self, platform: object) -> Module:
        m = Module()
        c = self.contract
        # The sync domain comes from the top level: its reset ``rst`` is a free input
        # (sby's multiclock off: one clock edge per step). History registers are never
        # reset, so they remember the cycle a reset happened.
        m.domains.past = past = ClockDomain("past", reset_less=True)
        m.d.comb += past.clk.eq(ClockSignal("sync"))
        dut = RvsmArray(c, mutation=self.mutation)
        m.submodules.dut = dut

        rst = ResetSignal("sync")
        m.d.comb += [
            dut.codes.eq(AnySeq(len(dut.codes))),
            dut.strobe.eq(AnySeq(1)),
            dut.clear.eq(AnySeq(1)),
            dut.cfg.we.eq(AnySeq(1)),
            dut.cfg.addr.eq(AnySeq(len(dut.cfg.addr))),
            dut.cfg.data.eq(AnySeq(len(dut.cfg.data))),
        ]
        self.check(m, "assume.threshold_in_range", ~dut.cfg.we | (dut.cfg.data >= 1),
                   "written thresholds lie in 1 .. 2**(W-1)-1 (the contract's range)",
                   "assume")

        prev = _Past(Signal(name="past_valid"), Signal(name="p_rst"),
                     Signal(name="p_strobe"), Signal(name="p_clear"), Signal(name="p_we"),
                     Signal.like(dut.cfg.addr, name="p_addr"),
                     Signal.like(dut.cfg.data, name="p_data"))
        m.d.past += [prev.started.eq(1), prev.rst.eq(rst), prev.strobe.eq(dut.strobe),
                     prev.clear.eq(dut.clear), prev.we.eq(dut.cfg.we),
                     prev.addr.eq(dut.cfg.addr), prev.data.eq(dut.cfg.data)]
        m.submodules.properties = ElaborateAfter(lambda platform: self._cells(dut, prev))
        self.check(m, "valid.latency",
                   ~prev.observed | (dut.valid == (prev.strobe & ~prev.clear)),
                   "valid is high exactly one cycle after a strobe without clear")
        return m

    def _cells(self, dut: RvsmArray, prev: _Past) -> Module:
        """Every cell's properties and the array-wide covers (``dut`` elaborated)."""
        m = Module()
        c = self.contract
        w = c.accumulator_bits
        lo, hi = signed_range(w)
        h, wd, n = c.height, c.width, c.adc_bits
        rails: tuple[list, list, list] = ([], [], [])
        full = (1 << n) - 1

        def lowest_shifted_sum(kernel, y: int, x: int) -> int:
            """The most negative shifted sum pixel (y, x) can receive (zero padding)."""
            half = len(kernel) // 2
            low = sum(wt * full for di, row in enumerate(kernel) for dj, wt in enumerate(row)
                      if wt < 0 and 0 <= y + di - half < h and 0 <= x + dj - half < wd)
            return low >> c.shift

        for s, kernel in enumerate(c.weights):
            half = len(kernel) // 2
            for y in range(h):
                for x in range(wd):
                    a = accumulator_index(c, s, y, x)
                    cell = dut.cells[a]
                    ref_sum = Signal(signed(len(cell.sum_in) + 1), name=f"ref_sum_{a}")
                    terms = [wt * dut.codes[((y + di - half) * wd + x + dj - half) * n:
                                            ((y + di - half) * wd + x + dj - half + 1) * n]
                             for di, row in enumerate(kernel) for dj, wt in enumerate(row)
                             if wt and 0 <= y + di - half < h and 0 <= x + dj - half < wd]
                    m.d.comb += ref_sum.eq(sum(terms) if terms else 0)
                    self.check(m, "receptive.sum", cell.sum_in == ref_sum,
                               "the cell's input is the exact weighted sum of the codes "
                               "(codes outside the array are 0)")
                    high, low, cleared = self._cell(m, a, s, cell, prev, lo, hi)
                    rails[0].append(high)
                    rails[1].append(cleared)
                    if c.signed and lowest_shifted_sum(kernel, y, x) < 0:
                        rails[2].append(low)
        self.check(m, "cover.saturate_high", Cat(*rails[0]).any(),
                   "a total above the high rail (any cell)", "cover")
        self.check(m, "cover.clear_after_spike", Cat(*rails[1]).any(),
                   "a clear right after a spike (any cell)", "cover")
        if rails[2]:
            self.check(m, "cover.saturate_low", Cat(*rails[2]).any(),
                       "a total below the low rail (any cell with a negative sum)", "cover")
        return m

    def _cell(self, m: Module, a: int, scale: int, cell: PixelCell, prev: _Past, lo: int,
              hi: int) -> tuple[Value, Value, Value]:
        """Cell ``a``'s (of scale ``scale``) properties; returns its rail and clear cover
        conditions. With shared thresholds the cell's threshold is its scale's register:
        written at address ``scale``, reset to the contract's nominal threshold."""
        c = self.contract
        shared = c.shared_thresholds is not None
        target = scale if shared else a  # the threshold's write address
        top = c.shared_thresholds[scale] if shared else hi  # its value after rst
        step = prev.step
        w = c.accumulator_bits
        p_acc = Signal(signed(w), name=f"p_acc_{a}")
        p_thr = Signal(unsigned(w - 1), name=f"p_thr_{a}")
        p_sum = Signal.like(cell.sum_in, name=f"p_sum_{a}")
        p_pos, p_neg = Signal(name=f"p_pos_{a}"), Signal(name=f"p_neg_{a}")
        m.d.past += [p_acc.eq(cell.acc), p_thr.eq(cell.threshold), p_sum.eq(cell.sum_in),
                     p_pos.eq(cell.spike_pos), p_neg.eq(cell.spike_neg)]

        # The contract's step (SPEC steps 2..5) from the previous cycle's state and sum.
        total = Signal(signed(max(w, len(p_sum)) + 2), name=f"total_{a}")
        m.d.comb += total.eq(p_acc + (p_sum >> c.shift))
        sat = Signal(signed(w), name=f"sat_{a}")
        m.d.comb += sat.eq(Mux(total > hi, hi, Mux(total < lo, lo, total)))
        pos = Signal(name=f"ref_pos_{a}")
        neg = Signal(name=f"ref_neg_{a}")
        m.d.comb += pos.eq(sat >= p_thr)
        if c.signed:
            m.d.comb += neg.eq(~pos & (sat <= -p_thr))
        after = Signal(signed(w), name=f"ref_acc_{a}")
        if c.reset == "zero":
            m.d.comb += after.eq(Mux(pos | neg, 0, sat))
        else:
            m.d.comb += after.eq(Mux(pos, sat - p_thr, Mux(neg, sat + p_thr, sat)))
        next_ok = ((cell.acc == after) & (cell.spike_pos == pos)
                   & (cell.spike_neg == neg))

        self.check(m, "saturation.high_rail", ~step | (total <= hi) | next_ok,
                   "a total above 2**(W-1)-1 clamps to it (never wraps): the next "
                   "accumulator and spikes are the contract's")
        self.check(m, "saturation.low_rail", ~step | (total >= lo) | next_ok,
                   "a total below -2**(W-1) clamps to it (never wraps): the next "
                   "accumulator and spikes are the contract's")
        fired_ok = ~cell.spike_pos | (sat >= p_thr)
        if c.signed:
            fired_ok = fired_ok & (~cell.spike_neg | ((sat <= -p_thr) & (sat < p_thr)))
        else:
            fired_ok = fired_ok & ~cell.spike_neg
        self.check(m, "fire.spike_implies_threshold", ~step | fired_ok,
                   "a +1 spike only when the saturated total reached the threshold, a -1 "
                   "only when it reached minus the threshold (signed models)")
        self.check(m, "fire.threshold_implies_spike", ~step | (sat < p_thr) | cell.spike_pos,
                   "a saturated total at or above the threshold fires +1")
        self.check(m, f"reset.{c.reset}", ~step | (cell.acc == after),
                   f"after a strobed step the accumulator is what reset mode "
                   f"{c.reset!r} leaves")
        held = ((cell.acc == p_acc) & (cell.spike_pos == p_pos)
                & (cell.spike_neg == p_neg))
        self.check(m, "hold.no_strobe", ~prev.observed | prev.clear | step | held,
                   "without strobe, clear or reset the accumulator and spikes keep")
        self.check(m, "clear.zeroes_state",
                   ~prev.observed | ~prev.clear
                   | ((cell.acc == 0) & ~cell.spike_pos & ~cell.spike_neg),
                   "clear zeroes the accumulator and the spikes")
        self.check(m, "reset.domain",
                   ~prev.started | ~prev.rst
                   | ((cell.acc == 0) & ~cell.spike_pos & ~cell.spike_neg
                      & (cell.threshold == top)),
                   f"the domain reset zeroes accumulator and spikes, threshold to {top}")
        written = prev.we & (prev.addr == target)
        self.check(m, "threshold.write", ~prev.observed | ~written
                   | (cell.threshold == prev.data),
                   "a threshold write to the cell's address loads it from the next cycle")
        self.check(m, "threshold.kept", ~prev.observed | written
                   | (cell.threshold == p_thr),
                   "without a write to its address (or a reset) the threshold keeps "
                   "(clear keeps it too)")

        # one statement per cell on one source line: covered when every cell (of every
        # scale) fires (sby names a cover by its line, so one name per line)
        self.check(m, "cover.spike_pos", step & cell.spike_pos,
                   "a +1 spike on every scale, in every cell", "cover")
        if c.signed:
            self.check(m, "cover.spike_neg", step & cell.spike_neg,
                       "a -1 spike on every scale, in every cell", "cover")
        return (step & (total > hi), step & (total < lo),
                prev.observed & prev.clear & (p_pos | p_neg))


def parallel_properties(contract: ArrayContract, mutation: str | None = None,
                        **options: int) -> ParallelProperties:
    """The ``"properties"`` harness factory of :data:`~rvsm.rtl.parallel.PARALLEL`."""
    require_spike_sensor(contract, "the formal properties")
    return ParallelProperties(contract, mutation=mutation)
