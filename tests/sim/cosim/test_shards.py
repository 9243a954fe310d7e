"""State-seeded, sharded long runs (:mod:`rvsm.sim.cosim.long_runs.shards`): a sharded run
equals the unbroken one (same spikes compared, 0 mismatches, every segment's end state
compared), a bit flipped in one segment's loaded state is caught at that segment's
boundary (exit 1), bad ``--shards`` values are bad input (exit 2); the twin's segments
(:meth:`StimulusChunks.chunks` with ``start``/``stop``) and the state word packing.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.fixed.point_toml import save_design_point
from rvsm.model.fixed.stimulus_chunks import StimulusChunks
from rvsm.model.scene.loaders import load_scene
from rvsm.sim.cli import main
from rvsm.sim.cosim.builds.chunk_harness import state_memories
from rvsm.sim.cosim.long_runs.segment_state import pack_words, unpack_words
from rvsm.sim.cosim.long_runs.shards import segment_bounds


@pytest.mark.parametrize("engine", ["fused", "numpy"])
def test_segments_of_the_twin_chain_to_the_whole_run(engine: str) -> None:
    """Segments ``0..19`` and ``19..40`` give the whole run's spikes; the second starts
    from the state the first ends in, and ends in the whole run's end state."""
    point = default_design_point().with_size(12, 16)
    scene = load_scene("coin", size=(12, 16))

    def source() -> StimulusChunks:
        return StimulusChunks.from_scene(scene, point, 40, engine=engine)

    whole = source()
    spikes = np.concatenate([c.spikes for c in whole.chunks(8)])
    first, second = source(), source()
    a = list(first.chunks(8, 0, 19))
    b = list(second.chunks(8, 19, 40))
    assert [c.t0 for c in b] == [19, 24, 32]
    assert np.array_equal(second.start_state(), first.state())
    assert np.abs(first.state()).sum() > 0
    assert np.array_equal(second.state(), whole.state())
    assert np.array_equal(np.concatenate([c.spikes for c in a + b]), spikes)


def test_state_words_round_trip() -> None:
    """Signed lanes packed as two's complement words and read back from
    ``$writememh`` text (with Icarus's heading comment); X words flagged."""
    rng = np.random.default_rng(1)
    values = rng.integers(-(1 << 17), 1 << 17, (7, 3))
    text = "".join(f"{w:014x}\n" for w in pack_words(values, 18))
    got, unknown = unpack_words(b"// 0x00000000\n" + text.encode(), 3, 18, signed=True)
    assert np.array_equal(got, values) and not unknown.any()
    _, unknown = unpack_words(b"x" * 14 + b"\n" + text.encode()[15:], 3, 18, signed=True)
    assert unknown[0] and not unknown[1:].any()


def test_segment_bounds_and_state_memories() -> None:
    """Equal segments covering the run; the state banks named in both Verilog forms."""
    assert segment_bounds(10, 3) == [(0, 3), (3, 6), (6, 10)]
    assert segment_bounds(5, 1) == [(0, 5)]
    amaranth = ("module \\top.acc_s0 (clk);\n  reg [35:0] b0 [23:0];\nendmodule\n"
                "module top (clk);\n  reg fresh_s0 = 1'h1;\nendmodule\n"
                "module \\top.thr_s0 (clk);\n  reg [33:0] b0 [23:0];\nendmodule\n")
    s = state_memories(amaranth, "top")
    assert s.fresh == "fresh_s0"
    assert [(b.name, b.width, b.depth, b.file) for b in s.banks] == [
        ("acc_s0.b0", 36, 24, "acc_s0.b0.hex"), ("thr_s0.b0", 34, 24, "thr_s0.b0.hex")]
    flat = ("module top (clk);\n  reg fresh_s0 = 1'h1;\n  reg [35:0] \\acc_s0.b1  [7:0];\n"
            "endmodule\n")
    assert [b.name for b in state_memories(flat, "top").banks] == ["\\acc_s0.b1 "]


def _point(tmp_path: Path, storage: str = "per-pixel") -> Path:
    point = tmp_path / "p.toml"
    save_design_point(point, dataclasses.replace(
        default_design_point(), model="dog2", threshold_storage=storage
    ).with_size(6, 8))
    return point


@pytest.mark.parametrize("storage, memories", [("per-pixel", 2), ("shared", 1)])
def test_sharded_run_equals_the_unbroken_run(tmp_path: Path, capsys: pytest.CaptureFixture,
                                             storage: str, memories: int) -> None:
    """``--shards 3`` on Icarus (segments one after another: ``--workers 0``): the same
    spikes compared as the unbroken run, 0 mismatches, 3 boundary states compared (one
    per segment: each segment's end, the last at the run's end). The state is the
    accumulator and threshold memories, or the accumulators alone for shared thresholds
    (which live in registers: a shared point's sharded run once failed on the threshold
    memories it does not have)."""
    point = str(_point(tmp_path, storage))
    work = str(tmp_path / "w")
    base = ["verify", "coin", "--fixed", point, "--steps", "30", "--lanes", "2",
            "--harness", "chunk", "--sim", "icarus", "--chunk-steps", "4", "--json",
            "--work", work]
    assert main(base) == 0
    whole = json.loads(capsys.readouterr().out)
    assert main([*base, "--shards", "3", "--workers", "0"]) == 0
    said = capsys.readouterr()
    sharded = json.loads(said.out)
    # --json keeps stdout for the result; what the run does goes to stderr as it happens
    assert "rvsm: running 3 segments of about 10 steps on this process" in said.err
    assert said.err.count("mismatches, ") == 3 and "segment 2 (steps 20..29) done" in said.err
    assert sharded["mismatches"] == whole["mismatches"] == 0
    assert sharded["compared"] == whole["compared"] == 30 * 2 * 6 * 8
    assert sharded["expected_spikes"] == whole["expected_spikes"] > 0
    assert sharded["shards"] == 3 and sharded["boundary_states_compared"] == 3
    assert [s["steps"] for s in sharded["segments"]] == [[0, 10], [10, 20], [20, 30]]
    assert all(s["boundary"]["words"] == memories * 2 * 24 for s in sharded["segments"])


def test_a_flipped_state_word_is_caught_at_its_boundary(
        tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """A bit flipped in segment 1's loaded accumulators (the twin's state left as it is)
    shows in segment 1's end state, named by memory, row and column: exit 1, the other
    segments clean."""
    point = str(_point(tmp_path))
    args = ["verify", "coin", "--fixed", point, "--steps", "6", "--lanes", "2",
            "--harness", "chunk", "--sim", "icarus", "--chunk-steps", "4", "--json",
            "--work", str(tmp_path / "w"), "--shards", "3", "--workers", "0",
            "--state-fault", "1:acc_s1.b0.hex:5:20"]
    assert main(args) == 1
    r = json.loads(capsys.readouterr().out)
    by_segment = {s["segment"]: s for s in r["segments"]}
    assert by_segment[1]["boundary"]["mismatches"] >= 1
    assert by_segment[0]["mismatches"] == by_segment[2]["mismatches"] == 0
    first = r["first_mismatch"]
    assert first["segment"] == 1 and first["error"] == "state at the segment's end"
    # word 5 (row 1, group 1), bit 20: lane 1's bit 2 with 18-bit accumulators
    assert (first["memory"], first["word"], first["row"], first["column"]) == \
        ("acc_s1", 5, 1, 3)
    assert abs(first["got"] - first["want"]) == 4


@pytest.mark.parametrize("bad, message", [
    (["--shards", "0"], "--shards must be >= 1"),
    (["--shards", "9"], "each segment needs at least one step"),
    (["--shards", "-2"], "--shards must be >= 1"),
    (["--shards", "2", "--harness", "cycle"], "--shards needs --harness chunk"),
    (["--workers", "2"], "go with --shards N"),
    (["--shards", "2", "--state-fault", "x"], "--state-fault must be K:FILE:WORD:BIT"),
])
def test_bad_shards_are_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture,
                                  bad: list[str], message: str) -> None:
    """Bad ``--shards`` values and combinations: exit 2, one line, before any build."""
    args = ["verify", "coin", "--fixed", str(_point(tmp_path)), "--steps", "8", "--lanes",
            "2", "--sim", "icarus", "--work", str(tmp_path / "w")]
    if "--harness" not in bad:
        args += ["--harness", "chunk"]
    assert main([*args, *bad]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "w" / "builds").exists()


@pytest.mark.parametrize("flip, message", [
    ("1:acc_s1.b3.hex:5:20", "'acc_s1.b3.hex' is not a state file of this design; its files "
                             "are acc_s0.b0.hex, acc_s1.b0.hex"),
    ("1:acc_s1.b0.hex:24:0", "word '24' of acc_s1.b0.hex is out of range: it has words 0..23"),
    ("1:acc_s1.b0.hex:5:36", "bit '36' of acc_s1.b0.hex is out of range: its words have bits "
                             "0..35"),
])
def test_a_seeded_fault_outside_the_state_is_bad_input(
        tmp_path: Path, capsys: pytest.CaptureFixture, flip: str, message: str) -> None:
    """A ``--state-fault`` naming a bank, word or bit the design's state does not have:
    exit 2 with one line naming what it has, before any segment runs (it crashed the
    testbench, exit 3, when a user named a fourth bank of the full sensor's three)."""
    args = ["verify", "coin", "--fixed", str(_point(tmp_path, "shared")), "--steps", "6",
            "--lanes", "2", "--harness", "chunk", "--sim", "icarus", "--work",
            str(tmp_path / "w"), "--shards", "2", "--workers", "0", "--state-fault", flip]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == f"rvsm: error: --state-fault: {message}", err
    assert not list((tmp_path / "w").glob("runs/segment*"))
