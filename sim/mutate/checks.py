"""The co-simulation checks a mutant must fail: the default suite's scenarios, in
``amaranth.sim``.

Each :class:`CosimCheck` drives one array (built with a mutation, or the shipped one) the
way the default co-simulation does (``tests/sim/cosim/test_stream.py``): random codes with
the extremes 0 and full scale, per-pixel thresholds, the input stalled every other beat, a
clear between steps, thresholds rewritten while the stream pauses, accumulators driven into
both rails. It compares every spike with :meth:`ArrayContract.run` and returns the number
of mismatches (an exception of the simulation counts as a kill too). ``amaranth.sim``
rather than cocotb: the same RTL (the co-simulation suite shows the generated Verilog
agrees with it spike for spike), a second per mutant instead of a Verilog build each.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.widths import unsigned_max

__all__ = ["COSIM_CHECKS", "CosimCheck", "stimulus"]


@dataclass(frozen=True)
class Stimulus:
    """Codes ``(T, H, W)``, thresholds ``(S, H, W)`` and how the run is driven."""

    codes: np.ndarray
    thresholds: np.ndarray
    clear_before: tuple[int, ...] = ()
    idle_every: int = 0
    threshold_updates: dict | None = None


def stimulus(contract: ArrayContract, kind: str, seed: int = 0) -> Stimulus:
    """The stimulus of check ``kind`` for ``contract`` (seeded). Thresholds are drawn
    around the typical shifted sum of each scale, so an accumulator integrates a few
    steps before it fires and its residual matters; ``exact`` sets each threshold to the
    accumulator's value after the first step (every pixel hits its threshold exactly);
    ``rails`` uses the top threshold, which saturation reaches before firing."""
    from rvsm.model.fixed.contract import arithmetic_shift, integer_receptive_sums

    c = contract
    rng = np.random.default_rng(seed)
    top_code, top_thr = unsigned_max(c.adc_bits), unsigned_max(c.threshold_bits)
    steps = 8 if kind != "rails" else 16
    codes = rng.integers(0, top_code + 1, (steps, c.height, c.width))
    codes[0, 0, :] = top_code  # the extremes, on borders and inside
    codes[1, :, -1] = 0
    if kind == "rails":
        codes = np.where(rng.random(codes.shape) < 0.5, top_code, 0)
    sums = arithmetic_shift(integer_receptive_sums(codes, c.weight_arrays), c.shift)
    typical = np.maximum(1, np.percentile(np.abs(sums), 75, axis=(0, 2, 3))).astype(np.int64)
    shape = (c.num_scales, c.height, c.width)
    thresholds = rng.integers(typical[:, None, None] // 2 + 1,
                              3 * typical[:, None, None] + 2, shape)
    if kind == "exact":
        thresholds = np.abs(sums[0])
    if kind == "rails":
        thresholds = np.full(shape, top_thr)
    thresholds = np.clip(thresholds, 1, top_thr).astype(np.int64)
    if kind == "stall":
        return Stimulus(codes, thresholds, idle_every=2)
    if kind == "clear":
        return Stimulus(codes, thresholds, clear_before=(steps // 2,))
    if kind == "threshold_update":
        new = np.clip(rng.permutation(thresholds.ravel()).reshape(shape), 1, top_thr)
        return Stimulus(codes, thresholds, threshold_updates={2: new})
    return Stimulus(codes, thresholds)


def _expected(contract: ArrayContract, stim: Stimulus) -> np.ndarray:
    """The contract's spikes; with a threshold update, the thresholds switched from the
    update's frame on (what ``docs/stream-array.md`` says a paused write does)."""
    if not stim.threshold_updates:
        return contract.run(stim.codes, stim.thresholds, stim.clear_before)
    from rvsm.model.fixed.contract import FixedIntegrator, arithmetic_shift, integer_receptive_sums

    (frame, new), = stim.threshold_updates.items()
    c = contract
    sums = arithmetic_shift(integer_receptive_sums(stim.codes, c.weight_arrays), c.shift)
    integrator = FixedIntegrator(stim.thresholds, c.accumulator_bits, c.signed, c.reset)
    out = np.zeros((len(sums), *integrator.thr.shape), np.int8)
    for t, step_sums in enumerate(sums):
        if t == frame:
            integrator.thr = np.asarray(new, dtype=np.int64)
        out[t] = integrator.step(step_sums)
    return out


def _run_stream(contract: ArrayContract, stim: Stimulus, lanes: int,
                mutation: str | None) -> int:
    from rvsm.rtl.stream.dimensions import StreamGeometry
    from rvsm.rtl.stream.drive import simulate
    from rvsm.rtl.stream.schedule import check_beats

    got = simulate(contract, stim.codes, stim.thresholds, lanes, stim.clear_before,
                   stim.threshold_updates, stim.idle_every, mutation=mutation)
    result = check_beats(StreamGeometry(contract, lanes).schedule,
                         _expected(contract, stim), got)
    return int(result["mismatches"])


def _run_parallel(contract: ArrayContract, stim: Stimulus, lanes: int,
                  mutation: str | None) -> int:
    from rvsm.rtl.parallel.drive import simulate

    got = simulate(contract, stim.codes, stim.thresholds, stim.clear_before,
                   mutation=mutation)
    return int((got != _expected(contract, stim)).sum())


def _run_collisions(contract: ArrayContract, lanes: int, mutation: str | None) -> int:
    """Threshold writes while the stream runs, many meeting the read of their word
    (``tests/rtl/stream/test_array.py``'s scenario)."""
    from rvsm.model.fixed.contract import FixedIntegrator, arithmetic_shift, integer_receptive_sums
    from rvsm.rtl.stream.dimensions import StreamGeometry
    from rvsm.rtl.stream.drive import colliding_threshold_writes, simulate_with_threshold_writes
    from rvsm.rtl.stream.schedule import check_beats

    c = contract
    stim = stimulus(c, "random")
    steps = len(stim.codes)
    geo = StreamGeometry(c, lanes)
    top = int(stim.thresholds.max()) + 1
    writes, frames, _, _ = colliding_threshold_writes(geo, stim.thresholds, steps, 7, top)
    integrator = FixedIntegrator(stim.thresholds, c.accumulator_bits, c.signed, c.reset)
    sums = arithmetic_shift(integer_receptive_sums(stim.codes, c.weight_arrays), c.shift)
    want = []
    for t in range(steps):
        integrator.thr = frames[t].reshape(c.num_scales, c.height, c.width)  # words -> pixels
        want.append(integrator.step(sums[t]))
    got = simulate_with_threshold_writes(c, lanes, stim.codes, stim.thresholds, writes,
                                         mutation=mutation)
    return int(check_beats(geo.schedule, np.stack(want), got)["mismatches"])


@dataclass(frozen=True)
class CosimCheck:
    """One co-simulation scenario: ``name``, ``description``, the architectures it runs
    on and :meth:`mismatches`."""

    name: str
    description: str
    architectures: tuple[str, ...]

    def mismatches(self, contract: ArrayContract, arch: str, lanes: int,
                   mutation: str | None) -> int:
        """Spikes of the (mutated) array that differ from the contract's."""
        if self.name == "threshold_collisions":
            return _run_collisions(contract, lanes, mutation)
        stim = stimulus(contract, self.name)
        run: Callable[..., int] = _run_stream if arch == "stream" else _run_parallel
        return run(contract, stim, lanes, mutation)


#: The co-simulation checks, in the order they run.
COSIM_CHECKS: tuple[CosimCheck, ...] = (
    CosimCheck("random", "random codes (0 and full scale included), per-pixel thresholds",
               ("stream", "parallel")),
    CosimCheck("stall", "the input stalled after every other beat", ("stream",)),
    CosimCheck("clear", "a clear between steps, mid-stream", ("stream", "parallel")),
    CosimCheck("threshold_update", "thresholds rewritten while the stream pauses",
               ("stream",)),
    CosimCheck("threshold_collisions", "threshold writes while the stream runs, many "
               "meeting the read of their own word", ("stream",)),
    CosimCheck("exact", "every threshold equal to the accumulator after the first step",
               ("stream", "parallel")),
    CosimCheck("rails", "the top threshold: accumulators saturate at both rails",
               ("stream", "parallel")),
)
