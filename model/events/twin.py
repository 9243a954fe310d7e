"""The event sensor's run pipeline: either engine, chunk by chunk in time, into a sink.

:func:`stream_events` writes events ``(T, S, H, W) int8`` into any spike sink
(:mod:`rvsm.model.spikes.sinks`: an array, an HDF5 file, a counter) in bounded memory;
:func:`sample_events` is the whole-array form. The engines ``"fused"`` (numba,
:mod:`.fused`) and ``"numpy"`` (the reference, :mod:`.numpy_engine`) give bit-identical
events for any chunk length and thread count.
"""

from __future__ import annotations

import numpy as np

from rvsm.model.events.config import EventConfig, EventTrain, contrast_thresholds, event_meta
from rvsm.model.events.fused import FusedEventSampler
from rvsm.model.events.numpy_engine import NumpyEventSampler
from rvsm.model.infra.memory import require_spike_memory
from rvsm.model.infra.progress import progress_bar
from rvsm.model.sampling.config import DEFAULT_CHUNK_STEPS, check_chunking, check_engine
from rvsm.model.scene.scene import Scene
from rvsm.model.spikes.sinks import ArraySink, SpikeSink, fill_sink

__all__ = ["sample_events", "stream_events"]


def stream_events(scene: Scene, config: EventConfig, sink: SpikeSink,
                  chunk_steps: int = DEFAULT_CHUNK_STEPS, engine: str = "fused",
                  progress: bool = False) -> EventTrain:
    """Run an event sampler over ``scene`` chunk by chunk into ``sink``; the returned
    :class:`EventTrain` has ``events = None`` (they went to the sink)."""
    check_engine(engine)
    check_chunking(chunk_steps, 1)
    spec = config.spec
    thresholds = contrast_thresholds(config, scene.shape)
    shape = (scene.num_steps, spec.num_scales) + scene.shape
    meta = event_meta(scene, config)
    sampler_type = FusedEventSampler if engine == "fused" else NumpyEventSampler
    sampler = sampler_type(scene, config, thresholds)
    buf = np.empty((min(chunk_steps, max(scene.num_steps, 1)),) + shape[1:], dtype=np.int8)

    def produce(t0: int, t1: int) -> np.ndarray:
        return sampler.run(t0, t1, buf[:t1 - t0])

    bar = progress_bar(scene.num_steps, f"dvs {spec.name} {scene.name}", progress)
    fill_sink(sink, shape, meta, produce, int(chunk_steps), bar)
    refs = sampler.references
    return EventTrain(None, thresholds, refs if refs is not None
                      else np.zeros_like(thresholds), config, meta)


def sample_events(scene: Scene, config: EventConfig, engine: str = "fused",
                  chunk_steps: int = DEFAULT_CHUNK_STEPS) -> EventTrain:
    """Events of a whole scene: :class:`EventTrain` with ``events (T, S, H, W) int8``."""
    check_engine(engine)
    require_spike_memory(scene, config.spec.num_scales)
    sink = ArraySink()
    train = stream_events(scene, config, sink, chunk_steps=chunk_steps, engine=engine)
    train.events = sink.spikes
    return train
