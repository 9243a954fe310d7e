"""Feasibility of a point on a device at a camera's size and rate: each budget's verdict."""

from __future__ import annotations

import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.block_ram import ScaleState, StateLayout
from rvsm.rtl.fpga.devices import get_budget
from rvsm.rtl.fpga.feasibility import Camera, LogicCost, MeasuredFmax, assess

CAMERA = Camera(250, 400, 40_000.0)
#: 436 LUT4 per lane (the shipped dog2 point's lane cost, 16x16), 131 LUT4 at zero lanes,
#: 1,042 FF per lane and 300 at zero lanes
DEFAULT_LOGIC = LogicCost(436, 131, 1042, 300)
ECP5 = get_budget("ecp5-85")


def _dog2_a17_shared() -> StateLayout:
    return StateLayout(250, 400, (ScaleState(17, 0),) * 2, adc_bits=7, radius=1)


def test_dog2_a17_shared_thresholds_fits_the_ecp5_85_at_40_lanes() -> None:
    f = assess(_dog2_a17_shared(), ECP5, CAMERA, DEFAULT_LOGIC, package="CABGA756")
    assert f.feasible and f.lanes == 40 and f.clock_needed_hz == 100e6
    c = f.checks
    assert (c["memory"].figure, c["memory"].budget) == (190, 208)
    # nextpnr's 1.199 x (131 + 40 x 436 + the bank multiplexers: per scale 3 banks of
    # 40 x 17 bits, 2 LUT4 a bit and 14.1 per extra bank) + the line buffer: 10 x (2 x 40 x
    # 7) bits in 16x4 RAMs, 4 LUT4 each (rtl/fpga/placed_logic.py)
    assert c["lut4"].figure == pytest.approx(
        1.199 * (131 + 40 * 436 + 2 * (2 * 680 + 2 * 14.1)) + 4 * 140)
    assert c["lut4"].budget == pytest.approx(0.8 * 83640)
    assert c["ff"].figure == 300 + 40 * 1042
    # P = 20, 25 need 200 and 160 MHz, above the ECP5 model (154.1 MHz at P = 8, 115.7 at
    # P = 40, the full sensor placed and routed)
    assert c["fmax"].budget == 115.7 and "measured at P = 40" in c["fmax"].detail
    assert "feasible on ecp5-85 at P = 40" in f.summary()
    # I/O on the CABGA756: one link each way, 35 + 20 data pairs + 2 x (clock, framing)
    assert (c["io"].figure, c["io"].budget, c["io"].unit) == (35 + 20 + 2 * 2, 112, "pairs")


def test_only_the_io_breaks_on_the_cabga381() -> None:
    f = assess(_dog2_a17_shared(), ECP5, CAMERA, DEFAULT_LOGIC)  # CABGA381 by default
    assert [c.name for c in f.broken] == ["io"] and f.lanes == 40
    io = f.checks["io"]
    # 28 Gbit/s in = 35 pairs of 8 bits a 100 MHz cycle, 16 Gbit/s out = 20 pairs; the
    # transmit link (+ framing + clock) needs 22 true-LVDS pairs on one edge clock, the
    # right side (banks 2+3) has 17
    assert (io.figure, io.budget, io.unit) == (22, 17,
                                               "true-LVDS transmit pairs on one edge clock")
    assert "io BREAKS: 22 / 17 true-LVDS transmit pairs on one edge clock (+29 %)" in \
        f.summary()
    assert f.io is not None and f.io.input.bits_per_pair_per_cycle == 8
    assert f.to_dict()["io"]["links"] == {"in": 0, "out": 0}
    bank = assess(_dog2_a17_shared(), ECP5, CAMERA, DEFAULT_LOGIC, io_links="bank")
    assert (bank.checks["io"].figure, bank.checks["io"].budget) == (22, 9)
    with pytest.raises(RvsmError, match="no package 'QFN9'; choose one of: LFE5U-85F "
                                        "CABGA381"):
        assess(_dog2_a17_shared(), ECP5, CAMERA, DEFAULT_LOGIC, package="QFN9")
    with pytest.raises(RvsmError, match="io_links must be one of side, bank"):
        assess(_dog2_a17_shared(), ECP5, CAMERA, DEFAULT_LOGIC, io_links="chip")


def test_the_shipped_point_fits_in_its_package_and_not_in_the_default_one() -> None:
    """The model ``rvsm datasheet`` judges it with: the I/O of points/ecp5-85-40khz.toml
    on its ``[rtl] package`` (CABGA756) fits, on the ecp5-85's default CABGA381 breaks."""
    from pathlib import Path

    from rvsm.model.fixed.point_toml import load_point_file
    from rvsm.rtl.fpga.camera import clock_needed_hz

    point, build = load_point_file(Path(__file__).parents[3] / "points" / "ecp5-85-40khz.toml")
    assert (build.device, build.package, build.lanes) == ("ecp5-85", "CABGA756", 40)
    h, w = point.shape
    layout = StateLayout.from_contract(point.contract(),
                                       shared_thresholds=point.shared_thresholds)
    camera = Camera(h, w, 40_000.0, clock_needed_hz(h, w, build.lanes, 40_000.0))
    own = assess(layout, ECP5, camera, DEFAULT_LOGIC, package=build.package)
    assert own.checks["io"].ok and own.io is not None and own.io.package.endswith("CABGA756")
    assert own.feasible and (own.checks["io"].figure, own.checks["io"].budget) == (59, 112)
    default = assess(layout, ECP5, camera, DEFAULT_LOGIC, package="CABGA381")
    assert [c.name for c in default.broken] == ["io"]
    assert (default.checks["io"].figure, default.checks["io"].budget) == (22, 17)


def test_default_point_breaks_memory_with_its_figures() -> None:
    lay = StateLayout.from_contract(default_design_point().contract())
    f = assess(lay, ECP5, CAMERA, DEFAULT_LOGIC)
    assert not f.feasible and f.lanes == 40  # the fewest lanes meeting the clock
    broken, io = f.broken  # and 40 + 2 transmit pairs for dog4, over a side's 17
    assert broken.name == "memory" and (broken.figure, broken.budget) == (779, 208)
    assert io.name == "io" and (io.figure, io.unit) == (
        42, "true-LVDS transmit pairs on one edge clock")
    assert broken.over_by == pytest.approx(779 / 208 - 1)
    assert "memory BREAKS: 779 / 208 DP16KD (+275 %)" in f.summary()
    # today's RTL organisation: per scale 3 banks (2 full, one of 452 words) of 40 + 38
    rtl = assess(lay, ECP5, CAMERA, DEFAULT_LOGIC, organisation="rtl")
    assert rtl.checks["memory"].figure == 4 * 3 * (40 + 38)


def test_logic_budget_breaks_with_headroom() -> None:
    heavy = LogicCost(1500, 0, 100, 0)
    f = assess(_dog2_a17_shared(), ECP5, CAMERA, heavy, package="CABGA756")
    assert [c.name for c in f.broken] == ["lut4"]
    lut = 1.199 * (40 * 1500 + 2 * (2 * 680 + 2 * 14.1)) + 560
    assert f.checks["lut4"].figure == pytest.approx(lut) and lut > 0.8 * 83640
    # the same logic fits with no headroom asked: 75,829 <= 83,640
    assert assess(_dog2_a17_shared(), ECP5, CAMERA, heavy, max_utilisation=1.0,
                  package="CABGA756").feasible
    with pytest.raises(RvsmError, match="max_utilisation"):
        assess(_dog2_a17_shared(), ECP5, CAMERA, heavy, max_utilisation=0)


def test_a_measured_fmax_below_the_model_decides() -> None:
    slow = MeasuredFmax(90.0, 1, "a test")
    light = LogicCost(1000, 131, 800, 300)
    f = assess(_dog2_a17_shared(), ECP5, CAMERA, light, measured=slow, package="CABGA756")
    # 90 MHz: P = 40 needs 100 MHz, so the fewest lanes are 50 (80 MHz)
    assert f.feasible and f.lanes == 50 and f.checks["fmax"].budget == 90.0
    assert "measured: 90.0 MHz at P = 1 (a test), taken for P = 50" in f.checks["fmax"].detail
    fast = MeasuredFmax(300.0, 1, "a test")
    f = assess(_dog2_a17_shared(), ECP5, CAMERA, light, measured=fast)
    assert f.lanes == 40 and f.checks["fmax"].budget == 115.7  # the model is lower


def test_a_fixed_clock_sets_the_lanes() -> None:
    cam = Camera(250, 400, 40_000.0, clock_hz=160e6)
    f = assess(StateLayout(250, 400, (ScaleState(17, 0),), 7, 1), ECP5, cam, DEFAULT_LOGIC)
    assert f.lanes == 25 and f.clock_needed_hz == 160e6
    assert f.checks["fmax"].ok is False and f.broken[0].name == "fmax"  # 115.7 < 160


def test_no_timing_model_or_logic_is_unknown_not_feasible() -> None:
    small = StateLayout(64, 64, (ScaleState(12, 0),), 7, 1)
    cam = Camera(64, 64, 1000.0)
    f = assess(small, get_budget("gw2a-18"), cam, DEFAULT_LOGIC)
    assert not f.feasible and not f.broken
    assert [c.name for c in f.unknown] == ["fmax", "io"]  # no per-bank I/O off the ECP5
    assert f.summary().startswith("unverified on gw2a-18 (estimate only)")
    assert f.to_dict()["status"] == "estimate only"
    assert "ECP5 figures as a proxy on gowin" in f.checks["lut4"].detail
    g = assess(small, ECP5, cam, None)
    assert {c.name for c in g.unknown} == {"lut4", "ff"}


def test_camera_parse_and_size_mismatch() -> None:
    cam = Camera.parse({"size": "250x400", "rate_hz": 40000})
    assert cam == CAMERA and cam.pixel_steps_per_s == 4e9
    assert Camera.parse({"size": "4x8", "rate_hz": 10, "clock_mhz": 1}).clock_hz == 1e6
    for bad, msg in (({"size": "250by400", "rate_hz": 1}, "camera.size"),
                     ({"size": "4x8", "rate_hz": 0}, "rate_hz"),
                     ({"size": "4x8"}, "takes size, rate_hz"),
                     ("250x400", "must be a table")):
        with pytest.raises(RvsmError, match=msg):
            Camera.parse(bad)
    with pytest.raises(RvsmError, match="the camera 250x400"):
        assess(StateLayout(8, 8, (ScaleState(8, 0),), 7, 1), ECP5, CAMERA, DEFAULT_LOGIC)


def test_logic_cost_from_a_lane_cost_record() -> None:
    rec = {"lanes": [1, 2], "ff": [1500, 2500], "ff_per_lane": 1000.0,
           "lut4_per_lane": 1400.0, "lut4_base": 120.0, "size": [16, 16]}
    logic = LogicCost.from_record(rec)
    assert (logic.ff_base, logic.lut4_base, logic.lut4_per_lane) == (500.0, 120.0, 1400.0)
