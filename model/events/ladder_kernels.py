"""Ladder sums and event rule, one loop (scripts/gen_orbit_kernels.py wrote it).

``ladder_events_S(pairs, pr, ring, w, width, thr, ref, ev, y)``: every scale's receptive
sum of padded row ``pr`` exactly as
:func:`rvsm.model.sampling.orbit_kernels.ladder_sum_S` forms it (rows modulo ``ring``,
the same operations in the same order), then, in the same loop, the event rule
(:func:`.event_rule.event_step`) on row ``y`` of every scale: thresholds and references
``thr, ref (S, H, W)``, events ``ev (S, H, W) int8``. The responses stay in registers (no
row of responses is stored and read back); the loop reads 45 + 8 rows and writes 8 for
four scales, so it vectorises only with the vectoriser's runtime alias-check limit raised
(:func:`rvsm.model.infra.simd.allow_alias_checks`, raised here). They are compiled as
functions of their own, not inlined: four inlined loops made the fused kernel 10 %
slower.
"""

from numba import njit

from rvsm.model.events.event_rule import event_step
from rvsm.model.infra.simd import allow_alias_checks

# The four-scale loop reads 53 rows and writes 8: up to 424 runtime alias checks.
allow_alias_checks(1024)


@njit(cache=True)
def ladder_events_1(pairs, pr, ring, w, width, thr, ref, ev, y):
    r0_m1 = pairs[0, (pr - 1) % ring]
    r0_p0 = pairs[0, (pr + 0) % ring]
    r0_p1 = pairs[0, (pr + 1) % ring]
    r1_m1 = pairs[1, (pr - 1) % ring]
    r1_p0 = pairs[1, (pr + 0) % ring]
    r1_p1 = pairs[1, (pr + 1) % ring]
    th0 = thr[0, y]
    rf0 = ref[0, y]
    ev0 = ev[0, y]
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
        event_step(t0, th0, rf0, ev0, x)


@njit(cache=True)
def ladder_events_2(pairs, pr, ring, w, width, thr, ref, ev, y):
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
    th0 = thr[0, y]
    rf0 = ref[0, y]
    ev0 = ev[0, y]
    w0_0 = w[0, 0]
    w0_1 = w[0, 1]
    w0_2 = w[0, 2]
    th1 = thr[1, y]
    rf1 = ref[1, y]
    ev1 = ev[1, y]
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
        event_step(t0, th0, rf0, ev0, x)
        event_step(t1, th1, rf1, ev1, x)


@njit(cache=True)
def ladder_events_3(pairs, pr, ring, w, width, thr, ref, ev, y):
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
    th0 = thr[0, y]
    rf0 = ref[0, y]
    ev0 = ev[0, y]
    w0_0 = w[0, 0]
    w0_1 = w[0, 1]
    w0_2 = w[0, 2]
    th1 = thr[1, y]
    rf1 = ref[1, y]
    ev1 = ev[1, y]
    w1_0 = w[1, 0]
    w1_1 = w[1, 1]
    w1_2 = w[1, 2]
    w1_3 = w[1, 3]
    w1_4 = w[1, 4]
    w1_5 = w[1, 5]
    th2 = thr[2, y]
    rf2 = ref[2, y]
    ev2 = ev[2, y]
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
        event_step(t0, th0, rf0, ev0, x)
        event_step(t1, th1, rf1, ev1, x)
        event_step(t2, th2, rf2, ev2, x)


@njit(cache=True)
def ladder_events_4(pairs, pr, ring, w, width, thr, ref, ev, y):
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
    th0 = thr[0, y]
    rf0 = ref[0, y]
    ev0 = ev[0, y]
    w0_0 = w[0, 0]
    w0_1 = w[0, 1]
    w0_2 = w[0, 2]
    th1 = thr[1, y]
    rf1 = ref[1, y]
    ev1 = ev[1, y]
    w1_0 = w[1, 0]
    w1_1 = w[1, 1]
    w1_2 = w[1, 2]
    w1_3 = w[1, 3]
    w1_4 = w[1, 4]
    w1_5 = w[1, 5]
    th2 = thr[2, y]
    rf2 = ref[2, y]
    ev2 = ev[2, y]
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
    th3 = thr[3, y]
    rf3 = ref[3, y]
    ev3 = ev[3, y]
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
        event_step(t0, th0, rf0, ev0, x)
        event_step(t1, th1, rf1, ev1, x)
        event_step(t2, th2, rf2, ev2, x)
        event_step(t3, th3, rf3, ev3, x)
