"""The model's log (:mod:`rvsm.model.events.log_intensity`): within ``LOG_MAX_ULP`` of
the exact ``ln`` on a dense range of inputs, exact where ``ln`` is, the clamp of
brightness below zero, and the same bits in vector and scalar code."""

from __future__ import annotations

import math

import numpy as np

from rvsm.model.events.log_intensity import LOG_MAX_ULP, log_intensity


def _ulp_error(x: np.ndarray) -> np.ndarray:
    """``|ln_model(x) - ln(x)|`` in units in the last place of the result, against the
    80-bit long-double ``ln`` (11 more bits than float64)."""
    got = log_intensity(x - 1.0)
    exact = np.log((x - 1.0 + 1.0).astype(np.longdouble))
    ulp = np.spacing(np.maximum(np.abs(got), np.finfo(np.float64).tiny))
    return (np.abs(got.astype(np.longdouble) - exact) / ulp).astype(np.float64)


def test_within_one_ulp_on_a_dense_range() -> None:
    """Inputs ``I + 1`` in ``[1, 2**20]``: log-uniform draws, the neighbourhood of 1 (where
    ``ln`` is small and cancellation bites) and the 8-bit range in steps of 1/64."""
    assert np.finfo(np.longdouble).nmant >= 63, "needs x86 long double for the reference"
    rng = np.random.default_rng(19)
    x = np.concatenate([
        np.exp(rng.uniform(0.0, math.log(2.0 ** 20), 400_000)),
        1.0 + rng.uniform(0.0, 1e-3, 50_000),
        np.sqrt(0.5) * 2.0 ** rng.integers(1, 20, 20_000) * (1.0 + rng.uniform(-1e-9, 1e-9,
                                                                                20_000)),
        np.arange(1.0, 257.0, 1.0 / 64.0),
    ])
    x = x[x >= 1.0]
    err = _ulp_error(x)
    assert err.max() <= LOG_MAX_ULP
    assert err.max() > 0.5  # not correctly rounded everywhere: the bound is a real one


def test_exact_values_and_clamp() -> None:
    got = log_intensity(np.array([0.0, -3.0, np.nan, 1.0, 255.0, np.inf, 1e300]))
    assert got[0] == 0.0 and got[1] == 0.0 and got[2] == 0.0  # ln 1, clamped, NaN -> 0
    assert got[3] == math.log(2.0)
    assert abs(got[4] - math.log(256.0)) <= np.spacing(got[4])
    assert got[5] == np.inf
    assert abs(got[6] - math.log(1e300)) <= np.spacing(got[6])
    assert np.all(np.diff(log_intensity(np.arange(0.0, 300.0, 0.01))) >= 0)  # monotone


def test_vector_and_scalar_code_agree() -> None:
    """Each element's log is the same whether it falls in a vectorised block or the scalar
    remainder of a row: rows of every width 1..9 against one long row."""
    rng = np.random.default_rng(7)
    v = rng.uniform(-5.0, 300.0, 4096)
    whole = log_intensity(v)
    for width in range(1, 10):
        n = (len(v) // width) * width
        assert np.array_equal(log_intensity(v[:n].reshape(-1, width)).ravel(), whole[:n])
