"""amaranth.sim tests of the link receiver against the link model (rtl/board/model.py):
every bit slip, skew between pairs, lost lock (clock stopped, training lost, a training
request) and the clock crossing at unrelated clock ratios."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.rtl.board.drive import HALF_BIT_S, beat_ints, simulate_receiver
from rvsm.rtl.board.model import (
    LinkFormat,
    beat_words,
    deserialise,
    idle_words,
    serialise,
    skewed,
    training_words,
)

FMT = LinkFormat(20)  # 3 data pairs and the framing lane


def random_beats(n: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    payload = rng.integers(0, 2, (n, FMT.payload_bits)).astype(np.uint8)
    return payload, rng.integers(0, 2, n).astype(bool), rng.integers(0, 2, n).astype(bool)


def link_words(beats: tuple[np.ndarray, ...], training: int = 48) -> np.ndarray:
    return np.concatenate([training_words(FMT, training), beat_words(FMT, *beats),
                           idle_words(FMT, 8)])


@pytest.mark.parametrize("slip", range(8))
def test_every_bit_slip_aligns(slip: int) -> None:
    beats = random_beats(12, slip)
    bits = skewed(serialise(link_words(beats)), [slip] * FMT.pairs, fill=1)
    got = simulate_receiver(FMT, bits, 3.3e-9)
    assert got["beats"] == beat_ints(*beats)
    assert got["lane_errors"] == [0] * FMT.pairs
    assert max(got["locked"]) == 1
    model = deserialise(FMT, bits)  # the model reads the same streams
    assert beat_ints(model.payload, model.sof, model.eol) == got["beats"]


@pytest.mark.parametrize("delays", [(0, 7, 3, 5), (7, 0, 1, 6), (2, 2, 0, 7)])
def test_skew_between_pairs(delays: tuple[int, ...]) -> None:
    beats = random_beats(16, sum(delays))
    bits = skewed(serialise(link_words(beats)), delays)
    got = simulate_receiver(FMT, bits, 4.1e-9)
    assert got["beats"] == beat_ints(*beats)
    assert got["lane_errors"] == [0] * FMT.pairs


def test_clock_stop_loses_lock_and_retraining_recovers() -> None:
    a, b = random_beats(10, 1), random_beats(10, 2)
    words_a = link_words(a)
    bits = serialise(np.concatenate([words_a, link_words(b)]))
    pause_at = words_a.shape[0] * 8
    got = simulate_receiver(FMT, skewed(bits, (1, 4, 0, 6)), 3.7e-9, {pause_at: 1.5e-6})
    assert got["beats"] == beat_ints(*a) + beat_ints(*b)
    locked = np.array(got["locked"])
    rises = int(np.sum(np.diff(locked) == 1))
    assert rises == 2  # locked, lost while the clock stopped, locked again
    assert got["lock_losses"] == 2  # the pause and the end of the stream


def test_lost_training_counts_errors_and_retrains() -> None:
    a, b = random_beats(10, 3), random_beats(10, 4)
    bad = idle_words(FMT, 6)
    bad[:, FMT.framing_pair] = 0x00  # framing words without SYNC: the framing is lost
    words = np.concatenate([link_words(a), bad, link_words(b)])
    got = simulate_receiver(FMT, serialise(words), 3.7e-9)
    assert got["beats"] == beat_ints(*a) + beat_ints(*b)
    assert got["lane_errors"][FMT.framing_pair] >= 4
    assert got["lane_errors"][:FMT.framing_pair] == [0] * FMT.data_pairs
    assert int(np.sum(np.diff(np.array(got["locked"])) == 1)) == 2


def test_parity_error_counts_on_the_framing_lane() -> None:
    a = random_beats(10, 5)
    words = link_words(a)
    words[50, 0] ^= 1  # one bit of one beat on pair 0
    got = simulate_receiver(FMT, serialise(words), 3.7e-9)
    assert got["lane_errors"] == list(deserialise(FMT, serialise(words)).errors)
    assert got["lane_errors"][FMT.framing_pair] == 1


def test_training_request_drops_and_regains_lock() -> None:
    a = random_beats(4, 6)
    words = np.concatenate([link_words(a), training_words(FMT, 64), idle_words(FMT, 8)])
    request = (48 + 4 + 8) * 8 * 2 * HALF_BIT_S + 200e-9  # during the second training
    got = simulate_receiver(FMT, serialise(words), 3.7e-9, train_at=request)
    locked = np.array(got["locked"])
    assert int(np.sum(np.diff(locked) == 1)) == 2
    assert got["beats"] == beat_ints(*a)


@pytest.mark.parametrize(("core_period", "idle_every"), [(2.3e-9, 0), (9.1e-9, 0),
                                                          (13.7e-9, 1)])
def test_clock_crossing_at_unrelated_ratios(core_period: float, idle_every: int) -> None:
    beats = random_beats(24, 7)
    words = beat_words(FMT, *beats)
    if idle_every:  # a slower core: the sensor leaves an idle word after every beat
        words = np.stack([words, idle_words(FMT, len(words))], axis=1).reshape(-1, FMT.pairs)
    bits = serialise(np.concatenate([training_words(FMT, 48), words, idle_words(FMT, 8)]))
    got = simulate_receiver(FMT, bits, core_period)
    assert got["beats"] == beat_ints(*beats)
    assert got["overflow"] == 0


def test_overflow_when_the_core_is_too_slow() -> None:
    beats = random_beats(40, 8)
    got = simulate_receiver(FMT, serialise(link_words(beats)), 30e-9)
    assert got["overflow"] == 1
    assert len(got["beats"]) < 40
