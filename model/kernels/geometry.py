"""Kernel geometry, in one place: radius, the square's 8-fold symmetry and its orbits.

A receptive-field kernel is an odd square array ``(2h+1, 2h+1)`` centred on the pixel
(``h`` its half-width). Its *radius* is the largest Chebyshev distance
``max(|dy|, |dx|)`` of a non-zero weight (at most ``h``). The DoG and Gauss templates
are invariant under the symmetries of the square (transpose and both flips), so their
weights are constant on each *orbit* ``(a, b)``, ``0 <= b <= a``: the taps
``(+-a, +-b)`` and ``(+-b, +-a)`` (1 tap for ``(0, 0)``, 4 for ``(a, 0)`` and
``(a, a)``, 8 otherwise). Orbits are listed in the order ``a = 0..L``, ``b = 0..a``.

Used by the float twin (:mod:`rvsm.model.kernels.orbits`), the fixed twin
(:func:`rvsm.model.fixed.contract.integer_receptive_sums`), the RTL sums
(:mod:`rvsm.rtl.stream.pipelined_sum`) and the FPGA state-memory arithmetic
(:mod:`rvsm.rtl.fpga.camera`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["is_symmetric", "kernel_radius", "orbit_taps", "symmetric_orbits"]


def is_symmetric(kernel: np.ndarray) -> bool:
    """True when ``kernel`` is odd, square and invariant under the square's symmetries."""
    k = np.asarray(kernel)
    return (
        k.ndim == 2 and k.shape[0] == k.shape[1] and k.shape[0] % 2 == 1
        and np.array_equal(k, k.T) and np.array_equal(k, k[::-1])
        and np.array_equal(k, k[:, ::-1])
    )


def kernel_radius(kernels: Sequence[np.ndarray]) -> int:
    """``L``: the largest Chebyshev radius of a non-zero weight over all ``kernels``
    (each an odd square array; 0 when every weight is zero)."""
    radius = 0
    for kernel in kernels:
        k = np.asarray(kernel)
        half = k.shape[0] // 2
        rows, cols = np.nonzero(k)
        if len(rows):
            radius = max(radius, int(np.max(np.maximum(abs(rows - half), abs(cols - half)))))
    return radius


def symmetric_orbits(radius: int) -> list[tuple[int, int]]:
    """Orbits ``(a, b)`` up to ``radius``, in sum order: ``a = 0..L``, ``b = 0..a``."""
    return [(a, b) for a in range(radius + 1) for b in range(a + 1)]


def orbit_taps(a: int, b: int) -> tuple[tuple[int, int], ...]:
    """Offsets ``(dy, dx)`` of orbit ``(a, b)``: ``(+-a, +-b)`` and ``(+-b, +-a)``,
    sorted, without repeats (1, 4 or 8 taps)."""
    return tuple(sorted({(sy * p, sx * q) for p, q in ((a, b), (b, a))
                         for sy in (1, -1) for sx in (1, -1)}))
