"""linear_form: exact forms of adder networks, modular where they truncate, and refusals
of what is not linear."""

from __future__ import annotations

import pytest
from amaranth.hdl import Cat, Const, Mux, Signal

from rvsm.rtl.linear_form import linear_form
from rvsm.rtl.receptive_sum import weighted_sum


def _leaves(n=4, bits=4):
    xs = [Signal(bits, name=f"x{i}") for i in range(n)]
    return xs, {id(x): i for i, x in enumerate(xs)}


def test_weighted_sum_expands_to_its_weights():
    xs, leaves = _leaves()
    f = linear_form(weighted_sum(xs, [3, -5, 3, 7], -75, 195), leaves)
    assert f.coefs == {0: 3, 1: -5, 2: 3, 3: 7} and f.const == 0
    assert f.bits == 9 and (f.lo, f.hi) == (-75, 195)


def test_truncation_makes_the_form_modular():
    xs, leaves = _leaves()
    assert linear_form(xs[0] + xs[1], leaves).bits is None
    assert linear_form((xs[0] + xs[1])[:3], leaves).bits == 3
    assert linear_form((xs[0] << 2) + Const(5, 8), leaves).coefs == {0: 4}


def test_zero_extension_of_a_negative_word_is_not_exact():
    xs, leaves = _leaves()
    f = linear_form(Cat(xs[0] - xs[1], Const(0, 3)), leaves)
    assert f.bits == 5  # only the low 5 bits are xs0 - xs1 (mod 32)


def test_what_is_not_an_adder_network_is_refused():
    xs, leaves = _leaves()
    with pytest.raises(ValueError):
        linear_form(Mux(xs[0][0], xs[1], xs[2]), leaves)
    with pytest.raises(ValueError):
        linear_form(xs[0][1:], leaves)
    with pytest.raises(ValueError):
        linear_form(xs[0] + Signal(4, name="stranger"), leaves)
