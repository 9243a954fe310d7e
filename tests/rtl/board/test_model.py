"""The link model (rtl/board/model.py): framing, serialisation and its reader."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.rtl.board.model import (
    MARK,
    SYNC,
    TRAIN,
    TRAIN_PERIOD,
    WORD_BITS,
    LinkFormat,
    beat_words,
    deserialise,
    idle_words,
    pixel_beats,
    serialise,
    skewed,
    spike_beats_to_frames,
    training_words,
)


def test_shipped_point_pairs() -> None:
    """250x400 at 40 lanes, 7-bit codes, dog2: 280 bits in, 160 bits out a core cycle."""
    rx, tx = LinkFormat(40 * 7), LinkFormat(2 * 2 * 40)
    assert (rx.data_pairs, rx.pairs) == (35, 36)
    assert (tx.data_pairs, tx.pairs) == (20, 21)


def test_training_word_has_one_matching_slip() -> None:
    rotations = {((TRAIN >> s) | (TRAIN << (WORD_BITS - s))) & 0xFF for s in range(WORD_BITS)}
    assert len(rotations) == WORD_BITS
    assert MARK not in rotations and MARK >> 4 != SYNC and TRAIN >> 4 != SYNC


def test_training_marks_every_period() -> None:
    w = training_words(LinkFormat(8), 2 * TRAIN_PERIOD)
    assert np.flatnonzero(w[:, 0] == MARK).tolist() == [TRAIN_PERIOD - 1, 2 * TRAIN_PERIOD - 1]
    assert (w == w[:, :1]).all()


def test_serialise_is_bit_zero_first() -> None:
    bits = serialise(np.array([[0b00000001, 0b10000000]], dtype=np.uint8))
    assert bits.tolist() == [[1, 0, 0, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0, 0, 1]]


@pytest.mark.parametrize("delays", [(0, 0, 0), (5, 0, 7), (3, 3, 1)])
def test_round_trip_through_skew(delays: tuple[int, ...]) -> None:
    fmt = LinkFormat(13)
    rng = np.random.default_rng(sum(delays))
    payload = rng.integers(0, 2, (20, 13)).astype(np.uint8)
    sof, eol = rng.integers(0, 2, 20).astype(bool), rng.integers(0, 2, 20).astype(bool)
    words = np.concatenate([training_words(fmt, 40), beat_words(fmt, payload, sof, eol),
                            idle_words(fmt, 3), beat_words(fmt, payload[:2], sof[:2],
                                                           eol[:2]), idle_words(fmt, 1)])
    got = deserialise(fmt, skewed(serialise(words), delays, fill=1))
    assert np.array_equal(got.payload, np.concatenate([payload, payload[:2]]))
    assert np.array_equal(got.sof, np.concatenate([sof, sof[:2]]))
    assert got.slips.tolist() == list(delays)
    assert got.errors.tolist() == [0, 0, 0]


def test_errors_are_counted_per_pair() -> None:
    fmt = LinkFormat(16)
    words = np.concatenate([training_words(fmt, 40), idle_words(fmt, 4),
                            beat_words(fmt, np.ones((2, 16), np.uint8), [1, 0], [0, 1])])
    words[41, 1] ^= 4  # an idle word on pair 1
    words[44, 0] ^= 1  # a beat's bit: parity, counted on the framing lane
    got = deserialise(fmt, serialise(words))
    assert got.errors.tolist() == [0, 1, 1]


def test_pixel_beats_and_spike_frames() -> None:
    codes = np.arange(2 * 2 * 4).reshape(2, 2, 4) % 4
    bits, sof, eol = pixel_beats(codes, 2, 2)
    assert bits.shape == (8, 4) and sof.tolist() == [1, 0, 0, 0] * 2
    assert eol.tolist() == [0, 1] * 4
    assert bits[1].tolist() == [0, 1, 1, 1]  # codes 2, 3 of row 0, lanes 0 and 1
    fmt = LinkFormat(2 * 2 * 2)
    rng = np.random.default_rng(0)
    spikes = rng.integers(-1, 2, (2, 2, 2, 4)).astype(np.int8)  # (T, S, H, W)
    beats = spikes.reshape(2, 2, 2, 2, 2).transpose(0, 2, 3, 1, 4).reshape(8, 2, 2)
    payload = np.concatenate([(beats == 1).reshape(8, 4), (beats == -1).reshape(8, 4)],
                             axis=1).astype(np.uint8)
    words = np.concatenate([training_words(fmt, 40), beat_words(fmt, payload, sof, eol)])
    got = spike_beats_to_frames(deserialise(fmt, serialise(words)), 2, 2, 4, 2)
    assert np.array_equal(got, spikes)
