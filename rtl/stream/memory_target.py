"""Where the state memories' banks come from: a :class:`MemoryTarget`.

A :class:`~rvsm.rtl.stream.banked_memory.BankedMemory` is split into banks of at most
``bank_words`` words; each bank is built by the array's memory target, a parameter of the
array (``RvsmStreamArray(..., memory=target)``, or the ``memory_target`` attribute of the
platform it is elaborated for: :func:`memory_target`). The generic target
(:data:`GENERIC_MEMORY`: Amaranth memories, what simulation, formal checks and ``rvsm
verilog`` use) is defined here; a device's own block RAMs are a target of the FPGA flow
(``rtl/fpga/ecp5_memory.py``: DP16KD primitives with the output register on), so nothing
in ``rtl/stream`` depends on a device.

**A bank** (:func:`bank_signature`, one per target) is a synchronous read port followed by
an output register, both loading at an edge where ``advance``: the word at ``read_addr``
is latched, and the latched word moves to ``data`` (two ``advance`` edges from address to
data). A read with ``read_gate`` high (a collision with the write of that edge) gives
undefined data. The write port writes ``write_data`` to ``write_addr`` at an edge where
``write_en``. ``advance_next`` is ``advance`` one edge ahead, for a target that registers
its enables beside every primitive; with ``held_write``, ``write_en_next`` (the write
enable one edge ahead, registered likewise) gates the writes and ``write_en`` is the bank
select alone. A target uses the enables it needs: the generic bank ``advance``,
``read_gate`` and ``write_en``; a registered-enable target ``advance_next`` (and
``write_en_next``), leaving its colliding reads ungated (their data is never used).

**A target** (:class:`MemoryTarget`) also says whether the accumulators write where the
registered ``valid`` holds (``held_write``) and builds the registers a one-bit pipeline
flag needs at each of its consumers (:meth:`MemoryTarget.flag_copy`: the generic target
shares one register; a device target may give each consumer its own, placed beside it).
"""

from __future__ import annotations

from typing import Protocol

from amaranth.hdl import Module, Shape, Signal, Value, unsigned
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

__all__ = ["GENERIC_MEMORY", "GenericBank", "GenericMemory", "MemoryTarget", "bank_address",
           "bank_signature", "memory_target"]


def bank_address(depth: int) -> Shape:
    """The word address of a bank of ``depth`` words (at least one bit)."""
    return unsigned(max(1, (depth - 1).bit_length()))


def bank_signature(width: int, depth: int, held_write: bool = False) -> wiring.Signature:
    """The ports of one bank of ``depth`` words of ``width`` bits (module docstring)."""
    addr = bank_address(depth)
    return wiring.Signature({
        "advance": In(1), "advance_next": In(1),
        "read_addr": In(addr), "read_gate": In(1),
        "write_en": In(1), "write_addr": In(addr), "write_data": In(unsigned(width)),
        **({"write_en_next": In(1)} if held_write else {}),
        "data": Out(unsigned(width)),
    })


class MemoryTarget(Protocol):
    """How the state memories are built on one target (module docstring)."""

    #: A short name for reports.
    name: str
    #: The accumulator memories write where their registered copy of ``valid`` holds
    #: (``held_write`` banks), instead of at ``advance`` edges only.
    held_write: bool

    def bank(self, width: int, depth: int, init_word: int = 0,
             held_write: bool = False) -> wiring.Component:
        """One bank (:func:`bank_signature`); every word ``init_word`` at configuration."""

    def flag_copy(self, m: Module, ahead: Value, shared: Value, name: str,
                  en: Value) -> Value:
        """A one-bit pipeline flag for one consumer: ``shared`` (the register every
        consumer reads) or a register of its own in ``m``, loaded from ``ahead`` (the flag
        one stage earlier) at edges where ``en``."""


class GenericBank(wiring.Component):
    """A bank as an Amaranth :class:`~amaranth.lib.memory.Memory`: a read port enabled by
    ``advance & ~read_gate``, then the output register ``q`` loading on ``advance``.

    For the ``"formal"`` platform only, ``probe_data`` shows the word at ``probe_addr``
    (an asynchronous read port), for harnesses to state what the memory holds.
    """

    def __init__(self, width: int, depth: int, init_word: int = 0):
        self.width, self.depth, self.init_word = width, depth, init_word
        #: Formal observation (driven for the ``"formal"`` platform only).
        self.probe_addr = Signal(bank_address(depth), name="probe_addr")
        self.probe_data = Signal(unsigned(width), name="probe_data")
        super().__init__(bank_signature(width, depth))

    def elaborate(self, platform: object) -> Module:
        m = Module()
        mem = Memory(shape=unsigned(self.width), depth=self.depth,
                     init=[self.init_word] * self.depth if self.init_word else [])
        m.submodules.mem = mem
        wp = mem.write_port()
        m.d.comb += [wp.data.eq(self.write_data), wp.en.eq(self.write_en),
                     wp.addr.eq(self.write_addr)]
        if platform == "formal":
            probe = mem.read_port(domain="comb")
            m.d.comb += [probe.addr.eq(self.probe_addr), self.probe_data.eq(probe.data)]
        rp = mem.read_port()
        m.d.comb += [rp.addr.eq(self.read_addr), rp.en.eq(self.advance & ~self.read_gate)]
        q = Signal(unsigned(self.width), name="q", reset_less=True)
        with m.If(self.advance):
            m.d.sync += q.eq(rp.data)
        m.d.comb += self.data.eq(q)
        return m


class GenericMemory:
    """The generic :class:`MemoryTarget`: :class:`GenericBank` banks, writes at
    ``advance`` edges, one shared register per pipeline flag."""

    name = "generic"
    held_write = False

    def bank(self, width: int, depth: int, init_word: int = 0,
             held_write: bool = False) -> wiring.Component:
        if held_write:
            raise ValueError("the generic memory target has no held writes")
        return GenericBank(width, depth, init_word)

    def flag_copy(self, m: Module, ahead: Value, shared: Value, name: str,
                  en: Value) -> Value:
        return shared


#: The generic target (simulation, formal checks, ``rvsm verilog``).
GENERIC_MEMORY = GenericMemory()


def memory_target(platform: object) -> MemoryTarget:
    """The memory target of ``platform``: its ``memory_target`` attribute (a device
    platform of the FPGA flow), else :data:`GENERIC_MEMORY` (``None``, ``"formal"``)."""
    return getattr(platform, "memory_target", GENERIC_MEMORY)
