"""A simulation loopback around a board front end: the simulator does the per-bit work.

:class:`LinkLoopback` puts a front end (:class:`~rvsm.rtl.board.front_end.BoardFrontEnd`
or :class:`~rvsm.rtl.board.ip_front_end.IpBoardFrontEnd`) between a sensor-side
serialiser and a board-side deserialiser, all on one clock ``clk`` (domain ``sync``),
which is the **bit clock** of both links::

    codes (a beat per core cycle) -> sensor LinkTransmitter (rx format) -> skew lines
      -> front end rx pins (sampled on clk's falling edge: mid-bit)  ...  tx pins
      -> board LinkReceiver (tx format) -> spikes (row, group, last from the framing)

The core clock is ``clk`` with a clock enable ``ce``, high one cycle in
:data:`CORE_BITS` (``EnableInserter`` on the ``sync`` domain of the three parts): a link
word is 8 bits, so both links have one idle word in 9 of slack, as a forwarded clock a
little faster than the core needs. The sensor's training follows the front end's
``train_request`` pin; beats are taken (``codes.ready``) only after ``train_request``
has been low for :data:`START_WAIT` core cycles (the sensor's reset training is over).

Pair ``i`` of the receive link is ``delays[i]`` bit times late (a skew line per pair:
a bit slip and skew between the pairs). With ``faults``: ``rx_run`` low stops the
forwarded clock (a lost lock), ``fault`` high adds ``fault_bits`` to pair
``fault_pair``'s delay while running (a bit slip on one pair). ``frame_start`` (IP
front end) and ``clear`` (the array's front end) restart the input framing at a frame.

Outputs are registered, one ``clk`` cycle per beat (``spikes.valid``), so a harness
sampling at every rising edge of ``clk`` sees each beat once. With the array's front end
the ports are the streaming array's (``codes``, ``spikes``, ``thr``, ``clear``), so the
long-run harness (:mod:`rvsm.sim.cosim.builds.chunk_harness`) drives it as an array: a
threshold write or ``clear`` is held until the next ``ce`` (writes at least
:data:`CORE_BITS` + 1 cycles apart). Simulation only: the bit clock is ``clk`` itself.
"""

from __future__ import annotations

from amaranth.hdl import Cat, ClockSignal, DomainRenamer, EnableInserter, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from rvsm.model.fixed.contract import ArrayContract
from rvsm.rtl.board.front_end import BoardFrontEnd
from rvsm.rtl.board.ip_front_end import IpBoardFrontEnd
from rvsm.rtl.board.receiver import LinkReceiver
from rvsm.rtl.board.spi_bridge import SpiSignature
from rvsm.rtl.board.transmitter import LinkTransmitter
from rvsm.rtl.stream.array import RvsmStreamArray
from rvsm.rtl.stream.dimensions import StreamGeometry

__all__ = ["CORE_BITS", "FRONT_ENDS", "START_WAIT", "LinkLoopback", "default_delays"]

#: Bit clocks per core cycle (a link word is 8 bits: 1 word in 9 idle).
CORE_BITS = 9
#: Core cycles ``train_request`` must stay low before beats are taken.
START_WAIT = 128
#: Bits of the skew lines (largest delay + fault, bits).
LINE_BITS = 24
#: The front ends a loopback can hold.
FRONT_ENDS = ("array", "ip")


def default_delays(pairs: int, slip: int = 3) -> tuple[int, ...]:
    """Per pair ``slip + (3 * i) % 8`` bits: a bit slip and up to 7 bits of skew."""
    return tuple(slip + (3 * i) % 8 for i in range(pairs))


class LinkLoopback(wiring.Component):
    """Sensor serialiser -> front end ``front_end`` (``"array"``: ``BoardFrontEnd``, or
    ``"ip"``) -> board deserialiser for ``contract`` at ``lanes`` lanes (module docstring).

    Ports: ``codes`` (In, the array's code beats), ``spikes`` (Out, the array's spike
    beats, always ready), ``ce``, ``train_request`` (the front end's pin),
    ``tx_link_errors`` (words the board receiver found wrong, all pairs, saturating at
    255), ``out_framing_errors`` (beats whose ``eol`` disagreed with the position,
    saturating), ``overflow`` (a FIFO of the sensor or the front end's transmitter
    overflowed, sticky); ``thr``, ``clear`` (``"array"``) or ``spi`` and
    ``frame_start`` (``"ip"``); ``rx_run``, ``fault`` (``faults``)."""

    def __init__(self, contract: ArrayContract, lanes: int, front_end: str = "array",
                 delays: tuple[int, ...] | None = None, faults: bool = False,
                 fault_pair: int = 0, fault_bits: int = 3):
        if front_end not in FRONT_ENDS:
            raise ValueError(f"front_end must be one of {FRONT_ENDS}, got {front_end!r}")
        self.contract = contract
        self.geometry = StreamGeometry(contract, lanes)
        self.front_end = front_end
        self.dut = (BoardFrontEnd(contract, lanes) if front_end == "array"
                    else IpBoardFrontEnd(contract, lanes))
        self.rx_format, self.tx_format = self.dut.rx_format, self.dut.tx_format
        self.delays = (default_delays(self.rx_format.pairs) if delays is None
                       else tuple(delays))
        if len(self.delays) != self.rx_format.pairs:
            raise ValueError(f"{len(self.delays)} delays for {self.rx_format.pairs} pairs")
        if max(self.delays) + fault_bits >= LINE_BITS or min(self.delays) < 0:
            raise ValueError(f"delays must be 0..{LINE_BITS - 1 - fault_bits} bits")
        self.faults, self.fault_pair, self.fault_bits = faults, fault_pair, fault_bits
        members = dict(RvsmStreamArray.interface(contract, lanes).members)
        ports = {"codes": members["codes"], "spikes": members["spikes"]}
        if front_end == "array":
            ports |= {"thr": members["thr"], "clear": members["clear"]}
        else:
            ports |= {"spi": In(SpiSignature()), "frame_start": In(1)}
        if faults:
            ports |= {"rx_run": In(1, init=1), "fault": In(1)}
        ports |= {"ce": Out(1), "train_request": Out(1), "tx_link_errors": Out(8),
                  "out_framing_errors": Out(8), "overflow": Out(1)}
        super().__init__(ports)

    @property
    def lag(self) -> int:
        """The front end's lag (beats): output ``p`` leaves after input beat ``p + lag``."""
        return self.dut.lag

    def elaborate(self, platform: object) -> Module:
        m = Module()
        c, geo, dut = self.contract, self.geometry, self.dut
        clk = ClockSignal("sync")
        count = Signal(range(CORE_BITS))
        ce = Signal()
        m.d.sync += [count.eq(Mux(count == CORE_BITS - 1, 0, count + 1)),
                     ce.eq(count == CORE_BITS - 2)]
        m.d.comb += self.ce.eq(ce)
        sensor = LinkTransmitter(self.rx_format)
        board = LinkReceiver(self.tx_format)
        m.submodules.sensor = EnableInserter({"sync": ce})(
            DomainRenamer({"tx": "sensor_tx"})(sensor))
        m.submodules.front_end = EnableInserter({"sync": ce})(dut)
        m.submodules.board = EnableInserter({"sync": ce})(
            DomainRenamer({"rx": "board_rx"})(board))

        # the receive link: sensor pins -> skew lines -> the front end, mid-bit
        run, fault = Signal(init=1), Signal()
        if self.faults:
            m.d.sync += [run.eq(self.rx_run), fault.eq(self.fault)]
        rx_pins = []
        for i, d in enumerate(self.delays):
            line = Signal(LINE_BITS, name=f"skew{i}", init=(1 << LINE_BITS) - 1)
            m.d.sync += line.eq(Cat(sensor.pins[i], line[:-1]))
            taps = Cat(sensor.pins[i], line)
            extra = self.fault_bits if (self.faults and i == self.fault_pair) else 0
            rx_pins.append(Mux(fault, taps[d + extra], taps[d]) if extra else taps[d])
        m.d.comb += [sensor.clock.eq(clk), dut.rx_clock.eq(~clk & run),
                     dut.rx_pins.eq(Cat(*rx_pins)), sensor.train.eq(dut.train_request),
                     self.train_request.eq(dut.train_request),
                     dut.tx_clock.eq(clk), board.clock.eq(~dut.tx_clock_out),
                     board.pins.eq(dut.tx_pins), board.beats.ready.eq(1)]
        with m.If((sensor.overflow | dut.tx_overflow) & ~self.overflow):
            m.d.sync += self.overflow.eq(1)

        # held inputs of the core domain: a write or a clear waits for ce
        restart = Signal()
        if self.front_end == "array":
            names = list(dut.thr.signature.members)  # we, addr, data
            held = {n: Signal.like(getattr(dut.thr, n), name=f"thr_{n}") for n in names}
            with m.If(self.thr.we):
                m.d.sync += [held[n].eq(getattr(self.thr, n)) for n in names]
            with m.Elif(ce):
                m.d.sync += held["we"].eq(0)
            clear = Signal()
            with m.If(self.clear):
                m.d.sync += clear.eq(1)
            with m.Elif(ce):
                m.d.sync += clear.eq(0)
            m.d.comb += [*(getattr(dut.thr, n).eq(held[n]) for n in names), dut.clear.eq(clear),
                         restart.eq(self.clear)]
        else:
            wiring.connect(m, wiring.flipped(self.spi), dut.spi)
            m.d.comb += restart.eq(self.frame_start)

        # the sensor's beats: taken once the link has been trained for START_WAIT cycles
        quiet = Signal(range(START_WAIT + 1))
        with m.If(ce):
            m.d.sync += quiet.eq(Mux(dut.train_request, 0,
                                     Mux(quiet == START_WAIT, quiet, quiet + 1)))
        go = quiet == START_WAIT
        in_pos = Signal(range(geo.beats_per_frame))
        in_group = Signal(range(geo.groups))
        pending = Signal()  # a restart waiting for ce: the beat taken then is at 0
        pos_now = Mux(pending, 0, in_pos)
        group_now = Mux(pending, 0, in_group)
        take = ce & go & self.codes.valid
        m.d.comb += [self.codes.ready.eq(ce & go),
                     sensor.beats.valid.eq(take),
                     sensor.beats.payload.payload.eq(self.codes.payload.as_value()),
                     sensor.beats.payload.sof.eq(pos_now == 0),
                     sensor.beats.payload.eol.eq(group_now == geo.groups - 1)]
        with m.If(restart):
            m.d.sync += pending.eq(1)
        with m.Elif(ce):
            m.d.sync += pending.eq(0)
        with m.If(take):
            m.d.sync += [in_pos.eq(Mux(pos_now == geo.beats_per_frame - 1, 0, pos_now + 1)),
                         in_group.eq(Mux(group_now == geo.groups - 1, 0, group_now + 1))]
        with m.Elif(ce & pending):
            m.d.sync += [in_pos.eq(0), in_group.eq(0)]

        # the board's beats -> spikes, the position implied by the framing
        beat = board.beats.payload
        sp = c.num_scales * geo.lanes
        row = Signal(range(c.height))
        group = Signal(range(geo.groups))
        cur_row = Mux(beat.sof, 0, row)
        cur_group = Mux(beat.sof, 0, group)
        end_row = cur_group == geo.groups - 1
        out = self.spikes.payload
        got = ce & board.beats.valid
        m.d.sync += self.spikes.valid.eq(got)
        with m.If(got):
            m.d.sync += [out.pos.eq(beat.payload[:sp]), out.neg.eq(beat.payload[sp:2 * sp]),
                         out.row.eq(cur_row), out.group.eq(cur_group),
                         out.last.eq(end_row & (cur_row == c.height - 1)),
                         group.eq(Mux(end_row, 0, cur_group + 1)),
                         row.eq(Mux(end_row, Mux(cur_row == c.height - 1, 0, cur_row + 1),
                                    cur_row))]
            with m.If((beat.eol != end_row) & (self.out_framing_errors != 255)):
                m.d.sync += self.out_framing_errors.eq(self.out_framing_errors + 1)
        total = sum(board.status.lane_errors[i] for i in range(self.tx_format.pairs))
        m.d.sync += self.tx_link_errors.eq(Mux(total > 255, 255, total))
        return m
