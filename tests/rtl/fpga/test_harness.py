"""The I/O harness: signature walking, LFSR stimulus and XOR-compacted outputs (amaranth.sim)."""

from __future__ import annotations

import pytest
from amaranth.hdl import Module, unsigned
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.amaranth_sim import run_simulation
from rvsm.rtl.fpga.harness import LFSR_TAPS, XOR_GROUP, IoHarness, component_ports


class Echo(wiring.Component):
    """Registers its ``n_in``-bit input ``a`` onto ``n_out`` outputs (cycled), plus a stream."""

    def __init__(self, n_in: int, n_out: int):
        self.n_in, self.n_out = n_in, n_out
        super().__init__({
            "a": In(n_in),
            "strobe": In(1),
            "s": In(stream.Signature(data.ArrayLayout(unsigned(3), 2))),
            "o": Out(stream.Signature(4, always_ready=True)),
            "y": Out(n_out),
            "v": Out(1).array(2),
        })

    def elaborate(self, platform: object) -> Module:
        m = Module()
        bits = [self.a[i % self.n_in] for i in range(self.n_out)]
        for i, b in enumerate(bits):
            m.d.sync += self.y[i].eq(b)
        m.d.comb += [self.s.ready.eq(self.strobe), self.o.valid.eq(self.s.valid),
                     self.o.payload.eq(self.s.payload.as_value()[:4]),
                     self.v[0].eq(self.a[0]), self.v[1].eq(self.strobe)]
        return m


def _unused(*objs: object) -> None:
    """Silence Amaranth's UnusedElaboratable warning for objects only inspected."""
    for obj in objs:
        obj._MustUse__silence = True
        if isinstance(obj, IoHarness):
            obj.component._MustUse__silence = True


def test_component_ports_walks_nested_and_array_members() -> None:
    echo = Echo(5, 7)
    _unused(echo)
    ports = {p.name: (p.direction, p.width) for p, _ in component_ports(echo)}
    assert ports == {
        "a": ("in", 5), "strobe": ("in", 1), "s.payload": ("in", 6), "s.valid": ("in", 1),
        "s.ready": ("out", 1), "o.payload": ("out", 4), "o.valid": ("out", 1),
        "y": ("out", 7), "v.0": ("out", 1), "v.1": ("out", 1),
    }  # o.ready of the always-ready stream is a constant, not a port


def test_default_hold_and_bad_hold() -> None:
    h, free = IoHarness(Echo(5, 7)), IoHarness(Echo(5, 7), hold={})
    _unused(h, free)
    assert h.hold == {"strobe": 1, "s.valid": 1}
    assert h.input_bits == 5 + 6
    assert free.input_bits == 5 + 1 + 6 + 1
    for kwargs, match in (({"hold": {"y": 1}}, "unknown input"),
                          ({"pins": 0}, "at least one output pin")):
        echo = Echo(5, 7)
        _unused(echo)
        with pytest.raises(RvsmError, match=match):
            IoHarness(echo, **kwargs)


def _lfsr_bits(cycles: int) -> list[int]:
    """Software model of the harness LFSR: the bit shifted into the chain each cycle."""
    width = LFSR_TAPS[0]
    state, out = 1, []
    for _ in range(cycles):
        out.append((state >> (width - 1)) & 1)
        fb = 0
        for t in LFSR_TAPS:
            fb ^= (state >> (t - 1)) & 1
        state = ((state << 1) | fb) & ((1 << width) - 1)
    return out


def _run(harness: IoHarness, cycles: int, probe) -> list:  # noqa: ANN001
    rows = []

    async def bench(ctx) -> None:  # noqa: ANN001
        for _ in range(cycles):
            await ctx.tick()
            rows.append(probe(ctx))

    run_simulation(harness, bench)
    return rows


def test_inputs_are_the_lfsr_stream_delayed_per_bit() -> None:
    h = IoHarness(Echo(5, 7), hold={})
    dut = h.component
    rows = _run(h, 60, lambda ctx: (ctx.get(dut.a), ctx.get(dut.strobe),
                                    ctx.get(dut.s.payload.as_value()), ctx.get(dut.s.valid)))
    seq = _lfsr_bits(80)
    # chain bit i after t+1 edges holds the LFSR output of cycle t - i (0 before start)
    for t, (a, strobe, payload, valid) in enumerate(rows):
        chain = sum((seq[t - i] if t - i >= 0 else 0) << i for i in range(h.input_bits))
        assert a == chain & 0x1F
        assert strobe == (chain >> 5) & 1
        assert payload == (chain >> 6) & 0x3F
        assert valid == (chain >> 12) & 1
    assert len({r[0] for r in rows}) > 10  # actually pseudo-random


@pytest.mark.parametrize("n_out", [3, 40, 300])
def test_pins_are_registered_xor_of_outputs(n_out: int) -> None:
    h = IoHarness(Echo(9, n_out), pins=8)
    depth = len(h.xor_stages)

    def probe(ctx):  # noqa: ANN001, ANN202
        outs = [v for p, v in h.ports if p.direction == "out"]
        bits = []
        for v in outs:
            value = ctx.get(v.as_value() if hasattr(v, "as_value") else v)
            bits += [(value >> i) & 1 for i in range(len(v))]
        return bits, ctx.get(h.pins_out)

    rows = _run(h, 40, probe)
    assert len(h.pins_out) == min(8, h.output_bits)
    for t in range(depth, len(rows)):
        bits, _ = rows[t - depth]
        pins = rows[t][1]
        parity = 0
        for b in bits:
            parity ^= b
        assert bin(pins).count("1") % 2 == parity  # every output bit reaches the pins
        if depth == 1:
            n = len(h.pins_out)
            for j in range(n):
                expect = 0
                for b in bits[j::n]:
                    expect ^= b
                assert (pins >> j) & 1 == expect
    assert any(r[1] for r in rows)


def test_xor_stages_keep_two_lut_levels() -> None:
    h = IoHarness(Echo(9, 300), pins=8)
    _unused(h)
    assert h.xor_stages == [-(-(300 + 4 + 1 + 2 + 1) // XOR_GROUP), 8]
    n = h.output_bits
    for m in h.xor_stages:
        assert -(-n // m) <= XOR_GROUP
        n = m
    assert h.overhead_ff == LFSR_TAPS[0] + h.input_bits + sum(h.xor_stages)
