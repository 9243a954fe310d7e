"""Unrolled orbit sums for numba (written by scripts/gen_orbit_kernels.py; do not edit).

``scale_sum_L(pairs, pr, w, width, out)``: ``out[x]`` = the receptive sum of padded row
``pr`` for one scale of half-width ``L`` with orbit weights ``w``, where
``pairs[b, r, x] = v(r, x - b) + v(r, x + b)`` (``pairs[0] = v``); the same float
operations in the same order as :func:`rvsm.model.kernels.orbits.orbit_receptive_sums` (``t``
starts at ``w[0] - w[0]``, i.e. 0 of the weights' type, so the same code sums integers
exactly for the fixed twin). The weighted sum stays in a register, so the loop over
``x`` vectorises.
"""

from numba import njit


@njit(inline="always", cache=True)
def scale_sum_0(pairs, pr, w, width, out):
    r0_p0 = pairs[0, pr + 0]
    for x in range(width):
        t = w[0] - w[0]
        t = t + w[0] * r0_p0[x]
        out[x] = t


@njit(inline="always", cache=True)
def scale_sum_1(pairs, pr, w, width, out):
    r0_m1 = pairs[0, pr - 1]
    r0_p0 = pairs[0, pr + 0]
    r0_p1 = pairs[0, pr + 1]
    r1_m1 = pairs[1, pr - 1]
    r1_p0 = pairs[1, pr + 0]
    r1_p1 = pairs[1, pr + 1]
    for x in range(width):
        t = w[0] - w[0]
        t = t + w[0] * r0_p0[x]
        t = t + w[1] * ((r0_m1[x] + r0_p1[x]) + r1_p0[x])
        t = t + w[2] * (r1_m1[x] + r1_p1[x])
        out[x] = t


@njit(inline="always", cache=True)
def scale_sum_2(pairs, pr, w, width, out):
    r0_m2 = pairs[0, pr - 2]
    r0_m1 = pairs[0, pr - 1]
    r0_p0 = pairs[0, pr + 0]
    r0_p1 = pairs[0, pr + 1]
    r0_p2 = pairs[0, pr + 2]
    r1_m2 = pairs[1, pr - 2]
    r1_m1 = pairs[1, pr - 1]
    r1_p0 = pairs[1, pr + 0]
    r1_p1 = pairs[1, pr + 1]
    r1_p2 = pairs[1, pr + 2]
    r2_m2 = pairs[2, pr - 2]
    r2_m1 = pairs[2, pr - 1]
    r2_p0 = pairs[2, pr + 0]
    r2_p1 = pairs[2, pr + 1]
    r2_p2 = pairs[2, pr + 2]
    for x in range(width):
        t = w[0] - w[0]
        t = t + w[0] * r0_p0[x]
        t = t + w[1] * ((r0_m1[x] + r0_p1[x]) + r1_p0[x])
        t = t + w[2] * (r1_m1[x] + r1_p1[x])
        t = t + w[3] * ((r0_m2[x] + r0_p2[x]) + r2_p0[x])
        t = t + w[4] * ((r1_m2[x] + r1_p2[x]) + (r2_m1[x] + r2_p1[x]))
        t = t + w[5] * (r2_m2[x] + r2_p2[x])
        out[x] = t


@njit(inline="always", cache=True)
def scale_sum_3(pairs, pr, w, width, out):
    r0_m3 = pairs[0, pr - 3]
    r0_m2 = pairs[0, pr - 2]
    r0_m1 = pairs[0, pr - 1]
    r0_p0 = pairs[0, pr + 0]
    r0_p1 = pairs[0, pr + 1]
    r0_p2 = pairs[0, pr + 2]
    r0_p3 = pairs[0, pr + 3]
    r1_m3 = pairs[1, pr - 3]
    r1_m2 = pairs[1, pr - 2]
    r1_m1 = pairs[1, pr - 1]
    r1_p0 = pairs[1, pr + 0]
    r1_p1 = pairs[1, pr + 1]
    r1_p2 = pairs[1, pr + 2]
    r1_p3 = pairs[1, pr + 3]
    r2_m3 = pairs[2, pr - 3]
    r2_m2 = pairs[2, pr - 2]
    r2_m1 = pairs[2, pr - 1]
    r2_p0 = pairs[2, pr + 0]
    r2_p1 = pairs[2, pr + 1]
    r2_p2 = pairs[2, pr + 2]
    r2_p3 = pairs[2, pr + 3]
    r3_m3 = pairs[3, pr - 3]
    r3_m2 = pairs[3, pr - 2]
    r3_m1 = pairs[3, pr - 1]
    r3_p0 = pairs[3, pr + 0]
    r3_p1 = pairs[3, pr + 1]
    r3_p2 = pairs[3, pr + 2]
    r3_p3 = pairs[3, pr + 3]
    for x in range(width):
        t = w[0] - w[0]
        t = t + w[0] * r0_p0[x]
        t = t + w[1] * ((r0_m1[x] + r0_p1[x]) + r1_p0[x])
        t = t + w[2] * (r1_m1[x] + r1_p1[x])
        t = t + w[3] * ((r0_m2[x] + r0_p2[x]) + r2_p0[x])
        t = t + w[4] * ((r1_m2[x] + r1_p2[x]) + (r2_m1[x] + r2_p1[x]))
        t = t + w[5] * (r2_m2[x] + r2_p2[x])
        t = t + w[6] * ((r0_m3[x] + r0_p3[x]) + r3_p0[x])
        t = t + w[7] * ((r1_m3[x] + r1_p3[x]) + (r3_m1[x] + r3_p1[x]))
        t = t + w[8] * ((r2_m3[x] + r2_p3[x]) + (r3_m2[x] + r3_p2[x]))
        t = t + w[9] * (r3_m3[x] + r3_p3[x])
        out[x] = t


@njit(inline="always", cache=True)
def scale_sum_4(pairs, pr, w, width, out):
    r0_m4 = pairs[0, pr - 4]
    r0_m3 = pairs[0, pr - 3]
    r0_m2 = pairs[0, pr - 2]
    r0_m1 = pairs[0, pr - 1]
    r0_p0 = pairs[0, pr + 0]
    r0_p1 = pairs[0, pr + 1]
    r0_p2 = pairs[0, pr + 2]
    r0_p3 = pairs[0, pr + 3]
    r0_p4 = pairs[0, pr + 4]
    r1_m4 = pairs[1, pr - 4]
    r1_m3 = pairs[1, pr - 3]
    r1_m2 = pairs[1, pr - 2]
    r1_m1 = pairs[1, pr - 1]
    r1_p0 = pairs[1, pr + 0]
    r1_p1 = pairs[1, pr + 1]
    r1_p2 = pairs[1, pr + 2]
    r1_p3 = pairs[1, pr + 3]
    r1_p4 = pairs[1, pr + 4]
    r2_m4 = pairs[2, pr - 4]
    r2_m3 = pairs[2, pr - 3]
    r2_m2 = pairs[2, pr - 2]
    r2_m1 = pairs[2, pr - 1]
    r2_p0 = pairs[2, pr + 0]
    r2_p1 = pairs[2, pr + 1]
    r2_p2 = pairs[2, pr + 2]
    r2_p3 = pairs[2, pr + 3]
    r2_p4 = pairs[2, pr + 4]
    r3_m4 = pairs[3, pr - 4]
    r3_m3 = pairs[3, pr - 3]
    r3_m2 = pairs[3, pr - 2]
    r3_m1 = pairs[3, pr - 1]
    r3_p0 = pairs[3, pr + 0]
    r3_p1 = pairs[3, pr + 1]
    r3_p2 = pairs[3, pr + 2]
    r3_p3 = pairs[3, pr + 3]
    r3_p4 = pairs[3, pr + 4]
    r4_m4 = pairs[4, pr - 4]
    r4_m3 = pairs[4, pr - 3]
    r4_m2 = pairs[4, pr - 2]
    r4_m1 = pairs[4, pr - 1]
    r4_p0 = pairs[4, pr + 0]
    r4_p1 = pairs[4, pr + 1]
    r4_p2 = pairs[4, pr + 2]
    r4_p3 = pairs[4, pr + 3]
    r4_p4 = pairs[4, pr + 4]
    for x in range(width):
        t = w[0] - w[0]
        t = t + w[0] * r0_p0[x]
        t = t + w[1] * ((r0_m1[x] + r0_p1[x]) + r1_p0[x])
        t = t + w[2] * (r1_m1[x] + r1_p1[x])
        t = t + w[3] * ((r0_m2[x] + r0_p2[x]) + r2_p0[x])
        t = t + w[4] * ((r1_m2[x] + r1_p2[x]) + (r2_m1[x] + r2_p1[x]))
        t = t + w[5] * (r2_m2[x] + r2_p2[x])
        t = t + w[6] * ((r0_m3[x] + r0_p3[x]) + r3_p0[x])
        t = t + w[7] * ((r1_m3[x] + r1_p3[x]) + (r3_m1[x] + r3_p1[x]))
        t = t + w[8] * ((r2_m3[x] + r2_p3[x]) + (r3_m2[x] + r3_p2[x]))
        t = t + w[9] * (r3_m3[x] + r3_p3[x])
        t = t + w[10] * ((r0_m4[x] + r0_p4[x]) + r4_p0[x])
        t = t + w[11] * ((r1_m4[x] + r1_p4[x]) + (r4_m1[x] + r4_p1[x]))
        t = t + w[12] * ((r2_m4[x] + r2_p4[x]) + (r4_m2[x] + r4_p2[x]))
        t = t + w[13] * ((r3_m4[x] + r3_p4[x]) + (r4_m3[x] + r4_p3[x]))
        t = t + w[14] * (r4_m4[x] + r4_p4[x])
        out[x] = t
