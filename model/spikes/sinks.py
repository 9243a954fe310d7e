"""Spike sinks: where a chunked run's spikes go, and the loop that fills one.

A sink has ``begin(shape, meta)`` with ``shape = (T, S, H, W)``, ``write(t0, spikes)``
with ``spikes (B, S, H, W) int8`` for steps ``t0 .. t0 + B - 1`` (called in step order),
``finish(meta)`` on success and ``abort()`` on failure (also after a ``begin`` that
failed half-way). A sink that can refuse a run (a file format that cannot hold its shape)
also has ``check(shape, meta)``, which raises before anything is opened: :class:`TeeSink`
checks every sink before it begins any, so a refused output leaves no other output's
partial file behind. Besides the ones here (an array,
counters, several at once), :class:`rvsm.model.spikes.h5.H5SpikeWriter` and
:class:`rvsm.model.spikes.dat.DatWriter` write files.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

import numpy as np

from rvsm.model.spikes.packing import count_spikes


class SpikeSink(Protocol):
    """Where chunks of spikes go (see the module docstring)."""

    def begin(self, shape: tuple[int, int, int, int], meta: dict) -> None: ...

    def write(self, t0: int, spikes: np.ndarray) -> None: ...

    def finish(self, meta: dict) -> None: ...

    def abort(self) -> None: ...


class ArraySink:
    """Collects every chunk into one ``(T, S, H, W) int8`` array (``self.spikes``)."""

    def __init__(self) -> None:
        self.spikes: np.ndarray | None = None
        self.meta: dict = {}

    def begin(self, shape, meta) -> None:
        self.spikes = np.empty(shape, dtype=np.int8)

    def write(self, t0, spikes) -> None:
        self.spikes[t0:t0 + spikes.shape[0]] = spikes

    def finish(self, meta) -> None:
        self.meta = meta

    def abort(self) -> None:
        self.spikes = None


class CountSink:
    """Keeps only counts: ``spikes`` (non-zero), ``negative`` and ``steps`` seen."""

    def __init__(self) -> None:
        self.spikes = 0
        self.negative = 0
        self.steps = 0
        self.per_scale: np.ndarray | None = None

    def begin(self, shape, meta) -> None:
        self.per_scale = np.zeros(shape[1], dtype=np.int64)

    def write(self, t0, spikes) -> None:
        nz, neg = count_spikes(spikes)
        self.per_scale += nz
        self.spikes += int(nz.sum())
        self.negative += neg
        self.steps += spikes.shape[0]

    def finish(self, meta) -> None:
        pass

    def abort(self) -> None:
        pass


class TeeSink:
    """Hands every chunk to several sinks (``None`` entries are skipped)."""

    def __init__(self, *sinks: SpikeSink | None) -> None:
        self.sinks = [s for s in sinks if s is not None]

    def check(self, shape, meta) -> None:
        """Every sink's ``check`` (those that have one), before any is opened."""
        for s in self.sinks:
            check = getattr(s, "check", None)
            if check is not None:
                check(shape, meta)

    def begin(self, shape, meta) -> None:
        """Check every sink, then begin each; a ``begin`` that fails aborts the sinks
        already begun (and itself) before the error goes on."""
        self.check(shape, meta)
        for i, s in enumerate(self.sinks):
            try:
                s.begin(shape, meta)
            except BaseException:
                for begun in self.sinks[:i + 1]:
                    begun.abort()
                raise

    def write(self, t0, spikes) -> None:
        for s in self.sinks:
            s.write(t0, spikes)

    def finish(self, meta) -> None:
        for s in self.sinks:
            s.finish(meta)

    def abort(self) -> None:
        for s in self.sinks:
            s.abort()


def fill_sink(
    sink: SpikeSink,
    shape: tuple[int, int, int, int],
    meta: dict,
    produce: Callable[[int, int], np.ndarray],
    chunk_steps: int,
    progress=None,
    final_meta: Callable[[], dict] | None = None,
) -> None:
    """Write ``produce(t0, t1) -> (t1 - t0, S, H, W) int8`` over steps ``0 .. T - 1``
    (``T = shape[0]``) into ``sink`` in chunks of ``chunk_steps``: ``begin(shape, meta)``,
    the writes and ``finish``, or ``abort`` on any failure. ``finish`` gets
    ``final_meta()`` when given (metadata known only once every step ran), else ``meta``.
    ``progress`` is an optional bar (``update(steps)``, ``close()``), closed either way."""
    num_steps = shape[0]
    try:
        try:
            sink.begin(shape, meta)
            for t0 in range(0, num_steps, chunk_steps):
                t1 = min(t0 + chunk_steps, num_steps)
                sink.write(t0, produce(t0, t1))
                if progress is not None:
                    progress.update(t1 - t0)
            sink.finish(final_meta() if final_meta is not None else meta)
        except BaseException:
            sink.abort()
            raise
    finally:
        if progress is not None:
            progress.close()
