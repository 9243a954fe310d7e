"""Exact linear forms of Amaranth adder networks: :func:`linear_form`.

An adder network over unsigned leaf signals (``+``, ``-``, constant ``<<``, low slices,
``Cat`` with constant zeros, ``as_signed``/``as_unsigned``) computes, as an integer,
``sum(coef[k] * leaf[k]) + const`` modulo ``2**bits``: two's-complement adders are a
ring homomorphism onto the integers modulo ``2**bits``, so truncations only lower
``bits``. The one step that is not modular is extending a narrower value with zeros
(``Cat(v, Const(0, k))``, or ``v`` used as the low part of a wider word): it is exact
only when the form of ``v`` is known exactly and its range (leaves from 0 to their
maximum) fits ``v``'s shape; otherwise the form is known modulo ``2**len(v)`` only.
:func:`linear_form` walks the expression tree and returns the form with the number of
low bits it determines, in exact Python integers (the formal ``sums`` lemma compares the
stream's and the parallel array's sums this way: docs/formal.md).
"""

from __future__ import annotations

from collections.abc import Hashable, Mapping
from dataclasses import dataclass

from amaranth.hdl import Const, Shape, Signal, Value
from amaranth.hdl._ast import Concat, Operator, Slice

__all__ = ["LinearForm", "linear_form"]


@dataclass(frozen=True)
class LinearForm:
    """``sum(coefs[k] * leaf[k]) + const``, equal to the value modulo ``2**bits``
    (``bits`` None: exactly); ``lo..hi`` its range over leaves from 0 to their maximum."""

    coefs: dict[Hashable, int]
    const: int
    bits: int | None
    lo: int
    hi: int


def _form(coefs: dict[Hashable, int], const: int, bits: int | None,
          tops: Mapping[Hashable, int]) -> LinearForm:
    coefs = {k: c for k, c in coefs.items() if c}
    lo = const + sum(c * tops[k] for k, c in coefs.items() if c < 0)
    hi = const + sum(c * tops[k] for k, c in coefs.items() if c > 0)
    return LinearForm(coefs, const, bits, lo, hi)


def _min_bits(a: int | None, b: int | None) -> int | None:
    return b if a is None else a if b is None else min(a, b)


def _as_shape(f: LinearForm, shape: Shape, tops: Mapping[Hashable, int]) -> LinearForm:
    """``f``'s value reinterpreted in (truncated to) ``shape``."""
    w = shape.width
    low, high = (-(1 << (w - 1)), (1 << (w - 1)) - 1) if shape.signed else (0, (1 << w) - 1)
    if f.bits is None and low <= f.lo and f.hi <= high:
        return f
    return _form(f.coefs, f.const, _min_bits(f.bits, w), tops)


def linear_form(value: Value, leaves: Mapping[int, Hashable]) -> LinearForm:
    """The linear form of ``value`` over the unsigned signals ``leaves`` maps
    (``id(signal) -> key``); any other signal or operator is a :class:`ValueError`."""
    tops: dict[Hashable, int] = {}
    memo: dict[int, LinearForm] = {}

    def walk(v: Value) -> LinearForm:
        got = memo.get(id(v))
        if got is None:
            got = memo[id(v)] = visit(v)
        return got

    def visit(v: Value) -> LinearForm:
        if isinstance(v, Const):
            return _form({}, v.value, None, tops)
        if isinstance(v, Signal):
            if id(v) not in leaves or v.shape().signed:
                raise ValueError(f"signal {v.name!r} is not an unsigned leaf")
            key = leaves[id(v)]
            tops[key] = (1 << len(v)) - 1
            return _form({key: 1}, 0, None, tops)
        if isinstance(v, Slice):
            if v.start != 0:
                raise ValueError(f"a slice not from bit 0 is not linear: {v!r}")
            return _as_shape(walk(v.value), Shape(v.stop), tops)
        if isinstance(v, Concat):
            coefs: dict[Hashable, int] = {}
            const, bits, offset = 0, None, 0
            for part in v.parts:
                f = _as_shape(walk(part), Shape(len(part)), tops)
                for k, c in f.coefs.items():
                    coefs[k] = coefs.get(k, 0) + (c << offset)
                const += f.const << offset
                if f.bits is not None:
                    bits = _min_bits(bits, offset + f.bits)
                offset += len(part)
            return _as_shape(_form(coefs, const, bits, tops), v.shape(), tops)
        if isinstance(v, Operator):
            ops = [walk(o) for o in v.operands]
            if v.operator in ("u", "s"):
                return _as_shape(ops[0], v.shape(), tops)
            if v.operator == "-" and len(ops) == 1:
                a = ops[0]
                return _as_shape(_form({k: -c for k, c in a.coefs.items()}, -a.const,
                                       a.bits, tops), v.shape(), tops)
            if v.operator in ("+", "-") and len(ops) == 2:
                a, b = ops
                sign = 1 if v.operator == "+" else -1
                coefs = dict(a.coefs)
                for k, c in b.coefs.items():
                    coefs[k] = coefs.get(k, 0) + sign * c
                return _as_shape(_form(coefs, a.const + sign * b.const,
                                       _min_bits(a.bits, b.bits), tops), v.shape(), tops)
            if v.operator == "<<" and isinstance(v.operands[1], Const):
                a, k = ops[0], v.operands[1].value
                return _as_shape(_form({key: c << k for key, c in a.coefs.items()},
                                       a.const << k, None if a.bits is None else a.bits + k,
                                       tops), v.shape(), tops)
        raise ValueError(f"not a linear adder network: {v!r}")

    return walk(Value.cast(value))
