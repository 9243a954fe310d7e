import numpy as np
import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.receptive_fields import (
    MODEL_NAMES,
    SCALES,
    dog_kernel,
    gauss_kernel,
    model_spec,
)

# SPEC section 2 check values: (centre weight, sum of weights) of the normalised kernels.
DOG_CHECK = {0.24: (0.921208, 0.842416), 0.348: (0.663422, 0.326844),
             0.5046: (0.518161, 0.036321), 0.7317: (0.279489, 0.000367)}
GAUSS_CENTRE = {0.24: 0.999321, 0.7317: 0.297241}


@pytest.mark.parametrize("index", range(4))
def test_dog_check_values(index):
    sigma, half = SCALES[index], index + 1
    k = dog_kernel(sigma, half)
    assert k.shape == (2 * half + 1, 2 * half + 1)
    centre, total = DOG_CHECK[sigma]
    assert k[half, half] == pytest.approx(centre, abs=5e-7)
    assert k.sum() == pytest.approx(total, abs=5e-7)
    assert np.abs(k).sum() == pytest.approx(1.0, abs=1e-12)
    np.testing.assert_allclose(k, k.T)
    np.testing.assert_allclose(k, k[::-1, ::-1])


@pytest.mark.parametrize("sigma,half", [(0.24, 1), (0.7317, 4)])
def test_gauss_check_values(sigma, half):
    k = gauss_kernel(sigma, half)
    assert k[half, half] == pytest.approx(GAUSS_CENTRE[sigma], abs=5e-7)
    assert k.sum() == pytest.approx(1.0, abs=1e-12)


def test_model_ladders():
    assert model_spec("fsm").num_scales == 1 and not model_spec("fsm").signed
    for n in range(1, 5):
        dog = model_spec(f"dog{n}")
        assert dog.scales == SCALES[:n] and dog.half_widths == tuple(range(1, n + 1))
        assert dog.signed
        assert [k.shape[0] for k in dog.kernels()] == [3, 5, 7, 9][:n]
    assert model_spec(" Gauss3 ").name == "gauss3"
    for name in MODEL_NAMES:  # every listed name parses to itself
        assert model_spec(name).name == name


@pytest.mark.parametrize("bad", ["dog5", "gauss0", "", "fsm2", "DoG"])
def test_unknown_model_is_refused(bad):
    with pytest.raises(RvsmError, match="unknown model"):
        model_spec(bad)


def test_kernels_are_read_only():
    with pytest.raises(ValueError):
        dog_kernel(0.24, 1)[0, 0] = 1.0
