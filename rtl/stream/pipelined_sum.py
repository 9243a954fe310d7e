"""Pipelined constant-weight receptive sums: shared symmetry orbits, retimed adder trees.

The streaming array (:mod:`rvsm.rtl.stream.array`) computes, per lane and per step,
``sum_s = sum_{dy,dx} w_s[dy,dx] * code[y+dy, x+dx]`` for every scale ``s``. Two ideas
from :mod:`rvsm.rtl.receptive_sum` are extended here:

1. **Orbits shared across scales.** When every kernel has the 8-fold symmetry of the
   DoG / Gauss templates, the codes of one orbit ``{(+-a, +-b), (+-b, +-a)}`` carry the
   same weight in every scale, so they are summed once per lane (:func:`weighted_orbits`)
   and each scale weights the orbit sums. Without the symmetry every tap is its own orbit.
2. **Constant weights as canonical signed digits** (:func:`~rvsm.rtl.receptive_sum.csd_digits`):
   ``w * orbit = sum_k +-(orbit << k)``; the signed terms of a scale are added in one
   tree, modulo ``2**width`` with ``width`` the exact sum's signed width (exact, since the
   true result fits; see :mod:`rvsm.rtl.receptive_sum`).

:class:`Pipeline` retimes the trees: every value carries the number of registers it has
passed (its *stage*) and the adder levels since its last register (its *level*). An add
first delays the earlier operand to the later one's stage (delay registers are shared:
one chain per value), and registers both when the add would exceed
``levels_per_stage`` levels. Operands are paired earliest first (Huffman order on
``(stage, level)``), which gives the shallowest tree. All registers load when
``enable`` is high (the streaming array's beat advance), so stages count beats.

With ``m=None`` a :class:`Pipeline` only plans: it tracks stages without building
hardware, which gives the pipeline depth before elaboration (a named property of the
array, never a number in a test).
"""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from amaranth.hdl import Cat, Const, Module, Signal, Value, unsigned

from rvsm.model.kernels.geometry import is_symmetric, kernel_radius, orbit_taps, symmetric_orbits
from rvsm.rtl.receptive_sum import csd_digits

__all__ = ["Orbit", "Pipeline", "Timed", "orbit_terms", "weighted_orbits"]


@dataclass(frozen=True)
class Orbit:
    """Taps summed together (``(dy, dx)`` offsets) and their weight in each scale."""

    offsets: tuple[tuple[int, int], ...]
    weights: tuple[int, ...]


def weighted_orbits(weights: Sequence[Sequence[Sequence[int]]]) -> list[Orbit]:
    """The orbits of the kernels' non-zero taps, with per-scale weights.

    8-fold symmetric kernels (all of them) give the orbits of
    :func:`~rvsm.model.kernels.geometry.symmetric_orbits` up to the kernels' radius
    (1, 4 or 8 taps); otherwise each non-zero tap is an orbit. Orbits whose weight is
    zero in every scale are dropped.
    """
    kernels = [np.asarray(k, dtype=np.int64) for k in weights]
    radius = kernel_radius(kernels)

    def weight(k: np.ndarray, dy: int, dx: int) -> int:
        half = k.shape[0] // 2
        if abs(dy) > half or abs(dx) > half:
            return 0
        return int(k[half + dy, half + dx])

    if all(is_symmetric(k) for k in kernels):
        groups = [orbit_taps(a, b) for a, b in symmetric_orbits(radius)]
    else:
        groups = [((dy, dx),) for dy in range(-radius, radius + 1)
                  for dx in range(-radius, radius + 1)]
    orbits: list[Orbit] = []
    for taps in groups:
        dy, dx = taps[0]
        ws = tuple(weight(k, dy, dx) for k in kernels)
        if any(ws):
            orbits.append(Orbit(taps, ws))
    return orbits


def _fit(value: Value, shift: int, width: int) -> Value:
    """``(value << shift) mod 2**width`` as exactly ``width`` unsigned bits."""
    v = Value.cast(value).as_unsigned()
    if shift:
        v = Cat(Const(0, shift), v)
    if len(v) >= width:
        return v[:width]
    return Cat(v, Const(0, width - len(v)))


class Timed:
    """A value in the pipeline: ``stage`` registers passed, ``level`` adders since."""

    __slots__ = ("value", "stage", "level", "_next")

    def __init__(self, value: Value | None, stage: int, level: int = 0):
        self.value = value
        self.stage = stage
        self.level = level
        self._next: Timed | None = None


class Pipeline:
    """Builder of retimed adder trees whose registers load on ``enable``.

    ``m`` is the module to add registers to, or ``None`` to plan only (values are
    ``None`` then). :meth:`emit` adds every register to ``m`` once building is done.
    Registers are data: reset-less unless ``reset_less=False``.
    """

    def __init__(self, m: Module | None, enable: Value | None = None,
                 levels_per_stage: int = 2, name: str = "p", reset_less: bool = True):
        if levels_per_stage < 1:
            raise ValueError("levels_per_stage must be >= 1")
        self.m = m
        self.enable = enable
        self.levels_per_stage = levels_per_stage
        self.name = name
        self.reset_less = reset_less
        self.registers = 0
        self._pending: list[tuple[Signal, Value]] = []
        self._seq = itertools.count()

    @property
    def planning(self) -> bool:
        """True when no hardware is built (``m is None``)."""
        return self.m is None

    def timed(self, value: Value | None, stage: int = 0, level: int = 0) -> Timed:
        """Wrap ``value`` available at ``stage`` (after ``level`` adder levels)."""
        return Timed(value, stage, level)

    def register(self, t: Timed, name: str | None = None) -> Timed:
        """``t`` one register later (shared: registering ``t`` twice gives one register)."""
        if t._next is None:
            self.registers += 1
            if self.planning:
                value = None
            else:
                reg = Signal(unsigned(len(t.value)), reset_less=self.reset_less,
                             name=name or f"{self.name}_r{self.registers}")
                self._pending.append((reg, t.value))
                value = reg
            t._next = Timed(value, t.stage + 1, 0)
        return t._next

    def at(self, t: Timed, stage: int) -> Timed:
        """``t`` delayed to ``stage`` (``t.stage <= stage``; level 0 when delayed)."""
        if stage < t.stage:
            raise ValueError(f"cannot move a stage-{t.stage} value back to stage {stage}")
        while t.stage < stage:
            t = self.register(t)
        return t

    def settle(self, t: Timed) -> Timed:
        """``t`` itself if it is a register output (level 0), else registered once."""
        return t if t.level == 0 else self.register(t)

    def _combine(self, a: Timed, sa: int, b: Timed, sb: int, width: int,
                 subtract: bool) -> Timed:
        """``(a << sa) +- (b << sb)`` modulo ``2**width``, retimed."""
        stage = max(a.stage, b.stage)
        a, b = self.at(a, stage), self.at(b, stage)
        if max(a.level, b.level) + 1 > self.levels_per_stage:
            stage += 1
            a, b = self.at(a, stage), self.at(b, stage)
        level = max(a.level, b.level) + 1
        if self.planning:
            return Timed(None, stage, level)
        va, vb = _fit(a.value, sa, width), _fit(b.value, sb, width)
        return Timed((va - vb if subtract else va + vb)[:width], stage, level)

    def sum(self, terms: Sequence[tuple[int, Timed, int]], width: int) -> Timed:
        """``sum(sign * (t << shift))`` modulo ``2**width`` for ``(sign, t, shift)`` terms.

        Signs are ``+1`` / ``-1``. The result is an unsigned ``width``-bit value holding
        the two's complement of the exact sum (exact when the sum fits ``width`` signed
        bits). Empty ``terms`` give constant 0 at stage 0.
        """
        if not terms:
            return Timed(None if self.planning else Const(0, width), 0, 0)
        heap = [(t.stage, t.level, next(self._seq), sign, t, shift)
                for sign, t, shift in terms]
        heapq.heapify(heap)
        while len(heap) > 1:
            _, _, _, s1, t1, h1 = heapq.heappop(heap)
            _, _, _, s2, t2, h2 = heapq.heappop(heap)
            if s1 == s2:
                r, sign = self._combine(t1, h1, t2, h2, width, False), s1
            elif s1 > 0:
                r, sign = self._combine(t1, h1, t2, h2, width, True), 1
            else:
                r, sign = self._combine(t2, h2, t1, h1, width, True), 1
            heapq.heappush(heap, (r.stage, r.level, next(self._seq), sign, r, 0))
        _, _, _, sign, t, shift = heap[0]
        if sign < 0:
            zero = Timed(None if self.planning else Const(0, width), t.stage, 0)
            return self._combine(zero, 0, t, shift, width, True)
        if shift:
            return Timed(None if self.planning else _fit(t.value, shift, width),
                         t.stage, t.level)
        return t

    def emit(self) -> None:
        """Add the registers built so far to ``m`` (loading when ``enable`` is high)."""
        if self.planning or not self._pending:
            return
        stmts = [reg.eq(value) for reg, value in self._pending]
        if self.enable is None:
            self.m.d.sync += stmts
        else:
            with self.m.If(self.enable):
                self.m.d.sync += stmts
        self._pending = []


def orbit_terms(orbit_sums: Sequence[Timed], orbits: Sequence[Orbit],
                scale: int) -> list[tuple[int, Timed, int]]:
    """Signed CSD terms ``(sign, orbit_sum, shift)`` of one scale's weighted sum."""
    terms: list[tuple[int, Timed, int]] = []
    for t, orbit in zip(orbit_sums, orbits, strict=True):
        w = orbit.weights[scale]
        for shift, d in csd_digits(abs(w)):
            terms.append((1 if (d > 0) == (w > 0) else -1, t, shift))
    return terms
