"""Protocol scripts on Icarus and Verilator (:mod:`rvsm.sim.cosim.protocol_run`): the
RTL follows every beat and cycle; a wrong expectation is a mismatch with its cycle and
a waveform; ``rvsm verify --protocol``'s exit statuses."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.fixed.point_toml import save_design_point
from rvsm.rtl.stream.protocol import random_script
from rvsm.sim.cli import main
from rvsm.sim.cosim.protocol_run import check_script_rtl


@pytest.mark.parametrize("sim", ["icarus", "verilator"])
def test_protocol_script_on_both_simulators(sim: str, small_contract, cosim_work: Path,
                                            rtl_builds: Path) -> None:
    c = small_contract("dog2", 6, 6, reset="zero")
    script = random_script(c, 3, 14, seed=2)
    r = check_script_rtl(script, sim, work_dir=cosim_work, build_root=rtl_builds)
    assert r["mismatches"] == 0, r["first_mismatch"]
    assert r["beats"] == len(script.expected.rows) > 0
    assert r["compared"] == script.expected.spikes.size
    assert r["coverage"][0]["thr_write_same_edge"] > 0


def test_wrong_expectation_is_found_with_its_cycle_and_waves(small_contract,
                                                             cosim_work: Path,
                                                             rtl_builds: Path) -> None:
    c = small_contract("dog2", 6, 6, reset="zero")
    script = random_script(c, 3, 14, seed=2)
    k = int(np.flatnonzero(script.expected.spikes.any(axis=(1, 2)))[5])
    script.expected.spikes[k] = 0
    r = check_script_rtl(script, "icarus", work_dir=cosim_work, build_root=rtl_builds)
    first = r["first_mismatch"]
    assert r["mismatches"] > 0 and first["beat"] == k
    assert first["cycle"] == int(script.expected_cycles[k])
    assert first["step"] == int(script.expected_steps[k])
    assert r["waves"] and Path(r["waves"]).stat().st_size > 0
    assert r["first_mismatch_time_ns"] > 0


def test_cli_verify_protocol(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    point = tmp_path / "p.toml"
    save_design_point(point, dataclasses.replace(default_design_point(), model="dog2"))
    work = str(tmp_path / "w")
    assert main(["verify", "--protocol", "1", "--fixed", str(point), "--size", "6x8",
                 "--steps", "14", "--lanes", "2", "--work", work]) == 0
    out = capsys.readouterr().out
    assert "protocol script 1" in out and "0 mismatches" in out
    assert "protocol coverage clears and stalls:" in out
    for extra in (["--arch", "parallel"], ["--harness", "chunk"], ["--random", "2"],
                  ["coin"]):
        assert main(["verify", "--protocol", "1", "--fixed", str(point), "--size", "6x8",
                     "--steps", "14", "--work", work, *extra]) == 2
    assert main(["verify", "--protocol", "1", "--fixed", str(point), "--work", work]) == 2
    assert "also needs --size, --steps" in capsys.readouterr().err
