"""Row-pair and orbit-sum numba kernels shared by the float and fixed fused engines.

A receptive sum of a ``(2L+1) x (2L+1)`` kernel with the 8-fold symmetry of
:mod:`rvsm.model.kernels.orbits` needs, per padded row ``r``, the pair sums
``pairs[b, r, x] = v(r, x - b) + v(r, x + b)`` (``b = 0``: the value itself);
:func:`scale_sum` then forms one scale's sum of one row from them with the unrolled orbit
sums of :mod:`.orbit_kernels`, and :func:`ladder_sum` every scale of a ``1..S`` ladder
in one pass (the same results, each orbit formed once). The same operations in the same
order sum floats for :mod:`.fused` and :mod:`rvsm.model.events.fused` and exact integers
for :mod:`rvsm.model.fixed.fused`.
"""

from __future__ import annotations

from numba import njit

from rvsm.model.infra.simd import allow_alias_checks
from rvsm.model.sampling.orbit_kernels import (
    ladder_sum_1,
    ladder_sum_2,
    ladder_sum_3,
    ladder_sum_4,
    scale_sum_0,
    scale_sum_1,
    scale_sum_2,
    scale_sum_3,
    scale_sum_4,
)

# The one loop of the four-scale ladder sums needs 180 runtime alias checks to vectorise
# (before any kernel using these functions compiles).
allow_alias_checks()


@njit(inline="always", cache=True)
def row_pairs(pad, nrows, lmax, width, pairs):
    """``pairs[b, r, x] = pad[r, x + L - b] + pad[r, x + L + b]`` (``b = 0``: the value)
    for rows ``0 .. nrows - 1`` of ``pad (R, W + 2L)``; ``pairs`` is ``(L + 1, R, W)``."""
    # Slices first: ``src[x + lmax - b]`` would carry numba's negative-index wraparound
    # check, which keeps the loop from vectorising.
    for r in range(nrows):
        src = pad[r]
        mid = src[lmax:lmax + width]
        dst = pairs[0, r]
        for x in range(width):
            dst[x] = mid[x]
        for b in range(1, lmax + 1):
            dst = pairs[b, r]
            left = src[lmax - b:lmax - b + width]
            right = src[lmax + b:lmax + b + width]
            for x in range(width):
                dst[x] = left[x] + right[x]


@njit(inline="always", cache=True)
def scale_sum(pairs, pr, w, half, width, out):
    """``out[x]``: the receptive sum of padded row ``pr`` for one scale of half-width
    ``half`` (0..4) with orbit weights ``w``, from the row pairs ``pairs``."""
    if half == 0:
        scale_sum_0(pairs, pr, w, width, out)
    elif half == 1:
        scale_sum_1(pairs, pr, w, width, out)
    elif half == 2:
        scale_sum_2(pairs, pr, w, width, out)
    elif half == 3:
        scale_sum_3(pairs, pr, w, width, out)
    else:
        scale_sum_4(pairs, pr, w, width, out)


def is_ladder(halves) -> bool:
    """True when the half-widths are ``1, 2, .., S`` (``S <= 4``): :func:`ladder_sum`
    serves them."""
    return 1 <= len(halves) <= 4 and [int(h) for h in halves] == list(range(1, len(halves) + 1))


@njit(inline="always", cache=True)
def ladder_sum(pairs, pr, ring, w, width, out):
    """``out[s, x]``: every scale's receptive sum of padded row ``pr`` for a ladder of
    half-widths ``1..S`` (:func:`is_ladder`) with orbit weights ``w (S, N)``, one pass;
    row ``pr + d`` is ``pairs[:, (pr + d) % ring]`` (a ring of ``ring`` rows stored once;
    ``ring = pairs.shape[1]`` for plain rows; ``pr >= S``). Equal bit for bit to
    :func:`scale_sum` per scale, about 3x faster for four."""
    num_scales = w.shape[0]
    if num_scales == 1:
        ladder_sum_1(pairs, pr, ring, w, width, out)
    elif num_scales == 2:
        ladder_sum_2(pairs, pr, ring, w, width, out)
    elif num_scales == 3:
        ladder_sum_3(pairs, pr, ring, w, width, out)
    else:
        ladder_sum_4(pairs, pr, ring, w, width, out)
