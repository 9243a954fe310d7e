"""cocotb 2.x testbench: the AXI IP's register file, driven by cocotbext-axi's
``AxiLiteMaster`` with a seeded random sequence of writes and reads, every response and
read-back checked against the Python model of the register map
(:class:`~rvsm.rtl.ip.register_model.RegisterFileModel`).

Inputs (environment, or ``+rvsm_<name>=`` plusargs): ``RVSM_STIMULUS`` (a stimulus file:
its contract), ``RVSM_PORTS`` (the build's port map: lanes, FIFO depth, provenance, from
which the register map is rebuilt as the IP's generator made it), ``RVSM_REGMAP`` (JSON:
``seed``, ``count`` operations), ``RVSM_RESULT``.

The sequence: addresses mostly the mapped registers' offsets, else any word of the
address space; values that sit on or just past each field's maximum (judged on its span),
else random; a tenth of the writes partial (one to three byte lanes, so a strobe other
than 0xF). The model follows what the IP does besides its registers: ``THR_ADDR``'s
``external`` fields take a written value and count up after each commit (word, then the
next field, each wrapping past its maximum); live read-only fields read their idle
values (0), except ``OUT_BEATS``/``IN_BEATS``, which must equal the stream handshakes
seen on ``m_axis``/``s_axis`` since the last ``counters_reset``. After a write that
pulses a ``WO`` field (flush, clear...) the bench waits, with the sink always ready, for
``STATUS`` to say the IP is idle before the next operation.
"""

from __future__ import annotations

import json
import random

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import ClockCycles, FallingEdge
from cocotbext.axi import AxiLiteBus, AxiLiteMaster

from rvsm.model.fixed.stimulus import load_stimulus
from rvsm.rtl.ip.register_map import (
    RESP_OKAY,
    RESP_SLVERR,
    Register,
    RegisterMap,
    ip_register_map,
)
from rvsm.rtl.ip.register_model import RegisterFileModel, field_key
from rvsm.rtl.ports import load_ports_json
from rvsm.sim.cosim.testbenches.tb_common import CLOCK_NS, beat_stream, testbench_arg

#: Cycles a WO pulse may keep the IP busy before the bench calls it stuck.
SETTLE_LIMIT = 20_000


def _value_for(rng: random.Random, reg: Register | None) -> int:
    """A 32-bit value: each field with a maximum (80 %) on or just past its limits, or
    a valid value."""
    value = rng.getrandbits(32)
    for f in reg.fields if reg is not None else ():
        if f.max is not None and rng.random() < 0.8:
            span = reg.span(f)
            pick = rng.choice([f.max, f.max + 1, 1 << f.width, (1 << span) - 1, 0,
                               rng.randint(0, f.max), rng.randint(0, f.max)])
            pick &= (1 << span) - 1
            value = (value & ~(((1 << span) - 1) << f.lsb)) | (pick << f.lsb)
    return value & 0xFFFFFFFF


def operations(rm: RegisterMap, seed: int, count: int) -> list[tuple[str, int, int, int]]:
    """``count`` operations ``(kind "w"/"r", word address, data, strobe)``."""
    rng = random.Random(seed)
    model = RegisterFileModel(rm)
    offsets = [r.offset for r in rm.registers]
    ops = []
    for _ in range(count):
        addr = rng.choice(offsets) if rng.random() < 0.85 \
            else rng.randrange(1 << rm.addr_bits) & ~3
        data = _value_for(rng, model.register_at(addr))
        if rng.random() < 0.1:  # one to three contiguous byte lanes
            first = rng.randrange(3)
            n = rng.randint(1, 3 - first)
            strb = ((1 << n) - 1) << first
        else:
            strb = 0xF
        ops.append(("w" if rng.random() < 0.6 else "r", addr, data, strb))
    return ops


class _Handshakes:
    """Counts the stream handshakes of ``prefix`` (``s_axis``/``m_axis``)."""

    def __init__(self, dut: object, prefix: str):
        self.valid = getattr(dut, f"{prefix}_tvalid")
        self.ready = getattr(dut, f"{prefix}_tready")
        self.clk = dut.clk
        self.count = 0

    async def run(self) -> None:
        while True:
            await FallingEdge(self.clk)
            if int(self.valid.value) and int(self.ready.value):
                self.count += 1


class _IpModel(RegisterFileModel):
    """The register model plus the IP's side of it: ``THR_ADDR`` counting up after a
    commit, live fields at their idle values, the beat counters from the handshakes."""

    def __init__(self, rm: RegisterMap, beats: dict[str, _Handshakes]):
        super().__init__(rm)
        self.beats = beats
        self.since_reset = {name: 0 for name in beats}
        for r in rm.registers:
            for f in r.fields:
                if f.external or (f.access == "RO" and f.live):
                    self.inputs[field_key(r, f)] = 0

    def write(self, addr: int, data: int, strb: int = 0xF, refused: bool = False) -> int:
        r = self.register_at(addr)
        resp = super().write(addr, data, strb, refused)
        if resp != RESP_OKAY or r is None:
            return resp
        external = [f for f in r.fields if f.external]
        for f in external:
            self.inputs[field_key(r, f)] = (data >> f.lsb) & ((1 << f.width) - 1)
        if r.commit:
            self._count_up()
        resets = [f for f in r.fields if f.access == "WO" and f.name == "counters_reset"]
        if any((data >> f.lsb) & 1 for f in resets):
            self.since_reset = {name: h.count for name, h in self.beats.items()}
        return resp

    def _count_up(self) -> None:
        """The address register's external fields as one counter, lowest field first."""
        for r in self.regmap.registers:
            fields = sorted((f for f in r.fields if f.external), key=lambda f: f.lsb)
            for f in fields:
                key = field_key(r, f)
                top = f.max if f.max is not None else (1 << f.width) - 1
                if self.inputs[key] < top:
                    self.inputs[key] += 1
                    break
                self.inputs[key] = 0

    def read(self, addr: int) -> tuple[int, int]:
        for name, h in self.beats.items():
            self.inputs[f"{name}.count"] = (h.count - self.since_reset[name]) & 0xFFFFFFFF
        return super().read(addr)


def _pulses(rm: RegisterMap, addr: int, data: int) -> bool:
    """Whether a write of ``data`` to ``addr`` pulses a WO field."""
    r = RegisterFileModel(rm).register_at(addr)
    return r is not None and any(f.access == "WO" and (data >> f.lsb) & 1 for f in r.fields)


@cocotb.test()
async def register_map_matches_model(dut: object) -> None:
    """Random writes and reads through AxiLiteMaster; every response and read-back."""
    stim = load_stimulus(testbench_arg("stimulus"))
    ports = load_ports_json(testbench_arg("ports"))
    cfg = json.loads(testbench_arg("regmap"))
    c, timing, prov = stim.contract, ports["timing"], ports["provenance"]
    geo = beat_stream(ports).geometry(c, int(timing["lanes"]))
    rm = ip_register_map(c, geo.lanes, int(timing["fifo_depth"]), prov["rtl_digest"],
                         prov["design_point_digest"], prov["rvsm_version"])

    cocotb.start_soon(Clock(dut.clk, CLOCK_NS, unit="ns").start())
    axil = AxiLiteMaster(AxiLiteBus.from_prefix(dut, "s_axil"), dut.clk, dut.rst)
    dut.s_axis_tvalid.value = 0
    dut.m_axis_tready.value = 1  # the sink is always ready: flush beats drain
    beats = {"IN_BEATS": _Handshakes(dut, "s_axis"), "OUT_BEATS": _Handshakes(dut, "m_axis")}
    for h in beats.values():
        cocotb.start_soon(h.run())
    dut.rst.value = 1
    await ClockCycles(dut.clk, 3)
    dut.rst.value = 0

    status = rm["STATUS"].offset
    idle = rm.field("STATUS", "busy").mask | rm.field("STATUS", "fifo_level").mask

    async def settle() -> bool:
        for _ in range(SETTLE_LIMIT // 8):
            if not int.from_bytes((await axil.read(status, 4)).data, "little") & idle:
                return True
            await ClockCycles(dut.clk, 8)
        return False

    problems: list[dict] = []
    if not await settle():
        problems.append({"op": -1, "error": "STATUS stays busy after reset"})
    model = _IpModel(rm, beats)
    ops = operations(rm, int(cfg["seed"]), int(cfg["count"]))
    tally = {"w": {RESP_OKAY: 0, RESP_SLVERR: 0}, "r": {RESP_OKAY: 0, RESP_SLVERR: 0}}
    for n, (kind, addr, data, strb) in enumerate(ops):
        if kind == "w":
            first = (strb & -strb).bit_length() - 1
            lanes = data.to_bytes(4, "little")[first:first + bin(strb).count("1")]
            got = int((await axil.write(addr + first, lanes)).resp)
            want = model.write(addr, data, strb)
            seen, expected = (got,), (want,)
            if want == RESP_OKAY and _pulses(rm, addr, data) and not await settle():
                problems.append({"op": n, "error": "STATUS stays busy after a pulse"})
        else:
            resp = await axil.read(addr, 4)
            got = int(resp.resp)
            value, want = model.read(addr)
            seen = (got, int.from_bytes(resp.data, "little"))
            expected = (want, value)
        tally[kind][want] = tally[kind].get(want, 0) + 1
        if seen != expected:
            problems.append({"op": n, "kind": kind, "addr": addr, "data": data,
                             "strb": strb, "got": list(seen), "expected": list(expected)})
    result = {"compared": len(ops), "mismatches": len(problems),
              "first_mismatch": problems[0] if problems else None,
              "mismatch_list": problems[:20],
              "responses": {k: {str(r): v for r, v in t.items()} for k, t in tally.items()},
              "out_beats": beats["OUT_BEATS"].count}
    with open(testbench_arg("result"), "w", encoding="utf-8") as f:
        json.dump(result, f)
    assert not problems, f"{len(problems)} mismatches; first {problems[0]}"
