"""Protocol scripts (:mod:`rvsm.rtl.stream.protocol`): the model against the contract,
the streaming array in ``amaranth.sim`` against the model (every clear position of a
frame, random scripts, both reset modes, odd lanes), seeded bugs caught, coverage."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.drive import simulate_script
from rvsm.rtl.stream.protocol import (
    PROTOCOL_BINS,
    Segment,
    build_script,
    check_script,
    load_script,
    random_script,
    save_script,
    script_coverage,
)
from rvsm.rtl.stream.protocol_coverage import CLEAR_POSITIONS


def _codes_thr(c, steps: int, seed: int, thr_hi: int = 120):
    rng = np.random.default_rng(seed)
    codes = rng.integers(0, 1 << c.adc_bits, (steps, c.height, c.width))
    thr = rng.integers(1, thr_hi, (c.num_scales, c.height, c.width))
    return codes, thr


def _assert_rtl_follows(script, **kwargs) -> dict:
    got, cycles = simulate_script(script, **kwargs)
    result = check_script(script, got, cycles)
    assert result["mismatches"] == 0, result["first_mismatch"]
    assert result["compared"] == script.expected.spikes.size
    return result


def test_plain_script_is_the_contract(small_contract) -> None:
    """Whole segments without writes or stalls: the expectation is
    :meth:`ArrayContract.run` with clears, in beat order, one beat per position."""
    c = small_contract("dog2", 5, 6)
    codes, thr = _codes_thr(c, 5, seed=1)
    script = build_script(c, 3, codes, thr, [Segment(2), Segment(3)])
    want = c.run(codes, thr, clear_before=(2,))
    sched = StreamGeometry(c, 3).schedule
    assert np.array_equal(script.expected.spikes, sched.expected_beats(want))
    rows, groups = sched.positions(5 * sched.beats_per_frame)
    assert np.array_equal(script.expected.rows, rows)
    assert np.array_equal(script.expected.groups, groups)
    assert np.array_equal(script.expected_steps, np.repeat(np.arange(5),
                                                           sched.beats_per_frame))
    _assert_rtl_follows(script)


@pytest.mark.parametrize("reset", ["subtract", "zero"])
def test_clear_at_every_position_of_a_frame(small_contract, reset: str) -> None:
    """A clear after one whole frame and ``q`` beats of the next, for every position
    ``q`` of the frame (inside the lag too), with and without idle cycles before it and
    ``codes.valid`` high during it: the released beats, and nothing else, come out, each
    in its cycle; the next segment starts from zero accumulators."""
    c = small_contract("dog2", 5, 6, reset=reset)
    lanes = 3
    geo = StreamGeometry(c, lanes)
    hg = geo.beats_per_frame
    segments = [Segment(1, q, idle_after=q % 3, clear_cycles=1 + q % 2,
                        valid_in_clear=bool(q % 2)) for q in range(hg)]
    segments.append(Segment(1, None))
    codes, thr = _codes_thr(c, 2 * hg + 1, seed=3)
    script = build_script(c, lanes, codes, thr, segments)
    _assert_rtl_follows(script)
    cov = script_coverage(script)[0]
    live = [b for b in CLEAR_POSITIONS if cov[b] is not None]
    assert live and all(cov[b] > 0 for b in live)
    assert cov["clear_in_lag"] > 0 and cov["clear_with_valid"] > 0


@pytest.mark.parametrize(("model", "lanes", "reset"), [
    ("dog4", 1, "subtract"), ("dog4", 2, "zero"), ("dog2", 3, "subtract"),
    ("gauss2", 4, "zero")])
def test_random_scripts(small_contract, model: str, lanes: int, reset: str) -> None:
    """Seeded scripts of stalls, clears and colliding threshold writes, several lane
    counts (1 and odd) and both reset modes: the array follows every beat and cycle."""
    c = small_contract(model, 8, 12 if lanes == 3 else 8, acc_bits=10, reset=reset)
    for seed in range(2):
        script = random_script(c, lanes, 16, seed)
        cov = script_coverage(script)
        assert sum(b["thr_write_same_edge"] for b in cov) > 0
        assert sum(b["thr_write_edge_before"] for b in cov) > 0
        _assert_rtl_follows(script)


@pytest.mark.parametrize("mutation", ["stream.stale_threshold",
                                      "stream.no_threshold_forwarding",
                                      "stream.advance_during_stall",
                                      "stream.clear_forgets_scale0"])
def test_seeded_bugs_are_caught(small_contract, mutation: str) -> None:
    """A deliberately broken array fails some of three seeded scripts."""
    c = small_contract("dog2", 6, 6)
    caught = 0
    for seed in range(3):
        script = random_script(c, 3, 12, seed)
        got, cycles = simulate_script(script, mutation=mutation)
        caught += check_script(script, got, cycles)["mismatches"] > 0
    assert caught


def test_checker_reports_cycle_and_position(small_contract) -> None:
    """A beat a cycle late, a wrong spike and a missing beat are each reported."""
    c = small_contract("dog2", 5, 6)
    codes, thr = _codes_thr(c, 3, seed=5, thr_hi=20)
    script = build_script(c, 3, codes, thr, [Segment(1, 4), Segment(1)])
    got, cycles = simulate_script(script)
    late = list(cycles)
    late[3] += 1
    r = check_script(script, got, late)
    assert r["mismatches"] == 1 and r["first_mismatch"]["beat"] == 3
    k = int(np.flatnonzero(np.abs(script.expected.spikes).sum(axis=(1, 2)))[0])
    flipped = got.spikes.copy()
    flipped[k] = -flipped[k] if flipped[k].any() else 1
    wrong = type(got)(got.rows, got.groups, got.last, flipped)
    r = check_script(script, wrong, cycles)
    assert r["mismatches"] > 0 and r["first_mismatch"]["beat"] == k
    assert r["first_mismatch"]["step"] == int(script.expected_steps[k])
    short = type(got)(got.rows[:-1], got.groups[:-1], got.last[:-1], got.spikes[:-1])
    r = check_script(script, short, cycles[:-1])
    assert "received" in r["first_mismatch"]["error"]


def test_coverage_counts_a_hand_made_script(small_contract) -> None:
    """Bins of a script with a clear before any beat, one after a drain and one cutting
    the first row; then a write at position 0's read edge (not seen) and one an edge
    before position 5's (seen)."""
    c = small_contract("dog2", 5, 6)
    geo = StreamGeometry(c, 3)  # G = 2: no middle group
    codes, thr = _codes_thr(c, 4, seed=7)
    script = build_script(c, 3, codes, thr,
                          [Segment(0, 0), Segment(1, None), Segment(0, 1), Segment(1)])
    cov = script_coverage(script)
    assert list(cov[0]) == list(PROTOCOL_BINS)
    assert cov[0]["clear_before_first_beat"] == 1
    assert cov[0]["clear_drained"] == 1

    def band(q: int) -> str:  # the position q of a frame as a clear bin
        y, g = divmod(q % geo.beats_per_frame, geo.groups)
        row = "top" if y < geo.radius else "bottom" if y >= c.height - geo.radius \
            else "middle"
        return f"clear_at_{row}_{'first' if g == 0 else 'last'}"

    # the drained clear follows a frame and lag flush beats; the cut one, 1 beat
    bins = [band(geo.beats_per_frame + geo.lag), band(1)]
    assert band(1) == "clear_at_top_last"
    for b in set(bins):
        assert cov[0][b] == bins.count(b)
    assert cov[0]["clear_at_middle_middle"] is None
    assert cov[0]["thr_write_same_edge"] == 0 and cov[0]["thr_write_streaming"] == 0
    load = c.num_scales * geo.beats_per_frame
    edges = np.flatnonzero(script.valid & ~script.clear)
    edges = edges[(edges > load)][: geo.beats_per_frame + geo.lag]  # the drained segment
    tl = geo.threshold_lag
    for cyc, scale, word in ((edges[tl] + 1, 1, 0), (edges[5 + tl], 0, 5)):
        script.thr_we[cyc], script.thr_scale[cyc], script.thr_word[cyc] = True, scale, word
    cov = script_coverage(script)
    assert cov[1]["thr_write_same_edge"] == 1 and cov[1]["thr_write_edge_before"] == 0
    assert cov[0]["thr_write_edge_before"] == 1 and cov[0]["thr_write_same_edge"] == 0
    assert cov[0]["thr_write_streaming"] == cov[1]["thr_write_streaming"] == 1


def test_save_and_load(tmp_path: Path, small_contract) -> None:
    c = small_contract("dog2", 5, 6)
    script = random_script(c, 3, 12, 4)
    path = tmp_path / "s.npz"
    save_script(path, script)
    back = load_script(path)
    assert back.contract == c and back.lanes == 3 and back.seed == 4
    for name in ("valid", "codes", "clear", "thr_we", "thr_word", "thr_data",
                 "expected_cycles", "expected_steps"):
        assert np.array_equal(getattr(back, name), getattr(script, name))
    assert np.array_equal(back.expected.spikes, script.expected.spikes)
    assert back.payload_words() == script.payload_words()


def test_bad_segments_are_refused(small_contract) -> None:
    c = small_contract("dog2", 5, 6)
    codes, thr = _codes_thr(c, 2, seed=1)
    with pytest.raises(RvsmError, match="steps"):
        build_script(c, 3, codes, thr, [Segment(2), Segment(1)])
    with pytest.raises(RvsmError, match="cut"):
        build_script(c, 3, codes, thr, [Segment(0, 99)])


@pytest.mark.parametrize("lanes", [1, 3])
def test_random_scripts_with_shared_thresholds(tmp_path: Path, small_contract,
                                               lanes: int) -> None:
    """threshold.storage = "shared": scripts load one threshold per scale and write
    scales while the stream runs (each write reaching every position read after it
    lands); the array follows every beat and cycle; the file keeps the storage."""
    import dataclasses

    c = dataclasses.replace(small_contract("dog2", 6, 6, acc_bits=10), reset="subtract",
                            shared_thresholds=(30, 70))
    for seed in range(2):
        script = random_script(c, lanes, 12, seed)
        assert script.thr_data[script.thr_we].min(axis=1).tolist() == \
            script.thr_data[script.thr_we].max(axis=1).tolist()  # one value per write
        _assert_rtl_follows(script)
    save_script(tmp_path / "s.npz", script)
    assert load_script(tmp_path / "s.npz").contract == c
