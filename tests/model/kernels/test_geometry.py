"""Kernel geometry shared by both twins, the RTL sums and the FPGA arithmetic."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.model.fixed.weights import quantise_model
from rvsm.model.kernels.geometry import (
    is_symmetric,
    kernel_radius,
    orbit_taps,
    symmetric_orbits,
)
from rvsm.model.kernels.receptive_fields import MODEL_NAMES


def test_radius_skips_zero_rings() -> None:
    k = np.zeros((9, 9), dtype=np.int64)
    k[4, 4], k[2, 4] = 5, -1
    assert kernel_radius([k]) == 2
    assert kernel_radius([np.ones((1, 1))]) == 0


def test_orbits_tile_the_window_once() -> None:
    radius = 3
    orbits = symmetric_orbits(radius)
    assert orbits[:4] == [(0, 0), (1, 0), (1, 1), (2, 0)]
    assert [len(orbit_taps(a, b)) for a, b in orbits[:3]] == [1, 4, 4]
    taps = [t for a, b in orbits for t in orbit_taps(a, b)]
    window = {(dy, dx) for dy in range(-radius, radius + 1) for dx in range(-radius, radius + 1)}
    assert len(taps) == len(window) and set(taps) == window


@pytest.mark.parametrize("model", MODEL_NAMES)
def test_templates_are_constant_on_orbits(model: str) -> None:
    for k in quantise_model(model, 9, "round-half-up"):
        assert is_symmetric(k)
        half = k.shape[0] // 2
        for a, b in symmetric_orbits(half):
            assert len({int(k[half + dy, half + dx]) for dy, dx in orbit_taps(a, b)}) == 1
    assert not is_symmetric(np.arange(9).reshape(3, 3))
