"""Pin planner (rtl/fpga/pin_plan.py) and board top ports (rtl/fpga/board_top.py)."""

from __future__ import annotations

import re

import pytest
from amaranth.back import verilog

from rvsm.model.fixed.point_toml import load_design_point
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.board_top import CONTROLS, BoardTop, board_ports
from rvsm.rtl.fpga.flow import build_component
from rvsm.rtl.fpga.package_pins import load_package
from rvsm.rtl.fpga.pin_plan import BoardPorts, LinkSpec, edge_clock_placements, plan_pins

POINT = "points/ecp5-85-40khz.toml"
TINY = BoardPorts((LinkSpec("rx0", "rx", 2), LinkSpec("tx0", "tx", 2)), ("rst_n", "led"))
#: The shipped point's links (the board front end's): 280 code bits = 35 pairs in, 160
#: spike bits = 20 pairs out, each with its framing lane (LinkSpec counts it as data).
FULL = BoardPorts((LinkSpec("rx0", "rx", 36), LinkSpec("tx0", "tx", 21)), CONTROLS)


def _pairs_by_ball(package: str) -> dict:
    return {p.p.ball: p for p in load_package(package).pairs}


def test_tiny_plan_puts_every_port_on_a_legal_site():
    plan = plan_pins(TINY)
    assert plan.package == "CABGA381" and not plan.rejected
    pairs = _pairs_by_ball("CABGA381")
    sites = {s.port: s for s in plan.sites}
    assert set(sites) == {"rx0_clk", "rx0_d0", "rx0_d1", "tx0_clk", "tx0_d0", "tx0_d1",
                          "clk_osc", "rst_n", "led"}
    assert len({s.ball for s in plan.sites}) == len(plan.sites)  # no ball twice
    for port in ("tx0_clk", "tx0_d0", "tx0_d1"):  # true LVDS output drivers only
        assert pairs[sites[port].ball].lvds_output
    assert pairs[sites["rx0_clk"].ball].pclk  # forwarded clock on a dedicated clock pair
    for s in plan.sites:
        if s.io_type == "LVDS":
            assert pairs[s.ball].gearing  # left/right banks: IDDRX2F/ODDRX2F exist there
    side = {s.port[:3]: s.pio[1] for s in plan.sites if s.io_type == "LVDS"}
    assert len(set(side.values())) == 2  # one link a side
    assert plan.pins_used == 6 * 2 + 3 and plan.pins_available == 205
    lpf = plan.lpf()
    for s in plan.sites:
        assert f'LOCATE COMP "{s.port}" SITE "{s.ball}";' in lpf
        assert f'IOBUF PORT "{s.port}" IO_TYPE={s.io_type};' in lpf
    assert 'FREQUENCY PORT "clk_osc" 100 MHZ;' in lpf
    assert 'FREQUENCY PORT "rx0_clk" 400 MHZ;' in lpf


def test_full_sensor_does_not_fit_cabga381_and_the_planner_chooses_cabga756():
    plan = plan_pins(FULL)
    assert plan.package == "CABGA756"
    assert [p for p, _ in plan.rejected] == ["CABGA381", "CABGA554"]
    why381 = dict(plan.rejected)["CABGA381"]
    assert "37 receive pairs and 22 transmit" in why381
    assert "left banks 6+7: 16+16 pairs, 8+8 true-LVDS output" in why381
    assert plan.pins_used == (37 + 22) * 2 + 8 == 126 and plan.pins_available == 365
    assert plan.link_sides == {"rx0": ("L", (6, 7)), "tx0": ("R", (2, 3))}
    why554 = dict(plan.rejected)["CABGA554"]
    assert "left banks 6+7: 24+16 pairs, 12+8 true-LVDS output" in why554
    # 18 transmit pairs with the framing lane (136 bits a cycle) would fit CABGA554
    assert plan_pins(BoardPorts((FULL.links[0], LinkSpec("tx0", "tx", 18)),
                                CONTROLS)).package == "CABGA554"
    with pytest.raises(RvsmError, match="CABGA381: 2 links need 37 receive pairs"):
        plan_pins(FULL, "CABGA381")


def test_edge_clock_rules_of_the_placements():
    links = [LinkSpec(f"l{i}", "rx", 1) for i in range(2)]
    for where in edge_clock_placements(links):
        sides = [s for s, _ in where.values()]
        if sides[0] == sides[1]:  # two links on a side share one bank
            assert where["l0"][1] == where["l1"][1] and len(where["l0"][1]) == 1
    with pytest.raises(RvsmError, match="4 CLKDIVF"):
        plan_pins(BoardPorts(tuple(LinkSpec(f"l{i}", "rx", 1) for i in range(5))))
    with pytest.raises(RvsmError, match="at least one data pair"):
        LinkSpec("x", "tx", 0)


def test_the_shipped_points_links():
    point = load_design_point(POINT)
    core, _ = build_component(point.contract(), "stream", lanes=40)
    core._MustUse__silence = True  # only its signature is read
    assert board_ports(core) == FULL  # 280 code bits in, 2 x 2 x 40 spike bits out


def test_board_top_ports_are_the_planned_ports():
    point = load_design_point(POINT)
    core, _ = build_component(point.with_size(4, 8).contract(), "stream", lanes=2)
    ports = board_ports(core)
    assert [(k.name, k.direction, k.data_pairs) for k in ports.links] == [
        ("rx0", "rx", 3), ("tx0", "tx", 2)]  # 14 code bits in, 8 spike bits out, + framing
    top = BoardTop(core, ports)
    text = verilog.convert(top, name="top", ports=top.port_list, emit_src=False)
    header = re.search(r"module top\((.*?)\);", text, re.S)[1]
    names = {n.strip() for n in header.split(",")}
    assert names == {s.port for s in plan_pins(ports).sites}
    for prim in ("IDDRX2F", "ODDRX2F", "ECLKSYNCB", "CLKDIVF", "EHXPLLL"):
        assert prim in text
