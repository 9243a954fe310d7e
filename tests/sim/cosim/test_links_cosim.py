"""cocotb runs through both board links with the simulator doing every bit: the link
loopback (sensor serialiser, front end, board deserialiser; skew between the receive
pairs and a bit slip) in the long-run harness, and the AXI IP on a board with its link
registers read over SPI through a bit slip and a stopped forwarded clock. Every spike
out of the transmit link equal to the fixed twin's."""

from __future__ import annotations

from pathlib import Path

import pytest

from rvsm.model.fixed.point_toml import load_design_point
from rvsm.sim.cosim.ip_links_run import ip_links_verify
from rvsm.sim.cosim.links_run import links_verify


def _check_run(result: dict, steps: int, beats_per_frame: int) -> None:
    assert result["mismatches"] == 0, result["first_mismatch"]
    assert result["beats_out"] == steps * beats_per_frame
    assert result["compared"] > 0 and result["spikes"] > 0
    assert result["stray"] == 0 and result["overflow"] == 0
    assert len(set(result["delays"])) > 1  # skew between the pairs


def test_tiny_point_through_the_links(tmp_path) -> None:  # noqa: ANN001
    point = load_design_point("tests/data/formal-tiny.toml").with_size(4, 8)
    _check_run(links_verify(point, 2, 3, tmp_path, sim="icarus", seed=1), 3, 16)


@pytest.mark.slow
def test_small_point_through_the_links_on_verilator(tmp_path) -> None:  # noqa: ANN001
    point = load_design_point("points/ecp5-85-40khz.toml").with_size(8, 40)
    _check_run(links_verify(point, 40, 6, tmp_path, sim="verilator", seed=2), 6, 8)


def test_ip_on_a_board_faults_reported_over_spi(tmp_path) -> None:  # noqa: ANN001
    point = load_design_point("tests/data/formal-tiny-shared.toml").with_size(4, 8)
    r = ip_links_verify(point, 2, 4, tmp_path, seed=1)
    assert r["mismatches"] == 0, r["first_mismatch"]
    assert r["beats_out"] == 4 * 16 and r["spikes"] > 0
    assert r["tx_link_errors"] == 0 and r["out_framing_errors"] == 0 and r["overflow"] == 0
    reg = r["registers"]
    # locked, aligned, no request, no error, no loss; the IP initialised
    assert reg["locked:LINK_STATUS"] == 0b011 and reg["locked:LINK_ERRORS0"] == 0
    assert reg["locked:LINK_LOSSES"] == 0 and reg["locked:STATUS"] & 0b10011 == 0
    # a 3-bit slip on pair 0: its words counted wrong (4 in a row drop the lock), relocked
    assert reg["slip:LINK_ERRORS0"] & 0xFF >= 4 and reg["slip:LINK_ERRORS0"] >> 8 == 0
    assert reg["slip:LINK_LOSSES"] == 1 and reg["slip:LINK_STATUS"] == 0b011
    # the forwarded clock stopped: not locked, not aligned, training requested
    assert reg["stopped:LINK_STATUS"] == 0b100
    assert reg["relocked:LINK_LOSSES"] == 2 and reg["relocked:LINK_STATUS"] == 0b011
    assert reg["end:LINK_STATUS"] == 0b011 and reg["end:LINK_LOSSES"] == 2
    assert reg["end:LINK_ERRORS0"] >> 8 == 0  # the framing lane: no error
    assert reg["end:STATUS"] & 0b11 == 0  # no IP overflow, no framing error


@pytest.mark.parametrize("args", [["--lanes", "3"], ["--size", "4by8"]])
def test_links_run_refuses_bad_input_with_status_2(tmp_path, args: list[str]) -> None:  # noqa: ANN001
    """``scripts/links_run.py``: lanes that do not divide the width, a malformed size."""
    import subprocess
    import sys

    run = subprocess.run([sys.executable, "scripts/links_run.py", "tests/data/formal-tiny.toml",
                          "--size", "4x8", *args, "--sim", "icarus", "--work", str(tmp_path)],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 2, run.stderr
    assert run.stderr.startswith("links_run: ") and not run.stdout


def test_a_wrong_spike_is_named_with_a_waveform_window(tmp_path) -> None:  # noqa: ANN001
    """One expected spike changed: one mismatch at its step, scale, row and column, and a
    waveform of the window before it (Icarus)."""
    point = load_design_point("tests/data/formal-tiny.toml").with_size(4, 8)
    r = links_verify(point, 2, 3, tmp_path, sim="icarus", seed=1, flip=(1, 1, 2, 5))
    assert r["mismatches"] == 1
    first = r["first_mismatch"]
    assert (first["step"], first["scale"], first["row"], first["column"]) == (1, 1, 2, 5)
    assert r["window_cycles"][0] < r["window_cycles"][1]
    wave = Path(r["waveform"])
    assert wave.suffix == ".fst" and wave.stat().st_size > 0
