"""``rvsm fpga --board`` end to end on a tiny array: every port at a named site, nextpnr
without --lpf-allow-unconstrained exits 0 (FSM model, 2x4, one lane: nextpnr about 30 s)."""

from __future__ import annotations

import json
import re
from pathlib import Path

from rvsm.rtl.fpga.flow import run_fpga


def test_board_build_places_every_port_at_its_planned_site(tmp_path: Path, fsm_point) -> None:
    r = run_fpga(fsm_point, tmp_path, arch="stream", lanes=1, size=(2, 4), target_mhz=100.0,
                 board=True)
    board = r.board
    assert board is not None and board["package"] == "CABGA381"
    plan = json.loads((tmp_path / "pin_plan.json").read_text())
    header = re.search(r"module rvsm_fpga_top\((.*?)\);", (tmp_path / "top.v").read_text(),
                       re.S)[1]
    ports = {n.strip() for n in header.split(",")}
    lpf = (tmp_path / "top.lpf").read_text()
    located = dict(re.findall(r'LOCATE COMP "([^"]+)" SITE "([A-Z]+\d+)";', lpf))
    assert set(located) == ports == {s["port"] for s in plan["sites"]}
    assert board["ports"] == len(ports)
    assert "--lpf-allow-unconstrained" not in (tmp_path / "nextpnr.log").read_text()
    lvds = [s for s in plan["sites"] if s["io_type"] == "LVDS"]
    rx_data = sum(1 for s in lvds if re.fullmatch(r"rx\d+_d\d+", s["port"]))
    tx_ports = sum(1 for s in lvds if s["port"].startswith("tx"))
    prim = board["primitives"]
    # an IDDRX2F per receive pair, an ODDRX2F per transmit pair (forwarded clock included)
    assert prim["IOLOGIC"]["used"] == rx_data + tx_ports and prim["SIOLOGIC"]["used"] == 0
    assert prim["ECLKSYNCB"]["used"] == prim["CLKDIVF"]["used"] == len(board["links"]) == 2
    assert prim["EHXPLLL"]["used"] == 1 and prim["TRELLIS_IO"]["used"] == len(ports)
    assert board["pins_used"] == 2 * len(lvds) + len(ports) - len(lvds)
    assert board["pins_available"] == 205
    want = {c["role"]: c["constraint_mhz"] for c in board["clocks"].values()}
    assert want == {"core": 100.0, "link rx0 SCLK": 200.0, "link tx0 SCLK": 200.0}
    achieved = {c["role"]: c["achieved_mhz"] for c in board["clocks"].values()}
    print("board clocks (MHz):", achieved)  # the figures docs/fpga.md quotes
    met = {c["role"]: c["met"] for c in board["clocks"].values()}
    # the receive SCLK does not meet 200 MHz yet (docs/fpga.md, "Timing of the link
    # clocks"): the core clock and the transmit SCLK do
    assert met["core"] and met["link tx0 SCLK"], achieved
    assert "board         CABGA381" in r.table()
    assert json.loads(r.to_json())["board"]["package"] == "CABGA381"
