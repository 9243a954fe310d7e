"""Orbit decomposition and retimed adder trees of :mod:`rvsm.rtl.stream.pipelined_sum`."""

from __future__ import annotations

import numpy as np
import pytest
from amaranth.hdl import Module, Signal, unsigned

from rvsm.model.fixed.weights import quantise_model
from rvsm.model.kernels.geometry import kernel_radius
from rvsm.model.kernels.receptive_fields import MODEL_NAMES
from rvsm.rtl.amaranth_sim import run_simulation
from rvsm.rtl.receptive_sum import sum_width
from rvsm.rtl.stream.pipelined_sum import Pipeline, weighted_orbits


@pytest.mark.parametrize("model", MODEL_NAMES)
def test_orbits_rebuild_every_kernel(model: str) -> None:
    ks = quantise_model(model, 9, "round-half-up")
    orbits = weighted_orbits(ks)
    radius = kernel_radius(ks)
    for s, k in enumerate(ks):
        half = k.shape[0] // 2
        rebuilt = np.zeros((2 * radius + 1, 2 * radius + 1), dtype=np.int64)
        for o in orbits:
            for dy, dx in o.offsets:
                rebuilt[radius + dy, radius + dx] += o.weights[s]
        full = np.zeros_like(rebuilt)
        lo = radius - half
        if lo >= 0:
            full[lo:lo + k.shape[0], lo:lo + k.shape[0]] = k
        else:  # the kernel's outer ring is zero
            full = k[-lo:-lo + 2 * radius + 1, -lo:-lo + 2 * radius + 1]
        assert np.array_equal(rebuilt, full)


@pytest.mark.parametrize("levels", [1, 2, 3])
def test_retimed_sum_is_exact_and_planned(levels: int) -> None:
    """A signed shifted sum of inputs with staggered stages, against numpy."""
    rng = np.random.default_rng(levels)
    n_in, bits = 11, 5
    stages = rng.integers(0, 3, n_in)
    terms_spec = [(int(rng.choice([-1, 1])), i, int(rng.integers(0, 4))) for i in range(n_in)]
    lo = sum(s * ((1 << bits) - 1) << sh for s, _, sh in terms_spec if s < 0)
    hi = sum(s * ((1 << bits) - 1) << sh for s, _, sh in terms_spec if s > 0)
    width = sum_width(lo, hi)

    plan = Pipeline(None, levels_per_stage=levels)
    p_in = [plan.timed(None, int(st)) for st in stages]
    planned = plan.settle(plan.sum([(s, p_in[i], sh) for s, i, sh in terms_spec], width))

    m = Module()
    en = Signal()
    ins = [Signal(unsigned(bits), name=f"x{i}") for i in range(n_in)]
    pipe = Pipeline(m, en, levels_per_stage=levels)
    b_in = [pipe.timed(x, int(st)) for x, st in zip(ins, stages, strict=True)]
    built = pipe.settle(pipe.sum([(s, b_in[i], sh) for s, i, sh in terms_spec], width))
    pipe.emit()
    assert built.stage == planned.stage
    assert plan.registers == pipe.registers
    out = Signal(unsigned(width))
    m.d.comb += out.eq(built.value)

    vectors = rng.integers(0, 1 << bits, (6, n_in))
    depth = built.stage
    got = []

    async def bench(ctx) -> None:  # noqa: ANN001
        ctx.set(en, 1)
        # hold each vector for `depth` cycles so every staggered input lines up
        for vec in vectors:
            for x, v in zip(ins, vec, strict=True):
                ctx.set(x, int(v))
            for _ in range(depth + 1):
                await ctx.tick()
            raw = ctx.get(out)
            got.append(raw - (1 << width) if raw >> (width - 1) else raw)

    run_simulation(m, bench)
    want = [sum(s * int(vec[i]) << sh for s, i, sh in terms_spec) for vec in vectors]
    assert got == want
