"""How many block RAMs a streaming array's state takes on a device: an exact packing model.

**One memory** (:class:`MemoryShape`: ``depth`` words of ``width`` bits, ``reads`` and
``writes`` per clock edge) on one RAM primitive (:class:`~rvsm.rtl.fpga.devices.BlockRamKind`)
is cut into *slices* side by side, each slice ``ceil(depth / d)`` primitives of one aspect
``d x w`` stacked in depth; :func:`pack` chooses the slices that cover the width with the
fewest primitives (a small knapsack over the aspects, so a 28-bit remainder beside
512x36 slices may take a narrower aspect). Ports: a pseudo-dual-port aspect (one read
port, one write port) serves one read and one write per edge, so ``reads`` copies hold
``reads > 1``; a true-dual-port aspect's two ports serve ``reads + writes <= 2``, more
reads take copies; a single-port aspect (the iCE40 SPRAM) serves ``reads + writes``
accesses by words of that many beats (half the depth, twice the width for one read and
one write per beat: the port alternates between them, possible for the raster order of
a streaming array). Counts are of what a designer instantiates; a mapper may use more.

**The state of an array** (:class:`StateLayout`: per scale its accumulator bits ``A``,
threshold bits ``T``, ``0`` when the thresholds are shared registers, and pitch ``p``, 1
for every pixel, 2 for every second row and column; ADC bits ``N`` and window radius
``L``) at ``P`` lanes is organised in one of :data:`ORGANISATIONS`:

* ``"rtl"``: what the RTL builds today (:mod:`rvsm.rtl.stream.array`): per scale one
  accumulator memory (word ``P*A``) and one threshold memory (word ``P*T``), ``H*W/P``
  words each, split into banks of at most ``bank_words`` (1024) words
  (:class:`~rvsm.rtl.stream.banked_memory.BankedMemory`); on a device whose RTL
  instantiates one configuration (ECP5: 1Kx18 DP16KD,
  :mod:`rvsm.rtl.fpga.ecp5_memory`) only that one;
* ``"per-scale"``: the same memories without the 1024-word banks, best aspects;
* ``"packed"``: the lanes and scales of one pitch in one wide word: one accumulator
  memory ``H*W/P`` words deep and ``P*S*A`` bits wide, one threshold memory ``P*S*T``
  wide (chip-notes: dog4, A = 18, shared thresholds, P = 40: 80 x 5 = 400 DP16KD).

A scale at pitch ``p`` keeps ``ceil(H/p)*ceil(W/P)`` words of ``ceil(P/p)`` lanes. The line
buffer (``2L`` rows of ``W`` codes: one memory ``ceil(W/P)`` deep, ``2L*P*N`` wide) goes to
distributed RAM where the device has it (as yosys maps it on the ECP5), else to block RAM.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.camera import state_memory
from rvsm.rtl.fpga.devices import Aspect, BlockRamKind, DeviceBudget

__all__ = ["ORGANISATIONS", "MemoryShape", "Packing", "ScaleState", "StateLayout",
           "StatePacking", "pack", "pack_state", "state_memories"]

#: Memory organisations of the state (module docstring).
ORGANISATIONS = ("rtl", "per-scale", "packed")
#: Words per bank in the RTL (``StreamGeometry.BANK_WORDS``).
RTL_BANK_WORDS = 1024


@dataclass(frozen=True)
class MemoryShape:
    """``copies`` identical memories of ``depth`` words x ``width`` bits, each read
    ``reads`` and written ``writes`` times per clock edge; ``name`` says what it holds."""

    name: str
    depth: int
    width: int
    reads: int = 1
    writes: int = 1
    copies: int = 1

    @property
    def bits(self) -> int:
        """Bits stored: ``copies * depth * width``."""
        return self.copies * self.depth * self.width


@dataclass(frozen=True)
class Packing:
    """One :class:`MemoryShape` on one primitive kind: ``slices`` (aspect, slices of it
    side by side, each ``ceil(depth' / aspect.depth)`` deep), ``replicas`` (copies for
    reads), ``beats`` (beats per word on a single port), ``primitives`` in all (``copies``
    included)."""

    memory: MemoryShape
    kind: str
    slices: tuple[tuple[Aspect, int], ...]
    replicas: int
    beats: int
    primitives: int

    def text(self) -> str:
        """``"80 x 5 of 512x36 (pseudo-dual)"``: slices wide x deep per aspect."""
        depth = -(-self.memory.depth // self.beats)
        parts = [f"{n} x {-(-depth // a.depth)} of {a.text()}" for a, n in self.slices]
        extra = (f", {self.replicas} replicas" if self.replicas > 1 else "") + \
                (f", {self.beats} beats per word" if self.beats > 1 else "")
        copies = f"{self.memory.copies} x (" if self.memory.copies > 1 else ""
        return f"{copies}{' + '.join(parts)}{')' if copies else ''}{extra}"


def _port_plan(a: Aspect, reads: int, writes: int) -> tuple[int, int] | None:
    """``(replicas, beats per word)`` for ``reads`` and ``writes`` per edge on ``a``, or
    None when its ports cannot serve them."""
    if a.ports == "single":
        return 1, reads + writes
    if a.ports == "pseudo-dual":
        return (max(1, reads), 1) if writes <= 1 else None
    free = 2 - writes  # true dual: the ports the writes leave for reads
    if writes > 2 or (free == 0 and reads > 0):
        return None
    return max(1, -(-reads // free)) if reads else 1, 1


def pack(memory: MemoryShape, kind: BlockRamKind,
         aspects: tuple[Aspect, ...] | None = None) -> Packing | None:
    """The fewest primitives of ``kind`` (only ``aspects`` if given) holding ``memory``,
    or None if no aspect's ports serve it (module docstring)."""
    if memory.depth <= 0 or memory.width <= 0:
        return Packing(memory, kind.name, (), 1, 1, 0)
    best: Packing | None = None
    plans: dict[tuple[int, int], list[Aspect]] = {}
    for a in aspects or kind.aspects:
        plan = _port_plan(a, memory.reads, memory.writes)
        if plan is not None:
            plans.setdefault(plan, []).append(a)
    for (replicas, beats), group in plans.items():
        depth, width = -(-memory.depth // beats), memory.width * beats
        cost = {a: replicas * -(-depth // a.depth) for a in group}
        # fewest primitives covering x bits of width: best[x], with the last slice's aspect
        best_w = [0] + [math.inf] * width
        last: list[Aspect | None] = [None] * (width + 1)
        for x in range(1, width + 1):
            for a in group:
                c = cost[a] + best_w[max(0, x - a.width)]
                if c < best_w[x]:
                    best_w[x], last[x] = c, a
        counts: dict[Aspect, int] = {}
        x = width
        while x > 0:
            a = last[x]
            assert a is not None
            counts[a] = counts.get(a, 0) + 1
            x = max(0, x - a.width)
        total = int(best_w[width]) * memory.copies
        if best is None or total < best.primitives:
            slices = tuple(sorted(counts.items(), key=lambda t: -t[0].width))
            best = Packing(memory, kind.name, slices, replicas, beats, total)
    return best


@dataclass(frozen=True)
class ScaleState:
    """One scale's state per kept pixel: ``accumulator_bits``, ``threshold_bits`` (0:
    shared threshold registers, no memory) and ``pitch`` (kept every ``pitch``-th row and
    column)."""

    accumulator_bits: int
    threshold_bits: int
    pitch: int = 1


@dataclass(frozen=True)
class StateLayout:
    """The state of an ``height x width`` array: its scales, ADC bits and window radius
    (module docstring)."""

    height: int
    width: int
    scales: tuple[ScaleState, ...]
    adc_bits: int
    radius: int

    @classmethod
    def from_contract(cls, contract: ArrayContract, shared_thresholds: bool | None = None,
                      pitches: tuple[int, ...] | None = None) -> StateLayout:
        """The layout of ``contract``'s array (:func:`~rvsm.rtl.fpga.camera.state_memory`):
        shared threshold registers when ``shared_thresholds`` (``None``: when the contract
        has them, ``threshold.storage = "shared"``), else per-pixel threshold memories;
        every scale at pitch 1 unless ``pitches`` says otherwise."""
        if shared_thresholds is None:
            shared_thresholds = contract.shared_thresholds is not None
        st = state_memory(contract)
        pitches = pitches or (1,) * st.num_scales
        if len(pitches) != st.num_scales or any(p < 1 for p in pitches):
            raise RvsmError(f"pitches must be {st.num_scales} integers >= 1, got {pitches}")
        t = 0 if shared_thresholds else st.threshold_bits
        return cls(st.height, st.width,
                   tuple(ScaleState(st.accumulator_bits, t, p) for p in pitches),
                   st.adc_bits, st.radius)

    def kept(self, pitch: int) -> int:
        """Pixels a scale at ``pitch`` keeps: ``ceil(H/p) * ceil(W/p)``."""
        return -(-self.height // pitch) * -(-self.width // pitch)

    @property
    def accumulator_bits(self) -> int:
        """Accumulator bits of all scales."""
        return sum(self.kept(s.pitch) * s.accumulator_bits for s in self.scales)

    @property
    def threshold_bits(self) -> int:
        """Threshold memory bits of all scales (0 for shared thresholds)."""
        return sum(self.kept(s.pitch) * s.threshold_bits for s in self.scales)

    @property
    def line_buffer_bits(self) -> int:
        """``2L * W * N``."""
        return 2 * self.radius * self.width * self.adc_bits

    @property
    def total_bits(self) -> int:
        """Accumulators + thresholds + line buffer."""
        return self.accumulator_bits + self.threshold_bits + self.line_buffer_bits


def _banks(name: str, depth: int, width: int, bank_words: int) -> list[MemoryShape]:
    full, rest = divmod(depth, bank_words)
    out = [MemoryShape(name, bank_words, width, copies=full)] if full else []
    return out + ([MemoryShape(name, rest, width)] if rest else [])


def state_memories(layout: StateLayout, lanes: int, organisation: str = "packed",
                   bank_words: int = RTL_BANK_WORDS) -> list[MemoryShape]:
    """The memories of ``layout`` at ``lanes`` lanes in ``organisation`` (module
    docstring); the line buffer last (``name == "line buffer"``)."""
    if organisation not in ORGANISATIONS:
        raise RvsmError(f"unknown memory organisation {organisation!r}; choose one of: "
                        f"{', '.join(ORGANISATIONS)}")
    if lanes < 1:
        raise RvsmError(f"lanes must be >= 1, got {lanes}")
    groups = -(-layout.width // lanes)
    out: list[MemoryShape] = []

    def words(p: int) -> int:
        return -(-layout.height // p) * groups

    if organisation == "packed":
        for p in sorted({s.pitch for s in layout.scales}):
            sc = [s for s in layout.scales if s.pitch == p]
            tag = "" if p == 1 else f" (pitch {p})"
            lanes_p = -(-lanes // p)
            out.append(MemoryShape(f"accumulators{tag}", words(p),
                                   lanes_p * sum(s.accumulator_bits for s in sc)))
            t = sum(s.threshold_bits for s in sc)
            if t:
                out.append(MemoryShape(f"thresholds{tag}", words(p), lanes_p * t))
    else:
        for i, s in enumerate(layout.scales):
            lanes_p = -(-lanes // s.pitch)
            for what, bits in (("accumulators", s.accumulator_bits),
                               ("thresholds", s.threshold_bits)):
                if not bits:
                    continue
                name, depth = f"{what} s{i}", words(s.pitch)
                if organisation == "rtl":
                    out += _banks(name, depth, lanes_p * bits, bank_words)
                else:
                    out.append(MemoryShape(name, depth, lanes_p * bits))
    if layout.radius:
        out.append(MemoryShape("line buffer", groups,
                               2 * layout.radius * lanes * layout.adc_bits))
    return out


@dataclass(frozen=True)
class StatePacking:
    """Where each state memory goes on a device: ``placed`` rows ``(memory, where,
    primitives, how)`` with ``where`` ``"bram"``, ``"extra"`` (e.g. SPRAM) or
    ``"lutram"``; totals per resource; ``unplaceable`` memories no primitive's ports
    serve."""

    organisation: str
    lanes: int
    placed: tuple[tuple[MemoryShape, str, int, str], ...]
    bram: int
    extra: int
    lutram: int
    lutram_lut4: int
    unplaceable: tuple[str, ...] = field(default=())

    def rows(self) -> list[str]:
        """One line per memory: what, shape, where and how many primitives."""
        return [f"{m.name}: {m.copies} x {m.depth} x {m.width} bits -> {n} {where} ({how})"
                if m.copies > 1 else
                f"{m.name}: {m.depth} x {m.width} bits -> {n} {where} ({how})"
                for m, where, n, how in self.placed]


def pack_state(layout: StateLayout, lanes: int, device: DeviceBudget,
               organisation: str = "packed") -> StatePacking:
    """Place the memories of ``layout`` at ``lanes`` lanes (:func:`state_memories`) on
    ``device``: the line buffer in distributed RAM if the device has enough, the rest in
    block RAM (``organisation == "rtl"``: in the aspect the RTL instantiates, if any),
    the largest first into the device's extra RAM while it has room (the UP5K's SPRAM)."""
    mems = state_memories(layout, lanes, organisation)
    aspects = (device.rtl_aspect,) if organisation == "rtl" and device.rtl_aspect else None
    placed, bad = [], []
    bram = extra = lutram = 0
    lines = [m for m in mems if m.name == "line buffer"]
    state = [m for m in mems if m.name != "line buffer"]
    lr = device.lutram
    for m in lines:
        n = -(-m.depth // lr.depth) * -(-m.width // lr.width) * m.copies if lr else 0
        if lr and lutram + n <= lr.available:
            lutram += n
            placed.append((m, "lutram", n, f"{lr.name} {lr.depth}x{lr.width}"))
        else:
            state.append(m)
    packs = []
    for m in state:
        p = pack(m, device.bram_kind, None if m.name == "line buffer" else aspects)
        if p is None:
            bad.append(m.name)
        else:
            packs.append(p)
    for p in sorted(packs, key=lambda p: -p.primitives):
        m = p.memory
        if device.extra_kind is not None and m.name != "line buffer":
            q = pack(m, device.extra_kind)
            if q is not None and extra + q.primitives <= device.extra_ram:
                extra += q.primitives
                placed.append((m, "extra", q.primitives, f"{q.kind}: {q.text()}"))
                continue
        bram += p.primitives
        placed.append((m, "bram", p.primitives, f"{p.kind}: {p.text()}"))
    return StatePacking(organisation, lanes, tuple(placed), bram, extra, lutram,
                        lutram * lr.lut4 if lr else 0, tuple(bad))
