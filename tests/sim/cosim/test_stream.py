"""cocotb regressions of the streaming array's Verilog against the fixed twin.

Default: a dog4 array at two lane counts on both simulators (random, saturating and
clear-mid-stream stimuli), three models on Icarus, the checker-can-fail proof with its
waveform, and the ``rvsm verify --arch stream`` command. ``-m slow``: every model x
several P on both simulators, and the full 250x400 dog4 sensor at P=40 on Verilator.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.kernels.receptive_fields import MODEL_NAMES
from rvsm.sim.cosim.verify import run_rtl

#: Icarus in the default suite; the Verilator variants (a build each, 30-45 s) run with
#: ``-m slow`` (``make regress``); the default suite still builds Verilator elsewhere
#: (code coverage, protocol scripts, the event mode, regressions)
SIMS = ["icarus", pytest.param("verilator", marks=pytest.mark.slow)]


@pytest.fixture
def work(cosim_work: Path) -> Path:
    return cosim_work


@pytest.fixture
def builds(rtl_builds: Path) -> Path:
    return rtl_builds


def check_cases(c: ArrayContract, lanes: int, sim: str, work: Path, builds: Path,
                seed: int, steps: int = 8) -> None:
    """Random, saturating, checkerboard and clear-mid-stream stimuli: zero mismatches,
    spikes of both signs (for signed models)."""
    rng = np.random.default_rng(seed)
    s, h, w = c.num_scales, c.height, c.width
    full = (1 << c.adc_bits) - 1
    top = (1 << c.threshold_bits) - 1
    rand = rng.integers(0, full + 1, (steps, h, w))
    thr = rng.integers(1, top // 4, (s, h, w))
    sat = np.concatenate([np.full((steps // 2, h, w), full),
                          rng.choice([0, full], (steps - steps // 2, h, w))])
    thr_rail = thr.copy()
    thr_rail.reshape(-1)[::3] = top  # the top rail fires only when saturated
    # dark pixels ringed by full-scale ones: DoG sums go negative, so -1 spikes fire
    yy, xx = np.indices((h, w))
    checker = np.broadcast_to(((yy + xx) % 2) * full, (steps, h, w)).copy()
    cases = {"random": (rand, thr, ()), "saturating": (sat, thr_rail, ()),
             "checkerboard": (checker, thr, ()),
             "clear_mid_stream": (rand, thr, (steps // 3, steps // 2 + 1))}
    signs = set()
    for name, (codes, t, clears) in cases.items():
        r = run_rtl(c, codes, t, sim, clear_before=clears, work_dir=work,
                    name=f"{name}_p{lanes}", build_root=builds, lanes=lanes)
        assert r["mismatches"] == 0, (name, r["first_mismatch"])
        assert r["compared"] == codes.size * s
        signs |= set(np.unique(c.run(codes, t, clears)).tolist())
    assert 1 in signs
    if c.signed and any((k < 0).any() for k in c.weight_arrays):
        assert -1 in signs


@pytest.mark.parametrize("sim", SIMS)
@pytest.mark.parametrize("lanes", [1, 3])
def test_dog4_stream(small_contract, sim: str, lanes: int, work: Path,
                     builds: Path) -> None:
    check_cases(small_contract("dog4", 5, 9), lanes, sim, work, builds, seed=lanes)


@pytest.mark.parametrize("model", ["fsm", "dog2", "gauss3"])
def test_models_icarus(small_contract, model: str, work: Path, builds: Path) -> None:
    c = small_contract(model, 4, 6, reset="zero")
    check_cases(c, 2, "icarus", work, builds, seed=5)


def test_checker_catches_wrong_expectation(small_contract, work: Path,
                                           builds: Path) -> None:
    """A deliberately wrong expectation is reported, named, and a waveform is kept."""
    c = small_contract("dog3", 5, 6)
    rng = np.random.default_rng(14)
    codes = rng.integers(0, 16, (6, 5, 6))
    thr = rng.integers(1, 60, (c.num_scales, 5, 6))
    wrong = c.run(codes, thr)
    step, scale, row, col = 3, 2, 4, 1
    good = int(wrong[step, scale, row, col])
    wrong[step, scale, row, col] = 1 if good != 1 else -1
    r = run_rtl(c, codes, thr, "icarus", expected=wrong, work_dir=work, name="wrong",
                build_root=builds, lanes=3)
    assert r["mismatches"] == 1
    first = dict(r["first_mismatch"])
    beat = first.pop("beat")
    assert first == {"step": step, "scale": scale, "row": row, "column": col,
                     "expected": int(wrong[step, scale, row, col]), "got": good}
    # the beat of (step, row, column) in the output order (row-major, 2 groups of 3
    # lanes per row), and where to look in the waves
    assert beat == step * 5 * 2 + row * 2 + col // 3
    assert 0 < r["first_mismatch_time_ns"] < r["sim_time_ns"]
    assert r["waves"] and Path(r["waves"]).exists()


def test_cli_verify_stream(work: Path, tmp_path: Path,
                           capsys: pytest.CaptureFixture) -> None:
    """``rvsm verify SCENE --fixed point.toml --arch stream --lanes P --json``."""
    from rvsm.model.fixed.design_point import default_design_point
    from rvsm.model.fixed.point_toml import save_design_point
    from rvsm.sim.cli import main

    point = tmp_path / "p.toml"
    save_design_point(point, default_design_point().with_size(8, 12))
    rc = main(["verify", "coin", "--fixed", str(point), "--sim", "icarus", "--steps", "4",
               "--arch", "stream", "--lanes", "4", "--json", "--work", str(work)])
    out = json.loads(capsys.readouterr().out)
    assert rc == 0
    assert out["arch"] == "stream" and out["lanes"] == 4 and out["mismatches"] == 0
    assert out["compared"] == 4 * 4 * 8 * 12


@pytest.mark.slow
@pytest.mark.parametrize("sim", SIMS)
@pytest.mark.parametrize("lanes", [1, 5, 15])
@pytest.mark.parametrize("model", MODEL_NAMES)
def test_every_model_and_lanes(small_contract, model: str, lanes: int, sim: str,
                               work: Path, builds: Path) -> None:
    c = small_contract(model, 6, 15, reset="zero" if lanes == 5 else "subtract")
    check_cases(c, lanes, sim, work, builds, seed=21, steps=12)


@pytest.mark.slow
def test_full_sensor_verilator(work: Path, tmp_path: Path,
                               capsys: pytest.CaptureFixture) -> None:
    """The default 250x400 dog4 point at P=40 on Verilator, 20 steps (several minutes)."""
    from rvsm.model.fixed.design_point import default_design_point
    from rvsm.model.fixed.point_toml import save_design_point
    from rvsm.sim.cli import main

    point = tmp_path / "p.toml"
    save_design_point(point, default_design_point())
    rc = main(["verify", "character", "--fixed", str(point), "--sim", "verilator",
               "--steps", "20", "--arch", "stream", "--lanes", "40", "--json",
               "--work", str(work)])
    out = json.loads(capsys.readouterr().out)
    print({k: out[k] for k in ("compared", "mismatches", "cycles_per_second",
                               "build_seconds", "sim_wall_seconds")})
    assert rc == 0 and out["mismatches"] == 0
    assert out["compared"] == 20 * 4 * 250 * 400
