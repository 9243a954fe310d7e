"""The register file against its Python model (:mod:`rvsm.rtl.ip.register_model`): random
writes and reads, every response and read-back compared; and the SLVERR promises of
``docs/ip.md`` for fields whose width is exactly their maximum's."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.rtl.amaranth_sim import run_simulation
from rvsm.rtl.ip.axi_lite import AxiLiteRegisters
from rvsm.rtl.ip.register_map import RESP_OKAY, RESP_SLVERR, RegisterMap, ip_register_map
from rvsm.rtl.ip.register_model import RegisterFileModel, field_key
from tests.conftest import model_contract


def _regmap(model: str, size: int, lanes: int) -> RegisterMap:
    return ip_register_map(model_contract(model, size, size), lanes, 8, "0" * 16, "0" * 16,
                           "0.1.0")


def _interesting_values(rm: RegisterMap, rng: np.random.Generator, reg) -> int:  # noqa: ANN001
    """A value for ``reg`` that sits on or just past a field's limits, or random."""
    value = int(rng.integers(0, 1 << 32))
    for f in reg.fields:
        if f.max is not None and rng.random() < 0.8:
            span = reg.span(f)
            pick = int(rng.choice([f.max, f.max + 1, (1 << f.width), (1 << span) - 1, 0]))
            pick &= (1 << span) - 1
            value = (value & ~(((1 << span) - 1) << f.lsb)) | (pick << f.lsb)
    return value & 0xFFFFFFFF


def _operations(rm: RegisterMap, seed: int, count: int) -> list[tuple]:
    rng = np.random.default_rng(seed)
    offsets = [r.offset for r in rm.registers]
    ops = []
    for _ in range(count):
        if rng.random() < 0.85:
            addr = int(rng.choice(offsets)) | int(rng.integers(0, 4))
        else:
            addr = int(rng.integers(0, 1 << rm.addr_bits))
        model = RegisterFileModel(rm)
        reg = model.register_at(addr)
        data = _interesting_values(rm, rng, reg) if reg is not None \
            else int(rng.integers(0, 1 << 32))
        strb = 0xF if rng.random() < 0.9 else int(rng.integers(0, 15))
        ops.append(("w" if rng.random() < 0.6 else "r", addr, data, strb))
    return ops


def _run_rtl(rm: RegisterMap, ops: list[tuple], inputs: dict[str, int]) -> list[tuple]:
    dut = AxiLiteRegisters(rm)
    bus = dut.bus
    seen: list[tuple] = []

    async def bench(ctx) -> None:  # noqa: ANN001
        for key, value in inputs.items():
            ctx.set(dut.value[key], value)
        ctx.set(bus.bready, 1)
        ctx.set(bus.rready, 1)
        for kind, addr, data, strb in ops:
            if kind == "w":
                ctx.set(bus.awaddr, addr)
                ctx.set(bus.wdata, data)
                ctx.set(bus.wstrb, strb)
                ctx.set(bus.awvalid, 1)
                ctx.set(bus.wvalid, 1)
                await ctx.tick()
                ctx.set(bus.awvalid, 0)
                ctx.set(bus.wvalid, 0)
                while not ctx.get(bus.bvalid):
                    await ctx.tick()
                seen.append(("w", ctx.get(bus.bresp)))
                await ctx.tick()
            else:
                ctx.set(bus.araddr, addr)
                ctx.set(bus.arvalid, 1)
                await ctx.tick()
                ctx.set(bus.arvalid, 0)
                while not ctx.get(bus.rvalid):
                    await ctx.tick()
                seen.append(("r", ctx.get(bus.rresp), ctx.get(bus.rdata)))
                await ctx.tick()

    run_simulation(dut, bench)
    return seen


def _run_model(rm: RegisterMap, ops: list[tuple], inputs: dict[str, int]) -> list[tuple]:
    model = RegisterFileModel(rm, inputs)
    out: list[tuple] = []
    for kind, addr, data, strb in ops:
        if kind == "w":
            out.append(("w", model.write(addr, data, strb)))
        else:
            value, resp = model.read(addr)
            out.append(("r", resp, value))
    return out


def _driven_inputs(rm: RegisterMap, seed: int) -> dict[str, int]:
    """Constant values for the fields the IP drives (live RO, external RW)."""
    rng = np.random.default_rng(seed + 1000)
    inputs = {}
    for r in rm.registers:
        for f in r.fields:
            if (f.access == "RO" and f.live) or f.external:
                top = f.max if f.max is not None else (1 << f.width) - 1
                inputs[field_key(r, f)] = int(rng.integers(0, top + 1))
    return inputs


@pytest.mark.parametrize(("model", "size", "lanes", "seed"),
                         [("dog4", 8, 2, 1), ("fsm", 8, 4, 2), ("dog2", 16, 8, 3)])
def test_random_accesses_match_the_register_model(model: str, size: int, lanes: int,
                                                  seed: int) -> None:
    rm = _regmap(model, size, lanes)
    ops = _operations(rm, seed, 250)
    inputs = _driven_inputs(rm, seed)
    rtl, expected = _run_rtl(rm, ops, inputs), _run_model(rm, ops, inputs)
    for n, (op, got, want) in enumerate(zip(ops, rtl, expected, strict=True)):
        assert got == want, (n, op, got, want)
    # the sequence exercised both answers of writes and reads
    assert {e[1] for e in expected if e[0] == "w"} == {RESP_OKAY, RESP_SLVERR}


def test_a_value_too_wide_for_its_field_is_refused() -> None:
    """dog4: the scale field is 2 bits for scales 0..3; scale 4 must answer SLVERR, not
    alias to 0 (issue 34, finding 6); so must a word index of exactly 2**bits."""
    rm = _regmap("dog4", 8, 2)
    thr_addr = rm["THR_ADDR"]
    scale, word = rm.field("THR_ADDR", "scale"), rm.field("THR_ADDR", "word")
    assert (1 << scale.width) - 1 == scale.max  # the case that used to alias
    ops = [("w", thr_addr.offset, 4 << scale.lsb, 0xF),
           ("w", thr_addr.offset, 3 << scale.lsb, 0xF),
           ("w", thr_addr.offset, (1 << word.width) << word.lsb, 0xF)]
    got = _run_rtl(rm, ops, {})
    assert [g[1] for g in got] == [RESP_SLVERR, RESP_OKAY, RESP_SLVERR]
    assert got == _run_model(rm, ops, {})
