"""cocotbext-axi co-simulation of the AXI IP: the fixed twin, beat for beat, under random
idle cycles and back-pressure; the drop policy against the cycle model."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.stimulus import Stimulus
from rvsm.sim.cosim.axis_run import axis_verify


def _stimulus(c: ArrayContract, steps: int, seed: int, clear_before: tuple[int, ...] = ()
              ) -> Stimulus:
    rng = np.random.default_rng(seed)
    codes = rng.integers(0, 1 << c.adc_bits, (steps, c.height, c.width))
    thr = rng.integers(1, 60, (c.num_scales, c.height, c.width))
    return Stimulus(codes, thr, c.run(codes, thr, clear_before).astype(np.int8), c,
                    clear_before=clear_before)


def _check(result: dict) -> None:
    assert result["mismatches"] == 0, result["first_mismatch"]
    assert result["cocotb_failed"] == 0


def test_stall_policy_icarus(small_contract, cosim_work: Path) -> None:
    """Two segments (a clear between), 30 % idle input cycles, 50 % back-pressure."""
    stim = _stimulus(small_contract("dog1", 4, 8), 3, seed=1, clear_before=(2,))
    r = axis_verify(stim, "icarus", "stall", seed=5, idle_in=0.3, idle_out=0.5, lanes=2,
                    fifo_depth=4, work_dir=cosim_work)
    _check(r)
    assert r["counters"]["OUT_BEATS"] == 3 * 16 and r["counters"]["DROPPED"] == 0
    assert r["compared"] == stim.spikes.size


@pytest.mark.slow
@pytest.mark.parametrize("sim", ["icarus", "verilator"])
def test_drop_policy_matches_the_cycle_model(small_contract, cosim_work: Path,
                                             sim: str) -> None:
    stim = _stimulus(small_contract("dog4", 4, 8), 3, seed=2)
    r = axis_verify(stim, sim, "drop", seed=7, idle_in=0.1, idle_out=0.6, lanes=2,
                    fifo_depth=4, work_dir=cosim_work)
    _check(r)
    assert r["dropped"] > 0 and r["counters"]["DROPPED"] == r["dropped"]


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2])
def test_stall_policy_verilator_and_wider(small_contract, cosim_work: Path,
                                          seed: int) -> None:
    stim = _stimulus(small_contract("dog4", 8, 8), 3, seed=seed, clear_before=(1,))
    for sim in ("icarus", "verilator"):
        r = axis_verify(stim, sim, "stall", seed=seed, idle_in=0.5, idle_out=0.7,
                        lanes=4, fifo_depth=6, work_dir=cosim_work)
        _check(r)
        assert r["counters"]["OUT_BEATS"] == 3 * 16


@pytest.mark.slow
def test_rvsm_verify_interface_axis(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    from rvsm.sim.cli.main import main

    point = tmp_path / "point.toml"
    assert main(["config", "new", "-o", str(point)]) == 0
    for policy in ("stall", "drop"):
        assert main(["verify", "--interface", "axis", "--policy", policy, "--random", "3",
                     "--fixed", str(point), "--size", "8x8", "--steps", "20", "--lanes",
                     "2", "--fifo-depth", "6", "--idle-out", "0.6", "--work",
                     str(tmp_path / "work")]) == 0
        out = capsys.readouterr().out
        assert f"{policy} policy" in out and ", 0 mismatches" in out
