"""Logic per lane (yosys on two lane counts) and exact memory bits of a design point."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.camera import state_memory
from rvsm.rtl.fpga.lane_cost import lane_cost, logic_lut4
from rvsm.rtl.fpga.report import parse_yosys_stat


def _point(model: str):
    return dataclasses.replace(default_design_point(), model=model)


def test_lane_cost_slope_and_memory(tmp_path: Path) -> None:
    point = _point("dog1")
    cost = lane_cost(point, size=(4, 4), lanes=(1, 2), work_dir=tmp_path)
    runs = []
    for p in (1, 2):
        stat = parse_yosys_stat(json.loads((tmp_path / f"p{p}" / "stat.json").read_text()))
        runs.append(logic_lut4(stat["cells"]))
    # the harness' XOR trees are taken off both counts; the slope is their difference
    assert cost.logic[1] - cost.logic[0] <= runs[1] - runs[0]
    assert cost.lut4_per_lane == cost.logic[1] - cost.logic[0]
    assert cost.lut4_per_lane > 0 and cost.ff_per_lane > 0
    assert cost.lut4_base == pytest.approx(cost.logic[0] - cost.lut4_per_lane)
    st = state_memory(point.contract())  # memory at the point's own (sensor) size
    assert cost.memory_bits == st.total
    assert cost.accumulator_bits == st.accumulators and cost.threshold_bits == st.thresholds
    assert cost.fmax_mhz is None
    assert cost.to_dict()["memory_bits"] == st.total


def test_lane_cost_rejects_bad_lanes() -> None:
    with pytest.raises(RvsmError, match="1 <= P1 < P2"):
        lane_cost(_point("dog1"), lanes=(2, 2))
    with pytest.raises(RvsmError, match="multiple of"):
        lane_cost(_point("dog1"), size=(4, 6), lanes=(1, 4))


@pytest.mark.slow
def test_more_scales_cost_more_logic_per_lane() -> None:
    one = lane_cost(_point("dog1"), size=(8, 8))
    four = lane_cost(_point("dog4"), size=(8, 8), fmax=True)
    assert four.lut4_per_lane > 1.5 * one.lut4_per_lane
    assert four.fmax_mhz is not None and four.fmax_mhz > 20
