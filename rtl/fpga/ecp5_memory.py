"""One state-memory bank as explicit ECP5 block RAMs with the output register on.

yosys' ECP5 memory mapping (``share/lattice/brams_16kd.txt``) has no output-register
option: it maps a synchronous read port to a DP16KD with ``REGMODE = "NOREG"`` and leaves
a register after it in fabric flip-flops, so the block RAM's slow clock-to-out (5.83 ns
at speed grade 6) starts the next path. :class:`Ecp5BlockRam` instead instantiates the
DP16KD primitives itself with ``REGMODE_B = "OUTREG"``: the same two registered stages
(the read latch, then the output register), both inside the block RAM, so the fabric
sees a short clock-to-out. It is the bank of :data:`ECP5_BLOCK_RAMS`, the
:class:`~rvsm.rtl.stream.memory_target.MemoryTarget` of the ECP5 build: the streaming
array takes it as a parameter (``RvsmStreamArray(..., memory=ECP5_BLOCK_RAMS)``) or from
the platform it is elaborated for (:data:`ECP5_PLATFORM`, whose ``memory_target`` it is:
what ``rvsm fpga`` converts with by default, so every array inside a wrapper gets it
too); simulation, formal and ``rvsm verilog`` keep the generic memories.

Configuration (one primitive per 18 bits of the word, side by side): port A writes, port
B reads, both 18 bits wide (1024 words: ``AD[13:4]`` is the word address, ``ADA[1:0]``
the byte enables), ``WRITEMODE`` ``NORMAL`` (port A's own read data is unused), chip
selects and resets tied off, ``GSR`` disabled, the initial contents in ``INITVAL_00`` ..
``INITVAL_3F`` (16 words of 18 bits per 320-bit value, each in a 20-bit slot, the layout
of yosys' own ``brams_map_16kd.v``). A read and a write of the same address at one edge
(through the two ports) give undefined read data, which the user must not use
(below). Only the 18-bit configuration is used: a bank of at most 1024
words (``StreamGeometry.BANK_WORDS``); shallower banks waste the rest (the 36-bit
pseudo-dual-port mode would halve the primitives at 512 words, but its data order is
not pinned down by the open tools' sources, so it is not used).

Cycle behaviour, equal to a generic synchronous read port with enable followed by a
register with enable, both enabled by ``advance``: at an edge where ``advance`` the word
at ``read_addr`` is latched and the latched word moves to ``data``. ``advance`` is given
**one edge ahead** (``advance_next``: the value it takes at the next edge) and
registered inside, per primitive, in a flip-flop instantiated as ``TRELLIS_FF``
(:func:`kept_register`; yosys does not merge instances, so every copy survives) that
drives the primitive's CEB and OCEB directly: no logic between a register and a block
RAM's enables, and no control net from one register to every block RAM of the device
(the critical path at 64x64, P = 8: 8.4-10.3 ns of it routing).

**Collisions.** A read of the word the other port writes at the same edge is not gated
off here (gating it put the collision logic between the enable registers and the block
RAMs: 7.5 ns at P = 8): its data is undefined on the device, and the array never uses
it (a threshold read meeting the registered write is replaced by the forwarded word, a
valid accumulator read never meets the write-back, a read of another bank's word is
discarded by the bank multiplexer). This assumes, as for block RAMs generally, that such
a collision leaves the written word intact and only the read data undefined. The
generic memories of simulation and ``rvsm verilog`` keep the gating (yosys needs it to
map them without read-first emulation).
"""

from __future__ import annotations

from amaranth.hdl import Cat, ClockSignal, Const, Instance, Module, Signal, Value, unsigned
from amaranth.lib import wiring

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.stream.memory_target import bank_signature

__all__ = ["DP16KD_DEPTH", "DP16KD_WIDTH", "ECP5_BLOCK_RAMS", "ECP5_PLATFORM", "Ecp5BlockRam",
           "Ecp5BlockRams", "Ecp5Platform", "dp16kd_count", "initval", "kept_register"]

#: Data bits and words of one DP16KD in the configuration used.
DP16KD_WIDTH = 18
DP16KD_DEPTH = 1024
_SLOT = 20  # bits per word slot in an INITVAL value
_PER_INITVAL = 16


def dp16kd_count(width: int) -> int:
    """DP16KD primitives side by side for a word of ``width`` bits (18 bits each)."""
    return -(-width // DP16KD_WIDTH)


def initval(words: list[int]) -> dict[str, Const]:
    """The ``INITVAL_00`` .. ``INITVAL_3F`` parameters (320 bits each) of one DP16KD
    holding ``words`` (18-bit values, word ``k`` at address ``k``; the rest zero)."""
    if len(words) > DP16KD_DEPTH:
        raise RvsmError(f"a DP16KD holds {DP16KD_DEPTH} words, got {len(words)}")
    params = {}
    for k in range(DP16KD_DEPTH // _PER_INITVAL):
        value = 0
        for i, word in enumerate(words[k * _PER_INITVAL:(k + 1) * _PER_INITVAL]):
            value |= (word & ((1 << DP16KD_WIDTH) - 1)) << (i * _SLOT)
        params[f"INITVAL_{k:02X}"] = Const(value, _SLOT * _PER_INITVAL)
    return params


def kept_register(m: Module, d: Value, name: str, en: Value | None = None) -> Signal:
    """A one-bit register ``q <= d`` at every ``sync`` edge (or at edges where ``en``:
    the flip-flop's own clock enable, ``CEMUX = "CE"``; no reset, 0 at configuration) as
    a ``TRELLIS_FF`` instance in ``m``: a cell yosys does not merge with an equivalent
    one (``opt_merge`` merges only its internal cells), so each copy keeps its own
    placement. Returns ``q``."""
    q = Signal(name=name)
    m.submodules[f"{name}_ff"] = Instance(
        "TRELLIS_FF", p_GSR="DISABLED", p_CEMUX="1" if en is None else "CE",
        p_CLKMUX="CLK", p_LSRMUX="LSR", p_REGSET="RESET", p_SRMODE="LSR_OVER_CE",
        i_CLK=ClockSignal(), i_LSR=Const(0), i_CE=Const(1) if en is None else en,
        i_DI=d, o_Q=q)
    return q


class Ecp5BlockRam(wiring.Component):
    """``depth`` (at most 1024) words of ``width`` bits in ``ceil(width / 18)`` DP16KD with
    the output register on (see the module docstring): a bank of
    :func:`~rvsm.rtl.stream.memory_target.bank_signature`.

    Ports used: ``write_en``, ``write_addr``, ``write_data`` (port A); ``read_addr``
    (port B); ``advance_next`` (the read and output registers' enable one edge ahead,
    module docstring) and ``data`` (the output register). ``advance`` and ``read_gate``
    are left unused (the enables come one edge ahead; collisions are not gated).
    ``init_word``: every word's value at configuration. ``write_ahead=True`` adds
    ``write_en_next``: the write enable one edge ahead, registered per primitive
    (:func:`kept_register`) and ANDed with ``write_en`` (then a bank select, constant 1
    for a single bank).
    """

    def __init__(self, width: int, depth: int, init_word: int = 0,
                 write_ahead: bool = False):
        if not 1 <= depth <= DP16KD_DEPTH:
            raise RvsmError(f"an ECP5 block-RAM bank holds 1..{DP16KD_DEPTH} words (banks "
                            f"of at most {DP16KD_DEPTH} words), got {depth}")
        if width < 1:
            raise RvsmError(f"word width must be >= 1 bit, got {width}")
        self.width, self.depth, self.init_word = width, depth, init_word
        self.write_ahead = write_ahead
        #: Primitives side by side (DP16KD).
        self.primitives = dp16kd_count(width)
        super().__init__(bank_signature(width, depth, held_write=write_ahead))

    def elaborate(self, platform: object) -> Module:
        """The DP16KD instances; slice ``k`` holds bits ``[18k, 18k+18)`` of every word."""
        m = Module()
        word_bits = DP16KD_DEPTH.bit_length() - 1  # 10 address bits at 18 bits wide
        low = 14 - word_bits  # AD[3:0]: sub-word bits (AD[1:0] the byte enables)
        outs = []
        for k in range(self.primitives):
            lo, hi = k * DP16KD_WIDTH, min(self.width, (k + 1) * DP16KD_WIDTH)
            n = hi - lo
            init = (self.init_word >> lo) & ((1 << n) - 1)
            params = initval([init] * self.depth) if init else {}
            do = Signal(unsigned(DP16KD_WIDTH), name=f"do{k}")
            di = Signal(unsigned(DP16KD_WIDTH), name=f"di{k}")
            m.d.comb += di.eq(self.write_data[lo:hi])
            # this primitive's own registered enables (placed beside it)
            adv = kept_register(m, self.advance_next, f"advance{k}")  # beside it
            we = (kept_register(m, self.write_en_next, f"write{k}") & self.write_en
                  if self.write_ahead else self.write_en)
            ports: dict = {
                "i_CLKA": ClockSignal(), "i_CLKB": ClockSignal(),
                "i_CEA": we, "i_WEA": we, "i_OCEA": Const(0),
                "i_RSTA": Const(0), "i_CEB": adv, "i_WEB": Const(0),
                "i_OCEB": adv, "i_RSTB": Const(0),
            }
            for p in ("A", "B"):
                for c in range(3):
                    ports[f"i_CS{p}{c}"] = Const(0)
            for b in range(14):
                if b < low:  # byte enables on port A (both bytes), sub-word bits zero
                    ports[f"i_ADA{b}"] = Const(1 if b < 2 else 0)
                    ports[f"i_ADB{b}"] = Const(0)
                else:
                    a = b - low
                    ports[f"i_ADA{b}"] = (self.write_addr[a] if a < len(self.write_addr)
                                          else Const(0))
                    ports[f"i_ADB{b}"] = (self.read_addr[a] if a < len(self.read_addr)
                                          else Const(0))
            for b in range(DP16KD_WIDTH):
                ports[f"i_DIA{b}"] = di[b]
                ports[f"i_DIB{b}"] = Const(0)
                ports[f"o_DOB{b}"] = do[b]
            m.submodules[f"ram{k}"] = Instance(
                "DP16KD",
                p_DATA_WIDTH_A=DP16KD_WIDTH, p_DATA_WIDTH_B=DP16KD_WIDTH,
                p_REGMODE_A="NOREG", p_REGMODE_B="OUTREG",
                p_WRITEMODE_A="NORMAL", p_WRITEMODE_B="NORMAL",
                p_CSDECODE_A="0b000", p_CSDECODE_B="0b000",
                p_RESETMODE="SYNC", p_ASYNC_RESET_RELEASE="SYNC", p_GSR="DISABLED",
                **{f"p_{name}": value for name, value in params.items()},
                **ports)
            outs.append(do[:n])
        m.d.comb += self.data.eq(Cat(*outs))
        return m


class Ecp5BlockRams:
    """The ECP5 build's :class:`~rvsm.rtl.stream.memory_target.MemoryTarget`:
    :class:`Ecp5BlockRam` banks; the accumulators write where their registered copy of
    ``valid`` holds (held writes: no enable logic between a register and a block RAM);
    every consumer of a pipeline flag gets its own :func:`kept_register` (no net from one
    register to the zero multiplexers of every accumulator-adder input)."""

    name = "ecp5-dp16kd"
    held_write = True

    def bank(self, width: int, depth: int, init_word: int = 0,
             held_write: bool = False) -> Ecp5BlockRam:
        return Ecp5BlockRam(width, depth, init_word, write_ahead=held_write)

    def flag_copy(self, m: Module, ahead: Value, shared: Value, name: str,
                  en: Value) -> Value:
        return kept_register(m, ahead, name, en=en)


#: The ECP5 build's memory target.
ECP5_BLOCK_RAMS = Ecp5BlockRams()


class Ecp5Platform:
    """The ``platform`` value of the ECP5 build (``verilog.convert(...,
    platform=ECP5_PLATFORM)``): it carries :data:`ECP5_BLOCK_RAMS` as its
    ``memory_target``, so every streaming array elaborated for it, inside any wrapper,
    maps its state memories to DP16KD with the output register."""

    memory_target = ECP5_BLOCK_RAMS

    def __repr__(self) -> str:
        return "ECP5_PLATFORM"


#: The platform of ``rvsm fpga``'s default memory (``--memory dp16kd``).
ECP5_PLATFORM = Ecp5Platform()
