"""A point's [rtl] build judged on its device (rtl/fpga/build_budget.py) and the
one-line verdicts of sim/sweep/verdict.py."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from rvsm.model.fixed.point_toml import load_point_file
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.build_budget import (
    clock_above_fmax,
    divisors_near,
    judge_build,
    lanes_error,
)
from rvsm.sim.sweep.verdict import prime_width_note

POINT = Path(__file__).parents[3] / "points" / "ecp5-85-40khz.toml"


def test_divisors_near_the_lanes_asked():
    assert divisors_near(400, 48) == [16, 20, 25, 40, 50, 80]
    assert all(400 % p == 0 for p in divisors_near(400, 7))
    line = lanes_error(400, 48)
    assert "rtl.lanes = 48" in line and "40, 50" in line and "\n" not in line


def test_shipped_point_fits_and_its_figures():
    point, build = load_point_file(POINT)
    assert judge_build(point, build, "p") == ("fits ecp5-85 CABGA756: state 192 / 208 DP16KD "
                                              "at 40 lane(s)")  # the package where the device is
    bare = dataclasses.replace(build, package=None)
    assert judge_build(point, bare, "p") == "fits ecp5-85: state 192 / 208 DP16KD at 40 lane(s)"


def test_an_estimate_only_rtl_device_is_judged_and_marked():
    point, build = load_point_file(POINT)
    gowin = dataclasses.replace(build, device="gw5ast-138", package=None)
    verdict = judge_build(point, gowin, "p")
    assert verdict.startswith("fits gw5ast-138: state ")
    assert verdict.endswith("(estimate only: rvsm fpga does not place gw5ast-138; no Fmax "
                            "model checks freq_mhz)")
    small = dataclasses.replace(build, device="ice40-hx8k", package=None)
    with pytest.raises(RvsmError, match="of rtl.device = ice40-hx8k"):
        judge_build(point, small, "p")


def test_clock_above_the_fmax_model_names_it():
    assert clock_above_fmax("ecp5-85", 40, 100.0) is None
    line = clock_above_fmax("ecp5-85", 40, 900.0)
    assert "rtl.freq_mhz = 900" in line and "115.7 MHz" in line and "set freq_mhz <= 116" in line
    point, build = load_point_file(POINT)
    with pytest.raises(RvsmError, match="freq_mhz = 900 is above the ecp5-85 Fmax model"):
        judge_build(point, dataclasses.replace(build, freq_mhz=900.0), "p")
    with pytest.raises(RvsmError, match="rtl.lanes = 48 does not divide the width 400"):
        judge_build(point, dataclasses.replace(build, lanes=48), "p")


def test_prime_width_named_with_each_lane_clock():
    note = prime_width_note(251, 401, 40000)
    assert "401 is prime" in note and "1 (4,026.0 MHz), 401 (10.0 MHz)" in note
    assert prime_width_note(250, 400, 40000) == ""
