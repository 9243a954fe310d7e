"""Steps 3-5 of the integer contract (:mod:`rvsm.model.fixed.contract`), one step at a
time on ``(S, H, W)`` shifted sums: the spike sensor's saturating integrate-and-fire
accumulators (:class:`FixedIntegrator`), the event sensor's references
(:class:`FixedEventIntegrator`), and :func:`make_integrator`, the one a sensor kind
uses."""

from __future__ import annotations

import numpy as np

from rvsm.model.fixed.integer_sums import bit_length_histogram
from rvsm.model.fixed.widths import signed_range
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kinds.sensor_kind import Output, SensorKind
from rvsm.model.sampling.config import RESET_MODES

__all__ = ["INTEGRATORS", "FixedEventIntegrator", "FixedIntegrator", "make_integrator"]


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
