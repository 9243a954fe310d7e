"""The base of the streaming array's formal harnesses: :class:`StreamHarness`.

It instantiates :class:`~rvsm.rtl.stream.array.RvsmStreamArray` as ``dut`` with free
inputs (``AnySeq``: codes, ``codes.valid``, ``clear``; no domain reset, which does what
``clear`` does; :attr:`StreamHarness.inputs` may bound the stalls and clears), checked to
:attr:`StreamHarness.depth` = two frames plus the lag plus two cycles, and gives the
counters the properties are stated with. The harnesses: :mod:`.harnesses` (the property
groups), :mod:`.equivalence_harness` (the miter with the parallel array),
:mod:`.formal_lemmas` (the compositional form of the miter).
"""

from __future__ import annotations

from amaranth.asserts import AnySeq
from amaranth.hdl import Module, Mux, ResetSignal, Signal, Value

from rvsm.model.fixed.contract import ArrayContract
from rvsm.rtl.formal_harness import FormalHarness
from rvsm.rtl.mutations import check_mutation
from rvsm.rtl.stream.array import RvsmStreamArray
from rvsm.rtl.stream.dimensions import StreamGeometry

__all__ = ["StreamHarness"]


class StreamHarness(FormalHarness):
    """What the stream harnesses share: the array, its free inputs and the beat
    bookkeeping."""

    provable = False

    def __init__(self, contract: ArrayContract, lanes: int = 1,
                 mutation: str | None = None) -> None:
        super().__init__()
        self.contract = contract
        self.geometry = StreamGeometry(contract, lanes)
        self.mutation = check_mutation(mutation, "stream")
        #: The most cycles with a stall (``codes.valid`` low) and with ``clear`` high
        #: within the bound (``"stalls"``, ``"clears"``; a missing key: any number).
        self.inputs: dict[str, int] = {}
        geo = self.geometry
        #: Two frames plus the lag, plus the two cycles from acceptance to output.
        self.depth = 2 * geo.beats_per_frame + geo.lag + 2
        self.cover_depth = self.depth

    def _array(self, m: Module) -> RvsmStreamArray:
        dut = RvsmStreamArray(self.contract, self.geometry.lanes, mutation=self.mutation)
        m.submodules.dut = dut
        self.check(m, "assume.no_domain_reset", ~ResetSignal("sync"),
                   "the domain reset is not used (it restarts the stream like clear)",
                   "assume")
        valid, clear = AnySeq(1), AnySeq(1)
        m.d.comb += [dut.codes.payload.eq(AnySeq(len(dut.codes.payload.as_value()))),
                     dut.codes.valid.eq(valid), dut.clear.eq(clear)]
        for name, event in (("stalls", ~valid), ("clears", clear)):
            limit = self.inputs.get(name)
            if limit is None:
                continue
            count = Signal(range(limit + 2), name=f"{name}_so_far")
            with m.If(event & (count <= limit)):
                m.d.sync += count.eq(count + 1)
            self.check(m, f"assume.{name}", ~event | (count < limit),
                       f"at most {limit} cycles with {name[:-1]} in the bound", "assume")
        return dut

    def _counter(self, m: Module, name: str, clear: Value, step: Value,
                 modulo: int) -> Signal:
        """A counter of ``step`` s modulo ``modulo``, 0 after ``clear``."""
        count = Signal(range(modulo), name=name)
        with m.If(clear):
            m.d.sync += count.eq(0)
        with m.Elif(step):
            m.d.sync += count.eq(Mux(count == modulo - 1, 0, count + 1))
        return count

    def _beats(self, m: Module, dut: RvsmStreamArray, lag: int) -> Value:
        """``accepted beats since the last clear >= lag`` (a counter saturating at lag)."""
        seen = Signal(range(lag + 1), name=f"beats_to_{lag}")
        taken = dut.codes.valid & dut.codes.ready
        with m.If(dut.clear):
            m.d.sync += seen.eq(0)
        with m.Elif(taken & (seen < lag)):
            m.d.sync += seen.eq(seen + 1)
        return seen >= lag
