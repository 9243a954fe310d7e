"""Parsing yosys/nextpnr outputs (fake JSON) and the FpgaReport's derived figures."""

from __future__ import annotations

import json

import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.infra.errors import ToolError
from rvsm.rtl.fpga.camera import state_memory
from rvsm.rtl.fpga.devices import DEVICES, get_device
from rvsm.rtl.fpga.report import FpgaReport, Usage, parse_nextpnr_report, parse_yosys_stat


def _step(kind: str, delay: float, cell: str, net: str | None = None) -> dict:
    s = {"type": kind, "delay": delay, "from": {"cell": cell, "port": "Q", "loc": [1, 1]},
         "to": {"cell": cell, "port": "D", "loc": [1, 2]}}
    if net is not None:
        s["net"] = net
    return s


def _fake_nextpnr() -> dict:
    clk = "posedge $glbnet$clk$TRELLIS_IO_IN"
    short = [_step("clk-to-q", 0.5, "u.a_TRELLIS_FF_Q"), _step("routing", 1.0, "x", "u.a[0]"),
             _step("setup", 0.4, "u.b_TRELLIS_FF_Q_3")]
    long = [_step("clk-to-q", 0.5, "u.acc_TRELLIS_FF_Q_7"),
            _step("routing", 2.0, "x", "u.acc[7]"),
            _step("logic", 0.45, "u.add$CCU2_COMB0"),
            _step("routing", 0.0, "x", "u.add$CCU2_FCI_INT"),
            _step("logic", 0.0, "u.add$CCU2_COMB1"),
            _step("routing", 1.5, "x", "u.sum[3]"),
            _step("setup", 0.4, "u.sat_TRELLIS_FF_Q_12")]
    async_path = [_step("source", 0.0, "rst$tr_io"), _step("routing", 9.0, "x", "rst")]
    return {
        "fmax": {"$glbnet$clk$TRELLIS_IO_IN": {"achieved": 123.5, "constraint": 125.0},
                 "$glbnet$clk2": {"achieved": 200.0, "constraint": 125.0}},
        "utilization": {
            "TRELLIS_COMB": {"used": 9298, "available": 83640},
            "TRELLIS_FF": {"used": 6381, "available": 83640},
            "DP16KD": {"used": 32, "available": 208},
            "TRELLIS_IO": {"used": 10, "available": 365},
        },
        "critical_paths": [
            {"from": clk, "to": clk, "path": short},
            {"from": "<async>", "to": clk, "path": async_path},
            {"from": clk, "to": clk, "path": long},
        ],
    }


def test_parse_nextpnr_report_fmax_usage_and_critical_path() -> None:
    r = parse_nextpnr_report(json.loads(json.dumps(_fake_nextpnr())))
    assert r["fmax_mhz"] == 123.5  # the slowest clock
    assert r["lut4"] == Usage(9298, 83640) and r["ff"] == Usage(6381, 83640)
    assert r["bram"] == Usage(32, 208)
    cp = r["critical_path"]
    assert cp.delay_ns == pytest.approx(0.5 + 2.0 + 0.45 + 1.5 + 0.4)  # not the async path
    assert cp.routing_ns == pytest.approx(3.5)
    assert cp.logic_ns == pytest.approx(1.35)
    assert cp.logic_steps == 1  # the zero-delay carry hop is not a step
    assert cp.start == "u.acc[7]" and cp.end == "u.sat (FF)"
    assert cp.nets == ("u.acc[7]", "u.sum[3]")
    assert "u.acc[7] -> u.sat (FF)" in cp.summary()


def test_parse_nextpnr_report_without_clock_paths() -> None:
    data = _fake_nextpnr()
    data["critical_paths"] = [p for p in data["critical_paths"] if p["from"] == "<async>"]
    assert parse_nextpnr_report(data)["critical_path"] is None
    with pytest.raises(ToolError, match="no Fmax"):
        parse_nextpnr_report({"utilization": data["utilization"]})


def test_parse_yosys_stat_counts_lut4_sites() -> None:
    stat = {"design": {"num_cells_by_type": {
        "$scopeinfo": 3, "LUT4": 100, "CCU2C": 10, "TRELLIS_DPR16X4": 2, "PFUMX": 4,
        "TRELLIS_FF": 77, "DP16KD": 5}}}
    r = parse_yosys_stat(stat)
    assert r["lut4"] == 100 + 2 * 10 + 4 * 2
    assert (r["ff"], r["bram"]) == (77, 5)
    assert "$scopeinfo" not in r["cells"]
    only_modules = {"modules": {"\\top": stat["design"]}}
    assert parse_yosys_stat(only_modules) == r
    with pytest.raises(ToolError):
        parse_yosys_stat({"modules": {}})


def _report(**kw) -> FpgaReport:  # noqa: ANN003
    point = default_design_point()
    dev = get_device("ecp5-85")
    args = dict(arch="stream", model="dog4", height=64, width=64, lanes=4, device=dev,
                speed=6, target_mhz=125.0, mode="place-and-route",
                lut4=Usage(9298, dev.lut4), ff=Usage(6381, dev.ff), bram=Usage(32, dev.bram),
                harness_ff=300, harness_lut4=20, sensor_height=250, sensor_width=400,
                sensor_state=state_memory(point.contract(), thresholds_uniform=True),
                fmax_mhz=117.5)
    args.update(kw)
    return FpgaReport(**args)


def test_report_throughput_and_camera_arithmetic() -> None:
    r = _report()
    assert r.lut4_per_lane == 9298 / 4
    assert r.pixel_steps_per_s == pytest.approx(4 * 117.5e6)
    assert r.sensor_pixel_steps_per_s == 250 * 400 * 40e3
    assert r.clock_needed_mhz == pytest.approx(250 * 100 * 40e3 / 1e6)  # 1000 MHz
    need = r.lanes_needed
    assert 400 % need == 0 and 250 * (400 // need) * 40e3 <= 117.5e6
    smaller = [p for p in range(1, need) if 400 % p == 0]
    assert all(250 * (400 // p) * 40e3 > 117.5e6 for p in smaller)
    d = json.loads(r.to_json())
    assert d["device"] == "ecp5-85" and d["lut4"]["percent"] == pytest.approx(11.12, abs=0.01)
    assert d["sensor_lanes_needed_at_fmax"] == need
    assert d["sensor_state"]["devices_holding_all_state"] == []
    text = r.table()
    assert "117.5 MHz (misses the 125 MHz target)" in text
    assert "no ECP5 holds it" in text


def test_report_synthesis_only_has_no_fmax() -> None:
    r = _report(mode="synthesis-only", fmax_mhz=None)
    assert r.pixel_steps_per_s is None and r.lanes_needed is None
    assert "not measured (synthesis only" in r.table()
    assert json.loads(r.to_json())["fmax_mhz"] is None


def test_devices_and_unknown_device() -> None:
    assert DEVICES["ecp5-85"].bram_bits == 208 * 18 * 1024
    from rvsm.model.infra.errors import RvsmError

    with pytest.raises(RvsmError, match="ecp5-85"):
        get_device("ice40")


def test_the_critical_path_is_shown_when_timing_is_met_too() -> None:
    from rvsm.rtl.fpga.report import CriticalPath

    path = CriticalPath("a.q[0]", "b (FF)", 6.5, 2.0, 4.5, 3, ("a.q[0]",))
    text = _report(fmax_mhz=153.8, target_mhz=150.0, critical_path=path, seed=2).table()
    assert "153.8 MHz (meets the 150 MHz target, placer seed 2)" in text
    assert "critical path a.q[0] -> b (FF): 6.50 ns" in text


def test_lanes_needed_name_the_fmax_and_lanes_and_flag_an_extrapolation() -> None:
    r = _report(fmax_mhz=150.0)  # measured at P = 4; 250x400 at 40 kHz needs P = 40
    assert r.lanes_needed == 40 and r.lanes_extrapolated
    text = r.table()
    assert "at the 150.0 MHz measured at P = 4, 64x64: 40 lanes (clock 100.0 MHz)" in text
    assert "extrapolated from P = 4" in text and "--lanes 40 to confirm" in text
    assert json.loads(r.to_json())["sensor_lanes_extrapolated"] is True
    same = _report(lanes=40, fmax_mhz=150.0)
    assert not same.lanes_extrapolated and "extrapolated" not in same.table()


def test_lane_slope_separates_the_fixed_part() -> None:
    from rvsm.rtl.fpga.report import LaneSlope

    s = LaneSlope(lanes=(4, 8), lut4=(7000, 13000), ff=(4400, 8000))
    assert s.lut4_per_lane == 1500 and s.ff_per_lane == 900
    assert s.lut4_fixed == 1000 and s.ff_fixed == 800
    text = _report(slope=s).table()
    assert "1,500 LUT4 and 900 FF (slope between P = 4 and 8" in text
    assert "fixed part 1,000 LUT4 and 800 FF" in text
    assert json.loads(_report(slope=s).to_json())["slope"]["lut4_fixed"] == 1000
    assert "(--slope-lanes: the slope)" in _report().table()
