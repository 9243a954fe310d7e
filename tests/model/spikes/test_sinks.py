"""Spike sinks: an ArraySink lends its own rows to producers (no copy of any chunk)."""

import numpy as np

from rvsm.model.spikes.sinks import ArraySink, CountSink, TeeSink, chunk_target, fill_sink

SHAPE = (10, 2, 3, 4)


def _spikes() -> np.ndarray:
    return np.random.default_rng(1).integers(-1, 2, SHAPE).astype(np.int8)


def _fill(sink, spikes: np.ndarray, lend: bool) -> list[bool]:
    """Fill ``sink`` in chunks of 4 steps; per chunk, whether it was written in place."""
    spare = np.empty((4,) + SHAPE[1:], dtype=np.int8)
    in_place = []

    def produce(t0, t1):
        out = chunk_target(sink, t0, t1, spare) if lend else spare[:t1 - t0]
        out[...] = spikes[t0:t1]
        in_place.append(not np.shares_memory(out, spare))
        return out

    fill_sink(sink, SHAPE, {}, produce, 4)
    return in_place


def test_array_sink_lends_its_rows_and_copies_otherwise():
    spikes = _spikes()
    for lend in (True, False):
        sink = ArraySink()
        in_place = _fill(sink, spikes, lend)
        assert in_place == [lend] * 3
        np.testing.assert_array_equal(sink.spikes, spikes)


def test_tee_lends_the_array_and_every_sink_sees_every_chunk():
    spikes = _spikes()
    array, counts = ArraySink(), CountSink()
    in_place = _fill(TeeSink(counts, array), spikes, lend=True)
    assert in_place == [True] * 3
    np.testing.assert_array_equal(array.spikes, spikes)
    assert counts.spikes == np.count_nonzero(spikes) and counts.steps == SHAPE[0]
    # no sink lends memory: the spare buffer is used
    assert _fill(TeeSink(CountSink()), spikes, lend=True) == [False] * 3
