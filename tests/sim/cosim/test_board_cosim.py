"""cocotb (Icarus) run of the board front end through its links: serial bit streams
with skew between the pairs, a bit slip and a lost lock in; every spike out of the
transmitter equal to the fixed twin's, and the fault reported by the link status."""

from __future__ import annotations

import pytest

from rvsm.model.fixed.point_toml import load_design_point
from rvsm.sim.cosim.board_run import board_verify


def _check(result: dict) -> None:
    assert result["mismatches"] == 0, result["first_mismatch"]
    assert result["compared"] > 0 and result["spikes"] > 0
    assert result["cocotb_failed"] == 0
    status = result["status"]
    assert status["locked"] == 1
    assert status["lock_losses"] == 1  # the stopped clock
    assert status["lane_errors"] == 0 and status["framing_errors"] == 0
    assert status["tx_overflow"] == 0 and status["rx_overflow"] == 0
    assert result["tx_link_errors"] == [0, 0]


def test_tiny_point_through_the_links(tmp_path) -> None:  # noqa: ANN001
    point = load_design_point("tests/data/formal-tiny.toml").with_size(4, 8)
    _check(board_verify(point, 2, 4, tmp_path, seed=1, delays=(0, 4), slip=3))


@pytest.mark.slow
@pytest.mark.parametrize("slip", range(8))
def test_every_slip_and_more_frames(tmp_path, slip: int) -> None:  # noqa: ANN001
    point = load_design_point("tests/data/formal-tiny.toml").with_size(8, 8)
    _check(board_verify(point, 2, 12, tmp_path, seed=slip, delays=(slip % 3, 7 - slip),
                        slip=slip))
