"""linear_form: exact forms of adder networks read from their netlist, modular where they
truncate, refusals of what is not linear, and a wrong coefficient put into the netlist
caught (by the forms, and by the stream's ``sums.linear_forms`` check)."""

from __future__ import annotations

import copy
import dataclasses

import pytest
from amaranth.hdl import Cat, Const, Mux, Signal, signed

from rvsm.rtl.linear_form import adder_netlist, linear_form, linear_forms, netlist_forms
from rvsm.rtl.receptive_sum import weighted_sum

WEIGHTS = [3, -5, 3, 7]


def _leaves(n=4, bits=4):
    xs = [Signal(bits, name=f"x{i}") for i in range(n)]
    return xs, dict(enumerate(xs))


def test_weighted_sum_expands_to_its_weights():
    xs, leaves = _leaves()
    f = linear_form(weighted_sum(xs, WEIGHTS, -75, 195), leaves)
    assert f.coefs == {0: 3, 1: -5, 2: 3, 3: 7} and f.const == 0
    # its 9 bits, read as the signed word they are, hold -75..195: exactly the sum
    assert f.bits is None and (f.lo, f.hi) == (-75, 195)


def test_truncation_makes_the_form_modular():
    xs, leaves = _leaves()
    exact, low3, shifted = linear_forms(
        [xs[0] + xs[1], (xs[0] + xs[1])[:3], (xs[0] << 2) + Const(5, 8)], leaves)
    assert exact.bits is None and exact.coefs == {0: 1, 1: 1}
    assert low3.bits == 3
    assert shifted.coefs == {0: 4} and shifted.const == 5


def test_zero_extension_of_a_negative_word_is_not_exact():
    xs, leaves = _leaves()
    f = linear_form(Cat(xs[0] - xs[1], Const(0, 3)), leaves)
    assert f.bits == 5  # only the low 5 bits are xs0 - xs1 (mod 32)
    assert f.coefs == {0: 1, 1: -1}


def test_sign_extension_and_constants_are_exact():
    xs, leaves = _leaves()
    wide, const = linear_forms([(xs[0] - xs[1]).as_signed() + xs[2],
                                Const(-3, signed(5))], leaves)
    assert wide.bits is None and wide.coefs == {0: 1, 1: -1, 2: 1}
    assert (wide.lo, wide.hi) == (-15, 30)
    assert const.coefs == {} and const.const == -3 and const.bits is None


def test_what_is_not_an_adder_network_is_refused():
    xs, leaves = _leaves()
    with pytest.raises(ValueError, match="mux"):
        linear_form(Mux(xs[0][0], xs[1], xs[2]), leaves)
    with pytest.raises(ValueError, match="slice not from bit 0"):
        linear_form(xs[0][1:], leaves)
    with pytest.raises(ValueError, match="stranger"):
        linear_form(xs[0] + Signal(4, name="stranger"), leaves)
    with pytest.raises(ValueError, match="unsigned"):
        linear_form(xs[0], {0: Signal(signed(4), name="s")})


def _wrong_shift(module: dict) -> str:
    """Shift the first constant left shift of ``module`` by one bit more: its operand's
    coefficient doubles. The cell's name."""
    for name, cell in module["cells"].items():
        b = cell["connections"].get("B", [])
        if cell["type"] == "$shl" and b and all(bit in ("0", "1") for bit in b):
            shift = int("".join(reversed(b)), 2) + 1
            cell["connections"]["B"] = list(reversed(format(shift, "b")))
            cell["parameters"]["B_WIDTH"] = format(shift.bit_length(), "032b")
            return name
    raise AssertionError("no constant shift in the netlist")


def test_a_wrong_coefficient_in_the_netlist_is_caught():
    xs, leaves = _leaves()
    netlist = adder_netlist([weighted_sum(xs, WEIGHTS, -75, 195)], leaves)
    assert netlist_forms(netlist)[0].coefs == dict(enumerate(WEIGHTS))
    module = copy.deepcopy(netlist.module)
    _wrong_shift(module)
    wrong = netlist_forms(dataclasses.replace(netlist, module=module))[0]
    assert wrong.coefs != dict(enumerate(WEIGHTS))
    assert sorted(wrong.coefs) == [0, 1, 2, 3]  # still a linear form, of other weights


def test_the_sum_lemma_catches_a_wrong_coefficient_in_the_netlist(formal_point,
                                                                  monkeypatch):
    """The stream's ``sums.linear_forms`` check reads the netlist: one shift made longer
    in it is a failure naming a pixel's weight."""
    import rvsm.rtl.linear_form as lf
    from rvsm.rtl.stream.formal_lemmas import StreamSumLemma

    contract = dataclasses.replace(formal_point, height=3, width=4).contract()
    assert StreamSumLemma(contract, 2).offline_failures() == []
    real = lf.adder_netlist

    def tampered(values, leaves):
        netlist = real(values, leaves)
        _wrong_shift(netlist.module)
        return netlist

    monkeypatch.setattr(lf, "adder_netlist", tampered)
    failures = StreamSumLemma(contract, 2).offline_failures()
    assert failures and all(name == "sums.linear_forms" for name, _ in failures)
    assert any(" has weight " in text for _, text in failures)
