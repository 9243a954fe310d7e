"""Ladder sums and event rule, one loop (written by python -m
rvsm.model.sampling.kernel_generator; do not edit).

``ladder_events_S(pairs, pr, ring, w, width, thr, ref, ev, y)``: every scale's receptive
sum of padded row ``pr`` exactly as
:func:`rvsm.model.sampling.orbit_kernels.ladder_sum_S` forms it (rows of ``pairs (L + 1,
R, W)`` taken modulo ``ring``, the same operations in the same order), then, in the same
loop, the event rule (:func:`.event_rule.event_step_at`) on row ``y`` of every scale:
thresholds and references ``thr, ref (S, H, W)``, events ``ev (S, H, W) int8``. The
responses stay in registers (no row of responses is stored and read back).
``ladder_events_S_2``: the same for rows ``y`` and ``y + 1`` (padded rows ``pr`` and
``pr + 1``) in one pass; the two windows share ``2S`` of their ``2S + 2`` rows, so each
loaded vector serves both rows' sums; each pixel's sums are formed exactly as by
``ladder_events_S``.

The loops index their arguments directly (no row views: a view costs numba two reference
count calls, about 100 a call for 45 rows) and are compiled with numba's ``noalias`` flag
(:class:`rvsm.model.infra.noalias.NoAliasCompiler`): LLVM vectorises them without runtime
alias checks, so the arguments must be distinct arrays. Compiled as functions of their
own, not inlined into the fused kernel (``noalias`` holds at a function's boundary).
"""

from numba import njit

from rvsm.model.events.event_rule import event_step_at
from rvsm.model.infra.noalias import NoAliasCompiler


@njit(cache=True, pipeline_class=NoAliasCompiler)
def ladder_events_1(pairs, pr, ring, w, width, thr, ref, ev, y):
    km1 = (pr - 1) % ring
    kp0 = (pr + 0) % ring
    kp1 = (pr + 1) % ring
    w0_0 = w[0, 0]
    w0_1 = w[0, 1]
    w0_2 = w[0, 2]
    for x in range(width):
        t0_0 = w0_0 - w0_0
        o = pairs[0, kp0, x]
        t0_0 = t0_0 + w0_0 * o
        o = ((pairs[0, km1, x] + pairs[0, kp1, x]) + pairs[1, kp0, x])
        t0_0 = t0_0 + w0_1 * o
        o = (pairs[1, km1, x] + pairs[1, kp1, x])
        t0_0 = t0_0 + w0_2 * o
        event_step_at(t0_0, thr, ref, ev, 0, y, x)


@njit(cache=True, pipeline_class=NoAliasCompiler)
def ladder_events_2(pairs, pr, ring, w, width, thr, ref, ev, y):
    km2 = (pr - 2) % ring
    km1 = (pr - 1) % ring
    kp0 = (pr + 0) % ring
    kp1 = (pr + 1) % ring
    kp2 = (pr + 2) % ring
    w0_0 = w[0, 0]
    w0_1 = w[0, 1]
    w0_2 = w[0, 2]
    w1_0 = w[1, 0]
    w1_1 = w[1, 1]
    w1_2 = w[1, 2]
    w1_3 = w[1, 3]
    w1_4 = w[1, 4]
    w1_5 = w[1, 5]
    for x in range(width):
        t0_0 = w0_0 - w0_0
        t0_1 = w1_0 - w1_0
        o = pairs[0, kp0, x]
        t0_0 = t0_0 + w0_0 * o
        t0_1 = t0_1 + w1_0 * o
        o = ((pairs[0, km1, x] + pairs[0, kp1, x]) + pairs[1, kp0, x])
        t0_0 = t0_0 + w0_1 * o
        t0_1 = t0_1 + w1_1 * o
        o = (pairs[1, km1, x] + pairs[1, kp1, x])
        t0_0 = t0_0 + w0_2 * o
        t0_1 = t0_1 + w1_2 * o
        o = ((pairs[0, km2, x] + pairs[0, kp2, x]) + pairs[2, kp0, x])
        t0_1 = t0_1 + w1_3 * o
        o = ((pairs[1, km2, x] + pairs[1, kp2, x]) + (pairs[2, km1, x] + pairs[2, kp1, x]))
        t0_1 = t0_1 + w1_4 * o
        o = (pairs[2, km2, x] + pairs[2, kp2, x])
        t0_1 = t0_1 + w1_5 * o
        event_step_at(t0_0, thr, ref, ev, 0, y, x)
        event_step_at(t0_1, thr, ref, ev, 1, y, x)


@njit(cache=True, pipeline_class=NoAliasCompiler)
def ladder_events_3(pairs, pr, ring, w, width, thr, ref, ev, y):
    km3 = (pr - 3) % ring
    km2 = (pr - 2) % ring
    km1 = (pr - 1) % ring
    kp0 = (pr + 0) % ring
    kp1 = (pr + 1) % ring
    kp2 = (pr + 2) % ring
    kp3 = (pr + 3) % ring
    w0_0 = w[0, 0]
    w0_1 = w[0, 1]
    w0_2 = w[0, 2]
    w1_0 = w[1, 0]
    w1_1 = w[1, 1]
    w1_2 = w[1, 2]
    w1_3 = w[1, 3]
    w1_4 = w[1, 4]
    w1_5 = w[1, 5]
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
        t0_0 = w0_0 - w0_0
        t0_1 = w1_0 - w1_0
        t0_2 = w2_0 - w2_0
        o = pairs[0, kp0, x]
        t0_0 = t0_0 + w0_0 * o
        t0_1 = t0_1 + w1_0 * o
        t0_2 = t0_2 + w2_0 * o
        o = ((pairs[0, km1, x] + pairs[0, kp1, x]) + pairs[1, kp0, x])
        t0_0 = t0_0 + w0_1 * o
        t0_1 = t0_1 + w1_1 * o
        t0_2 = t0_2 + w2_1 * o
        o = (pairs[1, km1, x] + pairs[1, kp1, x])
        t0_0 = t0_0 + w0_2 * o
        t0_1 = t0_1 + w1_2 * o
        t0_2 = t0_2 + w2_2 * o
        o = ((pairs[0, km2, x] + pairs[0, kp2, x]) + pairs[2, kp0, x])
        t0_1 = t0_1 + w1_3 * o
        t0_2 = t0_2 + w2_3 * o
        o = ((pairs[1, km2, x] + pairs[1, kp2, x]) + (pairs[2, km1, x] + pairs[2, kp1, x]))
        t0_1 = t0_1 + w1_4 * o
        t0_2 = t0_2 + w2_4 * o
        o = (pairs[2, km2, x] + pairs[2, kp2, x])
        t0_1 = t0_1 + w1_5 * o
        t0_2 = t0_2 + w2_5 * o
        o = ((pairs[0, km3, x] + pairs[0, kp3, x]) + pairs[3, kp0, x])
        t0_2 = t0_2 + w2_6 * o
        o = ((pairs[1, km3, x] + pairs[1, kp3, x]) + (pairs[3, km1, x] + pairs[3, kp1, x]))
        t0_2 = t0_2 + w2_7 * o
        o = ((pairs[2, km3, x] + pairs[2, kp3, x]) + (pairs[3, km2, x] + pairs[3, kp2, x]))
        t0_2 = t0_2 + w2_8 * o
        o = (pairs[3, km3, x] + pairs[3, kp3, x])
        t0_2 = t0_2 + w2_9 * o
        event_step_at(t0_0, thr, ref, ev, 0, y, x)
        event_step_at(t0_1, thr, ref, ev, 1, y, x)
        event_step_at(t0_2, thr, ref, ev, 2, y, x)


@njit(cache=True, pipeline_class=NoAliasCompiler)
def ladder_events_4(pairs, pr, ring, w, width, thr, ref, ev, y):
    km4 = (pr - 4) % ring
    km3 = (pr - 3) % ring
    km2 = (pr - 2) % ring
    km1 = (pr - 1) % ring
    kp0 = (pr + 0) % ring
    kp1 = (pr + 1) % ring
    kp2 = (pr + 2) % ring
    kp3 = (pr + 3) % ring
    kp4 = (pr + 4) % ring
    w0_0 = w[0, 0]
    w0_1 = w[0, 1]
    w0_2 = w[0, 2]
    w1_0 = w[1, 0]
    w1_1 = w[1, 1]
    w1_2 = w[1, 2]
    w1_3 = w[1, 3]
    w1_4 = w[1, 4]
    w1_5 = w[1, 5]
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
        t0_0 = w0_0 - w0_0
        t0_1 = w1_0 - w1_0
        t0_2 = w2_0 - w2_0
        t0_3 = w3_0 - w3_0
        o = pairs[0, kp0, x]
        t0_0 = t0_0 + w0_0 * o
        t0_1 = t0_1 + w1_0 * o
        t0_2 = t0_2 + w2_0 * o
        t0_3 = t0_3 + w3_0 * o
        o = ((pairs[0, km1, x] + pairs[0, kp1, x]) + pairs[1, kp0, x])
        t0_0 = t0_0 + w0_1 * o
        t0_1 = t0_1 + w1_1 * o
        t0_2 = t0_2 + w2_1 * o
        t0_3 = t0_3 + w3_1 * o
        o = (pairs[1, km1, x] + pairs[1, kp1, x])
        t0_0 = t0_0 + w0_2 * o
        t0_1 = t0_1 + w1_2 * o
        t0_2 = t0_2 + w2_2 * o
        t0_3 = t0_3 + w3_2 * o
        o = ((pairs[0, km2, x] + pairs[0, kp2, x]) + pairs[2, kp0, x])
        t0_1 = t0_1 + w1_3 * o
        t0_2 = t0_2 + w2_3 * o
        t0_3 = t0_3 + w3_3 * o
        o = ((pairs[1, km2, x] + pairs[1, kp2, x]) + (pairs[2, km1, x] + pairs[2, kp1, x]))
        t0_1 = t0_1 + w1_4 * o
        t0_2 = t0_2 + w2_4 * o
        t0_3 = t0_3 + w3_4 * o
        o = (pairs[2, km2, x] + pairs[2, kp2, x])
        t0_1 = t0_1 + w1_5 * o
        t0_2 = t0_2 + w2_5 * o
        t0_3 = t0_3 + w3_5 * o
        o = ((pairs[0, km3, x] + pairs[0, kp3, x]) + pairs[3, kp0, x])
        t0_2 = t0_2 + w2_6 * o
        t0_3 = t0_3 + w3_6 * o
        o = ((pairs[1, km3, x] + pairs[1, kp3, x]) + (pairs[3, km1, x] + pairs[3, kp1, x]))
        t0_2 = t0_2 + w2_7 * o
        t0_3 = t0_3 + w3_7 * o
        o = ((pairs[2, km3, x] + pairs[2, kp3, x]) + (pairs[3, km2, x] + pairs[3, kp2, x]))
        t0_2 = t0_2 + w2_8 * o
        t0_3 = t0_3 + w3_8 * o
        o = (pairs[3, km3, x] + pairs[3, kp3, x])
        t0_2 = t0_2 + w2_9 * o
        t0_3 = t0_3 + w3_9 * o
        o = ((pairs[0, km4, x] + pairs[0, kp4, x]) + pairs[4, kp0, x])
        t0_3 = t0_3 + w3_10 * o
        o = ((pairs[1, km4, x] + pairs[1, kp4, x]) + (pairs[4, km1, x] + pairs[4, kp1, x]))
        t0_3 = t0_3 + w3_11 * o
        o = ((pairs[2, km4, x] + pairs[2, kp4, x]) + (pairs[4, km2, x] + pairs[4, kp2, x]))
        t0_3 = t0_3 + w3_12 * o
        o = ((pairs[3, km4, x] + pairs[3, kp4, x]) + (pairs[4, km3, x] + pairs[4, kp3, x]))
        t0_3 = t0_3 + w3_13 * o
        o = (pairs[4, km4, x] + pairs[4, kp4, x])
        t0_3 = t0_3 + w3_14 * o
        event_step_at(t0_0, thr, ref, ev, 0, y, x)
        event_step_at(t0_1, thr, ref, ev, 1, y, x)
        event_step_at(t0_2, thr, ref, ev, 2, y, x)
        event_step_at(t0_3, thr, ref, ev, 3, y, x)


@njit(cache=True, pipeline_class=NoAliasCompiler)
def ladder_events_1_2(pairs, pr, ring, w, width, thr, ref, ev, y):
    km1 = (pr - 1) % ring
    kp0 = (pr + 0) % ring
    kp1 = (pr + 1) % ring
    kp2 = (pr + 2) % ring
    w0_0 = w[0, 0]
    w0_1 = w[0, 1]
    w0_2 = w[0, 2]
    for x in range(width):
        t0_0 = w0_0 - w0_0
        t1_0 = w0_0 - w0_0
        o = pairs[0, kp0, x]
        t0_0 = t0_0 + w0_0 * o
        o = pairs[0, kp1, x]
        t1_0 = t1_0 + w0_0 * o
        o = ((pairs[0, km1, x] + pairs[0, kp1, x]) + pairs[1, kp0, x])
        t0_0 = t0_0 + w0_1 * o
        o = ((pairs[0, kp0, x] + pairs[0, kp2, x]) + pairs[1, kp1, x])
        t1_0 = t1_0 + w0_1 * o
        o = (pairs[1, km1, x] + pairs[1, kp1, x])
        t0_0 = t0_0 + w0_2 * o
        o = (pairs[1, kp0, x] + pairs[1, kp2, x])
        t1_0 = t1_0 + w0_2 * o
        event_step_at(t0_0, thr, ref, ev, 0, y, x)
        event_step_at(t1_0, thr, ref, ev, 0, y + 1, x)


@njit(cache=True, pipeline_class=NoAliasCompiler)
def ladder_events_2_2(pairs, pr, ring, w, width, thr, ref, ev, y):
    km2 = (pr - 2) % ring
    km1 = (pr - 1) % ring
    kp0 = (pr + 0) % ring
    kp1 = (pr + 1) % ring
    kp2 = (pr + 2) % ring
    kp3 = (pr + 3) % ring
    w0_0 = w[0, 0]
    w0_1 = w[0, 1]
    w0_2 = w[0, 2]
    w1_0 = w[1, 0]
    w1_1 = w[1, 1]
    w1_2 = w[1, 2]
    w1_3 = w[1, 3]
    w1_4 = w[1, 4]
    w1_5 = w[1, 5]
    for x in range(width):
        t0_0 = w0_0 - w0_0
        t0_1 = w1_0 - w1_0
        t1_0 = w0_0 - w0_0
        t1_1 = w1_0 - w1_0
        o = pairs[0, kp0, x]
        t0_0 = t0_0 + w0_0 * o
        t0_1 = t0_1 + w1_0 * o
        o = pairs[0, kp1, x]
        t1_0 = t1_0 + w0_0 * o
        t1_1 = t1_1 + w1_0 * o
        o = ((pairs[0, km1, x] + pairs[0, kp1, x]) + pairs[1, kp0, x])
        t0_0 = t0_0 + w0_1 * o
        t0_1 = t0_1 + w1_1 * o
        o = ((pairs[0, kp0, x] + pairs[0, kp2, x]) + pairs[1, kp1, x])
        t1_0 = t1_0 + w0_1 * o
        t1_1 = t1_1 + w1_1 * o
        o = (pairs[1, km1, x] + pairs[1, kp1, x])
        t0_0 = t0_0 + w0_2 * o
        t0_1 = t0_1 + w1_2 * o
        o = (pairs[1, kp0, x] + pairs[1, kp2, x])
        t1_0 = t1_0 + w0_2 * o
        t1_1 = t1_1 + w1_2 * o
        o = ((pairs[0, km2, x] + pairs[0, kp2, x]) + pairs[2, kp0, x])
        t0_1 = t0_1 + w1_3 * o
        o = ((pairs[0, km1, x] + pairs[0, kp3, x]) + pairs[2, kp1, x])
        t1_1 = t1_1 + w1_3 * o
        o = ((pairs[1, km2, x] + pairs[1, kp2, x]) + (pairs[2, km1, x] + pairs[2, kp1, x]))
        t0_1 = t0_1 + w1_4 * o
        o = ((pairs[1, km1, x] + pairs[1, kp3, x]) + (pairs[2, kp0, x] + pairs[2, kp2, x]))
        t1_1 = t1_1 + w1_4 * o
        o = (pairs[2, km2, x] + pairs[2, kp2, x])
        t0_1 = t0_1 + w1_5 * o
        o = (pairs[2, km1, x] + pairs[2, kp3, x])
        t1_1 = t1_1 + w1_5 * o
        event_step_at(t0_0, thr, ref, ev, 0, y, x)
        event_step_at(t0_1, thr, ref, ev, 1, y, x)
        event_step_at(t1_0, thr, ref, ev, 0, y + 1, x)
        event_step_at(t1_1, thr, ref, ev, 1, y + 1, x)


@njit(cache=True, pipeline_class=NoAliasCompiler)
def ladder_events_3_2(pairs, pr, ring, w, width, thr, ref, ev, y):
    km3 = (pr - 3) % ring
    km2 = (pr - 2) % ring
    km1 = (pr - 1) % ring
    kp0 = (pr + 0) % ring
    kp1 = (pr + 1) % ring
    kp2 = (pr + 2) % ring
    kp3 = (pr + 3) % ring
    kp4 = (pr + 4) % ring
    w0_0 = w[0, 0]
    w0_1 = w[0, 1]
    w0_2 = w[0, 2]
    w1_0 = w[1, 0]
    w1_1 = w[1, 1]
    w1_2 = w[1, 2]
    w1_3 = w[1, 3]
    w1_4 = w[1, 4]
    w1_5 = w[1, 5]
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
        t0_0 = w0_0 - w0_0
        t0_1 = w1_0 - w1_0
        t0_2 = w2_0 - w2_0
        t1_0 = w0_0 - w0_0
        t1_1 = w1_0 - w1_0
        t1_2 = w2_0 - w2_0
        o = pairs[0, kp0, x]
        t0_0 = t0_0 + w0_0 * o
        t0_1 = t0_1 + w1_0 * o
        t0_2 = t0_2 + w2_0 * o
        o = pairs[0, kp1, x]
        t1_0 = t1_0 + w0_0 * o
        t1_1 = t1_1 + w1_0 * o
        t1_2 = t1_2 + w2_0 * o
        o = ((pairs[0, km1, x] + pairs[0, kp1, x]) + pairs[1, kp0, x])
        t0_0 = t0_0 + w0_1 * o
        t0_1 = t0_1 + w1_1 * o
        t0_2 = t0_2 + w2_1 * o
        o = ((pairs[0, kp0, x] + pairs[0, kp2, x]) + pairs[1, kp1, x])
        t1_0 = t1_0 + w0_1 * o
        t1_1 = t1_1 + w1_1 * o
        t1_2 = t1_2 + w2_1 * o
        o = (pairs[1, km1, x] + pairs[1, kp1, x])
        t0_0 = t0_0 + w0_2 * o
        t0_1 = t0_1 + w1_2 * o
        t0_2 = t0_2 + w2_2 * o
        o = (pairs[1, kp0, x] + pairs[1, kp2, x])
        t1_0 = t1_0 + w0_2 * o
        t1_1 = t1_1 + w1_2 * o
        t1_2 = t1_2 + w2_2 * o
        o = ((pairs[0, km2, x] + pairs[0, kp2, x]) + pairs[2, kp0, x])
        t0_1 = t0_1 + w1_3 * o
        t0_2 = t0_2 + w2_3 * o
        o = ((pairs[0, km1, x] + pairs[0, kp3, x]) + pairs[2, kp1, x])
        t1_1 = t1_1 + w1_3 * o
        t1_2 = t1_2 + w2_3 * o
        o = ((pairs[1, km2, x] + pairs[1, kp2, x]) + (pairs[2, km1, x] + pairs[2, kp1, x]))
        t0_1 = t0_1 + w1_4 * o
        t0_2 = t0_2 + w2_4 * o
        o = ((pairs[1, km1, x] + pairs[1, kp3, x]) + (pairs[2, kp0, x] + pairs[2, kp2, x]))
        t1_1 = t1_1 + w1_4 * o
        t1_2 = t1_2 + w2_4 * o
        o = (pairs[2, km2, x] + pairs[2, kp2, x])
        t0_1 = t0_1 + w1_5 * o
        t0_2 = t0_2 + w2_5 * o
        o = (pairs[2, km1, x] + pairs[2, kp3, x])
        t1_1 = t1_1 + w1_5 * o
        t1_2 = t1_2 + w2_5 * o
        o = ((pairs[0, km3, x] + pairs[0, kp3, x]) + pairs[3, kp0, x])
        t0_2 = t0_2 + w2_6 * o
        o = ((pairs[0, km2, x] + pairs[0, kp4, x]) + pairs[3, kp1, x])
        t1_2 = t1_2 + w2_6 * o
        o = ((pairs[1, km3, x] + pairs[1, kp3, x]) + (pairs[3, km1, x] + pairs[3, kp1, x]))
        t0_2 = t0_2 + w2_7 * o
        o = ((pairs[1, km2, x] + pairs[1, kp4, x]) + (pairs[3, kp0, x] + pairs[3, kp2, x]))
        t1_2 = t1_2 + w2_7 * o
        o = ((pairs[2, km3, x] + pairs[2, kp3, x]) + (pairs[3, km2, x] + pairs[3, kp2, x]))
        t0_2 = t0_2 + w2_8 * o
        o = ((pairs[2, km2, x] + pairs[2, kp4, x]) + (pairs[3, km1, x] + pairs[3, kp3, x]))
        t1_2 = t1_2 + w2_8 * o
        o = (pairs[3, km3, x] + pairs[3, kp3, x])
        t0_2 = t0_2 + w2_9 * o
        o = (pairs[3, km2, x] + pairs[3, kp4, x])
        t1_2 = t1_2 + w2_9 * o
        event_step_at(t0_0, thr, ref, ev, 0, y, x)
        event_step_at(t0_1, thr, ref, ev, 1, y, x)
        event_step_at(t0_2, thr, ref, ev, 2, y, x)
        event_step_at(t1_0, thr, ref, ev, 0, y + 1, x)
        event_step_at(t1_1, thr, ref, ev, 1, y + 1, x)
        event_step_at(t1_2, thr, ref, ev, 2, y + 1, x)


@njit(cache=True, pipeline_class=NoAliasCompiler)
def ladder_events_4_2(pairs, pr, ring, w, width, thr, ref, ev, y):
    km4 = (pr - 4) % ring
    km3 = (pr - 3) % ring
    km2 = (pr - 2) % ring
    km1 = (pr - 1) % ring
    kp0 = (pr + 0) % ring
    kp1 = (pr + 1) % ring
    kp2 = (pr + 2) % ring
    kp3 = (pr + 3) % ring
    kp4 = (pr + 4) % ring
    kp5 = (pr + 5) % ring
    w0_0 = w[0, 0]
    w0_1 = w[0, 1]
    w0_2 = w[0, 2]
    w1_0 = w[1, 0]
    w1_1 = w[1, 1]
    w1_2 = w[1, 2]
    w1_3 = w[1, 3]
    w1_4 = w[1, 4]
    w1_5 = w[1, 5]
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
        t0_0 = w0_0 - w0_0
        t0_1 = w1_0 - w1_0
        t0_2 = w2_0 - w2_0
        t0_3 = w3_0 - w3_0
        t1_0 = w0_0 - w0_0
        t1_1 = w1_0 - w1_0
        t1_2 = w2_0 - w2_0
        t1_3 = w3_0 - w3_0
        o = pairs[0, kp0, x]
        t0_0 = t0_0 + w0_0 * o
        t0_1 = t0_1 + w1_0 * o
        t0_2 = t0_2 + w2_0 * o
        t0_3 = t0_3 + w3_0 * o
        o = pairs[0, kp1, x]
        t1_0 = t1_0 + w0_0 * o
        t1_1 = t1_1 + w1_0 * o
        t1_2 = t1_2 + w2_0 * o
        t1_3 = t1_3 + w3_0 * o
        o = ((pairs[0, km1, x] + pairs[0, kp1, x]) + pairs[1, kp0, x])
        t0_0 = t0_0 + w0_1 * o
        t0_1 = t0_1 + w1_1 * o
        t0_2 = t0_2 + w2_1 * o
        t0_3 = t0_3 + w3_1 * o
        o = ((pairs[0, kp0, x] + pairs[0, kp2, x]) + pairs[1, kp1, x])
        t1_0 = t1_0 + w0_1 * o
        t1_1 = t1_1 + w1_1 * o
        t1_2 = t1_2 + w2_1 * o
        t1_3 = t1_3 + w3_1 * o
        o = (pairs[1, km1, x] + pairs[1, kp1, x])
        t0_0 = t0_0 + w0_2 * o
        t0_1 = t0_1 + w1_2 * o
        t0_2 = t0_2 + w2_2 * o
        t0_3 = t0_3 + w3_2 * o
        o = (pairs[1, kp0, x] + pairs[1, kp2, x])
        t1_0 = t1_0 + w0_2 * o
        t1_1 = t1_1 + w1_2 * o
        t1_2 = t1_2 + w2_2 * o
        t1_3 = t1_3 + w3_2 * o
        o = ((pairs[0, km2, x] + pairs[0, kp2, x]) + pairs[2, kp0, x])
        t0_1 = t0_1 + w1_3 * o
        t0_2 = t0_2 + w2_3 * o
        t0_3 = t0_3 + w3_3 * o
        o = ((pairs[0, km1, x] + pairs[0, kp3, x]) + pairs[2, kp1, x])
        t1_1 = t1_1 + w1_3 * o
        t1_2 = t1_2 + w2_3 * o
        t1_3 = t1_3 + w3_3 * o
        o = ((pairs[1, km2, x] + pairs[1, kp2, x]) + (pairs[2, km1, x] + pairs[2, kp1, x]))
        t0_1 = t0_1 + w1_4 * o
        t0_2 = t0_2 + w2_4 * o
        t0_3 = t0_3 + w3_4 * o
        o = ((pairs[1, km1, x] + pairs[1, kp3, x]) + (pairs[2, kp0, x] + pairs[2, kp2, x]))
        t1_1 = t1_1 + w1_4 * o
        t1_2 = t1_2 + w2_4 * o
        t1_3 = t1_3 + w3_4 * o
        o = (pairs[2, km2, x] + pairs[2, kp2, x])
        t0_1 = t0_1 + w1_5 * o
        t0_2 = t0_2 + w2_5 * o
        t0_3 = t0_3 + w3_5 * o
        o = (pairs[2, km1, x] + pairs[2, kp3, x])
        t1_1 = t1_1 + w1_5 * o
        t1_2 = t1_2 + w2_5 * o
        t1_3 = t1_3 + w3_5 * o
        o = ((pairs[0, km3, x] + pairs[0, kp3, x]) + pairs[3, kp0, x])
        t0_2 = t0_2 + w2_6 * o
        t0_3 = t0_3 + w3_6 * o
        o = ((pairs[0, km2, x] + pairs[0, kp4, x]) + pairs[3, kp1, x])
        t1_2 = t1_2 + w2_6 * o
        t1_3 = t1_3 + w3_6 * o
        o = ((pairs[1, km3, x] + pairs[1, kp3, x]) + (pairs[3, km1, x] + pairs[3, kp1, x]))
        t0_2 = t0_2 + w2_7 * o
        t0_3 = t0_3 + w3_7 * o
        o = ((pairs[1, km2, x] + pairs[1, kp4, x]) + (pairs[3, kp0, x] + pairs[3, kp2, x]))
        t1_2 = t1_2 + w2_7 * o
        t1_3 = t1_3 + w3_7 * o
        o = ((pairs[2, km3, x] + pairs[2, kp3, x]) + (pairs[3, km2, x] + pairs[3, kp2, x]))
        t0_2 = t0_2 + w2_8 * o
        t0_3 = t0_3 + w3_8 * o
        o = ((pairs[2, km2, x] + pairs[2, kp4, x]) + (pairs[3, km1, x] + pairs[3, kp3, x]))
        t1_2 = t1_2 + w2_8 * o
        t1_3 = t1_3 + w3_8 * o
        o = (pairs[3, km3, x] + pairs[3, kp3, x])
        t0_2 = t0_2 + w2_9 * o
        t0_3 = t0_3 + w3_9 * o
        o = (pairs[3, km2, x] + pairs[3, kp4, x])
        t1_2 = t1_2 + w2_9 * o
        t1_3 = t1_3 + w3_9 * o
        o = ((pairs[0, km4, x] + pairs[0, kp4, x]) + pairs[4, kp0, x])
        t0_3 = t0_3 + w3_10 * o
        o = ((pairs[0, km3, x] + pairs[0, kp5, x]) + pairs[4, kp1, x])
        t1_3 = t1_3 + w3_10 * o
        o = ((pairs[1, km4, x] + pairs[1, kp4, x]) + (pairs[4, km1, x] + pairs[4, kp1, x]))
        t0_3 = t0_3 + w3_11 * o
        o = ((pairs[1, km3, x] + pairs[1, kp5, x]) + (pairs[4, kp0, x] + pairs[4, kp2, x]))
        t1_3 = t1_3 + w3_11 * o
        o = ((pairs[2, km4, x] + pairs[2, kp4, x]) + (pairs[4, km2, x] + pairs[4, kp2, x]))
        t0_3 = t0_3 + w3_12 * o
        o = ((pairs[2, km3, x] + pairs[2, kp5, x]) + (pairs[4, km1, x] + pairs[4, kp3, x]))
        t1_3 = t1_3 + w3_12 * o
        o = ((pairs[3, km4, x] + pairs[3, kp4, x]) + (pairs[4, km3, x] + pairs[4, kp3, x]))
        t0_3 = t0_3 + w3_13 * o
        o = ((pairs[3, km3, x] + pairs[3, kp5, x]) + (pairs[4, km2, x] + pairs[4, kp4, x]))
        t1_3 = t1_3 + w3_13 * o
        o = (pairs[4, km4, x] + pairs[4, kp4, x])
        t0_3 = t0_3 + w3_14 * o
        o = (pairs[4, km3, x] + pairs[4, kp5, x])
        t1_3 = t1_3 + w3_14 * o
        event_step_at(t0_0, thr, ref, ev, 0, y, x)
        event_step_at(t0_1, thr, ref, ev, 1, y, x)
        event_step_at(t0_2, thr, ref, ev, 2, y, x)
        event_step_at(t0_3, thr, ref, ev, 3, y, x)
        event_step_at(t1_0, thr, ref, ev, 0, y + 1, x)
        event_step_at(t1_1, thr, ref, ev, 1, y + 1, x)
        event_step_at(t1_2, thr, ref, ev, 2, y + 1, x)
        event_step_at(t1_3, thr, ref, ev, 3, y + 1, x)
