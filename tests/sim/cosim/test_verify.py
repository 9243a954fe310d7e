"""cocotb regressions: generated Verilog vs the fixed twin, on Icarus and Verilator.

One build per (contract, simulator) is shared by many stimuli (the build cache of
:mod:`rvsm.sim.cosim.builds.build_cache`). Default: a border-heavy dog4 3x5 array and a
4x4 FSM array on both simulators, every model on Icarus, the checker-can-fail proof and tool errors.
``-m slow`` (``make regress``): every model on both shapes and simulators, longer streams.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.errors import RvsmError, ToolError
from rvsm.model.kernels.receptive_fields import MODEL_NAMES
from rvsm.sim.cosim.builds.cocotb_adapter import check_simulator
from rvsm.sim.cosim.verify import run_rtl

#: Icarus in the default suite; the Verilator variants (a build each, 30-45 s) run with
#: ``-m slow`` (``make regress``); the default suite still builds Verilator elsewhere
#: (code coverage, protocol scripts, the event mode, regressions)
SIMS = ["icarus", pytest.param("verilator", marks=pytest.mark.slow)]


def stimuli(c: ArrayContract, seed: int, steps: int = 60) -> dict[str, tuple]:
    """Named (codes, thresholds, clear_before) cases for one contract."""
    rng = np.random.default_rng(seed)
    s, h, w = c.num_scales, c.height, c.width
    full = (1 << c.adc_bits) - 1
    top = (1 << c.threshold_bits) - 1
    rand = rng.integers(0, full + 1, (steps, h, w))
    thr = rng.integers(1, top // 4, (s, h, w))
    extremes = np.concatenate([np.zeros((steps // 3, h, w), int),
                               np.full((steps // 3, h, w), full),
                               rng.choice([0, full], (steps - 2 * (steps // 3), h, w))])
    # fixed-pattern thresholds spanning 1..top: the top rail only fires when saturated
    fpn = np.clip(np.round(top / 8 * (1 + 0.5 * rng.standard_normal((s, h, w)))), 1, top)
    fpn.reshape(-1)[:: max(1, fpn.size // 3)] = top
    fpn.reshape(-1)[1] = 1
    # dark pixels ringed by full-scale ones: DoG sums go negative, so -1 spikes fire
    yy, xx = np.indices((h, w))
    checker = np.broadcast_to(((yy + xx) % 2) * full, (steps, h, w)).copy()
    return {
        "random": (rand, thr, ()),
        "extremes": (extremes, thr, ()),
        "checkerboard": (checker, thr, ()),
        "fixed_pattern": (rand, fpn.astype(np.int64), ()),
        "clear_mid_stream": (rand, thr, (steps // 3, steps // 2 + 1)),
    }


def exact_threshold_case(c: ArrayContract) -> tuple[np.ndarray, np.ndarray]:
    """Constant codes with thresholds equal to the first shifted sums: fire exactly."""
    codes = np.full((6, c.height, c.width), 5)
    sums = _shifted_sums(c, codes[:1])[0]
    thr = np.clip(np.abs(sums), 1, (1 << c.threshold_bits) - 1)
    return codes, thr


def _shifted_sums(c: ArrayContract, codes: np.ndarray) -> np.ndarray:
    from rvsm.model.fixed.contract import arithmetic_shift, integer_receptive_sums

    return arithmetic_shift(integer_receptive_sums(codes, c.weight_arrays), c.shift)


def check_all(c: ArrayContract, sim: str, cosim_work: Path, rtl_builds: Path, seed: int,
              steps: int = 60) -> None:
    """Every stimulus of :func:`stimuli` plus exact thresholds: zero mismatches."""
    spikes = {1: 0, -1: 0}
    cases = dict(stimuli(c, seed, steps))
    codes, thr = exact_threshold_case(c)
    cases["exact_threshold"] = (codes, thr, ())
    for name, (codes, thr, clears) in cases.items():
        r = run_rtl(c, codes, thr, sim, clear_before=clears, work_dir=cosim_work, name=name,
                    build_root=rtl_builds, arch="parallel")
        assert r["mismatches"] == 0, (name, r["first_mismatch"])
        assert r["compared"] == codes.shape[0] * c.num_scales * c.height * c.width
        want = c.run(codes, thr, clears)
        spikes[1] += int((want == 1).sum())
        spikes[-1] += int((want == -1).sum())
    assert spikes[1] > 0
    if c.signed and any((k < 0).any() for k in c.weight_arrays):
        assert spikes[-1] > 0  # DoG: negative sums fire -1 (Gaussians never go negative)


@pytest.mark.parametrize("sim", SIMS)
def test_dog4_border_array(small_contract, sim: str, cosim_work: Path, rtl_builds: Path) -> None:
    """dog4 on 3x5: 9x9 kernels mostly outside the array, 10-bit accumulators."""
    check_all(small_contract("dog4", 3, 5), sim, cosim_work, rtl_builds, seed=11)


@pytest.mark.parametrize("sim", SIMS)
def test_fsm_square_array(small_contract, sim: str, cosim_work: Path, rtl_builds: Path) -> None:
    """FSM (unsigned, zero reset) on 4x4 with 6-bit accumulators: the rail is hit."""
    c = small_contract("fsm", 4, 4, frac_bits=0, acc_bits=6, shift=0, reset="zero")
    check_all(c, sim, cosim_work, rtl_builds, seed=12)


@pytest.mark.parametrize("model", MODEL_NAMES)
def test_every_model_icarus(small_contract, model: str, cosim_work: Path, rtl_builds: Path) -> None:
    c = small_contract(model, 3, 5)
    rng = np.random.default_rng(13)
    codes = rng.integers(0, 16, (40, 3, 5))
    thr = rng.integers(1, 120, (c.num_scales, 3, 5))
    r = run_rtl(c, codes, thr, "icarus", work_dir=cosim_work, name=f"model_{model}",
                build_root=rtl_builds, arch="parallel")
    assert r["mismatches"] == 0, r["first_mismatch"]


def test_checker_catches_wrong_expectation(
    small_contract, cosim_work: Path, rtl_builds: Path
) -> None:
    """A deliberately wrong expectation is reported, named, and a waveform is kept."""
    c = small_contract("dog4", 3, 5)
    rng = np.random.default_rng(14)
    codes = rng.integers(0, 16, (30, 3, 5))
    thr = rng.integers(1, 60, (c.num_scales, 3, 5))
    wrong = c.run(codes, thr)
    step, scale, row, col = 17, 2, 1, 4
    good = int(wrong[step, scale, row, col])
    wrong[step, scale, row, col] = 1 if good != 1 else -1
    r = run_rtl(c, codes, thr, "icarus", expected=wrong, work_dir=cosim_work, name="wrong",
                build_root=rtl_builds, arch="parallel")
    assert r["mismatches"] == 1
    assert r["first_mismatch"] == {"step": step, "scale": scale, "row": row, "column": col,
                                   "expected": int(wrong[step, scale, row, col]),
                                   "got": good}
    assert r["waves"] and Path(r["waves"]).exists()


@pytest.mark.slow
def test_checker_catches_wrong_expectation_verilator(
    small_contract, cosim_work: Path, rtl_builds: Path
) -> None:
    """Same proof on Verilator, whose wave build (``--trace``) is made on demand."""
    c = small_contract("dog4", 3, 5)
    rng = np.random.default_rng(15)
    codes = rng.integers(0, 16, (20, 3, 5))
    thr = rng.integers(1, 60, (c.num_scales, 3, 5))
    wrong = c.run(codes, thr)
    wrong[9, 0, 0, 0] = 1 if wrong[9, 0, 0, 0] != 1 else 0
    r = run_rtl(c, codes, thr, "verilator", expected=wrong, work_dir=cosim_work,
                name="wrong_v", build_root=rtl_builds, arch="parallel")
    assert r["mismatches"] == 1 and r["first_mismatch"]["step"] == 9
    assert r["waves"] and Path(r["waves"]).exists()


def test_missing_simulator_is_one_clear_line(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PATH", "/nonexistent")
    with pytest.raises(ToolError, match="apt-get install iverilog"):  # exit status 3
        check_simulator("icarus")


@pytest.mark.slow
@pytest.mark.parametrize("sim", SIMS)
@pytest.mark.parametrize("shape", [(4, 4), (3, 5)])
@pytest.mark.parametrize("model", MODEL_NAMES)
def test_every_model_both_shapes(small_contract, model: str, shape: tuple[int, int], sim: str,
                                 cosim_work: Path, rtl_builds: Path) -> None:
    check_all(small_contract(model, *shape), sim, cosim_work, rtl_builds, seed=21, steps=300)


@pytest.mark.slow
@pytest.mark.parametrize("sim", SIMS)
def test_long_stream_8x12(small_contract, sim: str, cosim_work: Path, rtl_builds: Path) -> None:
    c = small_contract("dog2", 8, 12, frac_bits=8, acc_bits=14, shift=2, reset="zero")
    check_all(c, sim, cosim_work, rtl_builds, seed=22, steps=2000)


def test_simulator_check_finds_tools_on_path(tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    """``check_simulator`` accepts Icarus when both of its tools are on PATH."""
    for tool in ("iverilog", "vvp"):
        exe = tmp_path / tool
        exe.write_text("#!/bin/sh\n")
        exe.chmod(0o755)
    monkeypatch.setenv("PATH", str(tmp_path))
    check_simulator("icarus")
    (tmp_path / "vvp").unlink()
    with pytest.raises(RvsmError, match="apt-get install iverilog"):
        check_simulator("icarus")
    with pytest.raises(RvsmError, match="unknown simulator 'xcelium'"):
        check_simulator("xcelium")
