"""The numpy beat schedule: oracle tests against explicit loops, and the checker."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.rtl.stream.schedule import (
    OutputBeats,
    StreamChecker,
    StreamSchedule,
    check_beats,
    pack_lanes,
    unpack_bits,
)


@pytest.fixture
def sched() -> StreamSchedule:
    return StreamSchedule(height=3, width=6, lanes=2, lag=5, threshold_lag=2)


def test_beat_order_is_raster(sched: StreamSchedule) -> None:
    codes = np.arange(2 * 3 * 6).reshape(2, 3, 6)
    beats = sched.frame_beats(codes)
    k = 0
    for t in range(2):
        for y in range(3):
            for g in range(3):
                assert list(beats[k]) == [codes[t, y, g * 2 + i] for i in range(2)]
                k += 1
    full = sched.input_beats(codes)
    assert full.shape == (2 * 9 + sched.lag, 2)
    assert not full[18:].any()


def test_expected_beats_oracle_and_round_trip(sched: StreamSchedule) -> None:
    rng = np.random.default_rng(1)
    spikes = rng.integers(-1, 2, (2, 3, 3, 6)).astype(np.int8)
    beats = sched.expected_beats(spikes)
    rows, groups = sched.positions(len(beats))
    for k in range(len(beats)):
        t = k // sched.beats_per_frame
        for s in range(3):
            for i in range(2):
                assert beats[k, s, i] == spikes[t, s, rows[k], groups[k] * 2 + i]
    assert np.array_equal(sched.spikes_from_beats(beats), spikes)
    with pytest.raises(ValueError, match="whole frames"):
        sched.spikes_from_beats(beats[:-1])


def test_threshold_words_and_pause(sched: StreamSchedule) -> None:
    thr = np.arange(2 * 3 * 6).reshape(2, 3, 6)
    words = sched.threshold_words(thr)
    assert words.shape == (2, 9, 2)
    assert list(words[1, 4]) == [thr[1, 1, 2], thr[1, 1, 3]]  # address y*G + g = 1*3 + 1
    assert sched.threshold_pause_beat(2) == 2 * 9 + sched.threshold_lag
    assert sched.release_beat(4) == 4 + sched.lag


def test_segments() -> None:
    assert StreamSchedule.segments(7, (5, 2, 0, 9)) == [(0, 2), (2, 5), (5, 7)]
    assert StreamSchedule.segments(3) == [(0, 3)]


def test_lanes_must_divide_width() -> None:
    with pytest.raises(ValueError, match="divide"):
        StreamSchedule(3, 6, 4, lag=1)


def test_pack_unpack_round_trip() -> None:
    rng = np.random.default_rng(2)
    vals = rng.integers(0, 1 << 7, (5, 9))
    words = pack_lanes(vals, 7)
    for row, w in zip(vals, words, strict=True):
        assert w == sum(int(v) << (7 * i) for i, v in enumerate(row))
    bits = unpack_bits(words, 63)
    back = (bits.reshape(5, 9, 7) << np.arange(7)).sum(axis=2)
    assert np.array_equal(back, vals)


def _beats(sched: StreamSchedule, spikes: np.ndarray) -> OutputBeats:
    b = sched.expected_beats(spikes)
    rows, groups = sched.positions(len(b))
    last = (rows == sched.height - 1) & (groups == sched.groups - 1)
    return OutputBeats(rows, groups, last, b)


def test_checker_passes_and_catches(sched: StreamSchedule) -> None:
    rng = np.random.default_rng(3)
    spikes = rng.integers(-1, 2, (2, 2, 3, 6)).astype(np.int8)
    good = _beats(sched, spikes)
    ok = check_beats(sched, spikes, good)
    assert ok["mismatches"] == 0 and ok["compared"] == spikes.size

    wrong = spikes.copy()
    wrong[1, 0, 2, 5] = 1 - abs(wrong[1, 0, 2, 5])
    bad = check_beats(sched, wrong, good)
    assert bad["mismatches"] == 1
    # beat 17 = frame 1 (9 beats each) + row 2 (3 beats each) + column 5 // 2 lanes
    assert bad["first_mismatch"] == {"beat": 17, "step": 1, "scale": 0, "row": 2,
                                     "column": 5,
                                     "expected": int(wrong[1, 0, 2, 5]),
                                     "got": int(spikes[1, 0, 2, 5])}

    swapped = OutputBeats(good.rows[::-1].copy(), good.groups, good.last, good.spikes)
    assert check_beats(sched, spikes, swapped)["mismatches"] > 0

    short = OutputBeats(good.rows[:-1], good.groups[:-1], good.last[:-1], good.spikes[:-1])
    res = check_beats(sched, spikes, short)
    assert res["mismatches"] == 2 * 2 and "received 17 beats" in res["mismatch_list"][0]["error"]


def test_stream_checker_matches_check_beats_in_any_chunking() -> None:
    """:class:`StreamChecker` fed in random pieces (expectations and received beats
    split independently) gives :func:`check_beats`'s verdict, missing and wrong beats
    included; a restart (a clear) restarts the positions."""
    rng = np.random.default_rng(11)
    sched = StreamSchedule(3, 4, 2, lag=5)
    spikes = rng.integers(-1, 2, (7, 2, 3, 4)).astype(np.int8)
    beats = sched.expected_beats(spikes)
    rows, groups = sched.positions(len(beats))
    last = (rows == 2) & (groups == 1)
    for corrupt in (False, True):
        got_spikes = beats.copy()
        got_rows = rows.copy()
        n_got = len(beats)
        if corrupt:
            got_spikes[9, 1, 0] = -got_spikes[9, 1, 0] or 1
            got_rows[20] = (got_rows[20] + 1) % 3
            n_got -= 2  # two beats never come
        got = OutputBeats(got_rows[:n_got], groups[:n_got], last[:n_got],
                          got_spikes[:n_got])
        whole = check_beats(sched, spikes, got)
        checker = StreamChecker(sched)
        cuts = np.sort(rng.choice(np.arange(1, 7), 2, replace=False))
        for part in np.split(spikes, cuts):
            checker.expect(part)
        k = 0
        for size in (3, 1, 10, 100):
            piece = OutputBeats(got.rows[k:k + size], got.groups[k:k + size],
                                got.last[k:k + size], got.spikes[k:k + size])
            checker.receive(piece)
            k += size
        streamed = checker.result()
        for key in ("compared", "mismatches", "beats"):
            assert streamed[key] == whole[key], (corrupt, key)
        assert (streamed["mismatches"] > 0) == corrupt
        want = [{k: v for k, v in e.items() if k != "error"} for e in whole["mismatch_list"]]
        have = [{k: v for k, v in e.items() if k != "error"}
                for e in streamed["mismatch_list"]]
        assert [e["beat"] for e in have] == sorted(e["beat"] for e in want)
    # two segments (a clear before step 3): positions restart, steps are the run's
    checker = StreamChecker(sched)
    checker.expect(spikes[:3])
    checker.receive(OutputBeats(rows[:18], groups[:18], last[:18], beats[:18]))
    checker.restart(3)
    checker.expect(spikes[3:5])
    seg = beats[18:30].copy()
    seg[7, 0, 1] = 1 - seg[7, 0, 1] if seg[7, 0, 1] != 1 else 0
    checker.receive(OutputBeats(rows[:12], groups[:12], last[:12], seg))
    r = checker.result()
    assert r["mismatches"] == 1 and r["first_mismatch"]["step"] == 3 + 7 // 6
    assert r["first_mismatch"]["beat"] == 18 + 7
