"""A board top for place and route with real I/O: the board front end on real pins.

:class:`BoardTop` places the links of :mod:`rvsm.rtl.board`: a
:class:`~rvsm.rtl.board.front_end.BoardFrontEnd` (``LinkReceiver`` -> the streaming array ->
``LinkTransmitter``) built with ``primitive="ecp5"`` (``IDDRX2F``/``ODDRX2F``, ``ECLKSYNCB``,
``CLKDIVF``), so the place and route carries the real receiver (word alignment, deskew,
the link state machine, the AsyncFIFO into the core clock) and transmitter (framing,
training, the AsyncFIFO out of the core clock).

* Clocks: the board oscillator (``clk_osc``, :attr:`BoardPorts.oscillator_mhz`) feeds an
  EHXPLLL: CLKOP = the transmit edge clock (4 x the core clock), CLKOS = the core clock
  (domain ``sync``). Reset: ``rst_n`` low or the PLL out of lock, synchronised.
* Receive link ``rx0`` (``rx0_clk`` forwarded clock on a PCLK pair, ``rx0_d<i>``: the
  receiver's pairs, the framing lane last): its SCLK is the front end's domain ``rx``.
* Transmit link ``tx0`` (``tx0_d<i>``, the framing lane last, ``tx0_clk`` the forwarded
  clock): its edge clock is the PLL's CLKOP, its SCLK the front end's domain ``tx``.
* Control: a serial port (``spi_sck``, ``spi_mosi``, ``spi_cs_n``, ``spi_miso``; bits
  shifted in on ``spi_sck`` rising, MSB first, applied when ``spi_cs_n`` rises) sets
  ``{train, counters_reset, clear, thr.we, thr.addr, thr.data}`` (``counters_reset``,
  ``thr.we`` and ``clear`` as one-cycle pulses); ``spi_miso`` shifts out, MSB first from
  ``spi_cs_n`` falling, the status word (:func:`status_bits`). ``led`` is the receive
  link's ``locked``; ``rx0_train_request`` the pin asking the sensor for training.
* Around the AXI IP (``core`` an :class:`~rvsm.rtl.ip.wrapper.RvsmAxisIp`, ``rvsm fpga
  --interface axis --board``) the front end is
  :class:`~rvsm.rtl.board.ip_front_end.IpBoardFrontEnd` instead: the same links and
  clocks, and the four SPI pins are its :class:`~rvsm.rtl.board.spi_bridge.SpiBridge`'s
  (SPI mode 0 frames onto the IP's AXI4-Lite registers, the link registers among them:
  docs/board.md); ``tx0_overflow`` (:data:`IP_CONTROLS`) is the transmit FIFO's
  overflow, which has no register there.

At 100 MHz and a 400 MHz edge clock a pair carries 8 bits per core cycle (800 Mbit/s).
"""

from __future__ import annotations

from amaranth.hdl import Cat, ClockDomain, ClockSignal, Elaboratable, Instance, Module, Signal
from amaranth.lib.cdc import FFSynchronizer, ResetSynchronizer

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.board.front_end import BoardFrontEnd, link_formats
from rvsm.rtl.board.ip_front_end import IpBoardFrontEnd
from rvsm.rtl.fpga.pin_plan import BoardPorts, LinkSpec

__all__ = ["BITS_PER_PAIR", "CONTROLS", "IP_CONTROLS", "BoardTop", "board_ports",
           "front_end_name", "status_bits"]

#: Bits per pair per core cycle: X2 gearing (4 bits a SCLK) at SCLK = 2 x core clock.
BITS_PER_PAIR = 8
#: Single-ended control pins of the board top.
CONTROLS = ("rst_n", "spi_sck", "spi_mosi", "spi_cs_n", "spi_miso", "led",
            "rx0_train_request")
#: Single-ended control pins of the board top around the AXI IP: the SPI pins reach
#: the IP's registers, plus the transmit FIFO's overflow.
IP_CONTROLS = (*CONTROLS, "tx0_overflow")
#: PLL voltage-controlled oscillator frequency (MHz): within EHXPLLL's 400-800 MHz.
VCO_MHZ = 800.0


def _array_of(core: object) -> tuple:
    contract, lanes = getattr(core, "contract", None), getattr(core, "lanes", None)
    if contract is None or lanes is None or not hasattr(core, "geometry"):
        raise RvsmError("the board top needs the streaming array (rvsm fpga --arch stream)")
    return contract, lanes


def _is_ip(core: object) -> bool:
    from rvsm.rtl.ip.wrapper import RvsmAxisIp

    return isinstance(core, RvsmAxisIp)


def front_end_name(core: object) -> str:
    """The front end a board top puts around ``core``: ``"IpBoardFrontEnd"`` (the AXI
    IP, registers over SPI) or ``"BoardFrontEnd"`` (the streaming array)."""
    _array_of(core)
    return "IpBoardFrontEnd" if _is_ip(core) else "BoardFrontEnd"


def board_ports(core: object, core_mhz: float = 100.0, osc_mhz: float = 100.0) -> BoardPorts:
    """The links of the board front end around ``core`` (the streaming array or the AXI
    IP): ``rx0`` carries its codes (``P*N`` bits a beat, 8 a pair, plus the framing
    lane), ``tx0`` its spikes (``2*S*P`` bits a beat, positions implied by the framing,
    plus the framing lane); each with a forwarded clock pair. Control pins
    :data:`CONTROLS`, around the IP :data:`IP_CONTROLS`."""
    contract, lanes = _array_of(core)
    rx, tx = link_formats(contract, lanes)
    eclk = 4 * core_mhz
    links = (LinkSpec("rx0", "rx", rx.pairs, eclk), LinkSpec("tx0", "tx", tx.pairs, eclk))
    return BoardPorts(links, IP_CONTROLS if _is_ip(core) else CONTROLS, "clk_osc", osc_mhz)


def status_bits(front_end: BoardFrontEnd) -> Cat:
    """The status word ``spi_miso`` shifts out (LSB here = last bit out): ``locked``,
    ``aligned``, receive ``overflow``, ``tx_overflow``, ``lock_losses`` (8 bits),
    ``framing_errors`` (16 bits), then every pair's 8-bit error counter, pair 0 first."""
    st = front_end.status
    return Cat(st.locked, st.aligned, st.overflow, front_end.tx_overflow, st.lock_losses,
               front_end.framing_errors, *(st.lane_errors[i] for i in
                                           range(len(front_end.rx_pins))))


def _pll_divider(what: str, ratio: float) -> int:
    if ratio < 1 or abs(ratio - round(ratio)) > 1e-9:
        raise RvsmError(f"the board PLL needs an integer {what}, got {ratio:g}")
    return int(round(ratio))


def _silence(core: object) -> None:
    """``core`` and its parts are not elaborated (the front end builds its own)."""
    core._MustUse__silence = True
    for part in vars(core).values():
        if isinstance(part, Elaboratable):
            part._MustUse__silence = True


class BoardTop(Elaboratable):
    """The board front end for ``core``'s contract and lanes (``core`` stands for the
    front end's own array or IP: :class:`BoardFrontEnd` or :class:`IpBoardFrontEnd`
    builds the same one) between the pins of ``ports`` (:func:`board_ports`); top-level
    ports :attr:`pins` (name -> one-bit signal), named as in the pin plan. ``core_mhz``:
    the core clock (CLKOS of the PLL)."""

    #: No test harness: the board top's I/O logic is part of the design's area.
    overhead_ff = 0
    overhead_lut = 0

    def __init__(self, core: object, ports: BoardPorts, core_mhz: float = 100.0):
        self._MustUse__silence = True  # an __init__ that raises is not an unused design
        contract, lanes = _array_of(core)
        _silence(core)  # replaced by the front end's own array or IP
        self.ip = _is_ip(core)
        self.front_end: BoardFrontEnd | IpBoardFrontEnd = (
            IpBoardFrontEnd(contract, lanes, core.fifo_depth, primitive="ecp5") if self.ip
            else BoardFrontEnd(contract, lanes, primitive="ecp5"))
        self.controls = IP_CONTROLS if self.ip else CONTROLS
        self.ports, self.core_mhz = ports, core_mhz
        links = {k.name: k for k in ports.links}
        want = {"rx0": self.front_end.rx_format.pairs, "tx0": self.front_end.tx_format.pairs}
        if {k: v.data_pairs for k, v in links.items()} != want:
            raise RvsmError(f"the board top's links must be {want} pairs (board_ports)")
        self.pins: dict[str, Signal] = {}
        for link in ports.links:
            self.pins[link.clock_port] = Signal(name=link.clock_port)
            for i in range(link.data_pairs):
                self.pins[link.data_port(i)] = Signal(name=link.data_port(i))
        for name in (ports.oscillator, *ports.controls):
            self.pins[name] = Signal(name=name)
        missing = set(self.controls) - set(ports.controls)
        if missing:
            raise RvsmError(f"the board top needs the control pins {sorted(missing)}")
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

    def _control(self, m: Module, fe: BoardFrontEnd) -> None:
        """The serial control port: commands in, the status word out."""
        sck, mosi, cs_n = (Signal(name=f"{n}_s") for n in ("sck", "mosi", "cs_n"))
        for pin, sig in (("spi_sck", sck), ("spi_mosi", mosi), ("spi_cs_n", cs_n)):
            m.submodules[f"{pin}_sync"] = FFSynchronizer(self.pins[pin], sig,
                                                         init=pin != "spi_sck")
        targets = [fe.thr.data, fe.thr.addr, fe.thr.we, fe.clear, fe.control.counters_reset,
                   fe.control.train]
        pulses = (fe.thr.we, fe.clear, fe.control.counters_reset)
        width = sum(len(t) for t in targets)
        shift, command = Signal(width, name="spi_shift"), Signal(width, name="spi_command")
        sck_d, cs_d, apply = Signal(), Signal(init=1), Signal()
        rising = ~cs_n & sck & ~sck_d
        m.d.sync += [sck_d.eq(sck), cs_d.eq(cs_n), apply.eq(cs_n & ~cs_d)]
        with m.If(rising):
            m.d.sync += shift.eq(Cat(mosi, shift[:-1]))
        with m.If(cs_n & ~cs_d):
            m.d.sync += command.eq(shift)
        pos = 0
        for t in targets:
            value = command[pos:pos + len(t)]
            m.d.comb += t.eq(value & apply if any(t is p for p in pulses) else value)
            pos += len(t)
        status = status_bits(fe)
        out = Signal(len(status), name="spi_status")
        with m.If(~cs_n & cs_d):  # frame start: snapshot
            m.d.sync += out.eq(status)
        with m.Elif(rising):
            m.d.sync += out.eq(Cat(0, out[:-1]))
        m.d.comb += self.pins["spi_miso"].eq(out[-1])

    def _spi(self, m: Module, fe: IpBoardFrontEnd) -> None:
        """The IP's SPI bridge on the four SPI pins (it synchronises them itself)."""
        m.d.comb += [fe.spi.sclk.eq(self.pins["spi_sck"]), fe.spi.cs_n.eq(self.pins["spi_cs_n"]),
                     fe.spi.mosi.eq(self.pins["spi_mosi"]),
                     self.pins["spi_miso"].eq(fe.spi.miso),
                     self.pins["tx0_overflow"].eq(fe.tx_overflow)]

    def elaborate(self, platform: object) -> Module:
        m = Module()
        m.submodules.front_end = fe = self.front_end
        tx_eclk, core_clk, lock = self._pll(m)
        m.domains.sync = ClockDomain("sync")
        m.d.comb += ClockSignal("sync").eq(core_clk)
        m.submodules.rst_sync = ResetSynchronizer(~self.pins["rst_n"] | ~lock, domain="sync")
        rx, tx = (next(k for k in self.ports.links if k.name == n) for n in ("rx0", "tx0"))
        m.d.comb += [fe.rx_clock.eq(self.pins[rx.clock_port]), fe.tx_clock.eq(tx_eclk),
                     self.pins[tx.clock_port].eq(fe.tx_clock_out),
                     self.pins["led"].eq(fe.receiver.status.locked if self.ip
                                         else fe.status.locked),
                     self.pins["rx0_train_request"].eq(fe.train_request)]
        m.d.comb += [fe.rx_pins[i].eq(self.pins[rx.data_port(i)]) for i in range(rx.data_pairs)]
        m.d.comb += [self.pins[tx.data_port(i)].eq(fe.tx_pins[i])
                     for i in range(tx.data_pairs)]
        if self.ip:
            self._spi(m, fe)
        else:
            self._control(m, fe)
        return m
