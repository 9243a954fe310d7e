"""ADC codes and weight quantisation: every rounding and clipping rule, every kernel."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.model.fixed.adc import adc_codes, quantise
from rvsm.model.fixed.weights import quantise_model, weight_error_report
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.receptive_fields import MODEL_NAMES, model_spec


def test_rounding_rules():
    x = np.array([-2.5, -1.5, -0.3, 0.0, 0.5, 1.49, 1.5, 2.5, 2.7])
    assert list(quantise(x, "truncate")) == [-3, -2, -1, 0, 0, 1, 1, 2, 2]
    assert list(quantise(x, "round-half-up")) == [-2, -1, 0, 0, 1, 1, 2, 3, 3]
    with pytest.raises(RvsmError):
        quantise(x, "even")


def test_adc_codes_round_and_clip():
    b = np.array([[[-3.0, 0.0, 0.49, 0.5, 127.5, 254.6, 255.0, 300.0]]])
    assert adc_codes(b, 8, 255.0, "round-half-up").tolist() == [[[0, 0, 0, 1, 128, 255, 255,
                                                                  255]]]
    assert adc_codes(b, 8, 255.0, "truncate").tolist() == [[[0, 0, 0, 0, 127, 254, 255, 255]]]
    # 4 bits over full scale 150: gain 15/150 = 0.1 code per unit
    assert adc_codes(np.array([[[14.9, 15.0, 149.0, 150.0]]]), 4, 150.0, "truncate").tolist() \
        == [[[1, 1, 14, 15]]]
    with pytest.raises(RvsmError, match="adc.clip"):
        adc_codes(b, 8, 255.0, clip="error")
    assert adc_codes(b[..., 1:7], 8, 255.0, clip="error").dtype == np.int64


@pytest.mark.parametrize("model", MODEL_NAMES)
@pytest.mark.parametrize("rounding", ["truncate", "round-half-up"])
def test_weight_quantisation_of_each_kernel(model, rounding):
    frac = 10
    lsb = 2.0**-frac
    for k, w in zip(model_spec(model).kernels(), quantise_model(model, frac, rounding),
                    strict=True):
        assert w.dtype == np.int64 and w.shape == k.shape
        err = w * lsb - k
        if rounding == "truncate":
            assert np.all(err <= 0) and np.all(err > -lsb)
        else:
            assert np.all(np.abs(err) <= lsb / 2)
        assert np.array_equal(w, w.T) and np.array_equal(w, w[::-1])
    if model == "fsm":
        assert quantise_model(model, frac, rounding)[0].tolist() == [[1024]]


def test_weight_error_report():
    rep = weight_error_report("dog4", 12, 10, "round-half-up")
    assert [r["taps"] for r in rep] == [9, 25, 49, 81]
    assert all(r["max_abs_error_lsb"] <= 0.5 for r in rep)
    assert rep[0]["int_max"] == 943 and rep[0]["range_max"] == 2047
    assert abs(rep[3]["sum_float"] - 0.000367) < 1e-5 and rep[3]["sum_fixed"] == -2 / 1024
