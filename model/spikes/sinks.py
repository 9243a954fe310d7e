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
    """Collects every chunk into one ``(T, S, H, W) int8`` array (``self.spikes``).

    :meth:`target` lends the array's own rows to a producer, so a run that writes its
    chunks there (:func:`chunk_target`) needs no copy; :meth:`write` then copies nothing.
    """

    def __init__(self) -> None:
        self.spikes: np.ndarray | None = None
        self.meta: dict = {}

    def begin(self, shape, meta) -> None:
        self.spikes = np.empty(shape, dtype=np.int8)

    def target(self, t0: int, t1: int) -> np.ndarray:
        """Steps ``t0 .. t1 - 1`` of the array, ``(t1 - t0, S, H, W)``, to be written in place."""
        return self.spikes[t0:t1]

    def write(self, t0, spikes) -> None:
        dest = self.spikes[t0:t0 + spikes.shape[0]]
        if not _same_memory(dest, spikes):  # written in place through target(): no copy
            dest[...] = spikes

    def finish(self, meta) -> None:
        self.meta = meta

    def abort(self) -> None:
        self.spikes = None


def _same_memory(a: np.ndarray, b: np.ndarray) -> bool:
    """True when ``a`` and ``b`` are the same bytes (same start, shape and strides)."""
    return (a.shape == b.shape and a.strides == b.strides
            and a.__array_interface__["data"][0] == b.__array_interface__["data"][0])


def chunk_target(sink, t0: int, t1: int, spare: np.ndarray) -> np.ndarray:
    """Where a producer writes steps ``t0 .. t1 - 1``: the sink's own memory when it lends
    it (``sink.target(t0, t1)``, e.g. :class:`ArraySink`, saving a copy of every chunk),
    else ``spare[:t1 - t0]`` (a reused buffer). Call it after ``begin``."""
    target = getattr(sink, "target", None)
    out = target(t0, t1) if target is not None else None
    return spare[:t1 - t0] if out is None else out


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

    def target(self, t0: int, t1: int) -> np.ndarray | None:
        """The memory of the first sink that lends it (:meth:`ArraySink.target`), else None;
        the other sinks read the chunk from there."""
        for s in self.sinks:
            target = getattr(s, "target", None)
            if target is not None:
                return target(t0, t1)
        return None

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
