import numba
import numpy as np
import pytest
from scipy import stats

from rvsm.model.infra.errors import RvsmError
from rvsm.model.noise.sensor import NoiseParams, NoiseSource
from rvsm.model.noise.streams import ZIG_RATIO, ZIG_X, normal_block, stream_key


def test_every_deviate_is_a_function_of_its_coordinates():
    key = stream_key(7, 0)
    whole = normal_block(key, 0, 12, (9, 13), 0.0, 1.0)
    np.testing.assert_array_equal(whole[5:9], normal_block(key, 5, 4, (9, 13), 0.0, 1.0))
    # A cropped array sees the same noise at the same coordinates.
    np.testing.assert_array_equal(whole[:, :4, :6], normal_block(key, 0, 12, (4, 6), 0.0, 1.0))
    src = NoiseSource(NoiseParams(seed=7), (9, 13), 1)
    parts = np.concatenate([src.dark_current(n) for n in (3, 1, 8)])
    np.testing.assert_array_equal(parts, src.dark_current_at(0, 12))


def test_thread_count_does_not_change_the_stream():
    key = stream_key(3, 0)
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = normal_block(key, 4, 6, (17, 11), 2.0, 0.5)
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
        many = normal_block(key, 4, 6, (17, 11), 2.0, 0.5)
    finally:
        numba.set_num_threads(before)
    np.testing.assert_array_equal(one, many)


def test_standard_normal_statistics_and_tails():
    z = normal_block(stream_key(0, 0), 0, 40, (100, 100), 0.0, 1.0).ravel()
    assert abs(z.mean()) < 0.003 and abs(z.std() - 1.0) < 0.003
    assert stats.kstest(z, "norm").pvalue > 1e-3
    # The ziggurat's wedges and tail (about 1.2 % of draws) are exercised and correct.
    for cut in (2.0, 3.0, 3.5):
        expected = 2 * stats.norm.sf(cut)
        assert np.mean(np.abs(z) > cut) == pytest.approx(expected, rel=0.08)
    assert np.abs(z).max() > ZIG_X[1]  # beyond the base strip: the tail sampler ran
    assert len(ZIG_RATIO) == 128


def test_streams_differ_by_seed_and_stream():
    shape = (5, 8)
    a = normal_block(stream_key(1, 0), 0, 2, shape, 0.0, 1.0)
    assert not np.array_equal(a, normal_block(stream_key(2, 0), 0, 2, shape, 0.0, 1.0))
    assert not np.array_equal(a, normal_block(stream_key(1, 1), 0, 2, shape, 0.0, 1.0))
    assert abs(np.corrcoef(a[0].ravel(), a[1].ravel())[0, 1]) < 0.5


def test_fixed_pattern_shared_by_nested_ladders():
    one = NoiseSource(NoiseParams(seed=4), (6, 7), 1).fixed_pattern()
    four = NoiseSource(NoiseParams(seed=4), (6, 7), 4).fixed_pattern()
    np.testing.assert_array_equal(one[0][0], four[0][0])
    np.testing.assert_array_equal(one[1][0], four[1][0])
    assert not np.array_equal(four[0][0], four[0][1])


def test_coordinates_beyond_the_counter_layout_are_refused():
    with pytest.raises(RvsmError, match="65536"):
        NoiseSource(NoiseParams(), (70000, 2), 1)
    with pytest.raises(RvsmError, match="steps"):
        normal_block(stream_key(0, 0), (1 << 28) - 1, 2, (2, 2), 0.0, 1.0)
