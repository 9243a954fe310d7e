"""Constant-weight receptive-field sums: shift-and-add, grouped by equal weight.

One accumulator's per-step input is ``sum_{di,dj} w[di,dj] * code[y+di, x+dj]`` (codes
outside the array are 0, so those taps are simply dropped). The weights are constants,
so no multiplier is built:

1. taps with the same weight are first added together (DoG/Gaussian kernels are 8-fold
   symmetric, so a 9x9 kernel has at most 15 distinct weights);
2. each group sum is multiplied by its constant with canonical-signed-digit (CSD)
   shift-and-add: ``|w| = sum_k d_k 2^k``, ``d_k in {-1, 0, +1}``, no two adjacent
   non-zero digits, so at most ``ceil(bits/2)`` adders per distinct weight;
3. positive and negative terms are added in balanced trees and subtracted once.

All adders work modulo ``2**width`` where ``width`` is the signed width of the exact sum
range (:meth:`ArrayContract.sum_range`); since the true result fits, the two's-complement
result is exact and no intermediate word grows beyond ``width`` bits.
"""

from __future__ import annotations

from collections.abc import Sequence

from amaranth.hdl import Module, Value, signed, unsigned
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from rvsm.model.fixed.widths import signed_bits_for, unsigned_max

__all__ = ["ReceptiveSum", "csd_digits", "sum_width", "weighted_sum"]


def csd_digits(value: int) -> list[tuple[int, int]]:
    """Canonical signed digits of ``value >= 0`` as ``[(shift, +1|-1), ...]``."""
    if value < 0:
        raise ValueError("csd_digits takes a non-negative value")
    digits: list[tuple[int, int]] = []
    k = 0
    while value:
        if value & 1:
            d = 2 - (value & 3)  # +1 if value % 4 == 1, -1 if value % 4 == 3
            digits.append((k, d))
            value -= d
        value >>= 1
        k += 1
    return digits


def sum_width(lo: int, hi: int) -> int:
    """Bits of a signed word holding every integer in ``lo..hi`` (at least 2)."""
    return signed_bits_for(lo, hi, minimum=2)


def _tree_add(terms: list[Value], width: int) -> Value:
    """Balanced modular (``width``-bit) adder tree over ``terms``; 0 when empty."""
    if not terms:
        return Value.cast(0)
    level = list(terms)
    while len(level) > 1:
        nxt = [(level[i] + level[i + 1])[:width] for i in range(0, len(level) - 1, 2)]
        if len(level) % 2:
            nxt.append(level[-1])
        level = nxt
    return level[0]


def weighted_sum(
    inputs: Sequence[Value], weights: Sequence[int], lo: int, hi: int
) -> Value:
    """``sum(w * x)`` for constant ``weights`` as a signed value of :func:`sum_width`.

    ``inputs`` are unsigned values; ``lo..hi`` must bound the exact result (it does when
    it comes from the contract's ``sum_range``). Zero weights are dropped.
    """
    width = sum_width(lo, hi)
    groups: dict[int, list[Value]] = {}
    for x, w in zip(inputs, weights, strict=True):
        if w:
            groups.setdefault(int(w), []).append(Value.cast(x))
    pos: list[Value] = []
    neg: list[Value] = []
    for w in sorted(groups):
        group = _tree_add([x.as_unsigned()[:width] for x in groups[w]], width)
        for shift, d in csd_digits(abs(w)):
            term = (group << shift)[:width]
            (pos if (d > 0) == (w > 0) else neg).append(term)
    total = (_tree_add(pos, width) - _tree_add(neg, width))[:width]
    return total.as_signed()


class ReceptiveSum(wiring.Component):
    """Stand-alone combinational weighted sum, for unit tests of :func:`weighted_sum`.

    Ports: ``inputs`` (``n * input_bits``, tap ``i`` at bits ``[i*input_bits +:
    input_bits]``), ``sum`` (signed, exact).
    """

    def __init__(self, weights: Sequence[int], input_bits: int):
        self.weights = [int(w) for w in weights]
        self.input_bits = input_bits
        full = unsigned_max(input_bits)
        self.lo = sum(w for w in self.weights if w < 0) * full
        self.hi = sum(w for w in self.weights if w > 0) * full
        self.width = sum_width(self.lo, self.hi)
        super().__init__({
            "inputs": In(unsigned(len(self.weights) * input_bits)),
            "sum": Out(signed(self.width)),
        })

    def elaborate(self, platform: object) -> Module:
        """The adder network."""
        m = Module()
        n = self.input_bits
        taps = [self.inputs[i * n:(i + 1) * n] for i in range(len(self.weights))]
        m.d.comb += self.sum.eq(weighted_sum(taps, self.weights, self.lo, self.hi))
        return m
