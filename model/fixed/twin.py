"""The fixed twin's run pipeline: a scene through the bit-accurate contract of a design
point (SPEC section 5), either engine, chunk by chunk in time, into a sink.

Per step ``t``: analogue brightness ``I_t`` (+ dark current, when the point has noise) ->
ADC codes (:mod:`.adc`) -> exact integer receptive-field sums with the quantised weights
-> arithmetic right shift -> W-bit saturating accumulators -> compare with each
accumulator's integer threshold -> spike +1 / -1 -> reset (:mod:`.core`). The noise comes
from the same :class:`~rvsm.model.noise.sensor.NoiseSource` (same seed, same streams) as
the float twin, so float and fixed see identical analogue noise.

Two engines with identical spikes and statistics: ``"fused"`` (default; numba, the time
loop inside, :mod:`.fused`) and ``"numpy"`` (vectorised, :mod:`.numpy_engine`). The
spikes are exactly ``point.contract().run(codes, thresholds)``; the results are
:mod:`.results`. :func:`simulate_fixed` is the whole-array form of :func:`stream_fixed`.
"""

from __future__ import annotations

import numpy as np

from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.fused import FusedFixedTwin
from rvsm.model.fixed.numpy_engine import NumpyFixedTwin
from rvsm.model.fixed.results import FixedRun, FixedStats, fixed_meta
from rvsm.model.infra.memory import require_spike_memory
from rvsm.model.infra.progress import progress_bar
from rvsm.model.sampling.config import (
    DEFAULT_BLOCK_STEPS,
    DEFAULT_CHUNK_STEPS,
    check_chunking,
    check_engine,
)
from rvsm.model.sampling.fused import DEFAULT_TILE_ROWS
from rvsm.model.scene.scene import Scene
from rvsm.model.spikes.sinks import ArraySink, SpikeSink, chunk_target, fill_sink


def fit_point(scene: Scene, point: DesignPoint) -> DesignPoint:
    """``point`` sized to the scene: the array follows the scene's ``(H, W)``."""
    return point if scene.shape == point.shape else point.with_size(*scene.shape)


def make_twin(scene: Scene, point: DesignPoint, thresholds: np.ndarray, engine: str = "fused",
              tile_rows: int = DEFAULT_TILE_ROWS, ranges: bool = False,
              block_steps: int = DEFAULT_BLOCK_STEPS, keep_codes: bool = False,
              histograms: bool = False) -> FusedFixedTwin | NumpyFixedTwin:
    """The engine that runs ``point`` on ``scene`` (arguments as :func:`stream_fixed`):
    the fused twin when ``engine == "fused"`` and neither codes nor histograms are kept,
    for a sensor the fused engine runs (``point.rules.fused_twin``: the spike camera);
    otherwise the numpy engine (the event sensor has no fused kernel)."""
    if engine == "fused" and not keep_codes and not histograms and point.rules.fused_twin:
        return FusedFixedTwin(scene, point, thresholds, tile_rows, ranges)
    return NumpyFixedTwin(scene, point, thresholds, block_steps, keep_codes, histograms)


def stream_fixed(
    scene: Scene,
    point: DesignPoint,
    sink: SpikeSink,
    chunk_steps: int = DEFAULT_CHUNK_STEPS,
    engine: str = "fused",
    tile_rows: int = DEFAULT_TILE_ROWS,
    progress: bool = False,
    ranges: bool = False,
    block_steps: int = DEFAULT_BLOCK_STEPS,
    keep_codes: bool = False,
    histograms: bool = False,
) -> FixedRun:
    """Run the fixed twin of ``point`` over ``scene`` chunk by chunk into ``sink``.

    Returns a :class:`~.results.FixedRun` whose ``spikes`` is ``None`` (they went to the
    sink). A scene whose ``(H, W)`` differs from the point's runs on the same point
    resized to it (:func:`fit_point`); ``meta`` records the size used. The
    saturation counts are always kept; ``ranges=True`` also tracks the min/max datapath
    statistics (``sum_min`` .. ``acc_max``; None otherwise) in the fused engine, at about
    1.1x its time (``make bench``'s ``ranges cost`` line: 1.08x at 250x400 dog4), off by
    default so the default call runs at the benchmark's speed; the numpy engine always
    tracks them. ``keep_codes`` keeps every
    step's ADC codes in ``codes`` (for stimulus files) and ``histograms`` fills the
    profiling histograms; both run the numpy engine (dark current in blocks of
    ``block_steps``). The event sensor's twin (``array.sensor = "dvs"``) runs the numpy
    engine whichever ``engine`` is named: it has no fused kernel yet.
    """
    check_engine(engine)
    check_chunking(chunk_steps, tile_rows)
    point = fit_point(scene, point)
    thresholds = point.integer_thresholds(point.noise_source())
    s_count, (h, w), t_total = point.num_scales, point.shape, scene.num_steps
    shape = (t_total, s_count, h, w)
    twin = make_twin(scene, point, thresholds, engine, tile_rows, ranges, block_steps,
                     keep_codes, histograms)
    buf = np.empty((min(chunk_steps, max(t_total, 1)),) + shape[1:], dtype=np.int8)

    def produce(t0: int, t1: int) -> np.ndarray:
        return twin.run(t0, t1, chunk_target(sink, t0, t1, buf))

    def stats() -> FixedStats:
        return FixedStats(steps=t_total, accumulators=h * w, **twin.stats())

    def final_meta() -> dict:
        return fixed_meta(scene, point, thresholds, stats())

    begin_meta = fixed_meta(scene, point, thresholds, None)
    bar = progress_bar(t_total, f"fixed {point.model} {scene.name}", progress)
    fill_sink(sink, shape, begin_meta, produce, int(chunk_steps), bar, final_meta)
    final = stats()
    codes = twin.codes if isinstance(twin, NumpyFixedTwin) else None
    return FixedRun(None, thresholds, point, point.contract(), final,
                    fixed_meta(scene, point, thresholds, final), codes)


def simulate_fixed(
    scene: Scene,
    point: DesignPoint,
    progress: bool = False,
    block_steps: int = DEFAULT_BLOCK_STEPS,
    keep_codes: bool = False,
    histograms: bool = False,
    engine: str = "fused",
    ranges: bool = False,
) -> FixedRun:
    """Run the fixed twin of ``point`` over a whole scene: :func:`stream_fixed` into an
    array, ``spikes (T, S, H, W) int8``; the arguments are :func:`stream_fixed`'s."""
    check_engine(engine)
    require_spike_memory(scene, point.num_scales, 3 if keep_codes else 1)
    sink = ArraySink()
    run = stream_fixed(scene, point, sink, engine=engine, progress=progress, ranges=ranges,
                       block_steps=block_steps, keep_codes=keep_codes, histograms=histograms)
    run.spikes = sink.spikes
    return run
