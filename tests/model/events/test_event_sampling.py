"""The event sensor's float model (SPEC section 7, :mod:`rvsm.model.events`): a
hand-computed plain DVS, RVSM-DVS references and integrability, the fused engine against
the numpy reference (bit-identical for every chunking, tile height, thread count, model and
noise), validation."""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest

from rvsm.model.events.config import EventConfig, contrast_thresholds
from rvsm.model.events.fused import FusedEventSampler
from rvsm.model.events.numpy_engine import log_brightness
from rvsm.model.events.twin import sample_events
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.orbits import orbit_receptive_sums
from rvsm.model.noise.sensor import NoiseParams
from rvsm.model.scene.loaders import load_scene
from rvsm.model.scene.scene import Scene


def test_plain_dvs_by_hand() -> None:
    """One pixel steps from I = 0 to I = e^0.5 - 1 (L 0 -> 0.5) and back: with C = 0.2
    it fires ON, ON at the next two steps (at most one a step; the reference moves by
    exactly C to 0.4), then OFF, OFF when it returns to 0 (reference 0.4 -> 0.2 -> 0.0);
    the first step only captures the reference."""
    bright = math.exp(0.5) - 1.0
    frames = np.zeros((4, 3, 3))
    frames[1:3, 1, 1] = bright
    scene = Scene("step", frames, steps_per_frame=3, hold=True)
    train = sample_events(scene, EventConfig("fsm", contrast=0.2), engine="numpy")
    got = train.events[:, 0, 1, 1].tolist()
    assert got == [0, 0, 0, 1, 1, 0, 0, 0, 0, -1, -1, 0]
    assert np.count_nonzero(train.events) == 4  # no other pixel
    assert np.array_equal(train.references, np.zeros((1, 3, 3)))


def test_rvsm_dvs_references_and_integrability() -> None:
    """References are the responses of step 0; ``R_hat = ref + C * cumsum(events)``
    stays within C of the response wherever no event fired, and every event moves
    toward the response (the stream is integrable)."""
    scene = load_scene("flyball", size=(24, 32), num_frames=5)
    cfg = EventConfig("dog2", scale_contrast=(0.05, 0.1))
    train = sample_events(scene, cfg, engine="numpy")
    kernels = cfg.spec.kernels()
    responses = orbit_receptive_sums(log_brightness(scene, None, 0, scene.num_steps),
                                     kernels)
    assert np.array_equal(train.references, responses[0])
    thr = contrast_thresholds(cfg, scene.shape)
    r_hat = train.references + thr * np.cumsum(train.events, axis=0)
    quiet = train.events == 0
    assert np.all(np.abs(responses - r_hat)[quiet] < thr[None].repeat(len(r_hat), 0)[quiet]
                  + 1e-12)
    fired = ~quiet
    before = r_hat - thr * train.events  # the reference before this step's event
    assert np.all(np.sign(responses - before)[fired] == train.events[fired])
    assert np.count_nonzero(train.events) > 0


@pytest.mark.parametrize("model", ["fsm", "dog1", "dog2", "gauss3", "dog4"])
@pytest.mark.parametrize("noisy", [False, True])
def test_fused_equals_numpy(model: str, noisy: bool) -> None:
    scene = load_scene("flyball", size=(20, 28), num_frames=4)
    cfg = EventConfig(model, noise=NoiseParams(k=4, seed=3) if noisy else None)
    ref = sample_events(scene, cfg, engine="numpy", chunk_steps=30)
    for chunk in (1, 7):
        got = sample_events(scene, cfg, engine="fused", chunk_steps=chunk)
        assert np.array_equal(got.events, ref.events)
        assert np.array_equal(got.references, ref.references)
    assert np.count_nonzero(ref.events) > 0


@pytest.mark.parametrize("noisy", [False, True])
def test_fused_any_tile_height_and_thread_count(noisy: bool) -> None:
    """dog4 (L = 4) on 5 rows (fewer than the 2L + 1 rows a sum reads: zero rows in the
    fused kernel's ring) and on 20 rows, tiles of 1, 3 and 64 rows (odd tiles end with
    a row alone), 1 and 2 threads, two output rows a pass and one."""
    cfg = EventConfig("dog4", noise=NoiseParams(k=4, seed=5) if noisy else None)
    threads = numba.get_num_threads()
    try:
        for size in ((5, 11), (20, 28)):
            scene = load_scene("flyball", size=size, num_frames=3)
            ref = sample_events(scene, cfg, engine="numpy")
            thr = contrast_thresholds(cfg, scene.shape)
            for tile in (1, 3, 64):
                for n in range(1, min(2, numba.config.NUMBA_NUM_THREADS) + 1):
                    numba.set_num_threads(n)
                    for two_rows in (True, False):
                        fused = FusedEventSampler(scene, cfg, thr, tile_rows=tile,
                                                  two_rows=two_rows)
                        assert np.array_equal(fused.run(0, scene.num_steps), ref.events)
                        assert np.array_equal(fused.references, ref.references)
            assert np.count_nonzero(ref.events) > 0
    finally:
        numba.set_num_threads(threads)


def test_noise_adds_events_and_gain_scales_thresholds() -> None:
    """Dark current before the log makes events on a still scene; the thresholds are
    ``theta * C`` (the gain only: a zero-spread gain leaves them at C)."""
    still = Scene("still", np.full((1, 16, 16), 40.0), steps_per_frame=60, hold=True)
    quiet = sample_events(still, EventConfig("fsm"))
    assert np.count_nonzero(quiet.events) == 0
    noisy = sample_events(still, EventConfig("fsm", noise=NoiseParams(k=20, seed=1)))
    assert np.count_nonzero(noisy.events) > 0
    flat = EventConfig("dog2", noise=NoiseParams(k=5, b3=0.0))
    assert np.all(contrast_thresholds(flat, (4, 4)) == 0.2)


def test_bad_configs_are_refused() -> None:
    with pytest.raises(RvsmError, match="contrast threshold"):
        EventConfig("dog2", contrast=0)
    with pytest.raises(RvsmError, match="2 scale"):
        EventConfig("dog2", scale_contrast=(0.1,))
    with pytest.raises(RvsmError, match="per-scale contrast"):
        EventConfig("dog2", scale_contrast=(0.1, float("nan")))


def test_fused_refuses_steps_past_the_scene() -> None:
    """The kernel reads frames unchecked: a range past the scene's steps is refused."""
    scene = load_scene("flyball", size=(8, 12), num_frames=2)
    cfg = EventConfig("dog2")
    fused = FusedEventSampler(scene, cfg, contrast_thresholds(cfg, scene.shape))
    with pytest.raises(ValueError, match="past the scene"):
        fused.run(0, scene.num_steps + 1)
    assert fused.run(0, scene.num_steps).shape[0] == scene.num_steps
