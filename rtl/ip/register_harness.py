"""Formal check of the AXI IP's register file (``rvsm formal --arch stream --interface axis
--check registers``): :class:`RegisterFileProperties`.

The harness instantiates :class:`~rvsm.rtl.ip.axi_lite.AxiLiteRegisters` alone with the
IP's register map (:func:`~rvsm.rtl.ip.wrapper.ip_regmap`, so the check follows the
contract and the lanes: field widths, maxima, threshold chunks). Everything around it is
free (``AnySeq``) at every cycle: the AXI4-Lite master's channels (``bready``/``rready``
and every address, data and strobe), the IP's side (live ``RO`` and ``external`` ``RW``
values, ``W1C`` set pulses, ``refuse`` per register) and the domain reset ``rst``. The
only assumption is the master's half of the AXI handshake: a ``VALID`` that meets a low
``READY`` stays high with its payload until the handshake (``assume.*_held``).

The reference is written here in Amaranth from the
:class:`~rvsm.rtl.ip.register_map.RegisterMap` alone, as the Python model
(:class:`~rvsm.rtl.ip.register_model.RegisterFileModel`) states the rules, and it sees
only the bus: the write and read the master handed over (captured at their handshakes)
and the cycle the response rises. Per write: SLVERR exactly for an unmapped address, a
strobe other than 0xF, a register without a writable field, a field above its ``max``
judged on its span (:meth:`~rvsm.rtl.ip.register_map.Register.span`: every field with a
``max``, also where the maximum fills the field's width, the case a width-judged check
misses), or a write refused in its commit cycle (the cycle before ``bvalid`` rises);
OKAY otherwise. Its shadow of every field held in the register file (``RW`` but not
``external``; ``W1C``) follows: an OKAY write sets ``RW`` fields to the written bits and
clears the ``W1C`` bits written 1, a SLVERR write changes nothing, the IP's set pulses
land. Properties (one name per line: sby names a failing statement by its line):

* ``write.response``: ``bresp`` as the rules say, from the cycle ``bvalid`` rises;
* ``write.value``: every held field equals the shadow at every cycle (read-back of the
  last OKAY write, or the reset value);
* ``write.pulse`` / ``write.written``: ``WO`` pulses and ``written[reg]`` (with the
  write's data on ``wdata``) exactly for an OKAY write, in the cycle ``bvalid`` rises;
* ``read.response`` / ``read.data``: OKAY and the register's value in the cycle before
  ``rvalid`` rises (shadow, the IP's inputs, constants; ``WO`` bits 0), SLVERR and data 0
  for an unmapped address;
* ``axi.*``: the slave's half of the protocol, which the above rely on: one write and one
  read in flight (no second address or data accepted before the response is taken), a
  response only for a transaction received, ``bvalid`` exactly 3 cycles after the later
  of the AW and W handshakes and ``rvalid`` exactly 2 after AR (docs/ip.md), a response
  held with its payload until taken;
* ``invariant.*``: the register file's channel registers (its ``probes``) hold what the
  bus handed over; true in every run from reset, stated so that k-induction closes: the
  check is a proof for every input sequence of any length (``provable``), its base case
  every sequence of :attr:`RegisterFileProperties.depth` cycles from reset.

Covers (``--mode cover``): an OKAY write that changes an ``RW`` field, a write refused
only for a field above its maximum, one refused only for a field whose value fits its
own bits but not its span, one refused by the IP alone, a ``W1C`` bit cleared, the
read-back of a written ``RW`` value and a read of an unmapped address.
"""

from __future__ import annotations

from dataclasses import dataclass

from amaranth.asserts import AnySeq
from amaranth.hdl import Cat, Const, Module, Mux, Signal, Value

from rvsm.model.fixed.contract import ArrayContract
from rvsm.rtl.formal_harness import ElaborateAfter, FormalHarness
from rvsm.rtl.ip.axi_lite import AxiLiteRegisters
from rvsm.rtl.ip.register_map import RESP_OKAY, RESP_SLVERR, Field, Register, RegisterMap
from rvsm.rtl.ip.register_model import field_key
from rvsm.rtl.ip.wrapper import IP_ARCH, RvsmAxisIp, ip_regmap
from rvsm.rtl.mutations import check_mutation

__all__ = ["RegisterFileProperties", "ip_registers"]

#: Cycles from the later of the AW and W handshakes (cycle 0) to ``bvalid``, and from
#: the AR handshake to ``rvalid`` (docs/ip.md, "Registers").
WRITE_LATENCY, READ_LATENCY = 3, 2


@dataclass(frozen=True)
class _WriteRules:
    """The rules applied to the write in flight: per writable register, the write to it
    is ``accepted`` (OKAY); ``okay`` (some register accepts it); the covers' cases: a
    write refused only for a field ``above_max``, only for a field ``too_wide`` (its own
    bits within the maximum, its span not), or ``refused_only`` by the IP."""

    accepted: dict[str, Value]
    okay: Value
    above_max: Value
    too_wide: Value
    refused_only: Value


def _held(f: Field) -> bool:
    """The register file holds the field's value (``RW`` not ``external``, ``W1C``)."""
    return (f.access == "RW" and not f.external) or f.access == "W1C"


def _driven_by_ip(f: Field) -> bool:
    """The IP drives the field's value (live ``RO``, ``external`` ``RW``)."""
    return (f.access == "RO" and f.live) or (f.access == "RW" and f.external)


class RegisterFileProperties(FormalHarness):
    """The register file of ``regmap`` against its rules (module docstring)."""

    #: Steps of the base case (k-induction closes from 2): every sequence of 8 cycles
    #: from reset, two writes back to back with their responses (``bvalid`` at steps 3
    #: and 7) and reads beside them; a wrong write response shows at step 3, so 4 is the
    #: least depth that turns one into a counterexample (docs/formal.md).
    depth = 8
    #: Steps the covers need: a write, then the read-back of its value (step 4).
    cover_depth = 8
    #: The ``invariant.*`` properties make every property inductive.
    provable = True

    def __init__(self, regmap: RegisterMap) -> None:
        super().__init__()
        self.regmap = regmap

    def elaborate(self, platform: object) -> Module:
        m = Module()
        rm = self.regmap
        #: the shadow of each held field (``write.value``), read by ``read.data``
        self._shadows: dict[str, Signal] = {}
        #: the transactions in flight (``aw``, ``w``, ``ar``) and the write's payload
        self._in_flight: dict[str, Signal] = {}
        m.submodules.dut = dut = AxiLiteRegisters(rm)
        bus = dut.bus
        # the IP's side: free at every cycle
        for k, v in dut.value.items():
            register, name = k.split(".")
            if _driven_by_ip(rm.field(register, name)):
                m.d.comb += v.eq(AnySeq(len(v)))
        for s in (*dut.set.values(), *dut.refuse.values()):
            m.d.comb += s.eq(AnySeq(len(s)))
        self._master(m, bus)
        self._write(m, dut)
        self._read(m, dut)
        m.submodules.invariants = ElaborateAfter(lambda platform: self._invariants(dut))
        return m

    @staticmethod
    def _past(m: Module, value: Value, name: str, init: int = 0) -> Signal:
        """``value`` one cycle ago (a register of ``sync``: ``init`` after a reset)."""
        past = Signal(len(value), init=init, name=name)
        m.d.sync += past.eq(value)
        return past

    def _master(self, m: Module, bus) -> None:
        """The master's channels from ``AnySeq``, with AXI's rule for a ``VALID``: once
        high it stays high, with its payload, until ``READY``."""
        for name in ("awaddr", "awprot", "awvalid", "wdata", "wstrb", "wvalid", "bready",
                     "araddr", "arprot", "arvalid", "rready"):
            port = getattr(bus, name)
            m.d.comb += port.eq(AnySeq(len(port)))
        channels = {"aw": ("awaddr", "awprot"), "w": ("wdata", "wstrb"),
                    "ar": ("araddr", "arprot")}
        held = {}
        for ch, payload in channels.items():
            valid, ready = getattr(bus, f"{ch}valid"), getattr(bus, f"{ch}ready")
            waiting = self._past(m, valid & ~ready, f"{ch}_waiting")
            same = Cat(*(getattr(bus, p) == self._past(m, getattr(bus, p), f"{p}_past")
                         for p in payload))
            held[ch] = ~waiting | (valid & same.all())
        self.check(m, "assume.aw_held", held["aw"],
                   "AWVALID stays high with its address until AWREADY", "assume")
        self.check(m, "assume.w_held", held["w"],
                   "WVALID stays high with its data and strobe until WREADY", "assume")
        self.check(m, "assume.ar_held", held["ar"],
                   "ARVALID stays high with its address until ARREADY", "assume")

    @staticmethod
    def _hits(addr: Value, registers: tuple[Register, ...]) -> dict[str, Value]:
        """Per register, the byte address selects it (bits ``[addr_bits-1:2]``)."""
        return {r.name: addr[2:] == r.offset >> 2 for r in registers}

    def _transaction(self, m: Module, valid: Value, ready: Value, done: Value,
                     name: str, payload: dict[str, Value]) -> tuple[Signal, dict[str, Signal]]:
        """A channel's transaction in flight: from its handshake until ``done`` (its
        response taken); the payload captured at the handshake."""
        busy = Signal(name=f"{name}_in_flight")
        kept = {k: Signal(len(v), name=f"{name}_{k}", reset_less=True)
                for k, v in payload.items()}
        with m.If(valid & ready):
            m.d.sync += [busy.eq(1), *(kept[k].eq(v) for k, v in payload.items())]
        with m.Elif(done):
            m.d.sync += busy.eq(0)
        return busy, kept

    def _write(self, m: Module, dut: AxiLiteRegisters) -> None:
        """``axi.write_*``, ``write.*`` and the write covers."""
        bus = dut.bus
        b_taken = bus.bvalid & bus.bready
        aw, aw_kept = self._transaction(m, bus.awvalid, bus.awready, b_taken, "aw",
                                        {"addr": bus.awaddr})
        w, w_kept = self._transaction(m, bus.wvalid, bus.wready, b_taken, "w",
                                      {"data": bus.wdata, "strb": bus.wstrb})
        self._in_flight.update(aw=aw, w=w, **aw_kept, **w_kept)
        self.check(m, "axi.write_one_at_a_time",
                   ~(bus.awvalid & bus.awready & aw) & ~(bus.wvalid & bus.wready & w),
                   "no write address or data is accepted before the previous write's "
                   "response is taken")
        self.check(m, "axi.write_response_for_a_write", ~bus.bvalid | (aw & w),
                   "bvalid only for a write whose address and data were both accepted")
        b_rise = bus.bvalid & ~self._past(m, bus.bvalid, "bvalid_past")
        waiting = aw & w & ~bus.bvalid
        waited = Signal(range(WRITE_LATENCY + 1), name="b_waited")
        m.d.sync += waited.eq(Mux(waiting, waited + 1, 0))
        self.check(m, "axi.write_latency",
                   Mux(b_rise, waited == WRITE_LATENCY - 1,
                       ~waiting | (waited < WRITE_LATENCY - 1)),
                   f"bvalid rises exactly {WRITE_LATENCY} cycles after the later of the AW "
                   "and W handshakes")
        b_held = self._past(m, bus.bvalid & ~bus.bready, "b_waiting")
        bresp_past = self._past(m, bus.bresp, "bresp_past")
        self.check(m, "axi.write_response_held",
                   ~b_held | (bus.bvalid & (bus.bresp == bresp_past)),
                   "bvalid stays high with its bresp until bready")
        rules = self._write_rules(m, dut)
        self.check(m, "write.response",
                   ~b_rise | (bus.bresp == Mux(rules.okay, RESP_OKAY, RESP_SLVERR)),
                   "bresp: SLVERR for an unmapped address, a strobe other than 0xF, a "
                   "register without a writable field, a field above its max (on its span) "
                   "or a refused write; else OKAY")
        self._write_effects(m, dut, rules, b_rise)
        self.check(m, "cover.write_above_max", b_rise & rules.above_max,
                   "a write refused (SLVERR) only for a field above its maximum", "cover")
        self.check(m, "cover.write_too_wide", b_rise & rules.too_wide,
                   "a write refused (SLVERR) only for a field whose value fits its own bits "
                   "but not its span (refused, not truncated)", "cover")
        self.check(m, "cover.write_refused", b_rise & rules.refused_only,
                   "a write refused (SLVERR) by the IP alone", "cover")

    def _write_rules(self, m: Module, dut: AxiLiteRegisters) -> _WriteRules:
        """The rules for the write in flight (captured address, data, strobe; each
        register's ``refuse`` as sampled in the cycle before: the commit cycle, when
        ``bvalid`` rises now)."""
        addr, data, strb = (self._in_flight[k] for k in ("addr", "data", "strb"))
        hits = self._hits(addr, self.regmap.registers)
        accepted: dict[str, Value] = {}
        okay = above_max = too_wide = refused_only = Const(0)
        for r in self.regmap.registers:
            if not r.writable:
                continue
            refused = self._past(m, dut.refuse[r.name], f"{r.name}_refuse_past".lower())
            within, wide = Const(1), Const(0)
            for f in r.fields:
                if f.max is None:
                    continue
                span = r.span(f)
                within = within & (data[f.lsb:f.lsb + span] <= f.max)
                if span > f.width:
                    wide = wide | ((data[f.lsb:f.lsb + f.width] <= f.max)
                                   & data[f.lsb + f.width:f.lsb + span].any())
            sent = hits[r.name] & (strb == 0xF)
            accepted[r.name] = sent & within & ~refused
            okay = okay | accepted[r.name]
            above_max = above_max | (sent & ~within & ~refused)
            too_wide = too_wide | (sent & wide & ~refused)
            refused_only = refused_only | (sent & within & refused)
        return _WriteRules(accepted, okay, above_max, too_wide, refused_only)

    def _write_effects(self, m: Module, dut: AxiLiteRegisters, rules: _WriteRules,
                       b_rise: Value) -> None:
        """``write.value`` (the shadows), ``write.pulse``, ``write.written`` and the
        covers of a change."""
        data = self._in_flight["data"]
        commit = {name: b_rise & a for name, a in rules.accepted.items()}
        changed = cleared = Const(0)
        for r in self.regmap.registers:
            now = commit.get(r.name, Const(0))
            for f in r.fields:
                k, bits = field_key(r, f), data[f.lsb:f.lsb + f.width]
                tag = k.replace(".", "_").lower()
                if _held(f):
                    shadow = self._shadows[k] = Signal(f.width, name=f"{tag}_shadow")
                    before = self._past(m, shadow, f"{tag}_before", init=f.reset)
                    if f.access == "RW":
                        m.d.comb += shadow.eq(Mux(now, bits, before))
                        changed = changed | (now & (bits != before))
                    else:  # W1C: sticky, the IP's set (a cycle ago) wins over a clear
                        set_past = self._past(m, dut.set[k], f"{tag}_set_past")
                        m.d.comb += shadow.eq((before & ~Mux(now, bits, 0)) | set_past)
                        cleared = cleared | (now & (before & bits).any())
                    self.check(m, "write.value", dut.value[k] == shadow,
                               "every held field equals the last OKAY write (RW), its "
                               "sticky bits less those written 1 (W1C), or its reset value")
                elif f.access == "WO":
                    self.check(m, "write.pulse", dut.pulse[k] == Mux(now, bits, 0),
                               "WO fields pulse the written bits exactly in the cycle an "
                               "OKAY write's bvalid rises")
            written = dut.written[r.name]
            self.check(m, "write.written", (written == now) & (~written | (dut.wdata == data)),
                       "written[reg] is high (with the data on wdata) exactly in the cycle "
                       "an OKAY write to reg has its bvalid rise")
        self.check(m, "cover.write_okay_changes", changed,
                   "an OKAY write changes an RW field", "cover")
        self.check(m, "cover.w1c_cleared", cleared,
                   "an OKAY write clears a set W1C bit", "cover")

    def _read(self, m: Module, dut: AxiLiteRegisters) -> None:
        """``read.*``, ``axi.read_*`` and the read covers."""
        rm, bus = self.regmap, dut.bus
        r_taken = bus.rvalid & bus.rready
        ar, ar_kept = self._transaction(m, bus.arvalid, bus.arready, r_taken, "ar",
                                        {"addr": bus.araddr})
        self._in_flight["ar"] = ar
        self.check(m, "axi.read_one_at_a_time", ~(bus.arvalid & bus.arready & ar),
                   "no read address is accepted before the previous read's response is "
                   "taken")
        self.check(m, "axi.read_response_for_a_read", ~bus.rvalid | ar,
                   "rvalid only for a read whose address was accepted")
        r_past = self._past(m, bus.rvalid, "rvalid_past")
        r_rise = bus.rvalid & ~r_past
        waited = Signal(range(READ_LATENCY + 1), name="r_waited")
        m.d.sync += waited.eq(Mux(ar & ~bus.rvalid, waited + 1, 0))
        self.check(m, "axi.read_latency",
                   Mux(r_rise, waited == READ_LATENCY - 1,
                       ~(ar & ~bus.rvalid) | (waited < READ_LATENCY - 1)),
                   f"rvalid rises exactly {READ_LATENCY} cycles after the AR handshake")
        r_held = self._past(m, bus.rvalid & ~bus.rready, "r_waiting")
        rdata_past = self._past(m, bus.rdata, "rdata_past")
        rresp_past = self._past(m, bus.rresp, "rresp_past")
        self.check(m, "axi.read_response_held",
                   ~r_held | (bus.rvalid & (bus.rdata == rdata_past)
                              & (bus.rresp == rresp_past)),
                   "rvalid stays high with its rdata and rresp until rready")

        # the value of the read in flight, as the register file holds it now: the
        # response (registered) must carry it in the next cycle
        hits = self._hits(ar_kept["addr"], rm.registers)
        value = Const(0, 32)
        mapped = Const(0)
        written_back = Const(0)
        for r in rm.registers:
            word = Const(0, 32)
            for f in r.fields:
                k = field_key(r, f)
                if f.access == "WO":
                    continue
                if _held(f):
                    v = self._shadows[k]
                    if f.access == "RW":
                        written_back = written_back | (hits[r.name] & (v != f.reset))
                elif _driven_by_ip(f):
                    v = dut.value[k]
                else:
                    v = Const(f.reset, f.width)
                word = word | (v.as_unsigned() << f.lsb)[:32]
            value = value | Mux(hits[r.name], word, 0)
            mapped = mapped | hits[r.name]
        expected = self._past(m, value, "rdata_expected")
        was_mapped = self._past(m, mapped, "read_mapped")
        self.check(m, "read.response",
                   ~r_rise | (bus.rresp == Mux(was_mapped, RESP_OKAY, RESP_SLVERR)),
                   "rresp: OKAY for a mapped address, SLVERR for an unmapped one")
        self.check(m, "read.data", ~r_rise | (bus.rdata == expected),
                   "rdata: the register's value in the cycle before rvalid rises (held "
                   "fields as last written, the IP's values, constants; WO bits 0); 0 for "
                   "an unmapped address")
        was_written = self._past(m, written_back, "read_written_back")
        self.check(m, "cover.read_back", r_rise & was_written,
                   "a read returns an RW field changed by a write", "cover")
        self.check(m, "cover.read_unmapped", r_rise & ~was_mapped,
                   "a read of an unmapped address", "cover")

    def _invariants(self, dut: AxiLiteRegisters) -> Module:
        """``invariant.*``: the register file's channel registers hold what the bus
        handed over (its probes, once elaborated). They follow from the properties
        above in every run from reset; stated, they let k-induction close (without
        them it starts from states no run reaches, e.g. a write committed and its
        address still pending)."""
        m = Module()
        bus, p, t = dut.bus, dut.probes, self._in_flight
        self.check(m, "invariant.write_channel",
                   (t["aw"] == (p["aw_have"] | bus.bvalid)) & (t["w"] == (p["w_have"] | bus.bvalid))
                   & ~(bus.bvalid & (p["aw_have"] | p["w_have"])),
                   "a write in flight is pending in the register file (address, data) or "
                   "answered (bvalid), never both")
        self.check(m, "invariant.write_payload",
                   (~p["aw_have"] | (p["aw_addr"] == t["addr"]))
                   & (~p["w_have"] | ((p["w_data"] == t["data"]) & (p["w_strb"] == t["strb"]))),
                   "the register file holds the accepted write address, data and strobe")
        self.check(m, "invariant.read_channel",
                   (t["ar"] == (p["ar_have"] | bus.rvalid)) & ~(p["ar_have"] & bus.rvalid),
                   "a read in flight is pending in the register file or answered (rvalid), "
                   "never both")
        return m


def ip_registers(contract: ArrayContract, mutation: str | None = None, lanes: int = 1,
                 fifo_depth: int = RvsmAxisIp.FIFO_DEPTH,
                 **options: int) -> RegisterFileProperties:
    """The ``"registers"`` harness factory of :data:`~rvsm.rtl.ip.architecture.STREAM_AXIS`:
    the register file of the IP built for ``contract`` with ``lanes`` and ``fifo_depth``
    (no mutations: the IP has none registered)."""
    check_mutation(mutation, IP_ARCH)
    return RegisterFileProperties(ip_regmap(contract, lanes, fifo_depth))
