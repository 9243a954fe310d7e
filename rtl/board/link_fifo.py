"""The links' clock-crossing FIFO: an asynchronous FIFO whose link side is registered.

:class:`LinkFifo` is ``amaranth.lib.fifo.AsyncFIFO``'s design (Gray pointers through
two-flip-flop synchronisers, Cummings' "style #2", the write domain's reset emptying the
read side) with the same ports (``w_data``, ``w_en``, ``w_rdy``; ``r_data``, ``r_en``,
``r_rdy``), but one side, ``link`` (``"w"`` or ``"r"``), runs on a link's SCLK
(200 MHz), where a word comes at most every other cycle. There ``AsyncFIFO``'s
``en -> pointer increment -> memory address`` path does not fit a 5 ns cycle, so that
side is registered:

* link write side: ``w_rdy`` is a register, low for the cycle after each accepted
  write (so at most one write every other cycle); an accepted word is written to the
  memory and its pointer moved on the next cycle, from registers (``w_data`` is taken
  at the accepting edge).
* link read side: ``r_rdy`` is a register, low for the cycle after each read; the
  memory is read at the registered pointer (``r_data`` valid while ``r_rdy``), and a
  read picks the pointer's registered successor (no adder behind ``r_en``).

The other side (the 100 MHz core clock) is ``AsyncFIFO``'s. ``depth`` words (a power
of 2) fit in either case.
"""

from __future__ import annotations

from amaranth.hdl import Cat, Elaboratable, Module, Mux, ResetSignal, Signal
from amaranth.lib.cdc import AsyncFFSynchronizer, FFSynchronizer
from amaranth.lib.memory import Memory

from rvsm.model.infra.errors import RvsmError

__all__ = ["LinkFifo"]


def _gray(v: Signal) -> Signal:
    return v ^ v[1:]


def _from_gray(g: Signal) -> Cat:
    return Cat(g[k:].xor() for k in range(len(g)))


class LinkFifo(Elaboratable):
    """``depth`` words of ``width`` bits from ``w_domain`` to ``r_domain``; ``link``
    (``"w"`` or ``"r"``) names the registered side (see the module)."""

    def __init__(self, width: int, depth: int, w_domain: str, r_domain: str, link: str):
        if link not in ("w", "r") or depth < 2 or depth & (depth - 1):
            self._MustUse__silence = True  # an __init__ that raises is not an unused design
            raise RvsmError(f"LinkFifo needs link 'w' or 'r' and a power-of-2 depth, "
                            f"got {link!r}, {depth}")
        self.width, self.depth, self.link = width, depth, link
        self.w_domain, self.r_domain = w_domain, r_domain
        self.w_data, self.w_en, self.w_rdy = Signal(width), Signal(), Signal()
        self.r_data, self.r_en, self.r_rdy = Signal(width), Signal(), Signal()

    def elaborate(self, platform: object) -> Module:
        m = Module()
        bits = self.depth.bit_length()  # pointer bits: address plus a wrap bit
        w, r = m.d[self.w_domain], m.d[self.r_domain]
        m.submodules.storage = mem = Memory(shape=self.width, depth=self.depth, init=[])
        wp = mem.write_port(domain=self.w_domain)

        # write side: produce pointer (binary, Gray), consume pointer seen from it
        produce, produce_gry, nxt = Signal(bits), Signal(bits), Signal(bits)
        consume_w_gry = Signal(bits)
        consume_gry = Signal(bits, reset_less=True)  # the read side's
        m.submodules.consume_cdc = FFSynchronizer(consume_gry, consume_w_gry,
                                                  o_domain=self.w_domain)
        if self.link == "w":
            consume_w = Signal(bits)
            w += consume_w.eq(_from_gray(consume_w_gry))
            stage_en, stage_data = Signal(), Signal(self.width)
            accept = self.w_en & self.w_rdy
            # words accepted so far (the staged one included) and its successor,
            # registered: accepts are two cycles apart, so ``acc1`` is current at each
            acc, acc1 = Signal(bits), Signal(bits, init=1)
            w += acc1.eq(acc + 1)
            with m.If(accept):
                w += acc.eq(acc1)
            w += [stage_en.eq(accept), stage_data.eq(self.w_data),
                  produce.eq(acc), produce_gry.eq(_gray(acc)),
                  # fewer than depth words held or staged leaves room for one more
                  self.w_rdy.eq(~accept & ~(acc - consume_w)[bits - 1])]
            m.d.comb += [wp.addr.eq(produce[:-1]), wp.data.eq(stage_data),
                         wp.en.eq(stage_en)]
        else:
            do_write = self.w_en & self.w_rdy
            m.d.comb += [nxt.eq(produce + do_write),
                         self.w_rdy.eq(~((produce_gry[-1] != consume_w_gry[-1])
                                         & (produce_gry[-2] != consume_w_gry[-2])
                                         & (produce_gry[:-2] == consume_w_gry[:-2]))),
                         wp.addr.eq(produce[:-1]), wp.data.eq(self.w_data),
                         wp.en.eq(do_write)]
            w += [produce.eq(nxt), produce_gry.eq(_gray(nxt))]

        # read side: consume pointer (reset-less: the write side's reset empties it)
        produce_r_gry = Signal(bits)
        m.submodules.produce_cdc = FFSynchronizer(produce_gry, produce_r_gry,
                                                  o_domain=self.r_domain)
        consume = Signal(bits, reset_less=True)
        r_rst = Signal()
        m.submodules.rst_cdc = AsyncFFSynchronizer(
            ResetSignal(self.w_domain, allow_reset_less=True), r_rst, o_domain=self.r_domain)
        do_read = self.r_rdy & self.r_en
        nxt_r = Signal(bits)
        rp = mem.read_port(domain=self.r_domain)
        m.d.comb += [rp.en.eq(1), self.r_data.eq(rp.data)]
        if self.link == "r":
            # the pointer's successor and its Gray code, registered: a read only picks
            # them (reads are two cycles apart, so they are current at every read)
            rdy, succ = Signal(), Signal(bits)
            plus, plus_gry = Signal(bits, reset_less=True), Signal(bits, reset_less=True)
            m.d.comb += succ.eq(consume + 1)
            # Timing: the empty compares are registered (against the pointer now and its
            # successor, for the cycle after a read), so ``rdy`` sees the synchronised
            # write pointer a cycle later (only later, never wrong: the FIFO can only
            # look emptier); the cycle after a reset is empty.
            held, held_next = Signal(), Signal()
            read_d, rst_d = Signal(), Signal(init=1)
            r += [held.eq(consume_gry != produce_r_gry), held_next.eq(plus_gry != produce_r_gry),
                  read_d.eq(do_read), rst_d.eq(r_rst)]
            r += [rdy.eq(~do_read & ~r_rst & ~rst_d & Mux(read_d, held_next, held)),
                  plus.eq(succ), plus_gry.eq(_gray(succ))]
            m.d.comb += [rp.addr.eq(consume[:-1]), self.r_rdy.eq(rdy & ~r_rst),
                         nxt_r.eq(Mux(do_read, plus, consume))]
            gry_r = Mux(do_read, plus_gry, consume_gry)
        else:
            m.d.comb += [nxt_r.eq(consume + do_read), rp.addr.eq(nxt_r[:-1]),
                         self.r_rdy.eq((consume_gry != produce_r_gry) & ~r_rst)]
            gry_r = _gray(nxt_r)
        with m.If(r_rst):
            r += [consume_gry.eq(produce_r_gry), consume.eq(_from_gray(produce_r_gry))]
        with m.Else():
            r += [consume.eq(nxt_r), consume_gry.eq(gry_r)]
        return m
