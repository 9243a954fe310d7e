"""The AXI4-Lite register map of the AXI4-Stream IP: one declaration, every rendering.

:func:`ip_register_map` declares every register of
:class:`~rvsm.rtl.ip.wrapper.RvsmAxisIp` (name, byte offset, access, fields with bits
and reset values, description) for one design point; the register file
(:class:`~rvsm.rtl.ip.axi_lite.AxiLiteRegisters`) is built from it, and so are the files
``rvsm verilog --interface axis`` writes beside the Verilog: :func:`regs_markdown`
(``<top>.regs.md``), :func:`regs_json` (``<top>.regs.json``) and :func:`regs_c_header`
(``<top>.regs.h``). Constant registers (ID, VERSION, digests, geometry) carry their
value as the reset value, so the RTL and the documents cannot disagree.

Field access: ``RO`` read-only (a constant or a live value), ``RW`` read/write,
``W1C`` sticky, set by the hardware, cleared by writing 1, ``WO`` write 1 to act (a
one-cycle pulse; reads as 0). Registers are 32 bits at word-aligned byte offsets.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.signatures import field_bits, threshold_word_bits

__all__ = ["ACCESS", "EXTRA_WINDOW", "ID_MAGIC", "Field", "Register", "RegisterMap",
           "ip_register_map", "pack_version", "regs_c_header", "regs_json", "regs_markdown"]

#: Field access kinds and their meaning.
ACCESS = {
    "RO": "read-only",
    "RW": "read/write",
    "W1C": "sticky: set by the hardware, write 1 to clear",
    "WO": "write 1 to act (a one-cycle pulse); reads as 0",
}

#: The ID register's value: ASCII "RVSM".
ID_MAGIC = 0x5256534D

#: AXI response codes.
RESP_OKAY, RESP_SLVERR = 0b00, 0b10

#: Byte offset of the first threshold data chunk register.
THR_DATA_BASE = 0x100
#: Registers of 32 bits; the address window is 4 KiB.
ADDR_BITS = 12
#: Byte offsets left for the registers of a wrapper (:meth:`RegisterMap.extended`):
#: 0x080 to 0x0FC, between the IP's own (up to 0x040) and ``THR_DATA*`` (0x100 on).
EXTRA_WINDOW = range(0x080, THR_DATA_BASE, 4)


@dataclass(frozen=True)
class Field:
    """Bits ``[lsb +: width]`` of a register. ``reset`` is the value after ``rst`` (a
    constant field's value); ``live``: a read-only field driven by the hardware (not a
    constant); ``external``: a read/write field whose storage is in the IP (it changes
    by itself, e.g. an auto-incrementing address); ``max``: a write of a larger value is
    refused (SLVERR), judged on the field's span (:meth:`Register.span`), so a value
    that does not fit the field's bits is refused too."""

    name: str
    lsb: int
    width: int
    access: str
    reset: int
    desc: str
    live: bool = False
    external: bool = False
    max: int | None = None

    @property
    def mask(self) -> int:
        """The field's bits in the register."""
        return ((1 << self.width) - 1) << self.lsb


@dataclass(frozen=True)
class Register:
    """A 32-bit register at byte ``offset``; ``commit``: writing it commits a threshold
    word (it is the last data chunk)."""

    name: str
    offset: int
    fields: tuple[Field, ...]
    desc: str
    commit: bool = False

    @property
    def access(self) -> str:
        """The register's access: its fields' if they agree, else ``mixed``."""
        kinds = {f.access for f in self.fields}
        return kinds.pop() if len(kinds) == 1 else "mixed"

    def span(self, field: Field) -> int:
        """The bits a write to ``field`` is judged on: from its ``lsb`` up to the next
        field's (or bit 32). A field's ``max`` is checked on these bits, so a value too
        wide for the field (scale 4 into a 2-bit scale field) is refused, never
        truncated into range."""
        above = [f.lsb for f in self.fields if f.lsb > field.lsb]
        return min(above, default=32) - field.lsb

    @property
    def writable(self) -> bool:
        """Some field takes writes."""
        return any(f.access != "RO" for f in self.fields)

    @property
    def reset(self) -> int:
        """The register's value after ``rst`` (``WO`` fields read 0)."""
        return sum(f.reset << f.lsb for f in self.fields if f.access != "WO")


@dataclass(frozen=True)
class RegisterMap:
    """The registers in offset order, plus what a driver needs to pack threshold words:
    ``thr_chunks`` data registers of 32 bits hold one word of ``thresholds_per_word``
    thresholds of ``threshold_bits`` (threshold ``i`` at bits
    ``[i*threshold_bits +: threshold_bits]`` of the chunks' concatenation, chunk 0
    lowest): ``lanes`` (P, pixels per beat) with a threshold memory, 1 with shared
    thresholds (one register per scale)."""

    registers: tuple[Register, ...]
    addr_bits: int
    thr_chunks: int
    threshold_bits: int
    thresholds_per_word: int
    lanes: int

    def __post_init__(self) -> None:
        offsets = [r.offset for r in self.registers]
        if len(set(offsets)) != len(offsets) or any(o % 4 for o in offsets) \
                or max(offsets) >= 1 << self.addr_bits:
            raise ValueError("register offsets must be distinct, word-aligned and inside "
                             "the address window")
        for r in self.registers:
            used = 0
            for f in r.fields:
                if f.mask & used or f.lsb + f.width > 32 or f.reset >> f.width:
                    raise ValueError(f"register {r.name}: field {f.name} overlaps, leaves "
                                     "32 bits or has a reset value wider than its bits")
                used |= f.mask

    def __getitem__(self, name: str) -> Register:
        for r in self.registers:
            if r.name == name:
                return r
        raise KeyError(name)

    def field(self, register: str, name: str) -> Field:
        """Field ``name`` of ``register``."""
        for f in self[register].fields:
            if f.name == name:
                return f
        raise KeyError(f"{register}.{name}")

    def extended(self, registers: Sequence[Register]) -> RegisterMap:
        """This map with ``registers`` added (a wrapper's own, e.g. a board front end's
        link status), each inside :data:`EXTRA_WINDOW`; the offsets must be free."""
        if not registers:
            return self
        for r in registers:
            if r.offset not in EXTRA_WINDOW:
                raise RvsmError(f"register {r.name} at 0x{r.offset:03X}: extra registers "
                                f"go from 0x{EXTRA_WINDOW.start:03X} to "
                                f"0x{EXTRA_WINDOW.stop - 4:03X}")
        names = [r.name for r in (*self.registers, *registers)]
        if len(set(names)) != len(names):
            raise RvsmError(f"register names must be distinct, got {sorted(names)}")
        merged = tuple(sorted((*self.registers, *registers), key=lambda r: r.offset))
        return dataclasses.replace(self, registers=merged)

    def thr_data_registers(self) -> list[Register]:
        """The threshold data chunk registers, chunk 0 first (the last commits)."""
        return [self[f"THR_DATA{k}"] for k in range(self.thr_chunks)]


def pack_version(version: str) -> int:
    """``"X.Y.Z"`` as ``X << 16 | Y << 8 | Z`` (each part 0-255); 0 for another form."""
    parts = version.split(".")
    if len(parts) != 3 or not all(p.isdigit() and int(p) < 256 for p in parts):
        return 0
    x, y, z = (int(p) for p in parts)
    return x << 16 | y << 8 | z


def _const(name: str, lsb: int, width: int, value: int, desc: str) -> Field:
    if value >> width or value < 0:
        raise RvsmError(f"the IP's {name} field ({width} bits) cannot hold {value}")
    return Field(name, lsb, width, "RO", value, desc)


def ip_register_map(contract: ArrayContract, lanes: int, fifo_depth: int, rtl_digest: str,
                    point_digest: str, version: str) -> RegisterMap:
    """The register map of the IP around the streaming array for ``contract`` with
    ``lanes`` lanes and an output FIFO of ``fifo_depth`` beats; the digests are hex
    strings (their first 8 digits go into DIGEST_RTL / DIGEST_POINT), ``version`` the
    rvsm version (:func:`pack_version`)."""
    c, geo = contract, StreamGeometry(contract, lanes)
    tw, p, words = c.threshold_bits, geo.lanes, geo.threshold_words
    per_word = geo.threshold_data_bits // tw  # thresholds per word: P, or 1 when shared
    wb, sb = threshold_word_bits(words), field_bits(c.num_scales - 1)
    chunks = -(-per_word * tw // 32)
    if THR_DATA_BASE + 4 * chunks > 1 << ADDR_BITS:
        raise RvsmError(f"a threshold word of {p * tw} bits needs {chunks} data registers; "
                        f"the IP's 4 KiB register window holds at most "
                        f"{((1 << ADDR_BITS) - THR_DATA_BASE) // 4}: use fewer lanes")
    regs = [
        Register("ID", 0x00, (_const("magic", 0, 32, ID_MAGIC, 'ASCII "RVSM"'),),
                 "identification: the constant 0x5256534D"),
        Register("VERSION", 0x04, (
            _const("patch", 0, 8, pack_version(version) & 0xFF, "patch version"),
            _const("minor", 8, 8, pack_version(version) >> 8 & 0xFF, "minor version"),
            _const("major", 16, 8, pack_version(version) >> 16, "major version")),
            f"rvsm version that generated the IP ({version}; 0 if not X.Y.Z)"),
        Register("DIGEST_RTL", 0x08, (_const("digest", 0, 32, int(rtl_digest[:8], 16),
                                             "first 8 hex digits of the RTL digest"),),
                 "RTL digest (provenance header, ports.json): the RTL sources, the "
                 "design point, the architecture and its options"),
        Register("DIGEST_POINT", 0x0C, (_const("digest", 0, 32, int(point_digest[:8], 16),
                                               "first 8 hex digits of the design point "
                                               "digest"),),
                 "design point digest: the contract the array is built from"),
        Register("GEOMETRY0", 0x10, (
            _const("height", 0, 16, c.height, "H, rows"),
            _const("width", 16, 16, c.width, "W, columns")), "array size"),
        Register("GEOMETRY1", 0x14, (
            _const("lanes", 0, 8, p, "P, pixels per beat"),
            _const("scales", 8, 4, c.num_scales, "S, receptive-field scales"),
            _const("adc_bits", 12, 4, c.adc_bits, "N, ADC code bits"),
            _const("threshold_bits", 16, 8, tw, "threshold bits (W-1)"),
            _const("accumulator_bits", 24, 8, c.accumulator_bits, "accumulator bits W")),
            "lanes, scales and widths"),
        Register("TIMING", 0x18, (
            _const("lag", 0, 16, geo.lag, "lag: output p follows input beat p + lag "
                   "(beats)"),
            _const("fifo_depth", 16, 16, fifo_depth, "output FIFO depth (beats)")),
            "stream timing"),
        Register("CONTROL", 0x20, (
            Field("clear", 0, 1, "WO", 0, "restart the stream at frame 0 (after a flush "
                  "when FLUSH is written with it); accumulators zero in the next frame"),
            Field("flush", 1, 1, "WO", 0, "insert lag zero beats (input tready low "
                  "meanwhile): every accepted beat's output comes out"),
            Field("drop", 2, 1, "RW", 0, "output policy: 0 stall the input (no beat lost), "
                  "1 keep sampling and drop whole output beats when the FIFO is full"),
            Field("counters_reset", 3, 1, "WO", 0, "zero the three beat counters")),
            "control"),
        Register("STATUS", 0x24, (
            Field("overflow", 0, 1, "W1C", 0, "an output beat was dropped (drop policy)",
                  live=True),
            Field("framing", 1, 1, "W1C", 0, "an input beat's tuser/tlast disagreed with "
                  "its position (start of frame / end of line)", live=True),
            Field("init", 2, 1, "RO", 1, "thresholds are being set to "
                  + ("their nominal values" if geo.shared_thresholds else "the top rail")
                  + " after rst", live=True),
            Field("flushing", 3, 1, "RO", 0, "flush beats are being inserted", live=True),
            Field("busy", 4, 1, "RO", 1, "init, flush or clear in progress: input tready "
                  "is low", live=True),
            Field("fifo_level", 8, 16, "RO", 0, "output FIFO level (beats)", live=True)),
            "status"),
        Register("IN_BEATS", 0x30, (Field("count", 0, 32, "RO", 0, "input beats accepted "
                                          "(s_axis handshakes), wrapping", live=True),),
                 "input beats accepted, modulo 2**32"),
        Register("OUT_BEATS", 0x34, (Field("count", 0, 32, "RO", 0, "output beats sent "
                                           "(m_axis handshakes), wrapping", live=True),),
                 "output beats sent, modulo 2**32"),
        Register("DROPPED", 0x38, (Field("count", 0, 32, "RO", 0, "output beats dropped "
                                         "(FIFO full), wrapping", live=True),),
                 "output beats dropped, modulo 2**32"),
        _threshold_address(geo, wb, sb),
    ]
    for k in range(chunks):
        lo, hi = 32 * k, min(32 * (k + 1), per_word * tw)
        last = k == chunks - 1
        packing = (f"the scale's one threshold (threshold.storage = shared; configured to "
                   f"{', '.join(map(str, c.shared_thresholds))})" if geo.shared_thresholds
                   else f"lane i at [i*{tw} +: {tw}]")
        regs.append(Register(
            f"THR_DATA{k}", THR_DATA_BASE + 4 * k,
            (Field("data", 0, hi - lo, "RW", 0, f"bits [{hi - 1}:{lo}] of the threshold "
                   "word"),),
            f"threshold word bits [{hi - 1}:{lo}] ({packing})"
            + ("; writing this register commits the word to THR_ADDR (SLVERR while "
               "STATUS.init)" if last else ""),
            commit=last))
    return RegisterMap(tuple(regs), ADDR_BITS, chunks, tw, per_word, p)


def _threshold_address(geo: StreamGeometry, word_bits: int, scale_bits: int) -> Register:
    """THR_ADDR: the word (``y*G + g``) and scale of the next commit; with shared
    thresholds (one register per scale) the scale alone."""
    scales, words = geo.contract.num_scales, geo.threshold_words
    scale = Field("scale", 16, scale_bits, "RW", 0, f"scale s (0..{scales - 1})",
                  external=True, max=scales - 1)
    if geo.shared_thresholds:
        return Register("THR_ADDR", 0x40, (scale,),
                        "scale of the next threshold to commit (one register per scale, "
                        "threshold.storage = shared); after a commit it moves to the next "
                        "scale, wrapping to 0")
    return Register("THR_ADDR", 0x40, (
        Field("word", 0, word_bits, "RW", 0, f"threshold word y*G + g (0..{words - 1}); "
              "increments after each commit", external=True, max=words - 1), scale),
        "address of the next threshold word to commit; after a commit it moves to the "
        "next word (word, then scale, wrapping to 0)")


def regs_json(regmap: RegisterMap, meta: Mapping[str, object]) -> str:
    """``<top>.regs.json``: ``meta`` (provenance), ``access`` kinds and every register
    with its fields."""
    regs = [{"name": r.name, "offset": r.offset, "access": r.access, "reset": r.reset,
             "desc": r.desc, "commit": r.commit,
             "fields": [asdict(f) for f in r.fields]} for r in regmap.registers]
    return json.dumps({**meta, "addr_bits": regmap.addr_bits, "data_bits": 32,
                       "thr_chunks": regmap.thr_chunks,
                       "threshold_bits": regmap.threshold_bits,
                       "thresholds_per_word": regmap.thresholds_per_word,
                       "lanes": regmap.lanes,
                       "access": ACCESS, "registers": regs}, indent=2) + "\n"


def regs_markdown(regmap: RegisterMap, top: str) -> str:
    """``<top>.regs.md``: the register table and each register's fields."""
    lines = [f"# `{top}` registers (AXI4-Lite, 32-bit, byte addresses)", "",
             "Access: " + "; ".join(f"`{k}` {v}" for k, v in ACCESS.items()) + ". "
             "SLVERR for an unmapped address, a write with a strobe other than 0xF, a "
             "write to a read-only register or of a field above its maximum, and a "
             "threshold commit while thresholds are initialised.", "",
             "| offset | name | access | reset | meaning |", "|---|---|---|---|---|"]
    lines += [f"| 0x{r.offset:03X} | `{r.name}` | {r.access} | 0x{r.reset:08X} | {r.desc} |"
              for r in regmap.registers]
    for r in regmap.registers:
        lines += ["", f"## `{r.name}` (0x{r.offset:03X})", "",
                  "| bits | field | access | reset | meaning |", "|---|---|---|---|---|"]
        lines += [f"| [{f.lsb + f.width - 1}:{f.lsb}] | `{f.name}` | {f.access} | "
                  f"{f.reset} | {f.desc} |" for f in r.fields]
    return "\n".join(lines) + "\n"


def regs_c_header(regmap: RegisterMap, top: str, prefix: str | None = None) -> str:
    """``<top>.regs.h``: include-guarded ``#define`` s of every offset, field shift and
    mask, reset value, and the threshold word's packing: ``THR_CHUNKS`` data registers
    per word, ``THRESHOLD_BITS`` per threshold, ``THRESHOLDS_PER_WORD`` thresholds per
    word, and ``LANES`` the IP's pixels per beat (P)."""
    pre = (prefix or top).upper()
    guard = f"{pre}_REGS_H"
    lines = [f"#ifndef {guard}", f"#define {guard}", "",
             f"/* {top}: AXI4-Lite register map (32-bit registers, byte offsets). */", "",
             f"#define {pre}_ADDR_BITS {regmap.addr_bits}u",
             f"#define {pre}_THR_CHUNKS {regmap.thr_chunks}u",
             f"#define {pre}_THRESHOLD_BITS {regmap.threshold_bits}u",
             f"#define {pre}_THRESHOLDS_PER_WORD {regmap.thresholds_per_word}u",
             f"#define {pre}_LANES {regmap.lanes}u"]
    for r in regmap.registers:
        name = f"{pre}_{r.name}"
        lines += ["", f"/* {r.name}: {r.desc} */", f"#define {name}_OFFSET 0x{r.offset:03X}u",
                  f"#define {name}_RESET 0x{r.reset:08X}u"]
        for f in r.fields:
            fname = f"{name}_{f.name.upper()}"
            lines += [f"#define {fname}_SHIFT {f.lsb}u", f"#define {fname}_MASK 0x{f.mask:08X}u"]
    lines += ["", f"#endif /* {guard} */"]
    return "\n".join(lines) + "\n"
