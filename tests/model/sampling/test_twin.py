import numpy as np
import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.receptive_fields import MODEL_NAMES, dog_kernel
from rvsm.model.noise.sensor import NoiseParams
from rvsm.model.sampling.config import SamplerConfig
from rvsm.model.sampling.reference import reference_sample
from rvsm.model.sampling.twin import sample
from rvsm.model.scene.scene import Scene


def _scene(frames, m=4, hold=False):
    return Scene("test", np.asarray(frames, dtype=np.float64), m, hold)


@pytest.mark.parametrize("model", MODEL_NAMES)
@pytest.mark.parametrize("noisy", [False, True])
@pytest.mark.parametrize("reset", ["zero", "subtract"])
def test_fast_sampler_equals_spec_transcription(model, noisy, reset):
    """Vectorised sampler == literal SPEC equations, spike for spike, on random scenes."""
    rng = np.random.default_rng(11)
    scene = _scene(rng.uniform(0, 255, (4, 11, 14)), m=5)
    noise = NoiseParams(k=3.0, seed=5) if noisy else None
    config = SamplerConfig(model=model, phi=180.0, reset=reset, noise=noise)
    fast = sample(scene, config, block_steps=3).spikes
    assert fast.dtype == np.int8 and fast.shape == (15, config.spec.num_scales, 11, 14)
    np.testing.assert_array_equal(fast, reference_sample(scene, config))
    assert np.count_nonzero(fast) > 0


def test_fsm_hand_computed():
    # Brightness 100 with phi 250: acc 100, 200, 300 -> spike at step 2 (0-based), reset to 0.
    scene = _scene(np.full((2, 1, 1), 100.0), m=8)
    spikes = sample(scene, SamplerConfig(model="fsm", phi=250)).spikes[:, 0, 0, 0]
    np.testing.assert_array_equal(spikes, [0, 0, 1, 0, 0, 1, 0, 0])
    sub = sample(scene, SamplerConfig(model="fsm", phi=250, reset="subtract")).spikes
    # subtract keeps the remainder: 100,200,300->50,150,250->0,100,200,300->50
    np.testing.assert_array_equal(sub[:, 0, 0, 0], [0, 0, 1, 0, 1, 0, 0, 1])


def test_spike_exactly_at_threshold():
    scene = _scene(np.full((2, 2, 3), 100.0), m=4)
    spikes = sample(scene, SamplerConfig(model="fsm", phi=400)).spikes
    # 4 x 100 == 400 exactly: fires at step 3 (acc >= phi).
    np.testing.assert_array_equal(spikes[:, 0, 0, 0], [0, 0, 0, 1])
    assert (spikes[3] == 1).all()


def test_negative_spike_at_negative_threshold():
    # A bright pixel on black: the DoG accumulators next to it see a negative drive.
    frames = np.zeros((2, 5, 5))
    frames[:, 2, 2] = 200.0
    scene = _scene(frames, m=50)
    config = SamplerConfig(model="dog2", phi=100.0)
    spikes = sample(scene, config).spikes
    k = dog_kernel(0.348, 2)
    assert k[1, 2] < 0
    drive = k[1, 2] * 200.0  # scale 1 at (1, 2) sees the pixel through K(+1, 0)
    first = int(np.ceil(-100.0 / drive)) - 1
    assert spikes[first, 1, 1, 2] == -1
    assert (spikes[:first, 1, 1, 2] == 0).all()
    assert (spikes[:, 0, 2, 2] >= 0).all()


def test_zero_padding_at_borders():
    """A uniform scene: a corner accumulator sees only the in-array part of its kernel."""
    scene = _scene(np.full((2, 9, 9), 50.0), m=1)
    config = SamplerConfig(model="gauss4", phi=1e9)
    from rvsm.model.sampling.numpy_engine import iter_step_drives

    _, drive = next(iter_step_drives(scene, config))
    k = config.spec.kernels()[3]
    assert drive[3, 0, 0] == pytest.approx(50.0 * k[4:, 4:].sum())
    assert drive[3, 4, 4] == pytest.approx(50.0 * k.sum())
    assert drive[3, 0, 0] < drive[3, 4, 4]


def test_hold_and_interpolation_feed_the_sampler():
    frames = np.array([[[0.0]], [[100.0]]])
    lin = sample(_scene(frames, m=4), SamplerConfig(model="fsm", phi=25)).spikes[:, 0, 0, 0]
    # linear: I = 0, 25, 50, 75 -> acc 0, 25(spike), 50(spike), 75(spike)
    np.testing.assert_array_equal(lin, [0, 1, 1, 1])
    held = sample(_scene(frames, m=2, hold=True), SamplerConfig(model="fsm", phi=25)).spikes
    np.testing.assert_array_equal(held[:, 0, 0, 0], [0, 0, 1, 1])


def test_seeded_determinism_and_block_independence():
    rng = np.random.default_rng(3)
    scene = _scene(rng.uniform(0, 255, (3, 8, 10)), m=6)
    config = SamplerConfig(model="dog4", noise=NoiseParams(k=2.0, seed=9))
    a = sample(scene, config, block_steps=1).spikes
    b = sample(scene, config, block_steps=64).spikes
    np.testing.assert_array_equal(a, b)
    other = sample(scene, SamplerConfig(model="dog4", noise=NoiseParams(k=2.0, seed=10))).spikes
    assert not np.array_equal(a, other)


def test_nested_ladders_share_the_first_scale():
    rng = np.random.default_rng(4)
    scene = _scene(rng.uniform(0, 255, (3, 8, 10)), m=6)
    noise = NoiseParams(k=1.0, seed=2)
    one = sample(scene, SamplerConfig(model="dog1", noise=noise)).spikes
    four = sample(scene, SamplerConfig(model="dog4", noise=noise)).spikes
    np.testing.assert_array_equal(one[:, 0], four[:, 0])


def test_per_scale_thresholds():
    rng = np.random.default_rng(5)
    scene = _scene(rng.uniform(50, 255, (3, 6, 6)), m=6)
    base = sample(scene, SamplerConfig(model="gauss2", scale_phi=(400, 400))).spikes
    high = sample(scene, SamplerConfig(model="gauss2", scale_phi=(400, 4000))).spikes
    np.testing.assert_array_equal(base[:, 0], high[:, 0])
    assert np.abs(high[:, 1]).sum() < np.abs(base[:, 1]).sum()


@pytest.mark.parametrize("kwargs,match", [
    ({"phi": 0}, "phi"), ({"phi": -3}, "phi"), ({"phi": float("nan")}, "phi"),
    ({"model": "dog9"}, "unknown model"), ({"reset": "hold"}, "reset"),
    ({"model": "dog2", "scale_phi": (1.0,)}, "2 scale"),
    ({"model": "dog2", "scale_phi": (1.0, -1.0)}, "per-scale"),
])
def test_invalid_configs_are_refused(kwargs, match):
    with pytest.raises(RvsmError, match=match):
        SamplerConfig(**kwargs)


def test_meta_says_how_to_reload_the_scene():
    from rvsm.model.scene.loaders import load_scene

    scene = load_scene("coin", size=(12, 16), num_frames=3, steps_per_frame=4)
    meta = sample(scene, SamplerConfig(model="fsm")).meta
    assert {k: meta[k] for k in ("scene_arg", "height", "width", "num_frames",
                                 "steps_per_frame", "hold")} == {
        "scene_arg": "coin", "height": 12, "width": 16, "num_frames": 3,
        "steps_per_frame": 4, "hold": False}
    again = load_scene(meta["scene_arg"], size=(meta["height"], meta["width"]),
                       num_frames=meta["num_frames"], steps_per_frame=meta["steps_per_frame"])
    assert np.array_equal(again.frames, scene.frames)


def test_lazy_scene_chunked_equals_eager_scene_whole():
    """A built-in scene rendered a range at a time, run in chunks of any length on any
    engine and thread count, gives the spikes of its whole in-memory frames run at once."""
    import numba

    from rvsm.model.sampling.twin import stream_float
    from rvsm.model.scene.library import builtin_scene, render_frames
    from rvsm.model.spikes.sinks import ArraySink

    size, count, m = (21, 26), 9, 5
    lazy = builtin_scene("flyball", size, count, steps_per_frame=m)
    eager = Scene("flyball", render_frames("flyball", size, count), m)
    config = SamplerConfig(model="dog4", phi=150.0, noise=NoiseParams(k=2.0, seed=8))
    whole = sample(eager, config).spikes
    assert whole.shape[0] == (count - 1) * m and np.count_nonzero(whole) > 0
    before = numba.get_num_threads()
    try:
        for threads in (1, numba.config.NUMBA_NUM_THREADS):
            numba.set_num_threads(threads)
            for engine, chunk in (("fused", 1), ("fused", 7), ("fused", 13), ("numpy", 6)):
                sink = ArraySink()
                stream_float(lazy, config, sink, chunk_steps=chunk, engine=engine,
                             block_steps=4)
                np.testing.assert_array_equal(sink.spikes, whole, err_msg=f"{engine} {chunk}")
    finally:
        numba.set_num_threads(before)
