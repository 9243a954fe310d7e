"""The fused numba float sampler against the numpy reference engine: identical spikes."""

from pathlib import Path

import numba
import numpy as np
import pytest

from rvsm.model.kernels.filtering import receptive_field_sums
from rvsm.model.kernels.orbits import kernel_orbits, orbit_receptive_sums
from rvsm.model.kernels.receptive_fields import MODEL_NAMES, model_spec
from rvsm.model.noise.sensor import NoiseParams
from rvsm.model.sampling import kernel_generator
from rvsm.model.sampling.config import SamplerConfig
from rvsm.model.sampling.fused import filter_frames, view_spans
from rvsm.model.sampling.twin import sample, stream_float
from rvsm.model.scene.library import RENDER_BATCH, builtin_scene
from rvsm.model.scene.scene import Scene
from rvsm.model.spikes.sinks import ArraySink, CountSink

ROOT = Path(__file__).resolve().parents[3]


def _scene(seed=11, shape=(4, 23, 17), m=5, hold=False):
    rng = np.random.default_rng(seed)
    return Scene("t", rng.uniform(0, 255, shape), m, hold)


@pytest.mark.parametrize("model", MODEL_NAMES)
@pytest.mark.parametrize("noisy", [False, True])
@pytest.mark.parametrize("reset", ["zero", "subtract"])
def test_fused_equals_numpy_engine(model, noisy, reset):
    scene = _scene()
    config = SamplerConfig(model=model, phi=180.0, reset=reset,
                           noise=NoiseParams(k=3.0, seed=5) if noisy else None)
    ref = sample(scene, config, engine="numpy").spikes
    fused = sample(scene, config).spikes
    np.testing.assert_array_equal(fused, ref)
    assert np.count_nonzero(ref) > 0
    if model in ("dog3", "dog4"):
        assert (ref < 0).any()  # the signed path is exercised


def test_fsm_on_a_rendered_scene_runs_in_view_spans_and_equals_numpy_engine():
    # 2.5 batches of frames, chunks of 40 steps: spans cut at every batch's last frame
    scene = builtin_scene("flyball", size=(6, 9), num_frames=5 * RENDER_BATCH // 2,
                          steps_per_frame=3)
    spans = view_spans(scene, 40, 80)
    assert spans[0][0] == 40 and spans[-1][1] == 80 and len(spans) > 1
    assert all(a[1] == b[0] for a, b in zip(spans[:-1], spans[1:], strict=True))
    for u0, u1 in view_spans(scene, 0, scene.num_steps):
        f0, f1 = scene.frame_span(u0, u1)
        assert f0 // RENDER_BATCH == (f1 - 1) // RENDER_BATCH or f1 - f0 == 2
    assert view_spans(_scene(), 0, 15) == [(0, 15)]  # in-memory frames: one range
    for reset in ("zero", "subtract"):
        config = SamplerConfig(model="fsm", phi=40.0, reset=reset)
        ref = sample(scene, config, engine="numpy").spikes
        sink = ArraySink()
        stream_float(scene, config, sink, chunk_steps=40)
        np.testing.assert_array_equal(sink.spikes, ref)
        assert np.count_nonzero(ref) > 0


def test_hold_mode_per_scale_thresholds_and_zero_thresholds():
    scene = _scene(seed=2, m=7, hold=True)
    for config in (
        SamplerConfig(model="gauss3", scale_phi=(90.0, 300.0, 700.0)),
        # k = 60: many fixed-pattern thresholds clip to 0, where +1 must win.
        SamplerConfig(model="dog2", phi=20.0, noise=NoiseParams(k=60.0, seed=1)),
    ):
        np.testing.assert_array_equal(sample(scene, config).spikes,
                                      sample(scene, config, engine="numpy").spikes)


def test_tiles_chunks_and_threads_do_not_change_spikes():
    scene = _scene(seed=3, shape=(5, 29, 21), m=6)
    config = SamplerConfig(model="dog4", phi=150.0, noise=NoiseParams(k=2.0, seed=8))
    ref = sample(scene, config, engine="numpy").spikes
    before = numba.get_num_threads()
    try:
        for threads in (1, numba.config.NUMBA_NUM_THREADS):
            numba.set_num_threads(threads)
            for tile, chunk in ((1, 1), (4, 7), (29, 24), (64, 1000)):
                sink = ArraySink()
                stream_float(scene, config, sink, chunk_steps=chunk, tile_rows=tile)
                np.testing.assert_array_equal(sink.spikes, ref)
    finally:
        numba.set_num_threads(before)


def test_numpy_engine_streams_too_and_counts():
    scene = _scene(seed=4)
    config = SamplerConfig(model="gauss2", noise=NoiseParams(seed=2))
    sink, counts = ArraySink(), CountSink()
    train = stream_float(scene, config, sink, chunk_steps=4, engine="numpy")
    assert train.spikes is None and train.meta["model"] == "gauss2"
    stream_float(scene, config, counts, chunk_steps=3)
    assert counts.spikes == np.count_nonzero(sink.spikes)
    assert counts.steps == scene.num_steps


def test_orbit_sums_match_the_numpy_order_and_the_filter():
    rng = np.random.default_rng(0)
    frames = rng.uniform(0, 255, (3, 14, 19))
    for model in ("dog4", "gauss4", "fsm"):
        kernels = model_spec(model).kernels()
        ref = orbit_receptive_sums(frames, kernels)
        _, weights, halves, lmax = kernel_orbits(kernels)
        if lmax:
            for tile in (1, 5, 32):
                np.testing.assert_array_equal(
                    filter_frames(frames, weights, halves, lmax, tile_rows=tile), ref)
        # The same sums as scipy's correlation, up to float rounding.
        np.testing.assert_allclose(ref, receptive_field_sums(frames, kernels),
                                   rtol=1e-12, atol=1e-9)


def test_generated_orbit_kernels_are_up_to_date():
    text = (ROOT / "model" / "sampling" / "orbit_kernels.py").read_text()
    assert text == kernel_generator.generate()
    text = (ROOT / "model" / "events" / "ladder_kernels.py").read_text()
    assert text == kernel_generator.generate_events()


def test_kernel_generator_writes_both_files(tmp_path):
    """``python -m rvsm.model.sampling.kernel_generator`` writes what the test above
    compares, under the package folder it is given."""
    for folder in ("sampling", "events"):
        (tmp_path / folder).mkdir()
    written = kernel_generator.write_kernels(tmp_path)
    assert written == [tmp_path / "sampling" / "orbit_kernels.py",
                       tmp_path / "events" / "ladder_kernels.py"]
    assert written[0].read_text() == kernel_generator.generate()
    assert written[1].read_text() == kernel_generator.generate_events()


def test_bad_engine_and_chunking_are_refused():
    from rvsm.model.infra.errors import RvsmError

    scene = _scene()
    with pytest.raises(RvsmError, match="engine"):
        sample(scene, SamplerConfig(model="fsm"), engine="gpu")
    with pytest.raises(RvsmError, match="chunk_steps"):
        stream_float(scene, SamplerConfig(model="fsm"), ArraySink(), chunk_steps=0)


@pytest.mark.parametrize("model", ["fsm", "dog2"])
def test_fused_engines_refuse_steps_past_the_scene(model) -> None:
    """The fused kernels (float and fixed) index frames unchecked: a range past the
    scene's steps, or one that does not continue the last, is refused."""
    from rvsm.model.fixed.design_point import default_design_point
    from rvsm.model.fixed.fused import FusedFixedTwin
    from rvsm.model.sampling.config import accumulator_thresholds
    from rvsm.model.sampling.fused import FusedFloatSampler

    scene = builtin_scene("flyball", size=(8, 12), num_frames=2)
    config = SamplerConfig(model)
    point = default_design_point().with_size(8, 12)
    engines = [FusedFloatSampler(scene, config, accumulator_thresholds(config, scene.shape)),
               FusedFixedTwin(scene, point, point.integer_thresholds())]
    for engine in engines:
        with pytest.raises(ValueError, match="past the scene"):
            engine.run(0, scene.num_steps + 1)
        with pytest.raises(ValueError, match="consecutive"):
            engine.run(1, 2)
        assert engine.run(0, scene.num_steps).shape[0] == scene.num_steps
