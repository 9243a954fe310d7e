"""The source-synchronous receiver: pins to beats in the core clock domain.

:class:`LinkReceiver` joins, for a :class:`~rvsm.rtl.board.model.LinkFormat`::

    pins, forwarded clock
      -> Deserialiser (gearing.py: IDDRX2F or the behavioural model), 4 bits a pair per SCLK
      -> WordAligner per pair (aligner.py): 8-bit words every other SCLK, bit slip on TRAIN
      -> Deskew (deskew.py): pairs lined up on MARK
      -> the link state machine: SEARCH (until every pair is aligned) -> DESKEW (until
         every pair has shown MARK) -> LOCKED (data: framing lane read, beats written)
      -> LinkFifo (SCLK domain ``rx`` -> core domain ``sync``; link_fifo.py): beats out as a stream
         (payload, sof, eol; valid/ready)

Errors (the model's rules, :func:`~rvsm.rtl.board.model.deserialise`): in SEARCH and
DESKEW an aligned pair whose word is neither TRAIN nor MARK; when LOCKED, a data pair
that differs from the framing lane's TRAIN/MARK during training or from TRAIN in an idle
word, a framing word without the SYNC nibble, a beat whose parity disagrees (framing
lane). :data:`LOSS_WORDS` bad words in a row on one pair (or on the framing lane when
LOCKED) drop the link back to SEARCH, and so does ``control.train`` while high.

Clock loss: a heartbeat (bit 3 of a free-running SCLK counter) is watched from the core
domain; :data:`CLOCK_TIMEOUT` core cycles without a change make the clock dead, which
clears ``locked`` and holds the SCLK domain in reset (``ResetSynchronizer``) until the
clock has run again, so the link trains again from SEARCH. Error counters survive it
(they are not reset by the domain reset).
"""

from __future__ import annotations

from amaranth.hdl import Array, Cat, ClockDomain, DomainRenamer, Module, Signal, unsigned
from amaranth.lib import data, stream, wiring
from amaranth.lib.cdc import FFSynchronizer, PulseSynchronizer, ResetSynchronizer
from amaranth.lib.wiring import In, Out

from rvsm.rtl.board.aligner import WordAligner
from rvsm.rtl.board.deskew import DEPTH as DESKEW_DEPTH
from rvsm.rtl.board.deskew import Deskew
from rvsm.rtl.board.gearing import Deserialiser
from rvsm.rtl.board.link_fifo import LinkFifo
from rvsm.rtl.board.model import (
    EOL,
    MARK,
    PARITY,
    SOF,
    SYNC,
    TRAIN,
    VALID,
    WORD_BITS,
    LinkFormat,
)
from rvsm.rtl.board.status import COUNTER_BITS, LinkControlSignature, LinkStatusSignature

__all__ = ["CLOCK_TIMEOUT", "FIFO_DEPTH", "LOSS_WORDS", "LinkReceiver", "beat_layout"]

#: Bad words in a row that drop the link to SEARCH.
LOSS_WORDS = 4
#: Core cycles without a heartbeat change that make the forwarded clock dead.
CLOCK_TIMEOUT = 64
#: Beats the clock-crossing FIFO holds.
FIFO_DEPTH = 16


def beat_layout(payload_bits: int) -> data.StructLayout:
    """A received (or transmitted) beat: ``payload``, ``sof`` (first beat of a frame),
    ``eol`` (last beat of a row)."""
    return data.StructLayout({"payload": unsigned(payload_bits), "sof": 1, "eol": 1})


class LinkReceiver(wiring.Component):
    """Receiver of a :class:`LinkFormat` link: ``clock`` and ``pins`` (the board's
    forwarded clock and pairs), ``control`` in; ``beats`` (a stream in the core domain
    ``sync``), ``status`` out. ``primitive``: the gearing (:mod:`.gearing`)."""

    def __init__(self, fmt: LinkFormat, primitive: str = "behavioural"):
        self.format = fmt
        self.primitive = primitive
        super().__init__({
            "clock": In(1), "pins": In(fmt.pairs),
            "beats": Out(stream.Signature(beat_layout(fmt.payload_bits))),
            "status": Out(LinkStatusSignature(fmt.pairs)),
            "control": In(LinkControlSignature()),
        })

    def elaborate(self, platform: object) -> Module:
        m = Module()
        fmt, n, f = self.format, self.format.pairs, self.format.framing_pair
        m.domains += ClockDomain("rx")  # its clock is the gearing's SCLK
        m.submodules.gearing = gear = Deserialiser(n, self.primitive, "rx")
        m.d.comb += [gear.clock.eq(self.clock), gear.pins.eq(self.pins)]

        # the forwarded clock's heartbeat, watched from the core domain
        beat_count = Signal(4, reset_less=True)
        m.d.rx += beat_count.eq(beat_count + 1)
        heart = Signal()
        m.submodules.heart_sync = FFSynchronizer(beat_count[3], heart, o_domain="sync")
        heart_seen, quiet = Signal(), Signal(range(CLOCK_TIMEOUT + 1), init=CLOCK_TIMEOUT)
        alive = Signal()
        m.d.sync += heart_seen.eq(heart)
        with m.If(heart != heart_seen):
            m.d.sync += quiet.eq(0)
        with m.Elif(quiet != CLOCK_TIMEOUT):
            m.d.sync += quiet.eq(quiet + 1)
        m.d.comb += alive.eq(quiet != CLOCK_TIMEOUT)
        rx_reset = Signal()
        m.d.comb += rx_reset.eq(~alive)
        m.submodules.rx_reset = ResetSynchronizer(rx_reset, domain="rx")

        # alignment, deskew and the link state machine, all in the SCLK domain
        rx = DomainRenamer("rx")
        phase = Signal()
        m.d.rx += phase.eq(~phase)
        strobe = phase
        aligners = [rx(WordAligner()) for _ in range(n)]
        for i, a in enumerate(aligners):
            m.submodules[f"aligner{i}"] = a
            m.d.comb += [a.gear.eq(gear.words[i]), a.strobe.eq(strobe)]
        m.submodules.deskew = deskew = rx(Deskew(n))
        m.d.comb += deskew.strobe.eq(strobe)
        for i, a in enumerate(aligners):
            m.d.comb += deskew.words[i].eq(a.word)
        train = Signal()
        m.submodules.train_sync = FFSynchronizer(self.control.train, train, o_domain="rx")
        all_aligned = Signal()
        m.d.comb += all_aligned.eq(Cat(a.aligned for a in aligners).all())

        err = Signal(n)        # one-cycle error pulses (at a strobe)
        bad_run = [Signal(range(LOSS_WORDS + 1), name=f"bad_run{i}") for i in range(n)]
        drop = Signal()
        locked_rx = Signal()
        # Timing: ``drop`` is registered (a cycle later than the bad runs, i.e. at the
        # strobe after the one that completed a run); at that strobe it masks the
        # state's errors, beat, deskew and lock, so every strobe sees what an
        # unregistered drop gave: the link already back in SEARCH.
        err_raw, beat_raw, start_raw, locked_raw = Signal(n), Signal(), Signal(), Signal()
        words = deskew.out
        frame = words[f]
        payload = Cat(words[i] for i in range(fmt.data_pairs))[:fmt.payload_bits]
        beat_ok = Signal()
        m.d.comb += [err.eq(err_raw & ~drop.replicate(n)), beat_ok.eq(beat_raw & ~drop),
                     deskew.start.eq(start_raw & ~drop), locked_rx.eq(locked_raw & ~drop)]
        # Timing: every check on the aligned and deskewed words is registered each cycle;
        # those words change only at strobes (two cycles apart), so at every strobe the
        # registered checks equal their combinational values exactly.
        def checked(value, name):
            reg = Signal(len(value), name=name)
            m.d.rx += reg.eq(value)
            return reg
        not_training = checked(Cat((a.word != TRAIN) & (a.word != MARK) for a in aligners),
                               "not_training")
        frame_training = checked((frame == TRAIN) | (frame == MARK), "frame_training")
        frame_data = checked(frame[4:] == SYNC, "frame_data")
        frame_valid = checked((frame & VALID).any(), "frame_valid")
        # Timing: the beat's parity from per-pair partial parities (8 bits each), kept
        # in a shadow of the deskew's delay lines (same strobes, same taps), so they
        # are registered at the strobe that registers ``deskew.out``; the check then
        # XORs the partials in the cycle after (the full-width 280-bit tree did not fit
        # one SCLK). Equal to the payload's parity at every strobe.
        part_out = Signal(fmt.data_pairs)
        for i in range(fmt.data_pairs):
            bits_i = min(WORD_BITS, fmt.payload_bits - WORD_BITS * i)
            part_in = aligners[i].word[:bits_i].xor()
            line = [Signal(name=f"part{i}_{d}") for d in range(DESKEW_DEPTH - 1)]
            taps = Array([part_in, *line])
            with m.If(strobe):
                m.d.rx += [line[0].eq(part_in),
                           *(line[d].eq(line[d - 1]) for d in range(1, DESKEW_DEPTH - 1)),
                           part_out[i].eq(taps[deskew.delays[i]])]
        parity_bad = checked(part_out.xor() != (frame & PARITY).any(), "parity_bad")
        off_frame = checked(Cat(words[i] != frame for i in range(f)), "off_frame")
        off_train = checked(Cat(words[i] != TRAIN for i in range(f)), "off_train")
        m.submodules.fifo = fifo = LinkFifo(fmt.payload_bits + 2, FIFO_DEPTH, "rx", "sync",
                                            link="w")
        overflow_rx = Signal()
        with m.FSM(domain="rx"):
            with m.State("SEARCH"):
                for a in aligners:
                    m.d.comb += [a.search.eq(1), a.restart.eq(train | drop)]
                for i, a in enumerate(aligners):  # an aligned pair must keep training
                    m.d.comb += err_raw[i].eq(strobe & a.aligned & not_training[i])
                with m.If(all_aligned & ~train & ~drop):
                    m.next = "DESKEW"
            with m.State("DESKEW"):
                m.d.comb += start_raw.eq(1)
                m.d.comb += err_raw.eq(Cat(strobe & not_training[i] for i in range(n)))
                with m.If(train | drop):
                    m.d.comb += [a.restart.eq(1) for a in aligners]
                    m.next = "SEARCH"
                with m.Elif(deskew.done):
                    m.next = "LOCKED"
            with m.State("LOCKED"):
                m.d.comb += [start_raw.eq(1), locked_raw.eq(1)]
                with m.If(strobe):
                    with m.If(frame_training):
                        m.d.comb += err_raw[:f].eq(off_frame)
                    with m.Elif(~frame_data):
                        m.d.comb += err_raw[f].eq(1)
                    with m.Elif(frame_valid):
                        m.d.comb += [err_raw[f].eq(parity_bad), beat_raw.eq(1)]
                    with m.Else():
                        m.d.comb += err_raw[:f].eq(off_train)
                with m.If(train | drop):
                    m.d.comb += [a.restart.eq(1) for a in aligners]
                    m.next = "SEARCH"
        for i in range(n):
            with m.If(strobe):
                with m.If(err[i]):
                    m.d.rx += bad_run[i].eq(bad_run[i] + (bad_run[i] != LOSS_WORDS))
                with m.Else():
                    m.d.rx += bad_run[i].eq(0)
        m.d.rx += drop.eq(Cat(r == LOSS_WORDS for r in bad_run).any())
        m.d.comb += [fifo.w_data.eq(Cat(payload, (frame & SOF).any(), (frame & EOL).any())),
                     fifo.w_en.eq(beat_ok)]
        m.d.comb += overflow_rx.eq(beat_ok & ~fifo.w_rdy)

        # counters: SCLK-domain Gray counters (not reset by the domain reset), read in
        # the core domain through a synchroniser per bit
        clear = Signal()
        m.submodules.clear_sync = clear_sync = PulseSynchronizer("sync", "rx")
        m.d.comb += [clear_sync.i.eq(self.control.counters_reset), clear.eq(clear_sync.o)]
        err_d = Signal(n)  # timing: the counters count the error pulses a cycle later
        m.d.rx += err_d.eq(err)
        for i in range(n):
            count = Signal(COUNTER_BITS, reset_less=True, name=f"errors{i}")
            gray = Signal(COUNTER_BITS, reset_less=True, name=f"errors{i}_gray")
            with m.If(clear):
                m.d.rx += count.eq(0)
            with m.Elif(err_d[i] & (count != (1 << COUNTER_BITS) - 1)):
                m.d.rx += count.eq(count + 1)
            m.d.rx += gray.eq(count ^ (count >> 1))
            synced = Signal(COUNTER_BITS, name=f"errors{i}_sync")
            m.submodules[f"errors{i}_sync"] = FFSynchronizer(gray, synced, o_domain="sync")
            m.d.comb += self.status.lane_errors[i].eq(_from_gray(synced))
        lost = Signal(reset_less=True)
        with m.If(clear):
            m.d.rx += lost.eq(0)
        with m.Elif(overflow_rx):
            m.d.rx += lost.eq(1)
        m.submodules.overflow_sync = FFSynchronizer(lost, self.status.overflow,
                                                    o_domain="sync")

        # status in the core domain
        locked_sync, aligned_sync = Signal(), Signal()
        m.submodules.locked_sync = FFSynchronizer(locked_rx, locked_sync, o_domain="sync")
        m.submodules.aligned_sync = FFSynchronizer(all_aligned, aligned_sync,
                                                   o_domain="sync")
        m.d.comb += [self.status.locked.eq(locked_sync & alive),
                     self.status.aligned.eq(aligned_sync & alive)]
        was_locked = Signal()
        m.d.sync += was_locked.eq(self.status.locked)
        with m.If(self.control.counters_reset):
            m.d.sync += self.status.lock_losses.eq(0)
        with m.Elif(was_locked & ~self.status.locked
                    & (self.status.lock_losses != (1 << COUNTER_BITS) - 1)):
            m.d.sync += self.status.lock_losses.eq(self.status.lock_losses + 1)

        # beats out of the FIFO
        m.d.comb += [self.beats.payload.as_value().eq(fifo.r_data),
                     self.beats.valid.eq(fifo.r_rdy), fifo.r_en.eq(self.beats.ready)]
        return m


def _from_gray(gray: Signal) -> Cat:
    """Binary value of a Gray code (bit k = XOR of gray bits k and above)."""
    width = len(gray)
    return Cat(gray[k:].xor() for k in range(width))
