"""Unrolled orbit sums for numba (written by python -m
rvsm.model.sampling.kernel_generator; do not edit).

``scale_sum_L(pairs, pr, w, width, out)``: ``out[x]`` = the receptive sum of padded row
``pr`` for one scale of half-width ``L`` with orbit weights ``w``, where
``pairs[b, r, x] = v(r, x - b) + v(r, x + b)`` (``pairs[0] = v``); the same float
operations in the same order as :func:`rvsm.model.kernels.orbits.orbit_receptive_sums` (``t``
starts at ``w[0] - w[0]``, i.e. 0 of the weights' type, so the same code sums integers
exactly for the fixed twin). The weighted sum stays in a register, so the loop over
``x`` vectorises.

``ladder_sum_S(pairs, pr, ring, w, width, out)``: ``out[s, x]`` for every scale ``s`` of
a ladder of half-widths ``1..S`` (weights ``w (S, N)``), rows taken modulo ``ring`` (a
ring of rows stored once; ``ring`` = the rows of ``pairs`` for plain rows; ``pr >= S``),
every scale in one loop: each orbit is formed once and added to the sums of the scales
that use it, each sum in its own order, so every ``out[s]`` equals ``scale_sum_{s + 1}``
bit for bit with fewer loads and additions. The loop over four scales reads 45 rows and
writes 4: it vectorises only with the vectoriser's runtime alias-check limit raised
(:func:`rvsm.model.infra.simd.allow_alias_checks`, set by :mod:`.row_sums`).
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


@njit(inline="always", cache=True)
def ladder_sum_1(pairs, pr, ring, w, width, out):
    r0_m1 = pairs[0, (pr - 1) % ring]
    r0_p0 = pairs[0, (pr + 0) % ring]
    r0_p1 = pairs[0, (pr + 1) % ring]
    r1_m1 = pairs[1, (pr - 1) % ring]
    r1_p0 = pairs[1, (pr + 0) % ring]
    r1_p1 = pairs[1, (pr + 1) % ring]
    out0 = out[0]
    w0_0 = w[0, 0]
    w0_1 = w[0, 1]
    w0_2 = w[0, 2]
    for x in range(width):
        t0 = w0_0 - w0_0
        o = r0_p0[x]
        t0 = t0 + w0_0 * o
        o = ((r0_m1[x] + r0_p1[x]) + r1_p0[x])
        t0 = t0 + w0_1 * o
        o = (r1_m1[x] + r1_p1[x])
        t0 = t0 + w0_2 * o
        out0[x] = t0


@njit(inline="always", cache=True)
def ladder_sum_2(pairs, pr, ring, w, width, out):
    r0_m2 = pairs[0, (pr - 2) % ring]
    r0_m1 = pairs[0, (pr - 1) % ring]
    r0_p0 = pairs[0, (pr + 0) % ring]
    r0_p1 = pairs[0, (pr + 1) % ring]
    r0_p2 = pairs[0, (pr + 2) % ring]
    r1_m2 = pairs[1, (pr - 2) % ring]
    r1_m1 = pairs[1, (pr - 1) % ring]
    r1_p0 = pairs[1, (pr + 0) % ring]
    r1_p1 = pairs[1, (pr + 1) % ring]
    r1_p2 = pairs[1, (pr + 2) % ring]
    r2_m2 = pairs[2, (pr - 2) % ring]
    r2_m1 = pairs[2, (pr - 1) % ring]
    r2_p0 = pairs[2, (pr + 0) % ring]
    r2_p1 = pairs[2, (pr + 1) % ring]
    r2_p2 = pairs[2, (pr + 2) % ring]
    out0 = out[0]
    w0_0 = w[0, 0]
    w0_1 = w[0, 1]
    w0_2 = w[0, 2]
    out1 = out[1]
    w1_0 = w[1, 0]
    w1_1 = w[1, 1]
    w1_2 = w[1, 2]
    w1_3 = w[1, 3]
    w1_4 = w[1, 4]
    w1_5 = w[1, 5]
    for x in range(width):
        t0 = w0_0 - w0_0
        t1 = w1_0 - w1_0
        o = r0_p0[x]
        t0 = t0 + w0_0 * o
        t1 = t1 + w1_0 * o
        o = ((r0_m1[x] + r0_p1[x]) + r1_p0[x])
        t0 = t0 + w0_1 * o
        t1 = t1 + w1_1 * o
        o = (r1_m1[x] + r1_p1[x])
        t0 = t0 + w0_2 * o
        t1 = t1 + w1_2 * o
        o = ((r0_m2[x] + r0_p2[x]) + r2_p0[x])
        t1 = t1 + w1_3 * o
        o = ((r1_m2[x] + r1_p2[x]) + (r2_m1[x] + r2_p1[x]))
        t1 = t1 + w1_4 * o
        o = (r2_m2[x] + r2_p2[x])
        t1 = t1 + w1_5 * o
        out0[x] = t0
        out1[x] = t1


@njit(inline="always", cache=True)
def ladder_sum_3(pairs, pr, ring, w, width, out):
    r0_m3 = pairs[0, (pr - 3) % ring]
    r0_m2 = pairs[0, (pr - 2) % ring]
    r0_m1 = pairs[0, (pr - 1) % ring]
    r0_p0 = pairs[0, (pr + 0) % ring]
    r0_p1 = pairs[0, (pr + 1) % ring]
    r0_p2 = pairs[0, (pr + 2) % ring]
    r0_p3 = pairs[0, (pr + 3) % ring]
    r1_m3 = pairs[1, (pr - 3) % ring]
    r1_m2 = pairs[1, (pr - 2) % ring]
    r1_m1 = pairs[1, (pr - 1) % ring]
    r1_p0 = pairs[1, (pr + 0) % ring]
    r1_p1 = pairs[1, (pr + 1) % ring]
    r1_p2 = pairs[1, (pr + 2) % ring]
    r1_p3 = pairs[1, (pr + 3) % ring]
    r2_m3 = pairs[2, (pr - 3) % ring]
    r2_m2 = pairs[2, (pr - 2) % ring]
    r2_m1 = pairs[2, (pr - 1) % ring]
    r2_p0 = pairs[2, (pr + 0) % ring]
    r2_p1 = pairs[2, (pr + 1) % ring]
    r2_p2 = pairs[2, (pr + 2) % ring]
    r2_p3 = pairs[2, (pr + 3) % ring]
    r3_m3 = pairs[3, (pr - 3) % ring]
    r3_m2 = pairs[3, (pr - 2) % ring]
    r3_m1 = pairs[3, (pr - 1) % ring]
    r3_p0 = pairs[3, (pr + 0) % ring]
    r3_p1 = pairs[3, (pr + 1) % ring]
    r3_p2 = pairs[3, (pr + 2) % ring]
    r3_p3 = pairs[3, (pr + 3) % ring]
    out0 = out[0]
    w0_0 = w[0, 0]
    w0_1 = w[0, 1]
    w0_2 = w[0, 2]
    out1 = out[1]
    w1_0 = w[1, 0]
    w1_1 = w[1, 1]
    w1_2 = w[1, 2]
    w1_3 = w[1, 3]
    w1_4 = w[1, 4]
    w1_5 = w[1, 5]
    out2 = out[2]
    w2_0 = w[2, 0]
    w2_1 = w[2, 1]
    w2_2 = w[2, 2]
    w2_3 = w[2, 3]
    w2_4 = w[2, 4]
    w2_5 = w[2, 5]
    w2_6 = w[2, 6]
    w2_7 = w[2, 7]
    w2_8 = w[2, 8]
    w2_9 = w[2, 9]
    for x in range(width):
        t0 = w0_0 - w0_0
        t1 = w1_0 - w1_0
        t2 = w2_0 - w2_0
        o = r0_p0[x]
        t0 = t0 + w0_0 * o
        t1 = t1 + w1_0 * o
        t2 = t2 + w2_0 * o
        o = ((r0_m1[x] + r0_p1[x]) + r1_p0[x])
        t0 = t0 + w0_1 * o
        t1 = t1 + w1_1 * o
        t2 = t2 + w2_1 * o
        o = (r1_m1[x] + r1_p1[x])
        t0 = t0 + w0_2 * o
        t1 = t1 + w1_2 * o
        t2 = t2 + w2_2 * o
        o = ((r0_m2[x] + r0_p2[x]) + r2_p0[x])
        t1 = t1 + w1_3 * o
        t2 = t2 + w2_3 * o
        o = ((r1_m2[x] + r1_p2[x]) + (r2_m1[x] + r2_p1[x]))
        t1 = t1 + w1_4 * o
        t2 = t2 + w2_4 * o
        o = (r2_m2[x] + r2_p2[x])
        t1 = t1 + w1_5 * o
        t2 = t2 + w2_5 * o
        o = ((r0_m3[x] + r0_p3[x]) + r3_p0[x])
        t2 = t2 + w2_6 * o
        o = ((r1_m3[x] + r1_p3[x]) + (r3_m1[x] + r3_p1[x]))
        t2 = t2 + w2_7 * o
        o = ((r2_m3[x] + r2_p3[x]) + (r3_m2[x] + r3_p2[x]))
        t2 = t2 + w2_8 * o
        o = (r3_m3[x] + r3_p3[x])
        t2 = t2 + w2_9 * o
        out0[x] = t0
        out1[x] = t1
        out2[x] = t2


@njit(inline="always", cache=True)
def ladder_sum_4(pairs, pr, ring, w, width, out):
    r0_m4 = pairs[0, (pr - 4) % ring]
    r0_m3 = pairs[0, (pr - 3) % ring]
    r0_m2 = pairs[0, (pr - 2) % ring]
    r0_m1 = pairs[0, (pr - 1) % ring]
    r0_p0 = pairs[0, (pr + 0) % ring]
    r0_p1 = pairs[0, (pr + 1) % ring]
    r0_p2 = pairs[0, (pr + 2) % ring]
    r0_p3 = pairs[0, (pr + 3) % ring]
    r0_p4 = pairs[0, (pr + 4) % ring]
    r1_m4 = pairs[1, (pr - 4) % ring]
    r1_m3 = pairs[1, (pr - 3) % ring]
    r1_m2 = pairs[1, (pr - 2) % ring]
    r1_m1 = pairs[1, (pr - 1) % ring]
    r1_p0 = pairs[1, (pr + 0) % ring]
    r1_p1 = pairs[1, (pr + 1) % ring]
    r1_p2 = pairs[1, (pr + 2) % ring]
    r1_p3 = pairs[1, (pr + 3) % ring]
    r1_p4 = pairs[1, (pr + 4) % ring]
    r2_m4 = pairs[2, (pr - 4) % ring]
    r2_m3 = pairs[2, (pr - 3) % ring]
    r2_m2 = pairs[2, (pr - 2) % ring]
    r2_m1 = pairs[2, (pr - 1) % ring]
    r2_p0 = pairs[2, (pr + 0) % ring]
    r2_p1 = pairs[2, (pr + 1) % ring]
    r2_p2 = pairs[2, (pr + 2) % ring]
    r2_p3 = pairs[2, (pr + 3) % ring]
    r2_p4 = pairs[2, (pr + 4) % ring]
    r3_m4 = pairs[3, (pr - 4) % ring]
    r3_m3 = pairs[3, (pr - 3) % ring]
    r3_m2 = pairs[3, (pr - 2) % ring]
    r3_m1 = pairs[3, (pr - 1) % ring]
    r3_p0 = pairs[3, (pr + 0) % ring]
    r3_p1 = pairs[3, (pr + 1) % ring]
    r3_p2 = pairs[3, (pr + 2) % ring]
    r3_p3 = pairs[3, (pr + 3) % ring]
    r3_p4 = pairs[3, (pr + 4) % ring]
    r4_m4 = pairs[4, (pr - 4) % ring]
    r4_m3 = pairs[4, (pr - 3) % ring]
    r4_m2 = pairs[4, (pr - 2) % ring]
    r4_m1 = pairs[4, (pr - 1) % ring]
    r4_p0 = pairs[4, (pr + 0) % ring]
    r4_p1 = pairs[4, (pr + 1) % ring]
    r4_p2 = pairs[4, (pr + 2) % ring]
    r4_p3 = pairs[4, (pr + 3) % ring]
    r4_p4 = pairs[4, (pr + 4) % ring]
    out0 = out[0]
    w0_0 = w[0, 0]
    w0_1 = w[0, 1]
    w0_2 = w[0, 2]
    out1 = out[1]
    w1_0 = w[1, 0]
    w1_1 = w[1, 1]
    w1_2 = w[1, 2]
    w1_3 = w[1, 3]
    w1_4 = w[1, 4]
    w1_5 = w[1, 5]
    out2 = out[2]
    w2_0 = w[2, 0]
    w2_1 = w[2, 1]
    w2_2 = w[2, 2]
    w2_3 = w[2, 3]
    w2_4 = w[2, 4]
    w2_5 = w[2, 5]
    w2_6 = w[2, 6]
    w2_7 = w[2, 7]
    w2_8 = w[2, 8]
    w2_9 = w[2, 9]
    out3 = out[3]
    w3_0 = w[3, 0]
    w3_1 = w[3, 1]
    w3_2 = w[3, 2]
    w3_3 = w[3, 3]
    w3_4 = w[3, 4]
    w3_5 = w[3, 5]
    w3_6 = w[3, 6]
    w3_7 = w[3, 7]
    w3_8 = w[3, 8]
    w3_9 = w[3, 9]
    w3_10 = w[3, 10]
    w3_11 = w[3, 11]
    w3_12 = w[3, 12]
    w3_13 = w[3, 13]
    w3_14 = w[3, 14]
    for x in range(width):
        t0 = w0_0 - w0_0
        t1 = w1_0 - w1_0
        t2 = w2_0 - w2_0
        t3 = w3_0 - w3_0
        o = r0_p0[x]
        t0 = t0 + w0_0 * o
        t1 = t1 + w1_0 * o
        t2 = t2 + w2_0 * o
        t3 = t3 + w3_0 * o
        o = ((r0_m1[x] + r0_p1[x]) + r1_p0[x])
        t0 = t0 + w0_1 * o
        t1 = t1 + w1_1 * o
        t2 = t2 + w2_1 * o
        t3 = t3 + w3_1 * o
        o = (r1_m1[x] + r1_p1[x])
        t0 = t0 + w0_2 * o
        t1 = t1 + w1_2 * o
        t2 = t2 + w2_2 * o
        t3 = t3 + w3_2 * o
        o = ((r0_m2[x] + r0_p2[x]) + r2_p0[x])
        t1 = t1 + w1_3 * o
        t2 = t2 + w2_3 * o
        t3 = t3 + w3_3 * o
        o = ((r1_m2[x] + r1_p2[x]) + (r2_m1[x] + r2_p1[x]))
        t1 = t1 + w1_4 * o
        t2 = t2 + w2_4 * o
        t3 = t3 + w3_4 * o
        o = (r2_m2[x] + r2_p2[x])
        t1 = t1 + w1_5 * o
        t2 = t2 + w2_5 * o
        t3 = t3 + w3_5 * o
        o = ((r0_m3[x] + r0_p3[x]) + r3_p0[x])
        t2 = t2 + w2_6 * o
        t3 = t3 + w3_6 * o
        o = ((r1_m3[x] + r1_p3[x]) + (r3_m1[x] + r3_p1[x]))
        t2 = t2 + w2_7 * o
        t3 = t3 + w3_7 * o
        o = ((r2_m3[x] + r2_p3[x]) + (r3_m2[x] + r3_p2[x]))
        t2 = t2 + w2_8 * o
        t3 = t3 + w3_8 * o
        o = (r3_m3[x] + r3_p3[x])
        t2 = t2 + w2_9 * o
        t3 = t3 + w3_9 * o
        o = ((r0_m4[x] + r0_p4[x]) + r4_p0[x])
        t3 = t3 + w3_10 * o
        o = ((r1_m4[x] + r1_p4[x]) + (r4_m1[x] + r4_p1[x]))
        t3 = t3 + w3_11 * o
        o = ((r2_m4[x] + r2_p4[x]) + (r4_m2[x] + r4_p2[x]))
        t3 = t3 + w3_12 * o
        o = ((r3_m4[x] + r3_p4[x]) + (r4_m3[x] + r4_p3[x]))
        t3 = t3 + w3_13 * o
        o = (r4_m4[x] + r4_p4[x])
        t3 = t3 + w3_14 * o
        out0[x] = t0
        out1[x] = t1
        out2[x] = t2
        out3[x] = t3
