"""cocotbext-axi co-simulation of the AXI IP: the fixed twin, beat for beat, under random
idle cycles and back-pressure; the drop policy against the cycle model."""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

import numpy as np
import pytest

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.stimulus import Stimulus
from rvsm.sim.cosim.axis_run import axis_verify

ROOT = Path(__file__).resolve().parents[3]


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


#: The two ``rvsm verify --interface axis`` rows of docs/ip.md's table: command -> result.
_DOC_ROW = re.compile(r"^\| `(rvsm verify --interface axis [^`]*)` \| ([^|]*) \|$", re.M)


def _figure(text: str, pattern: str) -> int:
    found = re.search(pattern, text)
    assert found, (pattern, text)
    return int(found.group(1).replace(",", ""))


def test_rvsm_verify_interface_axis_as_docs_ip_says(tmp_path: Path,
                                                    capsys: pytest.CaptureFixture) -> None:
    """Runs the two commands of docs/ip.md's table as written and checks every figure the
    table gives (beats in, flush, out, dropped, spikes compared) against ``--json``, so the
    doc cannot drift from the tool (issue 34)."""
    from rvsm.sim.cli.main import main

    rows = _DOC_ROW.findall((ROOT / "docs" / "ip.md").read_text())
    assert len(rows) == 2, rows
    assert main(["config", "new", "-o", str(tmp_path / "point.toml")]) == 0
    capsys.readouterr()
    for command, said in rows:
        argv = shlex.split(command)[1:]
        argv = [str(tmp_path / "point.toml") if a == "point.toml" else a for a in argv]
        assert main([*argv, "--json", "--work", str(tmp_path / "work")]) == 0
        r = json.loads(capsys.readouterr().out)
        assert r["mismatches"] == 0
        assert _figure(said, r"([\d,]+) beats in") == r["input_beats"]
        assert _figure(said, r"([\d,]+) out") == r["output_beats"] == \
            r["counters"]["OUT_BEATS"]
        assert _figure(said, r"([\d,]+) dropped") == r["dropped"]
        if "flush" in said:
            stream_beats = _figure(said, r"\(([\d,]+) \+")
            assert stream_beats + _figure(said, r"\+ ([\d,]+) flush") == r["input_beats"]
        if "spikes compared" in said:
            assert _figure(said, r"([\d,]+) spikes compared") == r["compared"]
