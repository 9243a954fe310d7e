"""The float twin's run pipeline: either engine, chunk by chunk in time, into a sink.

Memory is bounded by one chunk of spikes ``(chunk_steps, S, H, W) int8`` plus the state
(accumulators, thresholds, the frames the chunk touches), whatever the run's length; the
sink (:mod:`rvsm.model.spikes.sinks`) decides where the spikes go (an array, an HDF5
file, a ``.dat`` file, a counter). :func:`sample` is the whole-array form.

Two engines give bit-identical spikes: ``"fused"`` (default; numba kernels with the time
loop inside, :mod:`.fused`) and ``"numpy"`` (the vectorised reference,
:mod:`.numpy_engine`).
"""

from __future__ import annotations

import numpy as np

from rvsm.model.infra.memory import require_spike_memory
from rvsm.model.infra.progress import progress_bar
from rvsm.model.sampling.config import (
    DEFAULT_BLOCK_STEPS,
    DEFAULT_CHUNK_STEPS,
    SamplerConfig,
    SpikeTrain,
    accumulator_thresholds,
    check_chunking,
    check_engine,
    sampling_meta,
)
from rvsm.model.sampling.fused import DEFAULT_TILE_ROWS, FusedFloatSampler
from rvsm.model.sampling.numpy_engine import NumpyFloatSampler
from rvsm.model.scene.scene import Scene
from rvsm.model.spikes.sinks import ArraySink, SpikeSink, chunk_target, fill_sink


def stream_float(
    scene: Scene,
    config: SamplerConfig,
    sink: SpikeSink,
    chunk_steps: int = DEFAULT_CHUNK_STEPS,
    engine: str = "fused",
    tile_rows: int | None = None,
    progress: bool = False,
    block_steps: int = DEFAULT_BLOCK_STEPS,
) -> SpikeTrain:
    """Run a float sampler over ``scene`` chunk by chunk into ``sink``.

    Returns a :class:`SpikeTrain` whose ``spikes`` is ``None`` (they went to the sink),
    with the thresholds and the metadata. Same spikes for every engine, chunk length,
    tile height, dark-current block (``block_steps``, numpy engine) and thread count.
    ``tile_rows`` defaults to 16 rows, 32 with noise (the dark current is drawn for a
    halo of ``L`` rows per tile; measured fastest).
    """
    check_engine(engine)
    if tile_rows is None:
        tile_rows = 2 * DEFAULT_TILE_ROWS if config.noise is not None else DEFAULT_TILE_ROWS
    check_chunking(chunk_steps, tile_rows)
    spec = config.spec
    thresholds = accumulator_thresholds(config, scene.shape)
    shape = (scene.num_steps, spec.num_scales) + scene.shape
    meta = sampling_meta(scene, config)
    buf = np.empty((min(chunk_steps, max(scene.num_steps, 1)),) + shape[1:], dtype=np.int8)
    if engine == "fused":
        sampler = FusedFloatSampler(scene, config, thresholds, tile_rows)
    else:
        sampler = NumpyFloatSampler(scene, config, thresholds, block_steps)

    def produce(t0: int, t1: int) -> np.ndarray:
        return sampler.run(t0, t1, chunk_target(sink, t0, t1, buf))

    bar = progress_bar(scene.num_steps, f"{spec.name} {scene.name}", progress)
    fill_sink(sink, shape, meta, produce, int(chunk_steps), bar)
    return SpikeTrain(None, thresholds, config, meta)


def sample(
    scene: Scene,
    config: SamplerConfig,
    block_steps: int = DEFAULT_BLOCK_STEPS,
    progress: bool = False,
    engine: str = "fused",
) -> SpikeTrain:
    """Run a float sampler over a whole scene.

    Returns a :class:`SpikeTrain` with ``spikes (T, S, H, W) int8`` (S = 1 for FSM).
    ``engine`` is ``"fused"`` (numba, default) or ``"numpy"`` (the reference); both give
    the same spikes. For long runs use :func:`stream_float`.
    """
    check_engine(engine)
    require_spike_memory(scene, config.spec.num_scales)
    sink = ArraySink()
    train = stream_float(scene, config, sink, engine=engine, progress=progress,
                         block_steps=block_steps)
    train.spikes = sink.spikes
    return train
