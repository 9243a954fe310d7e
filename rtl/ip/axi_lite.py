"""An AXI4-Lite slave register file built from a :class:`~rvsm.rtl.ip.register_map.RegisterMap`.

:class:`AxiLiteSignature` is the bus (32-bit data, byte addresses, the master's view:
a slave takes ``In(AxiLiteSignature(...))``). :class:`AxiLiteRegisters` decodes it
against the map: one transaction of each kind outstanding (a write and a read may
overlap), AW and W in either order or together; OKAY, or SLVERR for an unmapped address,
a write whose strobe is not 0xF, a write to a register without a writable field, a
field value above its ``max`` (judged on the bits up to the next field,
:meth:`~rvsm.rtl.ip.register_map.Register.span`: a value too wide for the field is refused,
not truncated) and a write the IP refuses (``refuse``, sampled in the
write's commit cycle). A refused write changes nothing.

Latency, the handshake's cycle counted 0 (for timing: every decode starts and ends at
flip-flops): a read's ``rvalid`` is high from cycle 2 (the handshake registers a one-hot
register select decoded from ``araddr``, the next edge the multiplexed ``rdata``;
``arready`` is low from the handshake until the R handshake); a write's ``bvalid``
from cycle 3 after the later of its AW and W handshakes (the handshakes register
address and data, the next edge per register "this address, strobe 0xF, fields within
``max``", the next commits).

What the IP sees, per field of the map: ``RW`` fields are registers here (``value``),
except ``external`` ones whose value the IP holds and drives (``value`` is then an
input, and the IP takes the written value from ``wdata`` on ``written``); ``W1C`` fields
are sticky registers here, set by the IP's ``set`` input; ``WO`` fields give a one-cycle
``pulse``; live ``RO`` fields read the IP's ``value`` input. ``written[reg]`` is high
for the cycle after a successful write to ``reg`` (every register updated by then),
with that write's data in ``wdata``.
"""

from __future__ import annotations

from amaranth.hdl import Cat, Const, Module, Mux, Signal, Value, unsigned
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from rvsm.rtl.ip.register_map import (
    RESP_OKAY,
    RESP_SLVERR,
    Field,
    Register,
    RegisterMap,
)

__all__ = ["AxiLiteRegisters", "AxiLiteSignature", "RESP_OKAY", "RESP_SLVERR"]



class AxiLiteSignature(wiring.Signature):
    """AXI4-Lite with ``addr_bits`` byte-address bits and 32-bit data (AMBA AXI4-Lite):
    ``aw*``, ``w*``, ``b*``, ``ar*``, ``r*`` channels, members named as the
    specification's signals without the ``AXI`` prefix (``awaddr``, ``awvalid``, ...);
    ``Out`` is driven by the master."""

    DATA_BITS = 32

    def __init__(self, addr_bits: int):
        self.addr_bits = int(addr_bits)
        d = self.DATA_BITS
        super().__init__({
            "awaddr": Out(addr_bits), "awprot": Out(3), "awvalid": Out(1), "awready": In(1),
            "wdata": Out(d), "wstrb": Out(d // 8), "wvalid": Out(1), "wready": In(1),
            "bresp": In(2), "bvalid": In(1), "bready": Out(1),
            "araddr": Out(addr_bits), "arprot": Out(3), "arvalid": Out(1), "arready": In(1),
            "rdata": In(d), "rresp": In(2), "rvalid": In(1), "rready": Out(1),
        })

    def __eq__(self, other: object) -> bool:
        return isinstance(other, AxiLiteSignature) and other.addr_bits == self.addr_bits

    def __hash__(self) -> int:
        return hash((AxiLiteSignature, self.addr_bits))

    def __repr__(self) -> str:
        return f"AxiLiteSignature({self.addr_bits})"


def _key(reg: str, field: Field) -> str:
    return f"{reg}.{field.name}"


class AxiLiteRegisters(wiring.Component):
    """The register file of ``regmap`` behind an AXI4-Lite slave port ``bus``.

    Per field, keyed ``"REG.field"``: ``value`` (the field's value: a register here for
    ``RW``/``W1C``, an input from the IP for live ``RO`` and ``external`` ``RW``),
    ``set`` (``W1C``: the IP's set pulse), ``pulse`` (``WO``); per register ``refuse``
    (input: answer SLVERR instead of writing) and ``written`` (output pulse); ``wdata``.
    """

    def __init__(self, regmap: RegisterMap):
        self.regmap = regmap
        super().__init__({"bus": In(AxiLiteSignature(regmap.addr_bits))})
        self.value: dict[str, Signal] = {}
        self.set: dict[str, Signal] = {}
        self.pulse: dict[str, Signal] = {}
        for r in regmap.registers:
            for f in r.fields:
                k = _key(r.name, f)
                if f.access == "WO":
                    self.pulse[k] = Signal(f.width, name=f"{r.name}_{f.name}_pulse".lower())
                elif not (f.access == "RO" and not f.live):
                    self.value[k] = Signal(f.width, init=f.reset,
                                           name=f"{r.name}_{f.name}".lower())
                if f.access == "W1C":
                    self.set[k] = Signal(f.width, name=f"{r.name}_{f.name}_set".lower())
        self.refuse = {r.name: Signal(name=f"{r.name}_refuse".lower())
                       for r in regmap.registers}
        self.written = {r.name: Signal(name=f"{r.name}_written".lower())
                        for r in regmap.registers}
        self.wdata = Signal(32, name="reg_wdata")
        self._probes: dict[str, Value] = {}

    @property
    def probes(self) -> dict[str, Value]:
        """Internal registers a formal harness observes (:mod:`rvsm.rtl.ip.register_harness`),
        once elaborated: ``aw_have`` / ``w_have`` (a write address / data accepted, not
        yet committed) with ``aw_addr``, ``w_data`` and ``w_strb`` (what was accepted), and
        ``ar_have`` (a read address accepted, its data not yet registered)."""
        if not self._probes:
            raise RuntimeError("the register file's probes exist once it is elaborated")
        return self._probes

    def read_value(self, reg: str) -> Cat:
        """The 32-bit value a read of ``reg`` returns."""
        parts, pos = [], 0
        for f in sorted(self.regmap[reg].fields, key=lambda f: f.lsb):
            if f.lsb > pos:
                parts.append(Const(0, f.lsb - pos))
            if f.access == "WO":
                parts.append(Const(0, f.width))
            elif f.access == "RO" and not f.live:
                parts.append(Const(f.reset, f.width))
            else:
                parts.append(self.value[_key(reg, f)])
            pos = f.lsb + f.width
        if pos < 32:
            parts.append(Const(0, 32 - pos))
        return Cat(*parts)

    def elaborate(self, platform: object) -> Module:
        m = Module()
        self._write_channel(m)
        self._read_channel(m)
        return m

    @staticmethod
    def _decode(m: Module, addr: Signal, name: str, regs: list[Register]) -> Signal:
        """One-hot (one bit per register of ``regs``), combinational: ``addr`` selects it."""
        hit = Signal(len(regs), name=name)
        m.d.comb += hit.eq(Cat(addr[2:] == r.offset >> 2 for r in regs))
        return hit

    def _write_channel(self, m: Module) -> None:
        bus, rm = self.bus, self.regmap
        aw_have, w_have = Signal(name="aw_have"), Signal(name="w_have")
        aw_addr = Signal(unsigned(rm.addr_bits), name="aw_addr_r", reset_less=True)
        w_data = Signal(32, name="w_data_r", reset_less=True)
        w_strb = Signal(4, name="w_strb_r", reset_less=True)
        bvalid, bresp = Signal(name="bvalid_r"), Signal(2, name="bresp_r")
        self._probes.update(aw_have=aw_have, w_have=w_have, aw_addr=aw_addr, w_data=w_data,
                            w_strb=w_strb)
        m.d.comb += [bus.awready.eq(~aw_have & ~bvalid), bus.wready.eq(~w_have & ~bvalid),
                     bus.bvalid.eq(bvalid), bus.bresp.eq(bresp)]
        with m.If(bus.awvalid & bus.awready):
            m.d.sync += [aw_have.eq(1), aw_addr.eq(bus.awaddr)]
        with m.If(bus.wvalid & bus.wready):
            m.d.sync += [w_have.eq(1), w_data.eq(bus.wdata), w_strb.eq(bus.wstrb)]
        with m.If(bvalid & bus.bready):
            m.d.sync += bvalid.eq(0)
        # decode cycle: per writable register, "this address, strobe 0xF, every field
        # within its max" registered (ok_r); the commit cycle (commit) writes
        writable = [r for r in rm.registers if r.writable]
        hit = self._decode(m, aw_addr, "aw_hit", writable)
        ok = Signal(len(writable), name="w_ok_r")
        decoded = Signal(name="w_decoded")
        m.d.sync += decoded.eq(aw_have & w_have & ~bvalid & ~decoded)
        for n, r in enumerate(writable):
            good = hit[n] & (w_strb == 0xF)
            for f in r.fields:
                span = r.span(f)
                if f.max is not None and f.max < (1 << span) - 1:
                    good = good & (w_data[f.lsb:f.lsb + span] <= f.max)
            m.d.sync += ok[n].eq(good)
        # sticky fields: the IP's set pulses always land; a write of 1 clears
        clears = {k: Signal(len(v), name=f"{v.name}_clr") for k, v in self.value.items()
                  if k in self.set}
        for k, v in self.value.items():
            if k in self.set:
                m.d.sync += v.eq((v & ~clears[k]) | self.set[k])
        for s in (*self.pulse.values(), *self.written.values()):
            m.d.sync += s.eq(0)
        with m.If(decoded):  # the commit cycle
            m.d.sync += [aw_have.eq(0), w_have.eq(0), bvalid.eq(1), bresp.eq(RESP_SLVERR),
                         self.wdata.eq(w_data)]
            for n, r in enumerate(writable):
                with m.If(ok[n] & ~self.refuse[r.name]):
                    m.d.sync += [bresp.eq(RESP_OKAY), self.written[r.name].eq(1)]
                    for f in r.fields:
                        k, bits = _key(r.name, f), w_data[f.lsb:f.lsb + f.width]
                        if f.access == "RW" and not f.external:
                            m.d.sync += self.value[k].eq(bits)
                        elif f.access == "WO":
                            m.d.sync += self.pulse[k].eq(bits)
                        elif f.access == "W1C":
                            m.d.comb += clears[k].eq(bits)

    def _read_channel(self, m: Module) -> None:
        bus, rm = self.bus, self.regmap
        regs = list(rm.registers)
        ar_have = Signal(name="ar_have")
        self._probes["ar_have"] = ar_have
        sel = Signal(len(regs), name="ar_sel_r", reset_less=True)
        rvalid = Signal(name="rvalid_r")
        rdata = Signal(32, name="rdata_r", reset_less=True)
        rresp = Signal(2, name="rresp_r")
        m.d.comb += [bus.arready.eq(~ar_have & ~rvalid), bus.rvalid.eq(rvalid),
                     bus.rdata.eq(rdata), bus.rresp.eq(rresp)]
        with m.If(rvalid & bus.rready):
            m.d.sync += rvalid.eq(0)
        # AR handshake: register the one-hot select; next edge: AND-OR multiplexer
        with m.If(bus.arvalid & bus.arready):
            m.d.sync += [ar_have.eq(1), sel.eq(self._decode(m, bus.araddr, "ar_hit", regs))]
        with m.If(ar_have):
            data = Const(0, 32)
            for n, r in enumerate(regs):
                data = data | (self.read_value(r.name) & sel[n].replicate(32))
            m.d.sync += [ar_have.eq(0), rvalid.eq(1), rdata.eq(data),
                         rresp.eq(Mux(sel.any(), RESP_OKAY, RESP_SLVERR))]
