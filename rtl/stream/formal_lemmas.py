"""The compositional form of the streaming array's bounded equivalence (``rvsm formal
--arch stream --check window sums composed``).

The end-to-end miter (:class:`~rvsm.rtl.stream.equivalence_harness.StreamEquivalence`) makes the
solver prove, at every compared position of both frames, that the stream's pipelined
receptive sums (orbit sums shared by the scales, retimed CSD trees:
:mod:`rvsm.rtl.stream.pipelined_sum`) equal the parallel array's (equal-weight groups,
balanced trees: :mod:`rvsm.rtl.receptive_sum`): a bit-level equivalence of differently
associated adder trees, which is what leaves dog4 with 2 and 3 lanes without a verdict.
Three checks cut the proof at the window register:

* ``window`` (:class:`StreamWindowLemma`): whenever stage 1 holds a position, every
  masked window register holds the code of its pixel of that position's frame, taken
  from the harness's own record of the accepted beats, and 0 where the window reaches
  outside the array (the line buffer, the slabs and the padding masks). Bounded to the
  equivalence's depth, same inputs (back to back, no clear).
* ``sums`` (:class:`StreamSumLemma`): the circuit the array builds from its window
  (:meth:`~rvsm.rtl.stream.dimensions.StreamGeometry.stage_q_sums`), fed free codes with
  the cells outside the array at 0 around each position in turn, gives at stage Q
  exactly the parallel array's sum of that pixel: :func:`~rvsm.rtl.receptive_sum.weighted_sum`
  over :func:`~rvsm.rtl.parallel.array.receptive_taps`, the expression
  :class:`~rvsm.rtl.parallel.array.RvsmArray` builds. The pipeline has no feedback, so
  ``Q - 1`` cycles after a window enters cover it; one (position, scale, lane) per cycle.
* ``composed`` (:class:`ComposedEquivalence`): the miter with the lemmas' conclusion
  assumed: whenever stage Q holds a position whose frame the parallel array has had,
  the stream's sums equal that array's ``sum_in`` of the same frame and pixel (kept in a
  ring from the cycle the frame was strobed). What is left is the state and tail logic
  of both arrays, which the solver relates quickly.

Why the three imply the end-to-end equivalence (docs/formal.md, "The compositional
proof"): the assumption of ``composed`` holds in every trace of its inputs, because the
k-th position stage Q holds is the k-th position stage 1 held, moved by the pipeline's
registers (all loaded on the same ``advance``, no feedback): ``window`` says its window
is the padded codes of its frame, ``sums`` that the pipeline maps such a window to the
parallel array's sum of those codes, and the parallel array's ``sum_in`` of that frame
is the same expression of the same accepted beats.
"""

from __future__ import annotations

import inspect
import os

from amaranth.asserts import AnySeq
from amaranth.hdl import Array, Cat, Const, Module, Mux, Signal

from rvsm.model.fixed.contract import ArrayContract
from rvsm.rtl.capabilities import require_spike_sensor
from rvsm.rtl.formal_harness import ElaborateAfter, FormalHarness, Property
from rvsm.rtl.linear_form import linear_forms
from rvsm.rtl.mutations import check_mutation
from rvsm.rtl.parallel.array import RvsmArray, accumulator_index, receptive_taps
from rvsm.rtl.receptive_sum import weighted_sum
from rvsm.rtl.stream.array import RvsmStreamArray, StreamProbes
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.equivalence_harness import StreamEquivalence
from rvsm.rtl.stream.harness_base import StreamHarness
from rvsm.rtl.stream.pipelined_sum import Pipeline, Timed

__all__ = ["ComposedEquivalence", "StreamSumLemma", "StreamWindowLemma",
           "composed_equivalence", "sum_lemma", "window_lemma"]


class StreamWindowLemma(StreamHarness):
    """``window.codes``: the masked window registers hold their pixels' codes (0 outside
    the array) whenever stage 1 holds a position; the stream runs back to back as in
    :class:`StreamEquivalence` (thresholds are outside the window's cone: not driven)."""

    def __init__(self, contract: ArrayContract, lanes: int = 1,
                 mutation: str | None = None) -> None:
        super().__init__(contract, lanes, mutation)
        self.inputs = {"stalls": 0, "clears": 0}

    def elaborate(self, platform: object) -> Module:
        m = Module()
        dut = self._array(m)
        m.d.comb += dut.thr.we.eq(0)
        m.submodules.lemma = ElaborateAfter(lambda platform: self._lemma(dut))
        return m

    def _lemma(self, dut: RvsmStreamArray) -> Module:
        m = Module()
        c, geo = self.contract, self.geometry
        p, n, g_count, r = geo.lanes, c.adc_bits, geo.groups, geo.radius
        words, h, w = geo.beats_per_frame, c.height, c.width
        probes: StreamProbes = dut.probes
        taken = dut.codes.valid & dut.codes.ready
        # the accepted beats of the last `frames` frames (stage 1 trails the input by
        # less than a lag)
        frames = geo.lag // words + 2
        in_pos = self._counter(m, "in_pos", dut.clear, taken, words)
        in_frame = self._counter(m, "in_frame", dut.clear, taken & (in_pos == words - 1),
                                 frames)
        record = [[Signal(p * n, name=f"rec_f{f}_w{k}") for k in range(words)]
                  for f in range(frames)]
        for f in range(frames):
            for k in range(words):
                with m.If(taken & (in_frame == f) & (in_pos == k)):
                    m.d.sync += record[f][k].eq(dut.codes.payload.as_value())
        # the position stage 1 holds: counted as it leaves (advance while valid)
        leaves = probes.advance & probes.window_valid
        pos = self._counter(m, "win_pos", probes.clear, leaves, words)
        frame = self._counter(m, "win_frame", probes.clear,
                              leaves & (pos == words - 1), frames)
        held = Array(Cat(*record[f]) for f in range(frames))[frame]
        ok = []
        for d, j in geo.window_cells():
            expected = []
            for a in range(words):  # the cell's code for each position a = y*G + g
                yy, xx = a // g_count + d - r, (a % g_count) * p + j - r
                if 0 <= yy < h and 0 <= xx < w:
                    k = (yy * g_count + xx // p) * p + xx % p
                    expected.append(held[k * n:(k + 1) * n])
                else:
                    expected.append(Const(0, n))
            ok.append(probes.window[(d, j)] == Array(expected)[pos])
        self.check(m, "window.codes", ~probes.window_valid | Cat(*ok).all(),
                   "the masked window holds the codes of its position's pixels (0 "
                   "outside the array) of its frame, as accepted")
        return m


class _Unregistered(Pipeline):
    """A :class:`Pipeline` whose registers are wires: the same adder trees, paired in the
    same order at the same widths (stages are tracked as before), combinational."""

    def register(self, t: Timed, name: str | None = None) -> Timed:
        if t._next is None:
            self.registers += 1
            t._next = Timed(t.value, t.stage + 1, 0)
        return t._next


class StreamSumLemma(FormalHarness):
    """The sum lemma in two parts (docs/formal.md, "The compositional proof"):

    * ``sums.retiming`` (the solver): the stream's sum circuit
      (:meth:`StreamGeometry.stage_q_sums`, registers always loading) gives at stage Q
      the same words as the same adder trees without their registers
      (:class:`_Unregistered`) applied to the window ``Q - 1`` cycles earlier, for free
      windows, every scale and lane: a comparison of one circuit with itself;
    * ``sums.linear_forms`` (exact, in Python, :meth:`offline_failures`): for every
      position, scale and lane, that register-free expression, with the window cells
      outside the array at 0, and the parallel array's :func:`weighted_sum` over
      :func:`receptive_taps` (the expression :class:`RvsmArray` builds) are the same
      linear form in the pixels' codes modulo ``2**W`` (:func:`linear_forms`, read from
      the netlist of those expressions).
    """

    provable = False
    offline_properties = ("sums.linear_forms",)

    def __init__(self, contract: ArrayContract, lanes: int = 1,
                 mutation: str | None = None) -> None:
        super().__init__()
        self.contract = contract
        self.geometry = StreamGeometry(contract, lanes)
        self.mutation = check_mutation(mutation, "stream")
        #: Every stage-Q output has a window ``Q - 1`` cycles before, plus one cycle.
        self.depth = self.geometry.sum_stage + 1
        self.cover_depth = self.depth

    def elaborate(self, platform: object) -> Module:
        m = Module()
        geo, n = self.geometry, self.contract.adc_bits
        stage_q = geo.sum_stage
        age = Signal(range(stage_q), name="age")  # the cycle, saturating at Q - 1
        with m.If(age != stage_q - 1):
            m.d.sync += age.eq(age + 1)
        cells = geo.window_cells()
        codes = {}
        for d, j in cells:
            code = Signal(n, name=f"window_r{d}_c{j}")
            m.d.comb += code.eq(AnySeq(n))
            codes[(d, j)] = code
        pipe = Pipeline(m, None, geo.LEVELS_PER_STAGE, name="sum")
        sums, _ = geo.stage_q_sums(pipe, {cell: pipe.timed(code, 1)
                                          for cell, code in codes.items()})
        pipe.emit()
        then = codes  # the window Q-1 cycles ago
        for k in range(stage_q - 1):
            delayed = {cell: Signal(n, name=f"d{k}_r{cell[0]}_c{cell[1]}")
                       for cell in cells}
            m.d.sync += [delayed[cell].eq(then[cell]) for cell in cells]
            then = delayed
        flat = _Unregistered(m, None, geo.LEVELS_PER_STAGE, name="flat")
        direct, _ = geo.stage_q_sums(flat, {cell: flat.timed(code, 1)
                                            for cell, code in then.items()})
        same = Cat(*[sums[i][s].value == direct[i][s].value
                     for i in range(geo.lanes) for s in range(self.contract.num_scales)])
        self.check(m, "sums.retiming", (age != stage_q - 1) | same.all(),
                   "the stream's sums at stage Q are its adder trees without registers "
                   "applied to the window Q-1 cycles earlier (every scale and lane)")
        frame = inspect.stack()[0]
        self.properties.append(Property(
            "sums.linear_forms", "assert", "without registers, with zeros outside the "
            "array, the stream's sums are the parallel array's as linear forms in the "
            "codes (every position, scale and lane; exact, checked in Python)",
            f"{os.path.abspath(frame.filename)}:{frame.lineno}"))
        return m

    def offline_failures(self) -> list[tuple[str, str]]:
        """``sums.linear_forms``: ``(property, message)`` per position, scale and lane
        whose stream and parallel sums differ as linear forms (none when it holds)."""
        c, geo = self.contract, self.geometry
        p, n, g_count, r = geo.lanes, c.adc_bits, geo.groups, geo.radius
        h, w = c.height, c.width
        m = Module()
        cells = {cell: Signal(n, name=f"cell_r{cell[0]}_c{cell[1]}")
                 for cell in geo.window_cells()}
        pix = [[Signal(n, name=f"pix_y{y}_x{x}") for x in range(w)] for y in range(h)]
        flat = _Unregistered(m, None, geo.LEVELS_PER_STAGE, name="flat")
        direct, _ = geo.stage_q_sums(flat, {cell: flat.timed(code, 1)
                                            for cell, code in cells.items()})
        leaves = {("cell", *cell): sig for cell, sig in cells.items()}
        leaves.update({("pixel", y, x): pix[y][x] for y in range(h) for x in range(w)})
        values = []  # per scale: the lanes' stream sums, then every position's parallel sum
        for s in range(c.num_scales):
            lo, hi = c.sum_range(s)
            values += [direct[i][s].value for i in range(p)]
            for a in range(geo.beats_per_frame):
                for i in range(p):
                    y, x = a // g_count, (a % g_count) * p + i
                    taps = receptive_taps(c, s, y, x)
                    values.append(weighted_sum([pix[yy][xx] for (yy, xx), _ in taps],
                                               [wt for _, wt in taps], lo, hi))
        forms = iter(linear_forms(values, leaves))  # one netlist of them all
        failures = []
        for s in range(c.num_scales):
            width = geo.sum_bits(s)
            stream_form = [next(forms) for _ in range(p)]
            for a in range(geo.beats_per_frame):
                for i in range(p):
                    y, x = a // g_count, (a % g_count) * p + i
                    par = next(forms)
                    st = stream_form[i]
                    # the window lemma's map: cell (d, j) holds pixel (y+d-r, x-i+j-r)
                    coefs: dict[tuple[int, int], int] = {}
                    for (_, d, j), coef in st.coefs.items():
                        yy, xx = y + d - r, x - i + j - r
                        if 0 <= yy < h and 0 <= xx < w:
                            coefs[(yy, xx)] = coef
                    par_coefs = {(yy, xx): coef for (_, yy, xx), coef in par.coefs.items()}
                    where = f"scale {s}, position {a} (row {y}, column {x}), lane {i}"
                    for name, f in (("stream", st), ("parallel", par)):
                        if f.bits is not None and f.bits < width:
                            failures.append(("sums.linear_forms", (
                                f"{where}: the {name} sum is a linear form in the codes "
                                f"modulo 2**{f.bits} only, not the sum's {width} bits")))
                    if st.const != par.const:
                        failures.append(("sums.linear_forms", (
                            f"{where}: constant {st.const} in the stream's sum, "
                            f"{par.const} in the parallel array's")))
                    for pixel in sorted(set(coefs) | set(par_coefs)):
                        cs, cp = coefs.get(pixel, 0), par_coefs.get(pixel, 0)
                        if cs != cp:
                            failures.append(("sums.linear_forms", (
                                f"{where}: pixel {pixel} has weight {cs} in the stream's "
                                f"sum, {cp} in the parallel array's")))
        return failures


class ComposedEquivalence(StreamEquivalence):
    """:class:`StreamEquivalence` with the conclusion of ``window`` and ``sums``
    assumed (``assume.sums``): the stream's stage-Q sums equal the parallel array's
    ``sum_in`` of the same frame and pixel once that array has had the frame."""

    def _compare(self, dut: RvsmStreamArray, ref: RvsmArray) -> Module:
        m = super()._compare(dut, ref)
        c, geo = self.contract, self.geometry
        p, words = geo.lanes, geo.beats_per_frame
        probes: StreamProbes = dut.probes
        depth = geo.lag // words + 2
        sums = Cat(*[ref.cells[accumulator_index(c, s, a // geo.groups,
                                                 (a % geo.groups) * p + i)].sum_in
                     for a in range(words) for s in range(c.num_scales)
                     for i in range(p)])
        strobe = ref.strobe & ~ref.clear
        ring = Array(Signal(len(sums), name=f"ref_sums{k}") for k in range(depth))
        head = Signal(range(depth), name="sums_head")
        with m.If(strobe):
            m.d.sync += [ring[head].eq(sums),
                         head.eq(Mux(head == depth - 1, 0, head + 1))]
        leaves = probes.advance & probes.sum_valid
        pos = self._counter(m, "sum_pos", probes.clear, leaves, words)
        done = leaves & (pos == words - 1)
        tail = self._counter(m, "sum_frame", probes.clear, done, depth)
        ready = Signal(range(depth + 1), name="sums_ready")
        m.d.sync += ready.eq(ready + strobe - done)
        per_word = len(sums) // words
        held = Array(ring[tail][a * per_word:(a + 1) * per_word] for a in range(words))[pos]
        stream = Cat(*[probes.sums[s][i] for s in range(c.num_scales) for i in range(p)])
        self.check(m, "assume.sums", ~probes.sum_valid | (ready == 0) | (stream == held),
                   "the stream's sums at stage Q are the parallel array's of the same "
                   "frame and pixel (proven by the window and sums checks)", "assume")
        return m


def window_lemma(contract: ArrayContract, mutation: str | None = None, lanes: int = 1,
                 **options: int) -> StreamWindowLemma:
    """The ``"window"`` harness factory of :data:`~rvsm.rtl.stream.STREAM`."""
    require_spike_sensor(contract, "the formal properties")
    return StreamWindowLemma(contract, lanes, mutation)


def sum_lemma(contract: ArrayContract, mutation: str | None = None, lanes: int = 1,
              **options: int) -> StreamSumLemma:
    """The ``"sums"`` harness factory of :data:`~rvsm.rtl.stream.STREAM`."""
    require_spike_sensor(contract, "the formal properties")
    return StreamSumLemma(contract, lanes, mutation)


def composed_equivalence(contract: ArrayContract, mutation: str | None = None,
                         lanes: int = 1, **options: int) -> ComposedEquivalence:
    """The ``"composed"`` harness factory of :data:`~rvsm.rtl.stream.STREAM`."""
    require_spike_sensor(contract, "the formal properties")
    return ComposedEquivalence(contract, lanes, mutation)
