import numpy as np
import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.model.noise.sensor import NoiseParams, NoiseSource


def test_dark_current_statistics_and_stream_order():
    params = NoiseParams(k=2.0, seed=1)
    whole = NoiseSource(params, (50, 60), 1).dark_current(40)
    assert whole.mean() == pytest.approx(2.0, abs=0.01)
    assert whole.std() == pytest.approx(1.5, rel=0.01)
    src = NoiseSource(params, (50, 60), 1)
    parts = np.concatenate([src.dark_current(n) for n in (7, 1, 32)])
    np.testing.assert_array_equal(whole, parts)


def test_fixed_pattern_statistics_and_reuse():
    src = NoiseSource(NoiseParams(k=1.0, seed=0), (100, 100), 4)
    theta, v_os = src.fixed_pattern()
    assert theta.shape == v_os.shape == (4, 100, 100)
    assert theta.mean() == pytest.approx(1.0, abs=0.002)
    assert theta.std() == pytest.approx(0.0275, rel=0.03)
    assert v_os.std() == pytest.approx(3.0, rel=0.03)
    again = src.fixed_pattern()
    np.testing.assert_array_equal(theta, again[0])
    thr = src.thresholds(np.array([400.0, 400.0, 500.0, 600.0]))
    np.testing.assert_allclose(thr[2], theta[2] * 500 + v_os[2])


def test_k_zero_means_no_spread():
    src = NoiseSource(NoiseParams(k=0.0, seed=0), (4, 4), 1)
    np.testing.assert_array_equal(src.dark_current(3), np.full((3, 4, 4), 2.0))
    np.testing.assert_array_equal(src.thresholds(np.array([400.0])), np.full((1, 4, 4), 400.0))


@pytest.mark.parametrize("kwargs", [{"k": -1}, {"seed": -1}, {"b1": -0.1},
                                    {"k": float("inf")}, {"seed": 1.5}])
def test_bad_noise_parameters(kwargs):
    with pytest.raises(RvsmError):
        NoiseParams(**kwargs)
