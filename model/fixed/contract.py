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
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rvsm.model.fixed.widths import signed_range, unsigned_max
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.geometry import is_symmetric, symmetric_orbits
from rvsm.model.kinds.sensor_kind import SENSOR_NAMES, SPIKE, Output, SensorKind, sensor_kind
from rvsm.model.sampling.config import RESET_MODES

#: The names :attr:`ArrayContract.sensor` takes: what an array senses, the spike camera's
#: integrate-and-fire or the event camera's log-intensity changes (SPEC section 7).
SENSORS = SENSOR_NAMES


def integer_receptive_sums(codes: np.ndarray, weights: Sequence[np.ndarray]) -> np.ndarray:
    """Exact weighted sums of ADC codes over each receptive field, zero outside the array.

    ``codes`` is ``(B, H, W)`` non-negative integers; ``weights`` ``S`` odd square integer
    arrays ``(2L+1, 2L+1)``; returns ``(B, S, H, W) int64``. Kernels with the 8-fold
    symmetry of the DoG / Gauss templates take a faster path that first sums the codes
    of each symmetry orbit (shared by all scales); the result is the same integers as
    :func:`integer_receptive_sums_direct`.
    """
    kernels = [np.asarray(k, dtype=np.int64) for k in weights]
    if all(is_symmetric(k) for k in kernels):
        return _symmetric_sums(np.asarray(codes, dtype=np.int64), kernels)
    return integer_receptive_sums_direct(codes, kernels)


def integer_receptive_sums_direct(
    codes: np.ndarray, weights: Sequence[np.ndarray]
) -> np.ndarray:
    """Tap-by-tap reference of :func:`integer_receptive_sums` (any kernel)."""
    codes = np.asarray(codes, dtype=np.int64)
    b, h, w = codes.shape
    out = np.zeros((b, len(weights), h, w), dtype=np.int64)
    for s, kernel in enumerate(weights):
        kernel = np.asarray(kernel, dtype=np.int64)
        half = kernel.shape[0] // 2
        padded = np.zeros((b, h + 2 * half, w + 2 * half), dtype=np.int64)
        padded[:, half:half + h, half:half + w] = codes
        target = out[:, s]
        for di in range(2 * half + 1):
            for dj in range(2 * half + 1):
                wt = int(kernel[di, dj])
                if wt:
                    target += wt * padded[:, di:di + h, dj:dj + w]
    return out


def _symmetric_sums(codes: np.ndarray, kernels: list[np.ndarray]) -> np.ndarray:
    """Sum codes per orbit ``{(+-a, +-b), (+-b, +-a)}`` once, then weight per scale."""
    bsz, h, w = codes.shape
    halves = [k.shape[0] // 2 for k in kernels]
    big = max(halves)
    padded = np.zeros((bsz, h + 2 * big, w + 2 * big), dtype=np.int64)
    padded[:, big:big + h, big:big + w] = codes
    # rows[b][:, y', x] = codes at (y', x - b) + (y', x + b), padded rows kept.
    rows = []
    for dj in range(big + 1):
        r = padded[:, :, big - dj:big - dj + w].copy()
        if dj:
            r += padded[:, :, big + dj:big + dj + w]
        rows.append(r)

    def cols(x: np.ndarray, di: int) -> np.ndarray:
        c = x[:, big - di:big - di + h].copy()
        if di:
            c += x[:, big + di:big + di + h]
        return c

    out = np.zeros((bsz, len(kernels), h, w), dtype=np.int64)
    tmp = np.empty((bsz, h, w), dtype=np.int64)
    for a, b in symmetric_orbits(big):
        users = [
            (s, int(k[halves[s] + a, halves[s] + b]))
            for s, k in enumerate(kernels) if halves[s] >= a
        ]
        users = [(s, wt) for s, wt in users if wt]
        if not users:
            continue
        orbit = cols(rows[b], a)
        if a != b:
            orbit += cols(rows[a], b)
        for s, wt in users:
            np.multiply(orbit, wt, out=tmp)
            out[:, s] += tmp
    return out


def arithmetic_shift(values: np.ndarray, shift: int) -> np.ndarray:
    """``values >> shift`` (floor of ``values / 2**shift``), as a hardware ``>>>`` does."""
    return np.right_shift(np.asarray(values, dtype=np.int64), int(shift))


def bit_lengths(values: np.ndarray) -> np.ndarray:
    """Bits of ``|v|`` (0 for 0, ``k`` for ``2**(k-1) <= |v| < 2**k``), ``int64``.

    Exact for ``|v| < 2**53``; used only for the profiling histograms.
    """
    _, exponent = np.frexp(np.abs(np.asarray(values, dtype=np.int64)).astype(np.float64))
    return exponent.astype(np.int64)


def bit_length_histogram(values: np.ndarray) -> np.ndarray:
    """Per scale (axis ``-3``), counts of :func:`bit_lengths`: ``(S, 64) int64``."""
    v = np.asarray(values)
    v = np.moveaxis(v.reshape((-1,) + v.shape[-3:]), 1, 0).reshape(v.shape[-3], -1)
    bits = np.minimum(bit_lengths(v), 63)
    return np.stack([np.bincount(row, minlength=64) for row in bits])


class FixedIntegrator:
    """W-bit saturating accumulators with integer thresholds: ``(S, H, W)`` of them.

    ``step(sums)`` takes one step's shifted sums ``(S, H, W) int64`` and returns spikes
    ``(S, H, W) int8``. ``saturated`` counts, per scale, the accumulator-steps at which
    the pre-saturation value left the representable range. With ``track=True`` it also
    keeps, per scale, ``acc_min`` / ``acc_max`` of the pre-saturation values and, with
    ``histogram=True``, ``acc_hist (S, 64)``: counts of :func:`bit_lengths` of them.
    Tracking observes only; it never changes the spikes.
    """

    def __init__(
        self,
        thresholds: np.ndarray,
        accumulator_bits: int,
        signed: bool,
        reset: str = "zero",
        track: bool = False,
        histogram: bool = False,
    ):
        if not 2 <= accumulator_bits <= 62:
            raise RvsmError(f"accumulator_bits must be 2..62, got {accumulator_bits}")
        if reset not in RESET_MODES:
            raise RvsmError(f"reset must be one of {RESET_MODES}, got {reset!r}")
        self.lo, self.hi = signed_range(accumulator_bits)
        thr = np.asarray(thresholds, dtype=np.int64)
        if thr.ndim != 3:
            raise RvsmError(f"thresholds must be (S, H, W), got shape {thr.shape}")
        if thr.min() < 1 or thr.max() > self.hi:
            raise RvsmError(
                f"integer thresholds must lie in 1..{self.hi} for {accumulator_bits}-bit "
                f"accumulators, got {thr.min()}..{thr.max()}"
            )
        self.thr = thr
        self.signed = signed
        self.reset = reset
        self.acc = np.zeros_like(thr)
        self.saturated = np.zeros(thr.shape[0], dtype=np.int64)
        self.track = track or histogram
        num_scales = thr.shape[0]
        self.acc_min = np.full(num_scales, np.iinfo(np.int64).max, dtype=np.int64)
        self.acc_max = np.full(num_scales, np.iinfo(np.int64).min, dtype=np.int64)
        self.acc_hist = np.zeros((num_scales, 64), dtype=np.int64) if histogram else None

    def clear(self) -> None:
        """Every accumulator back to 0 (the RTL's ``clear``; thresholds kept)."""
        self.acc[...] = 0

    def state(self) -> np.ndarray:
        """A copy of the accumulators ``(S, H, W) int64``: what the RTL's accumulator
        memories hold between steps."""
        return self.acc.copy()

    def step(self, sums: np.ndarray) -> np.ndarray:
        """Add ``sums (S, H, W) int64``, saturate, compare, reset; return spikes int8."""
        acc = self.acc
        acc += sums
        if self.track:
            np.minimum(self.acc_min, acc.min(axis=(1, 2)), out=self.acc_min)
            np.maximum(self.acc_max, acc.max(axis=(1, 2)), out=self.acc_max)
            if self.acc_hist is not None:
                self.acc_hist += bit_length_histogram(acc)
        over = (acc > self.hi) | (acc < self.lo)
        self.saturated += over.sum(axis=(1, 2))
        np.clip(acc, self.lo, self.hi, out=acc)
        pos = acc >= self.thr
        spikes = pos.astype(np.int8)
        if self.signed:
            neg = acc <= -self.thr
            spikes -= (neg & ~pos).astype(np.int8)
        if self.reset == "zero":
            acc[spikes != 0] = 0
        else:
            acc -= self.thr * spikes
        return spikes


class FixedEventIntegrator:
    """W-bit signed saturating references with integer contrast thresholds: the event
    sensor's state (module docstring), ``(S, H, W)`` of them.

    The interface of :class:`FixedIntegrator`: ``step(sums)`` takes one step's shifted
    sums and returns events ``(S, H, W) int8``; ``saturated`` counts, per scale, the
    reference updates (captures included) that left the W-bit range; with ``track``,
    ``acc_min``/``acc_max`` are the references' pre-saturation extremes and, with
    ``histogram``, ``acc_hist`` their bit lengths. :meth:`clear` makes the next step
    capture again.
    """

    def __init__(self, thresholds: np.ndarray, accumulator_bits: int, track: bool = False,
                 histogram: bool = False):
        self._events = FixedIntegrator(thresholds, accumulator_bits, True, "subtract",
                                       track, histogram)  # validation and counters
        self.lo, self.hi, self.thr = self._events.lo, self._events.hi, self._events.thr
        self.ref = np.zeros_like(self.thr)
        self.captured = False
        self.track = self._events.track

    def __getattr__(self, name: str):  # saturated, acc_min, acc_max, acc_hist
        return getattr(self._events, name)

    def clear(self) -> None:
        """The next step captures the references again (thresholds kept)."""
        self.captured = False

    def state(self) -> np.ndarray:
        """A copy of the references ``(S, H, W) int64`` (the RTL's accumulator memories
        hold them between steps)."""
        return self.ref.copy()

    def _update(self, new: np.ndarray) -> None:
        ev = self._events
        if self.track:
            np.minimum(ev.acc_min, new.min(axis=(1, 2)), out=ev.acc_min)
            np.maximum(ev.acc_max, new.max(axis=(1, 2)), out=ev.acc_max)
            if ev.acc_hist is not None:
                ev.acc_hist += bit_length_histogram(new)
        ev.saturated += ((new > self.hi) | (new < self.lo)).sum(axis=(1, 2))
        np.clip(new, self.lo, self.hi, out=self.ref)

    def step(self, sums: np.ndarray) -> np.ndarray:
        """One step's shifted sums ``(S, H, W) int64``; events ``(S, H, W) int8``."""
        sums = np.asarray(sums, dtype=np.int64)
        if not self.captured:
            self._update(sums.copy())
            self.captured = True
            return np.zeros(self.thr.shape, dtype=np.int8)
        d = sums - self.ref
        pos = d >= self.thr
        neg = (d <= -self.thr) & ~pos
        events = pos.astype(np.int8) - neg.astype(np.int8)
        self._update(self.ref + self.thr * events)
        return events


def _spike_integrator(thresholds: np.ndarray, accumulator_bits: int, signed: bool,
                      reset: str, track: bool, histogram: bool) -> FixedIntegrator:
    return FixedIntegrator(thresholds, accumulator_bits, signed, reset, track, histogram)


def _event_integrator(thresholds: np.ndarray, accumulator_bits: int, signed: bool,
                      reset: str, track: bool, histogram: bool) -> FixedEventIntegrator:
    return FixedEventIntegrator(thresholds, accumulator_bits, track, histogram)


#: The integrator of each output rule (arguments of :func:`make_integrator`).
INTEGRATORS = {Output.SPIKES: _spike_integrator, Output.EVENTS: _event_integrator}


def make_integrator(kind: SensorKind, thresholds: np.ndarray, accumulator_bits: int,
                    signed: bool, reset: str = "zero", track: bool = False,
                    histogram: bool = False) -> FixedIntegrator | FixedEventIntegrator:
    """The state of a ``kind`` sensor's accumulators, chosen by its output rule:
    :class:`FixedIntegrator` for spikes, :class:`FixedEventIntegrator` for events
    (``signed``, ``reset`` unused there)."""
    return INTEGRATORS[kind.output](thresholds, accumulator_bits, signed, reset, track,
                                    histogram)


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
