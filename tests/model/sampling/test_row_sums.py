"""The shared row-sum kernels (:mod:`rvsm.model.sampling.row_sums`): the ladder sums
equal the per-scale orbit sums bit for bit (floats and integer-valued floats). The sums
compile for about 13 CPU seconds, so the direct comparison runs under the slow marker; the
default suite covers the ladder through the event engines' agreement
(``tests/model/events/test_event_sampling.py``)."""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from rvsm.model.kernels.orbits import kernel_orbits
from rvsm.model.kernels.receptive_fields import model_spec
from rvsm.model.sampling.row_sums import is_ladder, ladder_sum, scale_sum


@njit(cache=True)
def _both(pairs, w, halves, rows, width, lad, per):
    for r in range(rows):
        ladder_sum(pairs, halves[-1] + r, pairs.shape[1], w, width, lad[r])
        for s in range(w.shape[0]):
            scale_sum(pairs, halves[-1] + r, w[s], halves[s], width, per[r, s])


@njit(cache=True)
def _ring(pairs, pr, w, width, out):
    ladder_sum(pairs, pr, pairs.shape[1], w, width, out)


@pytest.mark.slow
@pytest.mark.parametrize("model", ["dog1", "gauss2", "dog3", "dog4"])
def test_ladder_sum_equals_scale_sums(model: str) -> None:
    _, w, halves, lmax = kernel_orbits(model_spec(model).kernels())
    assert is_ladder(halves)
    rng = np.random.default_rng(5)
    rows = 3
    for width in (1, 7, 37):
        for pairs in (rng.uniform(-3.0, 9.0, (lmax + 1, rows + 2 * lmax, width)),
                      rng.integers(-500, 500, (lmax + 1, rows + 2 * lmax, width)) * 1.0):
            lad = np.empty((rows, len(halves), width))
            per = np.empty_like(lad)
            _both(pairs, np.ascontiguousarray(w), halves, rows, width, lad, per)
            assert np.array_equal(lad, per)
            # A ring of the 2L + 1 rows of output row 0, rotated by k: the same sums.
            window = np.ascontiguousarray(pairs[:, :2 * lmax + 1])
            for k in range(2 * lmax + 1):
                ring = np.ascontiguousarray(np.roll(window, k, axis=1))
                got = np.empty((len(halves), width))
                _ring(ring, lmax + k, np.ascontiguousarray(w), width, got)
                assert np.array_equal(got, per[0])


def test_is_ladder() -> None:
    assert is_ladder([1, 2, 3, 4]) and is_ladder(np.array([1]))
    assert not is_ladder([0]) and not is_ladder([2, 3]) and not is_ladder([1, 2, 3, 4, 5])
