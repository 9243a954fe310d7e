"""The event sensor's RTL on Icarus and Verilator (``array.sensor = "dvs"``): the
per-cycle testbench, the long-run harness and the parallel array against the fixed twin;
commands that do not apply to it refuse it in one line."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.fixed.point_toml import save_design_point
from rvsm.sim.cli import main


@pytest.fixture
def dvs_point(tmp_path: Path) -> Path:
    path = tmp_path / "dvs.toml"
    save_design_point(path, dataclasses.replace(default_design_point(), model="dog2",
                                                sensor="dvs", adc_bits=8))
    return path


@pytest.mark.parametrize("sim", ["icarus", "verilator"])
def test_stream_event_mode_on_both_simulators(sim: str, dvs_point: Path, tmp_path: Path,
                                              capsys) -> None:
    work = str(tmp_path / "w")
    assert main(["verify", "flyball", "--fixed", str(dvs_point), "--size", "8x12",
                 "--frames", "3", "--lanes", "3", "--sim", sim, "--work", work]) == 0
    assert "0 mismatches" in capsys.readouterr().out
    if sim == "icarus":  # the long-run harness (Verilator's: the slow test below)
        assert main(["verify", "flyball", "--fixed", str(dvs_point), "--size", "8x12",
                     "--frames", "6", "--lanes", "2", "--sim", sim, "--harness", "chunk",
                     "--chunk-steps", "7", "--quiet", "--work", work]) == 0
        assert "0 mismatches" in capsys.readouterr().out


def test_parallel_event_mode_and_random(dvs_point: Path, tmp_path: Path, capsys) -> None:
    work = str(tmp_path / "w")
    assert main(["verify", "coin", "--fixed", str(dvs_point), "--size", "4x5", "--frames",
                 "3", "--arch", "parallel", "--work", work]) == 0
    assert main(["verify", "--random", "3", "--fixed", str(dvs_point), "--size", "6x6",
                 "--steps", "20", "--lanes", "2", "--work", work]) == 0
    out = capsys.readouterr().out
    assert out.count("0 mismatches") == 2


def test_formal_and_mutate_refuse_the_event_sensor(dvs_point: Path, capsys) -> None:
    assert main(["formal", str(dvs_point), "--size", "3x4", "--lanes", "2"]) == 2
    assert "formal properties of the event sensor" in capsys.readouterr().err
    assert main(["mutate", str(dvs_point)]) == 2
    assert "mutations of the event sensor" in capsys.readouterr().err


@pytest.mark.slow
def test_full_sensor_event_mode(tmp_path: Path, capsys) -> None:
    """250x400 dog4, P = 40, 20 steps on Verilator in the long-run harness (about 5 min
    with the build)."""
    point = tmp_path / "dvs.toml"
    save_design_point(point, dataclasses.replace(default_design_point(), sensor="dvs",
                                                 adc_bits=8))
    assert main(["verify", "flyball", "--fixed", str(point), "--lanes", "40", "--sim",
                 "verilator", "--harness", "chunk", "--frames", "3", "--steps", "20",
                 "--quiet", "--work", str(tmp_path / "w")]) == 0
    assert "0 mismatches" in capsys.readouterr().out
