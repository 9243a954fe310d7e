"""An I/O harness that makes any Amaranth component placeable on an FPGA with a few pins.

A pixel array's ports are far wider than any package has pins (a 64x64 fully parallel
array has 28,672 input bits), and unconnected ports let synthesis delete the logic they
feed. :class:`IoHarness` wraps any :class:`amaranth.lib.wiring.Component` by walking its
signature (:meth:`~amaranth.lib.wiring.Signature.flatten`, nested and array members
included) and replaces its ports with on-chip stimulus and a compacted response:

* **Inputs.** A 32-bit maximal-length Fibonacci LFSR (taps 32, 22, 2, 1) feeds a shift
  chain of flip-flops, one per input bit; input bit ``i`` of the component is the LFSR
  output delayed by ``i + 1`` cycles. Every input bit is therefore a distinct,
  pseudo-random register (identical drivers would let yosys merge identical lanes and
  under-count area), and every input path starts at a flip-flop, as it would behind a
  real receiver. Inputs listed in ``hold`` are tied to a constant instead; by default
  one-bit handshake/enable inputs named ``valid``, ``strobe``, ``en``, ``enable``,
  ``ce`` or ``ready`` (last path element) are held at 1, so the datapath runs every cycle.
* **Outputs.** Every output bit of the component is XOR-reduced in groups of 16 (two
  levels of LUT4), each group registered, and the groups reduced again the same way until
  at most ``pins`` bits remain; those drive the top-level ``pins`` port. Any output bit
  flipping flips a pin, so no logic that reaches an output can be removed, and every
  harness path has at most two LUT levels between flip-flops, off the design's critical
  path.

The top level has ports ``clk``, ``rst`` and ``pins`` only. The harness' own cost is
:attr:`IoHarness.overhead_ff` flip-flops (exact) and about :attr:`IoHarness.overhead_lut`
LUT4 (XOR trees); reports state both so the design's own area can be read off.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from amaranth.hdl import Cat, Const, Elaboratable, Module, Signal, Value, unsigned
from amaranth.lib import wiring

from rvsm.model.infra.errors import RvsmError

__all__ = [
    "DEFAULT_HOLD_NAMES",
    "LFSR_TAPS",
    "XOR_GROUP",
    "IoHarness",
    "PortBits",
    "component_ports",
]

#: Feedback taps of the 32-bit maximal-length LFSR (x^32 + x^22 + x^2 + x + 1).
LFSR_TAPS: tuple[int, ...] = (32, 22, 2, 1)
#: Output bits XOR-ed per registered group: 16 inputs = two levels of LUT4.
XOR_GROUP = 16
#: One-bit inputs held at 1 by default (matched against the last path element).
DEFAULT_HOLD_NAMES: tuple[str, ...] = ("valid", "strobe", "en", "enable", "ce", "ready")


@dataclass(frozen=True)
class PortBits:
    """One flattened port of a component: its path, direction and width (bits)."""

    path: tuple[str | int, ...]
    direction: str  # "in" or "out"
    width: int

    @property
    def name(self) -> str:
        """Dotted path, e.g. ``"codes"`` or ``"stream.valid"``."""
        return ".".join(str(p) for p in self.path)


def component_ports(component: wiring.Component) -> list[tuple[PortBits, Value]]:
    """Every port of ``component`` with its Amaranth value, in signature order.

    Members whose value is a constant (e.g. ``ready`` of an ``always_ready`` stream) are
    not ports and are left out.
    """
    out = []
    for path, member, value in component.signature.flatten(component):
        v = Value.cast(value)
        if isinstance(v, Const):
            continue
        direction = "in" if member.flow == wiring.In else "out"
        out.append((PortBits(tuple(path), direction, len(v)), v))
    return out


def _default_hold(ports: list[PortBits]) -> dict[str, int]:
    return {p.name: 1 for p in ports
            if p.direction == "in" and p.width == 1 and str(p.path[-1]) in DEFAULT_HOLD_NAMES}


class IoHarness(Elaboratable):
    """``component`` with LFSR-driven inputs and XOR-compacted registered outputs.

    ``hold`` maps dotted input paths to constants (``None``: the default handshake rule
    of the module docstring; ``{}``: every input pseudo-random). ``pins`` is the number of
    output pins (>= 1). Top-level ports: :attr:`pins_out` (``pins`` bits); the clock and
    synchronous reset come from the ``sync`` domain (``clk``, ``rst``).
    """

    def __init__(self, component: wiring.Component, pins: int = 8,
                 hold: Mapping[str, int] | None = None):
        self._MustUse__silence = True  # an __init__ that raises is not an unused design
        if pins < 1:
            raise RvsmError(f"the harness needs at least one output pin, got {pins}")
        self.component = component
        self.ports = component_ports(component)
        infos = [p for p, _ in self.ports]
        self.hold = dict(_default_hold(infos) if hold is None else hold)
        names = {p.name for p in infos if p.direction == "in"}
        unknown = sorted(set(self.hold) - names)
        if unknown:
            raise RvsmError(f"harness hold names unknown input(s) {unknown}; inputs are "
                            f"{sorted(names)}")
        self.input_bits = sum(p.width for p in infos
                              if p.direction == "in" and p.name not in self.hold)
        self.output_bits = sum(p.width for p in infos if p.direction == "out")
        if self.output_bits == 0:
            raise RvsmError("the component has no outputs: synthesis would remove it all")
        self.num_pins = min(pins, self.output_bits)
        self.xor_stages = self._plan_xor_stages(self.output_bits, self.num_pins)
        self.pins_out = Signal(self.num_pins, name="pins")
        self._MustUse__silence = False

    @staticmethod
    def _plan_xor_stages(n: int, pins: int) -> list[int]:
        """Bit counts after each registered XOR stage, down to at most ``pins``."""
        stages = []
        while n > pins:
            n = max(pins, -(-n // XOR_GROUP))
            stages.append(n)
        return stages or [n]

    @property
    def overhead_ff(self) -> int:
        """Flip-flops the harness adds: LFSR, input chain and XOR-stage registers."""
        return LFSR_TAPS[0] + self.input_bits + sum(self.xor_stages)

    @property
    def overhead_lut(self) -> int:
        """About how many LUT4 the harness' XOR trees take (a LUT4 XORs 4 bits)."""
        total, n = 0, self.output_bits
        for m in self.xor_stages:
            per = -(-n // m)
            total += m * -(-(per - 1) // 3) if per > 1 else 0
            n = m
        return total

    def elaborate(self, platform: object) -> Module:
        """LFSR, input shift chain, component, registered XOR reduction."""
        m = Module()
        m.submodules.dut = self.component

        width = LFSR_TAPS[0]
        lfsr = Signal(unsigned(width), init=1, name="lfsr")
        feedback = lfsr[LFSR_TAPS[0] - 1]
        for t in LFSR_TAPS[1:]:
            feedback = feedback ^ lfsr[t - 1]
        m.d.sync += lfsr.eq((lfsr << 1) | feedback)

        if self.input_bits:
            chain = Signal(self.input_bits, name="stim")
            m.d.sync += chain.eq((chain << 1) | lfsr[width - 1])
        pos = 0
        outputs = []
        for info, value in self.ports:
            if info.direction == "out":
                outputs.append(value)
            elif info.name in self.hold:
                m.d.comb += value.eq(Const(self.hold[info.name], len(value)))
            else:
                m.d.comb += value.eq(chain[pos:pos + info.width])
                pos += info.width

        bits = [v[i] for v in outputs for i in range(len(v))]
        for k, n in enumerate(self.xor_stages):
            if n >= len(bits):  # nothing to compact (few output bits): register only
                stage = Signal(len(bits), name=f"xor_s{k}")
                for i, b in enumerate(bits):
                    m.d.sync += stage[i].eq(b)
            else:
                stage = Signal(n, name=f"xor_s{k}")
                for j in range(n):
                    acc = Const(0, 1)
                    for b in bits[j::n]:
                        acc = acc ^ b
                    m.d.sync += stage[j].eq(acc)
            bits = [stage[i] for i in range(len(stage))]
        m.d.comb += self.pins_out.eq(Cat(*bits))
        return m
