"""A board top for place and route with real I/O: the core between LVDS links on real pins.

Stand-in until the links' own front end (``rvsm.rtl.board``) lands: it has what the place
and route needs (every core port reached from or driven to real differential pins through
the ECP5 gearing primitives, real clocks) and none of the link protocol (no training,
alignment, deskew or framing; the links' ``BoardFrontEnd`` replaces :class:`BoardTop`).

* Clocks: the board oscillator (``clk_osc``, :attr:`BoardPorts.oscillator_mhz`) feeds an
  EHXPLLL: CLKOP = the transmit edge clock (4 x the core clock), CLKOS = the core clock
  (domain ``sync``). Reset: ``rst_n`` low or the PLL out of lock, synchronised per domain.
* Receive link ``rxK`` (``rxK_clk`` forwarded clock, ``rxK_d<i>`` data): ECLKSYNCB ->
  edge clock, CLKDIVF /2 -> SCLK (domain ``rxK``); per pair an IDDRX2F gives 4 bits per
  SCLK; two SCLK words make 8 bits per pair, written to an AsyncFIFO read in ``sync``.
  The receive bits, links in order, drive the core's ``codes.payload`` (cyclically if
  narrower); ``codes.valid`` is "every receive FIFO has a word".
* Transmit link ``txK``: the core's output bits (``spikes`` payload and valid, in
  signature order, zero-padded) cross into domain ``txK`` (SCLK = CLKDIVF /2 of the PLL's
  edge clock through an ECLKSYNCB, so related to the core clock) through a ring of
  :data:`RING` registered words; each word leaves in two SCLK halves through one ODDRX2F
  per pair; the forwarded clock is an ODDRX2F sending 1010.
* Control: a write-only serial port (``spi_sck``, ``spi_mosi``, ``spi_cs_n``; bits shifted
  in on ``spi_sck`` rising, MSB first, applied when ``spi_cs_n`` rises) sets
  ``{clear, thr.we, thr.addr, thr.data}``; ``led`` shows "receive FIFOs not empty".

At 100 MHz and a 400 MHz edge clock a pair carries 8 bits per core cycle (800 Mbit/s).
"""

from __future__ import annotations

from amaranth.hdl import (
    Cat,
    ClockDomain,
    ClockSignal,
    Const,
    Elaboratable,
    Instance,
    Module,
    ResetSignal,
    Signal,
)
from amaranth.lib import wiring
from amaranth.lib.cdc import FFSynchronizer, ResetSynchronizer
from amaranth.lib.fifo import AsyncFIFO

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.harness import component_ports
from rvsm.rtl.fpga.pin_plan import BoardPorts, LinkSpec

__all__ = ["BITS_PER_PAIR", "CONTROLS", "BoardTop", "board_ports"]

#: Bits per pair per core cycle: X2 gearing (4 bits a SCLK) at SCLK = 2 x core clock.
BITS_PER_PAIR = 8
#: Single-ended control pins of the board top.
CONTROLS = ("rst_n", "spi_sck", "spi_mosi", "spi_cs_n", "led")
#: Words in a transmitter's clock-crossing ring.
RING = 4
#: PLL voltage-controlled oscillator frequency (MHz): within EHXPLLL's 400-800 MHz.
VCO_MHZ = 800.0


def _split(pairs: int, max_pairs: int) -> list[int]:
    """``pairs`` as evenly as possible into links of at most ``max_pairs``."""
    n = -(-pairs // max_pairs)
    return [pairs // n + (i < pairs % n) for i in range(n)]


def board_ports(core: wiring.Component, core_mhz: float = 100.0, osc_mhz: float = 100.0,
                max_pairs_per_link: int = 64) -> BoardPorts:
    """The links a :class:`BoardTop` around ``core`` has: receive pairs for
    ``codes.payload``, transmit pairs for the outputs (:data:`BITS_PER_PAIR` bits per pair
    per core cycle), links of at most ``max_pairs_per_link`` data pairs."""
    ins, outs = _core_bits(core)
    eclk = 4 * core_mhz
    rx = _split(-(-ins // BITS_PER_PAIR), max_pairs_per_link)
    tx = _split(-(-outs // BITS_PER_PAIR), max_pairs_per_link)
    links = [LinkSpec(f"rx{i}", "rx", n, eclk) for i, n in enumerate(rx)]
    links += [LinkSpec(f"tx{i}", "tx", n, eclk) for i, n in enumerate(tx)]
    return BoardPorts(tuple(links), CONTROLS, "clk_osc", osc_mhz)


def _core_bits(core: wiring.Component) -> tuple[int, int]:
    ports = {p.name: p for p, _ in component_ports(core)}
    if "codes.payload" not in ports or "spikes.payload" not in ports:
        raise RvsmError("the board top needs a streaming core (codes and spikes streams)")
    outs = sum(p.width for p in ports.values()
               if p.direction == "out" and p.name.startswith("spikes"))
    return ports["codes.payload"].width, outs


def _pll_divider(what: str, ratio: float) -> int:
    if ratio < 1 or abs(ratio - round(ratio)) > 1e-9:
        raise RvsmError(f"the board PLL needs an integer {what}, got {ratio:g}")
    return int(round(ratio))


class BoardTop(Elaboratable):
    """``core`` between the links of ``ports`` (:func:`board_ports`); top-level ports
    :attr:`pins` (name -> one-bit signal), named as in the pin plan. ``core_mhz``: the core
    clock (CLKOS of the PLL)."""

    #: No test harness: the board top's I/O logic is part of the design's area.
    overhead_ff = 0
    overhead_lut = 0

    def __init__(self, core: wiring.Component, ports: BoardPorts, core_mhz: float = 100.0):
        self._MustUse__silence = True  # an __init__ that raises is not an unused design
        self.core, self.ports, self.core_mhz = core, ports, core_mhz
        self.pins: dict[str, Signal] = {}
        for link in ports.links:
            self.pins[link.clock_port] = Signal(name=link.clock_port)
            for i in range(link.data_pairs):
                self.pins[link.data_port(i)] = Signal(name=link.data_port(i))
        for name in (ports.oscillator, *ports.controls):
            self.pins[name] = Signal(name=name)
        eclks = {link.eclk_mhz for link in ports.links}
        if len(eclks) != 1:
            raise RvsmError("the board top's links share one edge clock frequency")
        self.eclk_mhz = eclks.pop()
        self.fb_div = _pll_divider("edge clock / oscillator", self.eclk_mhz / ports.oscillator_mhz)
        self.op_div = _pll_divider("VCO / edge clock", VCO_MHZ / self.eclk_mhz)
        self.os_div = _pll_divider("VCO / core clock", VCO_MHZ / core_mhz)
        self._MustUse__silence = False

    @property
    def port_list(self) -> list[Signal]:
        return list(self.pins.values())

    def _pll(self, m: Module) -> tuple[Signal, Signal, Signal]:
        tx_eclk, core_clk, lock = Signal(), Signal(), Signal()
        m.submodules.pll = Instance(
            "EHXPLLL", p_CLKI_DIV=1, p_CLKFB_DIV=self.fb_div, p_CLKOP_DIV=self.op_div,
            p_CLKOS_DIV=self.os_div, p_CLKOP_ENABLE="ENABLED", p_CLKOS_ENABLE="ENABLED",
            p_CLKOP_CPHASE=self.op_div - 1, p_CLKOP_FPHASE=0,
            p_CLKOS_CPHASE=self.os_div - 1, p_CLKOS_FPHASE=0, p_FEEDBK_PATH="CLKOP",
            i_CLKI=self.pins[self.ports.oscillator], i_CLKFB=tx_eclk, i_RST=0, i_STDBY=0,
            i_PHASESEL0=0, i_PHASESEL1=0, i_PHASEDIR=0, i_PHASESTEP=0, i_PHASELOADREG=0,
            i_PLLWAKESYNC=0, i_ENCLKOP=0, o_CLKOP=tx_eclk, o_CLKOS=core_clk, o_LOCK=lock)
        return tx_eclk, core_clk, lock

    def _edge(self, m: Module, link: LinkSpec, source: Signal) -> Signal:
        """ECLKSYNCB + CLKDIVF /2 for ``link``: its domain (SCLK) and the edge clock."""
        eclk, sclk = Signal(name=f"{link.name}_eclk"), Signal(name=f"{link.name}_sclk")
        m.submodules[f"{link.name}_eclksync"] = Instance(
            "ECLKSYNCB", i_ECLKI=source, i_STOP=0, o_ECLKO=eclk)
        m.submodules[f"{link.name}_clkdiv"] = Instance(
            "CLKDIVF", p_DIV="2.0", i_CLKI=eclk, i_RST=0, i_ALIGNWD=0, o_CDIVX=sclk)
        m.domains += ClockDomain(link.name)
        m.d.comb += ClockSignal(link.name).eq(sclk)
        m.submodules[f"{link.name}_rst"] = ResetSynchronizer(ResetSignal("sync"),
                                                             domain=link.name)
        return eclk

    def _receiver(self, m: Module, link: LinkSpec) -> AsyncFIFO:
        eclk = self._edge(m, link, self.pins[link.clock_port])
        n, dom = link.data_pairs, link.name
        word = Signal(4 * n, name=f"{dom}_word")
        for i in range(n):
            m.submodules[f"{dom}_iddr{i}"] = Instance(
                "IDDRX2F", i_D=self.pins[link.data_port(i)], i_ECLK=eclk,
                i_SCLK=ClockSignal(dom), i_RST=ResetSignal(dom), i_ALIGNWD=0,
                **{f"o_Q{k}": word[4 * i + k] for k in range(4)})
        fifo = AsyncFIFO(width=8 * n, depth=4, w_domain=dom, r_domain="sync")
        m.submodules[f"{dom}_fifo"] = fifo
        first, half = Signal(name=f"{dom}_half"), Signal(4 * n, name=f"{dom}_first")
        m.d[dom] += [half.eq(~half), first.eq(word)]
        m.d.comb += [fifo.w_data.eq(Cat(first, word)), fifo.w_en.eq(half)]
        return fifo

    def _transmitter(self, m: Module, link: LinkSpec, tx_eclk: Signal,
                     bits: Signal) -> None:
        eclk = self._edge(m, link, tx_eclk)
        n, dom = link.data_pairs, link.name
        # Mesochronous ring: SCLK and the core clock come from one PLL (2 SCLK a core
        # cycle), so a ring of RING words written every core cycle and read two SCLKs a
        # word, RING / 2 words behind, never over- or underruns; no handshake to time.
        ring = [Signal(8 * n, name=f"{dom}_ring{k}") for k in range(RING)]
        wp = Signal(range(RING), name=f"{dom}_wp")
        m.d.sync += wp.eq(wp + 1)
        with m.Switch(wp):
            for k in range(RING):
                with m.Case(k):
                    m.d.sync += ring[k].eq(bits)
        count = Signal(range(2 * RING), name=f"{dom}_count", init=RING)
        m.d[dom] += count.eq(count + 1)
        out = Signal(4 * n, name=f"{dom}_out")
        with m.Switch(count):
            for k in range(2 * RING):
                with m.Case(k):
                    m.d[dom] += out.eq(ring[k // 2].word_select(k % 2, 4 * n))
        for i in range(n):
            m.submodules[f"{dom}_oddr{i}"] = Instance(
                "ODDRX2F", i_ECLK=eclk, i_SCLK=ClockSignal(dom), i_RST=ResetSignal(dom),
                **{f"i_D{k}": out[4 * i + k] for k in range(4)},
                o_Q=self.pins[link.data_port(i)])
        m.submodules[f"{dom}_oddr_clk"] = Instance(
            "ODDRX2F", i_ECLK=eclk, i_SCLK=ClockSignal(dom), i_RST=ResetSignal(dom),
            i_D0=1, i_D1=0, i_D2=1, i_D3=0, o_Q=self.pins[link.clock_port])

    def _control(self, m: Module, ports: dict) -> None:
        """The serial control port -> ``clear`` and the threshold write."""
        sck, mosi, cs_n = (Signal(name=f"{n}_s") for n in ("sck", "mosi", "cs_n"))
        for pin, sig in (("spi_sck", sck), ("spi_mosi", mosi), ("spi_cs_n", cs_n)):
            m.submodules[f"{pin}_sync"] = FFSynchronizer(self.pins[pin], sig, init=pin != "spi_sck")
        targets = [ports[k] for k in ("thr.data", "thr.addr", "thr.we", "clear") if k in ports]
        width = sum(len(t) for t in targets)
        shift, command = Signal(width, name="spi_shift"), Signal(width, name="spi_command")
        sck_d, cs_d, apply = Signal(), Signal(init=1), Signal()
        m.d.sync += [sck_d.eq(sck), cs_d.eq(cs_n), apply.eq(cs_n & ~cs_d)]
        with m.If(~cs_n & sck & ~sck_d):
            m.d.sync += shift.eq(Cat(mosi, shift[:-1]))
        with m.If(cs_n & ~cs_d):
            m.d.sync += command.eq(shift)
        pos = 0
        for t in targets:
            value = command[pos:pos + len(t)]
            is_pulse = t is ports.get("thr.we") or t is ports.get("clear")
            m.d.comb += t.eq(value & apply if is_pulse else value)
            pos += len(t)

    def elaborate(self, platform: object) -> Module:
        m = Module()
        m.submodules.core = self.core
        tx_eclk, core_clk, lock = self._pll(m)
        m.domains.sync = ClockDomain("sync")
        m.d.comb += ClockSignal("sync").eq(core_clk)
        m.submodules.rst_sync = ResetSynchronizer(~self.pins["rst_n"] | ~lock, domain="sync")
        ports = {p.name: v for p, v in component_ports(self.core)}

        rx = [self._receiver(m, k) for k in self.ports.links if k.direction == "rx"]
        every = Const(1, 1)
        for f in rx:
            every = every & f.r_rdy
        ready = ports.get("codes.ready", Const(1, 1))
        rx_bits = Cat(*(f.r_data for f in rx))
        codes = ports["codes.payload"]
        m.d.comb += [codes.eq(Cat(*(rx_bits[i % len(rx_bits)] for i in range(len(codes))))),
                     ports["codes.valid"].eq(every)]
        for f in rx:
            m.d.comb += f.r_en.eq(every & ready)
        m.d.comb += self.pins["led"].eq(every)
        self._control(m, ports)

        out_bits = Cat(*(v for p, v in component_ports(self.core)
                         if p.direction == "out" and p.name.startswith("spikes")))
        tx_reg = Signal(len(out_bits), name="tx_bits")
        m.d.sync += tx_reg.eq(out_bits)
        pos = 0
        for link in (k for k in self.ports.links if k.direction == "tx"):
            width = 8 * link.data_pairs
            chunk = Signal(width, name=f"{link.name}_bits")
            m.d.comb += chunk.eq(tx_reg[pos:pos + width])
            self._transmitter(m, link, tx_eclk, chunk)
            pos += width
        return m
