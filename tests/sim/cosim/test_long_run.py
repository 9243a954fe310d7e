"""The long-run harness (:mod:`rvsm.sim.cosim.builds.chunk_harness`, :mod:`.long_run`)
against the fixed twin, on both simulators: equal verdicts to the per-cycle testbench, clears, a
wrong expectation found at its step with a waveform window around it, and the CLI.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.fixed.point_toml import save_design_point
from rvsm.model.fixed.stimulus import Stimulus, make_stimulus
from rvsm.model.fixed.stimulus_chunks import StimulusChunks
from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.loaders import load_scene
from rvsm.rtl.stream.schedule import pack_lanes
from rvsm.sim.cli import main
from rvsm.sim.cosim.long_runs.chunk_files import (
    decode_output_beats,
    encode_input_beats,
    encode_threshold_writes,
)
from rvsm.sim.cosim.long_runs.long_run import check_chunks
from rvsm.sim.cosim.verify import AUTO_CHUNK_BEATS, choose_harness, run_rtl

#: Icarus in the default suite; the Verilator variants (a build each, 30-45 s) run with
#: ``-m slow`` (``make regress``); the default suite still builds Verilator elsewhere
#: (code coverage, protocol scripts, the event mode, regressions)
SIMS = ["icarus", pytest.param("verilator", marks=pytest.mark.slow)]


def _random_stimulus(c: ArrayContract, steps: int, seed: int,
                     clears: tuple[int, ...] = ()) -> Stimulus:
    rng = np.random.default_rng(seed)
    full = (1 << c.adc_bits) - 1
    codes = rng.integers(0, full + 1, (steps, c.height, c.width))
    thr = rng.integers(1, ((1 << c.threshold_bits) - 1) // 4, (c.num_scales, c.height,
                                                                 c.width))
    return Stimulus(codes.astype(np.uint16), thr, c.run(codes, thr, clears), c,
                    clear_before=clears)


def test_hex_chunks_round_trip() -> None:
    """Input beats are written as the integers :func:`pack_lanes` makes, most significant
    digit first; output text decodes to the same bits (with Icarus's heading comment
    too), X/Z lines flagged; threshold writes as ``{addr, data}`` words."""
    rng = np.random.default_rng(3)
    beats = rng.integers(0, 128, (50, 5))
    text = encode_input_beats(beats, 7, 35)
    lines = text.decode().split("\n")[:-1]
    assert [int(ln, 16) for ln in lines] == pack_lanes(beats, 7)
    assert {len(ln) for ln in lines} == {9}
    bits, unknown = decode_output_beats(text + b"// a comment\n\n", 35)
    assert not unknown.any()
    want = ((beats[:, :, None] >> np.arange(7)) & 1).reshape(50, 35)
    assert np.array_equal(bits, want)
    _, unknown = decode_output_beats(b"0x1\n123\n", 12)
    assert unknown.tolist() == [True, False]
    headed, _ = decode_output_beats(b"// 0x00000000\n" + text, 35)  # as Icarus writes
    assert np.array_equal(headed, want)
    thr = encode_threshold_writes([(5, 9), (0x12, 0x3FF)], 6, 10)
    assert thr == b"1409\n4bff\n"  # {addr, data}: 6 + 10 bits, 4 hex digits


@pytest.mark.parametrize("sim", SIMS)
def test_long_run_agrees_with_the_per_cycle_testbench(sim: str, small_contract,
                                                      cosim_work: Path,
                                                      rtl_builds: Path) -> None:
    """The same stimulus (with two clears) through both testbenches: 0 mismatches and the
    same spikes compared; chunks smaller than a frame and memories of a few beats."""
    c = small_contract("dog2", 6, 8)
    stim = _random_stimulus(c, 12, 1, clears=(4, 9))
    per_cycle = run_rtl(c, stim.codes, stim.thresholds, sim, clear_before=stim.clear_before,
                        work_dir=cosim_work, name="cycle", build_root=rtl_builds, lanes=2)
    long = check_chunks(StimulusChunks.from_stimulus(stim), sim, work_dir=cosim_work,
                        name="chunk", build_root=rtl_builds, chunk_steps=3, lanes=2)
    assert per_cycle["mismatches"] == long["mismatches"] == 0, long["first_mismatch"]
    assert long["compared"] == per_cycle["compared"] == stim.spikes.size
    assert long["expected_spikes"] == np.count_nonzero(stim.spikes) > 0
    assert long["harness"] == "chunk" and long["steps"] == 12
    assert long["cycles_per_second"] > 0 and long["waves"] is None
    # the twin's process made and checked every chunk file, and removed it
    assert set(long["timeline"]) >= {"connected", "reset", "thresholds", "first_chunk",
                                     "last_done", "end", "twin_first_chunk"}
    assert {"decode", "check", "twin", "simulate", "handover"} <= set(long["seconds"])
    assert not list(Path(long["run_dir"]).glob("chunk_*.*.hex"))


@pytest.mark.parametrize("sim", SIMS)
def test_long_run_finds_a_wrong_spike_and_keeps_a_window(sim: str, small_contract,
                                                         cosim_work: Path,
                                                         rtl_builds: Path) -> None:
    """A flipped expected spike: one mismatch at its step, scale, row and column, its
    clock cycle and time, the run stopped after that chunk, and an FST of the window
    around it (starting at the window's first cycle)."""
    c = small_contract("dog2", 6, 8)
    stim = _random_stimulus(c, 30, 2)
    wrong = stim.spikes.copy()
    wrong[17, 1, 2, 5] = 0 if wrong[17, 1, 2, 5] else 1
    bad = dataclasses.replace(stim, spikes=wrong)
    r = check_chunks(StimulusChunks.from_stimulus(bad), sim, work_dir=cosim_work,
                     name="wrong", build_root=rtl_builds, chunk_steps=4, lanes=2)
    first = r["first_mismatch"]
    assert r["mismatches"] == 1
    assert (first["step"], first["scale"], first["row"], first["column"]) == (17, 1, 2, 5)
    assert r["first_mismatch_time_ns"] == first["cycle"] * 10
    assert r["stopped_at_step"] == 20  # the failing chunk (steps 16..19) was the last
    # chunks the twin made ahead of the stop are dropped with their files
    assert not list(Path(r["run_dir"]).glob("chunk_*.*.hex"))
    lo, hi = r["wave_window_cycles"]
    assert lo < first["cycle"] < hi
    wave = Path(r["waves"])
    assert wave.name == "window.fst" and wave.stat().st_size > 0
    header = wave.read_bytes()[:25]  # FST header block: type 0, length, start time (ps)
    assert header[0] == 0 and int.from_bytes(header[9:17], "big") == lo * 10_000


def test_stimulus_from_a_scene_matches_the_whole_twin(tmp_path: Path) -> None:
    """A scene's chunks (both engines, any chunk size) are the stimulus the fixed twin
    makes of the whole scene: same codes, same spikes."""
    point = default_design_point().with_size(12, 16)
    scene = load_scene("coin", size=(12, 16))
    whole = make_stimulus(scene, point, num_steps=23)
    for engine, chunk in (("fused", 5), ("numpy", 7), ("fused", 23)):
        src = StimulusChunks.from_scene(scene, point, 23, engine=engine)
        parts = list(src.chunks(chunk))
        assert [p.t0 for p in parts] == list(range(0, 23, chunk))
        assert np.array_equal(np.concatenate([p.codes for p in parts]), whole.codes)
        assert np.array_equal(np.concatenate([p.spikes for p in parts]), whole.spikes)
        assert np.array_equal(src.thresholds, whole.thresholds)
    with pytest.raises(RvsmError, match="number of steps"):
        StimulusChunks.from_scene(scene, point, scene.num_steps + 1)


def test_cli_verify_with_the_long_run_harness(tmp_path: Path,
                                              capsys: pytest.CaptureFixture) -> None:
    """``rvsm verify SCENE --fixed P --harness chunk``: exit 0 with the harness named;
    --harness chunk with the parallel array, or --chunk-steps 0, is bad usage (2)."""
    point = tmp_path / "p.toml"
    save_design_point(point, dataclasses.replace(default_design_point(), model="dog2")
                      .with_size(6, 8))
    work = str(tmp_path / "w")
    assert main(["verify", "coin", "--fixed", str(point), "--steps", "15", "--lanes", "2",
                 "--harness", "chunk", "--json", "--work", work]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["mismatches"] == 0 and out["harness"] == "chunk" and out["steps"] == 15
    assert {"spike_pos", "top_lane0", "bottom_lane1"} <= set(out["coverage"][0])
    assert out["compared"] == 15 * 2 * 6 * 8
    assert main(["verify", "coin", "--fixed", str(point), "--steps", "5", "--lanes", "2",
                 "--harness", "chunk", "--waves", "--json", "--work", work]) == 0
    waves = Path(json.loads(capsys.readouterr().out)["waves"])
    assert waves.name == "waves.fst" and waves.stat().st_size > 0  # the whole run
    assert main(["verify", "coin", "--fixed", str(point), "--harness", "chunk", "--arch",
                 "parallel", "--work", work]) == 2
    assert "--harness chunk drives the stream architecture only" in capsys.readouterr().err
    assert main(["verify", "coin", "--fixed", str(point), "--harness", "chunk",
                 "--chunk-steps", "0", "--work", work]) == 2
    assert "--chunk-steps must be >= 1" in capsys.readouterr().err


def test_replay_of_a_stimulus_file_in_the_long_run_harness(
        tmp_path: Path, capsys: pytest.CaptureFixture, monkeypatch: pytest.MonkeyPatch) -> None:
    """``rvsm verify --stimulus F --harness chunk`` reads the file a chunk of steps at a
    time (never whole: ``MemberArray.__array__`` is refused), with ``--steps`` and
    ``--recompute-expected`` passed to the testbench in its spec; a wrong spike is a bad
    stimulus (2) found chunk by chunk before any simulator runs."""
    from rvsm.model.fixed.stimulus import save_stimulus
    from rvsm.model.fixed.stimulus_reader import MemberArray

    c = default_design_point().with_size(6, 8).contract()
    stim = _random_stimulus(dataclasses.replace(c, weights=c.weights[:2]), 20, 4,
                            clears=(7,))
    path = tmp_path / "s.npz"
    save_stimulus(path, stim)
    wrong = stim.spikes.copy()
    wrong[15, 1, 2, 5] = 0 if wrong[15, 1, 2, 5] else 1
    save_stimulus(tmp_path / "bad.npz", dataclasses.replace(stim, spikes=wrong))

    def whole(self, dtype=None, copy=None):
        raise AssertionError("a stimulus file read whole")

    monkeypatch.setattr(MemberArray, "__array__", whole)
    work = str(tmp_path / "w")
    base = ["verify", "--harness", "chunk", "--lanes", "2", "--chunk-steps", "3", "--json",
            "--work", work, "--stimulus"]
    assert main([*base, str(path), "--steps", "13"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["mismatches"] == 0 and out["steps"] == 13 and out["harness"] == "chunk"
    assert out["compared"] == 13 * 2 * 6 * 8
    assert main([*base, str(tmp_path / "bad.npz")]) == 2
    assert "step 15, scale 1, row 2, column 5" in capsys.readouterr().err
    assert main([*base, str(tmp_path / "bad.npz"), "--recompute-expected"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["mismatches"] == 0 and out["expectation"] == "recomputed"


def test_auto_harness_takes_the_long_run_one_for_long_streams() -> None:
    """``--harness auto``: the long-run harness beyond AUTO_CHUNK_BEATS input beats of the
    streaming array (and a reloadable stimulus), the per-cycle testbench otherwise."""
    big = AUTO_CHUNK_BEATS + 1
    assert choose_harness("auto", "stream", big, 1, {"lanes": 1}) == "chunk"
    assert choose_harness("auto", "stream", big, 1, {"lanes": 2}) == "cycle"
    assert choose_harness("auto", "stream", 250 * 400, 20, {"lanes": 40}) == "cycle"
    assert choose_harness("auto", "stream", 250 * 400, 1000, {"lanes": 40}) == "chunk"
    assert choose_harness("auto", "stream", big, 1, {}, reloadable=False) == "cycle"
    assert choose_harness("auto", "parallel", big, 10, {}) == "cycle"
    assert choose_harness("cycle", "stream", big, 10, {}) == "cycle"


@pytest.mark.slow
def test_full_sensor_long_run(cosim_work: Path, tmp_path: Path,
                              capsys: pytest.CaptureFixture) -> None:
    """The default 250x400 dog4 point at P=40 on Verilator, 200 steps in the long-run
    harness (``--harness auto`` picks it): 0 mismatches (about 2 minutes with the build;
    the one-second run is `make long-run`)."""
    point = tmp_path / "p.toml"
    save_design_point(point, default_design_point())
    rc = main(["verify", "character", "--fixed", str(point), "--sim", "verilator",
               "--steps", "200", "--lanes", "40", "--json", "--work", str(cosim_work)])
    out = json.loads(capsys.readouterr().out)
    print({k: out[k] for k in ("compared", "mismatches", "cycles_per_second",
                               "build_seconds", "stream_seconds")})
    assert rc == 0 and out["mismatches"] == 0 and out["harness"] == "chunk"
    assert out["compared"] == 200 * 4 * 250 * 400
