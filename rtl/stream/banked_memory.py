"""A state memory of the streaming array, split into block-RAM sized banks.

:class:`BankedMemory` holds ``depth`` words of ``width`` bits in banks of at most
``bank_words`` words (a power of two), each bank's read data registered before the
bank multiplexer (block-RAM timing: no logic right after a block RAM's slow read). All
registers load on ``advance`` (the array's beat advance), so stages count beats:

* **Read.** ``read_addr`` is sampled at an ``advance`` edge; the bank's data is
  registered at the next ``advance`` edge and multiplexed by ``read_bank``, which must
  be the bank of that address delayed alike (one ``advance`` edge). ``data`` is the
  result (``read_stages=2``), or that result registered at the third ``advance`` edge
  (``read_stages=3``: a registered bank multiplexer, forwarding included).
* **Write.** One port: ``write_en``, ``write_addr``, ``write_data`` (the enable is used
  as given; gate it with ``advance`` outside).
* **Collisions.** A bank's read is gated (``read_gate``) at an edge where the write port
  writes its address: the read data is then undefined (yosys needs no read-first bypass
  multiplexer after the block RAM; a target with registered enables leaves such reads
  ungated and their data unused, :mod:`rvsm.rtl.stream.memory_target`). Either such
  collisions never meet a valid read, or ``forward=True`` adds ``forward_hit`` /
  ``forward_data``: where ``forward_hit`` was set with the read address, ``data`` is
  ``forward_data`` (the forwarded word, delayed alike: two ``advance`` edges) instead of
  the read. ``guard_bits = k`` adds ``may_write`` and gates the read where ``may_write``
  holds and the low ``k`` address bits match: a cheaper superset of the collisions, for
  a memory whose valid reads and writes never match in those bits. The collision is a
  bank's: its word address written meets its word address read, whichever bank the read
  is for (a read of another bank's word is discarded after the bank registers, but is
  still a read).
* **Banks from the target.** Each bank is built by ``target``
  (:class:`~rvsm.rtl.stream.memory_target.MemoryTarget`, the generic Amaranth memories
  by default; the FPGA flow's block RAMs put the bank register in the primitive's output
  register, same cycle behaviour). ``advance_next`` (the value ``advance`` takes at the
  next edge) goes to every bank, for a target that registers it beside each primitive as
  its own enable; the generic banks ignore it. ``held_write=True`` (only for a target
  with ``held_write``) adds ``write_en_next``: a write enable that may stay high through
  cycles without ``advance`` (the caller's ``valid`` alone, where a held write repeats
  the same word to the same address), given one edge ahead and registered per block
  RAM; the banks write where it holds and the bank matches. The caller must keep the
  write address and data constant while ``advance`` is low, and read nothing that a
  write outside ``advance`` edges changes (the array: the write of a clear edge lands in
  a word the fresh frame after the clear reads as zero and overwrites).
* **Initial contents.** ``init_word``: every word's value at configuration (block-RAM
  initialisation; 0 by default). No reset reloads it.
* **Formal observation.** For the ``"formal"`` platform only, ``probe_data`` shows the
  word at ``probe_addr`` (the generic banks' asynchronous read ports), for harnesses to
  state what the memory holds; other platforms elaborate no such port.
"""

from __future__ import annotations

from amaranth.hdl import Const, Module, Mux, Shape, Signal, Value, unsigned
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from rvsm.rtl.stream.memory_target import GENERIC_MEMORY, MemoryTarget

__all__ = ["BankedMemory"]


class BankedMemory(wiring.Component):
    """``depth`` words of ``width`` bits in banks of ``bank_words``; see the module
    docstring for the ports ``advance``, ``read_addr``, ``read_bank``, ``write_en``,
    ``write_addr``, ``write_data``, ``data`` and the optional ``forward_hit``,
    ``forward_data`` (``forward=True``), ``may_write`` (``guard_bits``),
    ``advance_next`` and ``write_en_next`` (``held_write=True``); banks from ``target``."""

    def __init__(self, width: int, depth: int, bank_words: int, forward: bool = False,
                 guard_bits: int | None = None, init_word: int = 0,
                 read_stages: int = 2, held_write: bool = False,
                 target: MemoryTarget = GENERIC_MEMORY):
        if read_stages not in (2, 3):
            raise ValueError(f"read_stages must be 2 or 3, got {read_stages}")
        if held_write and not target.held_write:
            raise ValueError(f"memory target {target.name!r} has no held writes")
        self.target = target
        self.read_stages = read_stages
        self.width = width
        self.init_word = init_word
        self.depth = depth
        self.bank_words = bank_words
        self.bank_sizes = [min(bank_words, depth - i) for i in range(0, depth, bank_words)]
        self.guard_bits = guard_bits
        self.forward = forward
        self.held_write = held_write
        addr = Shape.cast(range(depth))
        #: Formal observation (driven only when elaborated for the ``"formal"``
        #: platform, never in a user's Verilog): ``probe_data`` is the word at
        #: ``probe_addr`` now (an asynchronous read port per bank).
        self.probe_addr = Signal(addr, name="probe_addr")
        self.probe_data = Signal(unsigned(width), name="probe_data")
        members = {
            "advance": In(1),
            "read_addr": In(addr),
            "read_bank": In(addr),
            "write_en": In(1),
            "write_addr": In(addr),
            "write_data": In(unsigned(width)),
            "data": Out(unsigned(width)),
            "advance_next": In(1),
        }
        if forward:
            members.update(forward_hit=In(1), forward_data=In(unsigned(width)))
        if guard_bits is not None:
            members["may_write"] = In(1)
        if held_write:
            members["write_en_next"] = In(1)
        super().__init__(members)

    def _offset(self, addr: Value) -> Value:
        """The word address inside a bank."""
        return addr[:(self.bank_words - 1).bit_length()] if len(self.bank_sizes) > 1 \
            else addr

    def _hit(self, addr: Value, b: int) -> Value:
        """``addr`` is in bank ``b``."""
        if len(self.bank_sizes) == 1:
            return Const(1)
        return (addr >> (self.bank_words - 1).bit_length()) == b

    def _collide(self, b: int, write_en: Value, write_addr: Value, read_addr: Value,
                 may_write: Value | None) -> Value:
        """Bank ``b``'s read must be disabled: its write port writes the word address it
        reads, or with ``guard_bits`` the cheaper superset (``may_write`` and the low
        address bits)."""
        hit = self._hit(write_addr, b)
        wr, rd = self._offset(write_addr), self._offset(read_addr)
        if self.guard_bits is None:
            return write_en & hit & (wr == rd)
        k = min(self.guard_bits, len(rd))
        return may_write & hit & (wr[:k] == rd[:k])

    def elaborate(self, platform: object) -> Module:
        """The banks, the bank multiplexer and the forwarding."""
        m = Module()
        banked = len(self.bank_sizes) > 1
        offset_bits = (self.bank_words - 1).bit_length()
        outs, probes = [], []
        for b, depth in enumerate(self.bank_sizes):
            bank = self.target.bank(self.width, depth, self.init_word,
                                    held_write=self.held_write)
            m.submodules[f"b{b}"] = bank
            hit = self._hit(self.write_addr, b)
            if self.held_write:  # write_en_next registered per primitive, bank select
                m.d.comb += [bank.write_en.eq(hit), bank.write_en_next.eq(self.write_en_next)]
            else:
                m.d.comb += bank.write_en.eq(self.write_en & hit)
            m.d.comb += [bank.advance.eq(self.advance), bank.advance_next.eq(self.advance_next),
                         bank.read_addr.eq(self._offset(self.read_addr)),
                         bank.read_gate.eq(self._collide(b, self.write_en, self.write_addr,
                                                         self.read_addr,
                                                         getattr(self, "may_write", None))),
                         bank.write_addr.eq(self._offset(self.write_addr)),
                         bank.write_data.eq(self.write_data)]
            if platform == "formal":
                if not hasattr(bank, "probe_addr"):
                    raise ValueError(f"memory target {self.target.name!r} has no formal "
                                     "probe ports")
                m.d.comb += bank.probe_addr.eq(self.probe_addr[:offset_bits] if banked
                                               else self.probe_addr)
                probes.append(bank.probe_data)
            outs.append(bank.data)
        out = outs[-1]
        for b in range(len(outs) - 2, -1, -1):
            out = Mux(self.read_bank == b, outs[b], out)
        if probes:
            word = probes[-1]
            for b in range(len(probes) - 2, -1, -1):
                word = Mux((self.probe_addr >> offset_bits) == b, probes[b], word)
            m.d.comb += self.probe_data.eq(word)
        if self.forward:
            hit1 = Signal(name="fwd1", reset_less=True)
            hit2 = Signal(name="fwd2", reset_less=True)
            with m.If(self.advance):
                m.d.sync += [hit1.eq(self.forward_hit), hit2.eq(hit1)]
            out = Mux(hit2, self.forward_data, out)
        if self.read_stages == 3:  # the registered bank multiplexer
            muxed = Signal(unsigned(self.width), name="data_q", reset_less=True)
            with m.If(self.advance):
                m.d.sync += muxed.eq(out)
            out = muxed
        m.d.comb += self.data.eq(out)
        return m
