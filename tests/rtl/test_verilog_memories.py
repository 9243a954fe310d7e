"""Memories as yosys ``$mem`` cells (rtl/verilog_memories.py): the Verilog is
byte-identical to Amaranth's converter followed by ``strip_zero_memory_init``, for every
registered architecture, with several banks, a transparent read port, non-zero and signed
contents, and a memory the cell cannot express (left to Amaranth)."""

from __future__ import annotations

import re

import pytest
from amaranth.back import rtlil
from amaranth.back import verilog as amaranth_verilog
from amaranth.hdl import Module, signed, unsigned
from amaranth.lib import wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from rvsm.model.infra.errors import ToolError
from rvsm.rtl.architectures.registry import ARCHITECTURES, get_architecture
from rvsm.rtl.architectures.verilog import generate_verilog, strip_zero_memory_init
from rvsm.rtl.ports import verilog_ports
from rvsm.rtl.stream.array import RvsmStreamArray
from rvsm.rtl.verilog_memories import MemoryCells, convert_verilog, rename_ports


def _amaranth(component: wiring.Component, top: str) -> str:
    text = amaranth_verilog.convert(component, name=top, emit_src=False,
                                    ports=verilog_ports(component))
    return strip_zero_memory_init(text)[0]


@pytest.mark.parametrize("arch", ARCHITECTURES)
def test_every_architecture_gets_amaranths_verilog(arch, small_contract):
    c = small_contract("dog2", 4, 8)
    a = get_architecture(arch)
    options = {"lanes": 2} if arch == "stream" else {}
    new = generate_verilog(c, a, **options).text
    assert new == _amaranth(a.component(c, **a.resolve(options)), a.default_top)


def test_several_banks_and_the_top_rail(small_contract):
    """Eight-word banks: three banks a memory; the thresholds keep their top-rail
    initialisers, the all-zero memories have none."""
    c = small_contract("dog4", 4, 12)
    dut = RvsmStreamArray(c, 2, bank_words=8)
    new = convert_verilog(dut, "a", verilog_ports(dut))
    assert "initial begin" in new
    assert new == _amaranth(RvsmStreamArray(c, 2, bank_words=8), "a")


class _Memories(wiring.Component):
    """One memory of each kind the lowering meets."""

    def __init__(self) -> None:
        super().__init__({"addr": In(2), "data": In(8), "we": In(1), "out": Out(8 * 5)})

    def elaborate(self, platform):
        m = Module()
        outs = []
        for name, shape, init, transparent, reads in (
                ("zero", unsigned(8), [], False, 1),
                ("words", unsigned(8), [3, 0, 255], False, 1),
                ("neg", signed(8), [-1, 2], True, 1),
                ("two_reads", unsigned(8), [7, 7, 7, 7], False, 2)):
            mem = Memory(shape=shape, depth=4, init=init)
            m.submodules[name] = mem
            wp = mem.write_port()
            m.d.comb += [wp.addr.eq(self.addr), wp.data.eq(self.data), wp.en.eq(self.we)]
            for _ in range(reads):
                rp = mem.read_port(transparent_for=(wp,) if transparent else ())
                m.d.comb += [rp.addr.eq(self.addr + 1), rp.en.eq(~self.we)]
                outs.append(rp.data)
        for k, data in enumerate(outs):
            m.d.comb += self.out[8 * k:8 * k + 8].eq(data)
        return m


def test_each_kind_of_memory():
    dut = _Memories()
    new = convert_verilog(dut, "mems", verilog_ports(dut))
    assert new == _amaranth(_Memories(), "mems")
    assert "zero[" in new and "initial begin\n    zero" not in new  # no initialiser
    assert "words[2] = 8'hff;" in new


def test_only_non_zero_contents_are_written():
    """In the RTLIL: the lowered all-zero memory has no initialiser, the lowered ones with
    contents have theirs one word a constant, the memory left to Amaranth keeps its own."""
    cells = MemoryCells()
    dut = _Memories()
    text = cells.rtlil(rtlil.convert(dut, name="mems", ports=verilog_ports(dut),
                                     emit_src=False, platform=cells))
    assert len(cells.lowered) == 3 and "$mem " not in text
    inits = re.findall(r'cell \$meminit_v2 \S+\n    parameter \\MEMID "\\\\(\w+)"', text)
    assert sorted(inits) == ["neg", "two_reads", "words"]
    assert "connect \\DATA { 8'00000000 8'11111111 8'00000000 8'00000011 }" in text
    assert [m for m in re.findall(r"memory width 8 size 4 \\(\w+)", text)] == [
        "zero", "words", "neg", "two_reads"]


def test_port_names_renumbered_in_order():
    """The cell-named ports keep their order and take Amaranth's numbers; a different count
    of names is a tool error, not a silent mismatch."""
    text = "wire input 1 \\port$4$0\nconnect \\port$9$2 \\port$4$0\n"
    assert rename_ports(text, [6, 13]) == (
        "wire input 1 \\port$6$0\nconnect \\port$13$2 \\port$6$0\n")
    with pytest.raises(ToolError):
        rename_ports(text, [6])


def test_no_private_amaranth_import():
    """Deliverable 6 of issue 39: the lowering uses public Amaranth only."""
    from pathlib import Path

    import rvsm.rtl.verilog_memories as module

    source = Path(module.__file__).read_text(encoding="utf-8")
    assert not re.search(r"amaranth\.hdl\._|from amaranth\.hdl import .*\b_[a-z]+", source)
