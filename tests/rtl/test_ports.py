"""Ports derived from signatures: the threshold-write bus and the Verilog port map."""

from __future__ import annotations

import pytest
from amaranth.hdl import Fragment
from amaranth.lib import wiring

from rvsm.rtl.interfaces import ThresholdWriteSignature
from rvsm.rtl.parallel.architecture import PARALLEL
from rvsm.rtl.parallel.array import RvsmArray
from rvsm.rtl.parallel.pixel_cell import PixelCell
from rvsm.rtl.ports import port_map, verilog_ports


def test_cell_and_array_share_the_threshold_bus(small_contract) -> None:
    c = small_contract("dog2", 3, 4, acc_bits=12)
    array = RvsmArray(c)
    cell = PixelCell(14, 1, 12, True)
    cfg = array.signature.members["cfg"]
    thr = cell.signature.members["thr"]
    assert cfg.flow == thr.flow == wiring.In
    assert cfg.signature == ThresholdWriteSignature(11, array.addr_bits)
    assert thr.signature == ThresholdWriteSignature(11)
    assert list(cfg.signature.members) == ["we", "addr", "data"]
    assert list(thr.signature.members) == ["we", "data"]
    assert array.signature == RvsmArray.interface(c)
    Fragment.get(array, None), Fragment.get(cell, None)  # both elaborate with it


def test_verilog_ports_follow_the_signature(small_contract) -> None:
    c = small_contract("dog2", 3, 4, acc_bits=12)
    dut = RvsmArray(c)
    ports = verilog_ports(dut)
    Fragment.get(dut, None)
    assert list(ports) == ["codes", "strobe", "clear", "cfg_we", "cfg_addr", "cfg_data",
                           "spike_pos", "spike_neg", "valid"]
    rows = PARALLEL.port_map(c)
    widths = {r["name"]: r["width"] for r in rows}
    assert [r["name"] for r in rows][:2] == ["clk", "rst"]
    assert widths["cfg_addr"] == dut.addr_bits == 5 and widths["cfg_data"] == 11
    assert widths["codes"] == 12 * 4 and widths["spike_pos"] == 2 * 12
    assert {r["dir"] for r in rows if r["name"].startswith("spike")} == {"out"}


def test_port_map_of_any_component_refuses_missing_or_stale_docs() -> None:
    cell = PixelCell(10, 0, 8, False)
    names = ["clk", "rst", "sum_in", "strobe", "clear", "thr_we", "thr_data", "spike_pos",
             "spike_neg", "acc", "threshold"]
    docs = {n: n.upper() for n in names}
    rows = port_map(cell, docs)
    assert port_map(cell.signature, docs) == rows
    Fragment.get(cell, None)
    assert [r["name"] for r in rows] == names and rows[2]["width"] == 10
    with pytest.raises(ValueError, match="missing"):
        port_map(cell, {k: v for k, v in docs.items() if k != "acc"})
    with pytest.raises(ValueError, match="unknown"):
        port_map(cell, {**docs, "thr_addr": "gone"})
