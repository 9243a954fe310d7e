"""Chunked sampling: run a twin chunk by chunk in time and hand every chunk to a sink.

Memory is bounded by one chunk of spikes ``(chunk_steps, S, H, W) int8`` plus the state
(accumulators, thresholds, the frames the chunk touches), whatever the run's length; the
sink decides where the spikes go (an array, an HDF5 file, a ``.dat`` file, a counter).

A sink has ``begin(shape, meta)`` with ``shape = (T, S, H, W)``, ``write(t0, spikes)``
with ``spikes (B, S, H, W) int8`` for steps ``t0 .. t0 + B - 1`` (called in step order),
``finish(meta)`` on success and ``abort()`` on failure.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.progress import progress_bar
from rvsm.model.sampling.fused import DEFAULT_CHUNK_STEPS, DEFAULT_TILE_ROWS, FusedFloatSampler
from rvsm.model.sampling.samplers import (
    ENGINES,
    Integrator,
    SamplerConfig,
    SpikeTrain,
    accumulator_thresholds,
    iter_step_drives,
    sampling_meta,
)
from rvsm.model.scene.scene import Scene
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
    """Hands every chunk to several sinks."""

    def __init__(self, *sinks) -> None:
        self.sinks = [s for s in sinks if s is not None]

    def begin(self, shape, meta) -> None:
        for s in self.sinks:
            s.begin(shape, meta)

    def write(self, t0, spikes) -> None:
        for s in self.sinks:
            s.write(t0, spikes)

    def finish(self, meta) -> None:
        for s in self.sinks:
            s.finish(meta)

    def abort(self) -> None:
        for s in self.sinks:
            s.abort()


def check_chunking(chunk_steps: int, tile_rows: int) -> None:
    """Refuse chunk lengths and tile heights below 1."""
    if isinstance(chunk_steps, bool) or int(chunk_steps) < 1:
        raise RvsmError(f"chunk_steps must be an integer >= 1, got {chunk_steps!r}")
    if isinstance(tile_rows, bool) or int(tile_rows) < 1:
        raise RvsmError(f"tile_rows must be an integer >= 1, got {tile_rows!r}")


def run_chunks(sink, shape, meta, num_steps, chunk_steps, produce, bar) -> None:
    """Drive ``produce(t0, t1) -> spikes`` over ``0..num_steps`` into ``sink``."""
    sink.begin(shape, meta)
    try:
        for t0 in range(0, num_steps, chunk_steps):
            t1 = min(t0 + chunk_steps, num_steps)
            sink.write(t0, produce(t0, t1))
            bar.update(t1 - t0)
        sink.finish(meta)
    except BaseException:
        sink.abort()
        raise
    finally:
        bar.close()


def stream_float(
    scene: Scene,
    config: SamplerConfig,
    sink,
    chunk_steps: int = DEFAULT_CHUNK_STEPS,
    engine: str = "fused",
    tile_rows: int | None = None,
    progress: bool = False,
) -> SpikeTrain:
    """Run a float sampler over ``scene`` chunk by chunk into ``sink``.

    Returns a :class:`SpikeTrain` whose ``spikes`` is ``None`` (they went to the sink),
    with the thresholds and the metadata. Same spikes for every engine, chunk length,
    tile height and thread count. ``tile_rows`` defaults to 16 rows, 32 with noise (the
    dark current is drawn for a halo of ``L`` rows per tile; measured fastest).
    """
    if engine not in ENGINES:
        raise RvsmError(f"engine must be one of {ENGINES}, got {engine!r}")
    if tile_rows is None:
        tile_rows = 2 * DEFAULT_TILE_ROWS if config.noise is not None else DEFAULT_TILE_ROWS
    check_chunking(chunk_steps, tile_rows)
    spec = config.spec
    thresholds = accumulator_thresholds(config, scene.shape)
    shape = (scene.num_steps, spec.num_scales) + scene.shape
    meta = sampling_meta(scene, config)
    buf = np.empty((min(chunk_steps, max(scene.num_steps, 1)),) + shape[1:], dtype=np.int8)
    if engine == "fused":
        fused = FusedFloatSampler(scene, config, thresholds, tile_rows)

        def produce(t0: int, t1: int) -> np.ndarray:
            return fused.run(t0, t1, buf[:t1 - t0])
    else:
        integrator = Integrator(thresholds, spec.signed, config.reset)
        drives = iter_step_drives(scene, config)

        def produce(t0: int, t1: int) -> np.ndarray:
            for b in range(t1 - t0):
                t, drive = next(drives)
                integrator.step(drive, buf[b])
            return buf[:t1 - t0]

    bar = progress_bar(scene.num_steps, f"{spec.name} {scene.name}", progress)
    run_chunks(sink, shape, meta, scene.num_steps, int(chunk_steps), produce, bar)
    return SpikeTrain(None, thresholds, config, meta)
