"""The integer heart of the hardware contract (SPEC section 5), on plain integer arrays.

This is what one pixel-array step does in hardware, with no configuration object in the
way, so the fixed twin (:mod:`rvsm.model.fixed.twin`) and the RTL tests share one model:

1. ``sum[s, y, x] = sum_{di,dj} weights[s][di, dj] * codes[y+di, x+dj]`` -- exact integer
   weighted sum over the receptive field; codes outside the array are 0.
2. ``shifted = sum >> shift`` -- arithmetic right shift, i.e. floor division by
   ``2**shift`` (rounds toward minus infinity: ``-5 >> 1 == -3``).
3. ``acc = clamp(acc + shifted, -2**(W-1), 2**(W-1) - 1)`` -- W-bit signed, saturating.
4. fire ``+1`` if ``acc >= thr``; else, for signed models, ``-1`` if ``acc <= -thr``;
   ``thr`` is the accumulator's own integer threshold, ``1 <= thr <= 2**(W-1) - 1``.
5. reset a firing accumulator: ``"zero"`` sets ``acc = 0``; ``"subtract"`` sets
   ``acc -= thr`` after +1 and ``acc += thr`` after -1.

All arithmetic is ``int64``; widths are checked so nothing can overflow it.

The event sensor (``sensor = "dvs"``, SPEC section 7; its kind's
:class:`~rvsm.model.kinds.sensor_kind.Output` is ``EVENTS``) keeps steps 1-2 (its codes come
from a log ADC) and replaces 3-5 by a W-bit signed saturating reference per accumulator
(:class:`FixedEventIntegrator`): captured as ``clamp(shifted)`` at the first step after
a clear (no event); afterwards ``d = shifted - ref`` (exact), ``d >= thr`` is ON (+1,
``ref = clamp(ref + thr)``), else ``d <= -thr`` is OFF (-1, ``ref = clamp(ref - thr)``).

Steps 1-2 are :mod:`.integer_sums`, steps 3-5 :mod:`.integrators` (re-exported here);
this module runs them (:class:`ContractStream`, :func:`run_integer_array`) and holds the
contract record, :class:`ArrayContract`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rvsm.model.fixed.integer_sums import (
    arithmetic_shift,
    bit_length_histogram,
    bit_lengths,
    integer_receptive_sums,
    integer_receptive_sums_direct,
)
from rvsm.model.fixed.integrators import (
    INTEGRATORS,
    FixedEventIntegrator,
    FixedIntegrator,
    make_integrator,
)
from rvsm.model.fixed.widths import unsigned_max
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kinds.sensor_kind import SENSOR_NAMES, SPIKE, SensorKind, sensor_kind

__all__ = ["INTEGRATORS", "SENSORS", "ArrayContract", "ContractStream", "FixedEventIntegrator",
           "FixedIntegrator", "arithmetic_shift", "bit_length_histogram", "bit_lengths",
           "integer_receptive_sums", "integer_receptive_sums_direct", "make_integrator",
           "run_integer_array"]

#: The names :attr:`ArrayContract.sensor` takes: what an array senses, the spike camera's
#: integrate-and-fire or the event camera's log-intensity changes (SPEC section 7).
SENSORS = SENSOR_NAMES


class ContractStream:
    """The integer contract run chunk by chunk: state carried from one call to the next.

    :meth:`run` takes consecutive chunks of ADC codes ``(B, H, W)`` and returns their
    spikes ``(B, S, H, W) int8``, exactly those of one :func:`run_integer_array` call on
    the concatenated codes (steps are computed in blocks of ``block_steps``, which does
    not change the spikes); :meth:`clear` is the RTL's ``clear`` (every accumulator back
    to 0, thresholds kept). This is how long co-simulation runs get their expectation
    with bounded memory.
    """

    def __init__(self, weights: Sequence[np.ndarray], shift: int, thresholds: np.ndarray,
                 accumulator_bits: int, signed: bool, reset: str = "zero",
                 block_steps: int = 32, sensor: SensorKind = SPIKE):
        self.weights = list(weights)
        self.shift = int(shift)
        self.block_steps = max(1, int(block_steps))
        self.integrator = make_integrator(sensor, thresholds, accumulator_bits, signed, reset)

    def clear(self) -> None:
        """Every accumulator back to 0 (an event sensor: capture again); thresholds
        kept."""
        self.integrator.clear()

    def run(self, codes: np.ndarray) -> np.ndarray:
        """Spikes ``(B, S, H, W) int8`` of the next ``B`` steps, codes ``(B, H, W)``."""
        codes = np.asarray(codes)
        if codes.ndim != 3:
            raise RvsmError(f"ADC codes must be (T, H, W), got shape {codes.shape}")
        t_total = codes.shape[0]
        spikes = np.zeros((t_total, len(self.weights)) + codes.shape[1:], dtype=np.int8)
        for t0 in range(0, t_total, self.block_steps):
            t1 = min(t0 + self.block_steps, t_total)
            sums = arithmetic_shift(integer_receptive_sums(codes[t0:t1], self.weights),
                                    self.shift)
            for b in range(t1 - t0):
                spikes[t0 + b] = self.integrator.step(sums[b])
        return spikes


def run_integer_array(
    codes: np.ndarray,
    weights: Sequence[np.ndarray],
    shift: int,
    thresholds: np.ndarray,
    accumulator_bits: int,
    signed: bool,
    reset: str = "zero",
    block_steps: int = 32,
    sensor: SensorKind = SPIKE,
) -> np.ndarray:
    """Spikes (or events) ``(T, S, H, W) int8`` of the whole contract on ``codes (T, H,
    W)``.

    This is the bit-accurate model the RTL is checked against.
    """
    return ContractStream(weights, shift, thresholds, accumulator_bits, signed, reset,
                          block_steps, sensor).run(codes)


@dataclass(frozen=True)
class ArrayContract:
    """The integer parameters of one pixel array: everything the RTL is built from.

    ``weights`` holds, per scale, the integer kernel as a tuple of row tuples (hashable, so
    a contract can key a cache of generated RTL). Thresholds are *not* part of it: they are
    loaded at run time through the configuration interface (fixed-pattern noise lives
    there), each in ``1 .. 2**(accumulator_bits-1) - 1``. ``shared_thresholds`` (``None``:
    a threshold per accumulator, in memories) is, for an array with one threshold
    register per scale (``threshold.storage = "shared"``), each register's reset and
    configuration value: the nominal thresholds, still writable at run time. ``sensor``
    is the name of its :attr:`kind`: ``"spike"`` (the spike camera) or ``"dvs"`` (the
    event sensor: log ADC codes, references instead of accumulators; module docstring).
    It stays a name so a contract is written to JSON and digested as text.
    """

    height: int
    width: int
    adc_bits: int
    weights: tuple[tuple[tuple[int, ...], ...], ...]
    shift: int
    accumulator_bits: int
    signed: bool
    reset: str = "zero"
    sensor: str = SPIKE.name
    shared_thresholds: tuple[int, ...] | None = None

    def __post_init__(self) -> None:
        shared = self.shared_thresholds
        if shared is None:
            return
        shared = tuple(int(t) for t in shared)  # a JSON list reads back as a tuple
        object.__setattr__(self, "shared_thresholds", shared)
        top = unsigned_max(self.threshold_bits)
        if len(shared) != self.num_scales or not all(1 <= t <= top for t in shared):
            raise RvsmError(f"shared_thresholds must be {self.num_scales} threshold(s) in "
                            f"1..{top}, one per scale, got {shared!r}")

    @property
    def threshold_storage(self) -> str:
        """``"shared"`` (one threshold register per scale, reset to
        :attr:`shared_thresholds`) or ``"per-pixel"`` (a threshold per accumulator)."""
        return "per-pixel" if self.shared_thresholds is None else "shared"

    def storable_thresholds(self, thresholds: np.ndarray, rng: np.random.Generator
                            ) -> np.ndarray:
        """``thresholds (S, H, W)`` as this array can hold them: unchanged per pixel; with
        shared thresholds, for each scale one of its values (drawn with ``rng``) for every
        accumulator of the scale. For stimulus generators that draw per accumulator."""
        if self.shared_thresholds is None:
            return thresholds
        flat = np.asarray(thresholds).reshape(len(thresholds), -1)
        picked = flat[np.arange(len(flat)), rng.integers(0, flat.shape[1], len(flat))]
        return np.broadcast_to(picked[:, None, None], np.shape(thresholds)).copy()

    @property
    def kind(self) -> SensorKind:
        """The sensor kind named by :attr:`sensor`; its ``output`` is the RTL's output
        rule."""
        return sensor_kind(self.sensor)

    @property
    def num_scales(self) -> int:
        """S, accumulators per pixel."""
        return len(self.weights)

    @property
    def weight_arrays(self) -> list[np.ndarray]:
        """The kernels as ``(2L+1, 2L+1) int64`` arrays."""
        return [np.array(k, dtype=np.int64) for k in self.weights]

    @property
    def threshold_bits(self) -> int:
        """Width of an unsigned threshold register: ``accumulator_bits - 1``."""
        return self.accumulator_bits - 1

    def sum_range(self, scale: int) -> tuple[int, int]:
        """``(lo, hi)`` of scale ``scale``'s per-step weighted sum before the shift."""
        k = self.weight_arrays[scale]
        full = unsigned_max(self.adc_bits)
        return int(k[k < 0].sum()) * full, int(k[k > 0].sum()) * full

    def run(
        self, codes: np.ndarray, thresholds: np.ndarray, clear_before: Sequence[int] = ()
    ) -> np.ndarray:
        """Spikes ``(T, S, H, W) int8`` for ``codes (T, H, W)`` and ``thresholds (S, H, W)``.

        ``clear_before`` lists steps before which the array is cleared (the RTL's
        ``clear``): every accumulator restarts from 0 at those steps, thresholds kept.
        Steps outside ``1 .. T-1`` change nothing.
        """
        codes = np.asarray(codes)
        cuts = sorted({int(t) for t in clear_before if 0 < int(t) < len(codes)})
        bounds = [0, *cuts, len(codes)]
        parts = [
            run_integer_array(
                codes[a:b], self.weight_arrays, self.shift, thresholds,
                self.accumulator_bits, self.signed, self.reset, sensor=self.kind,
            )
            for a, b in zip(bounds[:-1], bounds[1:], strict=True)
        ]
        return parts[0] if len(parts) == 1 else np.concatenate(parts, axis=0)

    def stream(self, thresholds: np.ndarray) -> ContractStream:
        """This contract run chunk by chunk from a cleared array (:class:`ContractStream`)."""
        return ContractStream(self.weight_arrays, self.shift, thresholds,
                              self.accumulator_bits, self.signed, self.reset,
                              sensor=self.kind)
