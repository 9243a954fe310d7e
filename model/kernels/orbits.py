"""Receptive-field sums in one fixed floating-point order, shared by every float path.

The DoG and Gauss templates have the 8-fold symmetry of the square, so a kernel is a
weight per *orbit* ``(a, b)``, ``0 <= b <= a <= L``: the taps ``(+-a, +-b)`` and
``(+-b, +-a)``. With ``v(dy, dx)`` the (zero-padded) value at ``(y + dy, x + dx)``:

- ``O(0, 0) = v(0, 0)``
- ``O(a, 0) = (v(-a, 0) + v(a, 0)) + (v(0, -a) + v(0, a))``
- ``O(a, a) = (v(-a, -a) + v(-a, a)) + (v(a, -a) + v(a, a))``
- ``O(a, b) = ((v(-a, -b) + v(-a, b)) + (v(a, -b) + v(a, b)))
  + ((v(-b, -a) + v(-b, a)) + (v(b, -a) + v(b, a)))``

and a scale's sum is ``((0 + w_00 O(0,0)) + w_10 O(1,0)) + w_11 O(1,1) + ...`` over its
orbits in the order ``a = 0..L``, ``b = 0..a`` (every orbit of the scale, zero weights
too). IEEE arithmetic makes the result a function of this order only, so the numpy
reference here and the fused numba kernels (:mod:`rvsm.model.sampling.fused`, unrolled in
:mod:`rvsm.model.sampling.orbit_kernels`) agree bit for bit. With row-pair sums shared by all
scales it costs about 75 additions and 34 multiplications per pixel for the four-scale
ladder, against 164 multiply-adds tap by tap.
FSM's 1x1 kernel of 1.0 gives the value itself.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.geometry import is_symmetric, symmetric_orbits


def kernel_orbits(
    kernels: Sequence[np.ndarray],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """``(orbits (N, 2) int64, weights (S, N), halves (S,) int64, L)``: orbit ``(a, b)``
    list in sum order, each scale's weight per orbit (0 beyond its half-width), each
    scale's half-width and the largest. Scale ``s`` uses the first
    ``(L_s + 1)(L_s + 2) / 2`` orbits. The weights keep the kernels' dtype.
    """
    ks = [np.asarray(k) for k in kernels]
    if not all(is_symmetric(k) for k in ks):
        raise RvsmError("orbit sums need kernels with the square's 8-fold symmetry")
    halves = [k.shape[0] // 2 for k in ks]
    big = max(halves)
    orbits = symmetric_orbits(big)
    dtype = np.result_type(*[k.dtype for k in ks])
    weights = np.zeros((len(ks), len(orbits)), dtype=dtype)
    for s, (k, half) in enumerate(zip(ks, halves, strict=True)):
        for n, (a, b) in enumerate(orbits):
            if a <= half:
                weights[s, n] = k[half + a, half + b]
    return (np.array(orbits, dtype=np.int64).reshape(-1, 2), weights,
            np.array(halves, dtype=np.int64), big)


def orbit_receptive_sums(stack: np.ndarray, kernels: Sequence[np.ndarray]) -> np.ndarray:
    """Receptive-field sums of ``stack (B, H, W)`` for ``S`` symmetric kernels, zero
    padding, in the order of the module docstring: ``(B, S, H, W) float64``."""
    stack = np.asarray(stack, dtype=np.float64)
    orbits, weights, halves, big = kernel_orbits(kernels)
    bsz, h, w = stack.shape
    padded = np.zeros((bsz, h + 2 * big, w + 2 * big))
    padded[:, big:big + h, big:big + w] = stack

    def v(dy: int, dx: int) -> np.ndarray:
        return padded[:, big + dy:big + dy + h, big + dx:big + dx + w]

    out = np.zeros((bsz, len(kernels), h, w))
    for n, (a, b) in enumerate(orbits):
        users = [s for s in range(len(kernels)) if halves[s] >= a]
        if not users:
            continue
        if a == 0:
            orbit = v(0, 0)
        elif b == 0:
            orbit = (v(-a, 0) + v(a, 0)) + (v(0, -a) + v(0, a))
        elif a == b:
            orbit = (v(-a, -a) + v(-a, a)) + (v(a, -a) + v(a, a))
        else:
            orbit = ((v(-a, -b) + v(-a, b)) + (v(a, -b) + v(a, b))) + (
                (v(-b, -a) + v(-b, a)) + (v(b, -a) + v(b, a))
            )
        for s in users:
            out[:, s] += weights[s, n] * orbit
    return out
