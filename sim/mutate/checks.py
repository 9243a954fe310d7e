"""The co-simulation checks a mutant must fail: the default suite's scenarios, in
``amaranth.sim``.

Each :class:`CosimCheck` drives one array (built with a mutation, or the shipped one)
through its architecture's ``amaranth.sim`` driver (:attr:`Architecture.simulate` and
:attr:`Architecture.running_threshold_writes`), on every architecture whose driver can
play it (:meth:`CosimCheck.runs_on`), the way the default co-simulation does
(``tests/sim/cosim/test_stream.py``): random codes with the extremes 0 and full scale,
per-pixel thresholds, the input stalled every other beat, a clear between steps,
thresholds rewritten while the stream pauses, accumulators driven into both rails. It
compares every spike with :meth:`ArrayContract.run` and returns the number of mismatches
(an exception of the simulation counts as a kill too). ``amaranth.sim`` rather than
cocotb: the same RTL (the co-simulation suite shows the generated Verilog agrees with it
spike for spike), a second per mutant instead of a Verilog build each.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.widths import unsigned_max
from rvsm.rtl.architectures.registry import get_architecture
from rvsm.rtl.capabilities import Architecture

__all__ = ["COSIM_CHECKS", "RUNNING_WRITES", "CosimCheck", "stimulus"]


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
    ``rails`` uses the top threshold, which saturation reaches before firing. With
    shared thresholds each scale takes one of its drawn values
    (:meth:`~rvsm.model.fixed.contract.ArrayContract.storable_thresholds`)."""
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
    thresholds = c.storable_thresholds(np.clip(thresholds, 1, top_thr).astype(np.int64), rng)
    if kind == "stall":
        return Stimulus(codes, thresholds, idle_every=2)
    if kind == "clear":
        return Stimulus(codes, thresholds, clear_before=(steps // 2,))
    if kind == "threshold_update":
        new = np.clip(rng.permutation(thresholds.ravel()).reshape(shape), 1, top_thr)
        new = c.storable_thresholds(new, rng)
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


def _run(contract: ArrayContract, stim: Stimulus, arch: Architecture,
         options: dict[str, int], mutation: str | None) -> int:
    """``stim`` through ``arch``'s ``amaranth.sim`` driver, compared with the contract."""
    drive = {k: v for k, v in (("idle_every", stim.idle_every),
                               ("threshold_updates", stim.threshold_updates)) if v}
    got = arch.simulate(contract, stim.codes, stim.thresholds,
                        clear_before=stim.clear_before, mutation=mutation, **drive, **options)
    return int(arch.compare(contract, _expected(contract, stim), got, **options)["mismatches"])


def _run_collisions(contract: ArrayContract, arch: Architecture, options: dict[str, int],
                    mutation: str | None) -> int:
    """Threshold writes while the stream runs, many meeting the read of their word
    (``tests/rtl/stream/test_array.py``'s scenario)."""
    from rvsm.model.fixed.contract import FixedIntegrator, arithmetic_shift, integer_receptive_sums

    c = contract
    stim = stimulus(c, "random")
    top = int(stim.thresholds.max()) + 1
    frames, got = arch.running_threshold_writes(c, stim.codes, stim.thresholds, 7, top,
                                                mutation=mutation, **options)
    integrator = FixedIntegrator(stim.thresholds, c.accumulator_bits, c.signed, c.reset)
    sums = arithmetic_shift(integer_receptive_sums(stim.codes, c.weight_arrays), c.shift)
    want = []
    for t in range(len(stim.codes)):
        integrator.thr = frames[t]
        want.append(integrator.step(sums[t]))
    return int(arch.compare(c, np.stack(want), got, **options)["mismatches"])


#: What a scenario needs of an architecture's ``amaranth.sim`` driver: a keyword of its
#: ``simulate`` (:attr:`Architecture.simulate_keywords`), or :data:`RUNNING_WRITES`, its
#: :attr:`Architecture.running_threshold_writes`.
RUNNING_WRITES = "running_threshold_writes"


@dataclass(frozen=True)
class CosimCheck:
    """One co-simulation scenario: ``name``, ``description``, what it ``needs`` of an
    architecture's driver (``None``: codes, thresholds and clears only) and
    :meth:`mismatches`."""

    name: str
    description: str
    needs: str | None = None

    def runs_on(self, arch: str | Architecture) -> bool:
        """Whether ``arch``'s driver can play this scenario."""
        a = get_architecture(arch)
        if self.needs is None:
            return True
        if self.needs == RUNNING_WRITES:
            return a.running_threshold_writes is not None
        return self.needs in a.simulate_keywords

    def mismatches(self, contract: ArrayContract, arch: str | Architecture, lanes: int,
                   mutation: str | None) -> int:
        """Spikes of the (mutated) array that differ from the contract's; ``lanes`` for
        an architecture that takes them."""
        a = get_architecture(arch)
        options = a.resolve_own({"lanes": lanes})
        if self.needs == RUNNING_WRITES:
            return _run_collisions(contract, a, options, mutation)
        return _run(contract, stimulus(contract, self.name), a, options, mutation)


#: The co-simulation checks, in the order they run.
COSIM_CHECKS: tuple[CosimCheck, ...] = (
    CosimCheck("random", "random codes (0 and full scale included), per-pixel thresholds"),
    CosimCheck("stall", "the input stalled after every other beat", "idle_every"),
    CosimCheck("clear", "a clear between steps, mid-stream"),
    CosimCheck("threshold_update", "thresholds rewritten while the stream pauses",
               "threshold_updates"),
    CosimCheck("threshold_collisions", "threshold writes while the stream runs, many "
               "meeting the read of their own word", RUNNING_WRITES),
    CosimCheck("exact", "every threshold equal to the accumulator after the first step"),
    CosimCheck("rails", "the top threshold: accumulators saturate at both rails"),
)
