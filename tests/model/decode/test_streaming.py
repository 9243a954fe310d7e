"""Streaming evaluation equals the whole-array evaluation, for any chunk length."""

import numpy as np
import pytest

from rvsm.model.decode.evaluation import evaluate_spikes
from rvsm.model.decode.streaming import evaluate_source
from rvsm.model.noise.sensor import NoiseParams
from rvsm.model.sampling.config import SamplerConfig
from rvsm.model.sampling.twin import sample
from rvsm.model.scene.library import builtin_scene
from rvsm.model.sensors.files import open_spikes
from rvsm.model.spikes.files import write_spikes
from rvsm.model.spikes.source import array_source


@pytest.fixture(scope="module")
def scene():
    return builtin_scene("flyball", size=(32, 48), num_frames=9)


@pytest.mark.parametrize("model,method", [("fsm", "tfi"), ("fsm", "tfp"), ("dog2", "rvsm"),
                                          ("dog2", "inverse")])
def test_chunked_equals_whole(scene, tmp_path, model, method):
    config = SamplerConfig(model=model, noise=NoiseParams(seed=1))
    spikes = sample(scene, config).spikes
    whole = evaluate_spikes(spikes, scene, model, config.phis, method=method)
    for chunk in (1, 6, 37, 10_000):
        got = evaluate_source(array_source(spikes), scene, model, config.phis,
                              method=method, chunk_steps=chunk)
        assert got == whole
    path = tmp_path / "s.h5"
    write_spikes(path, spikes, {})
    with open_spikes(path) as src:
        assert evaluate_source(src, scene, model, config.phis, method=method,
                               chunk_steps=13) == whole


def test_tfi_look_ahead_crosses_chunk_borders(scene):
    # Sparse spikes: most intervals span many chunks of 3 steps.
    t, h, w = scene.num_steps, *scene.shape
    spikes = np.zeros((t, 1, h, w), dtype=np.int8)
    rng = np.random.default_rng(5)
    for y in range(h):
        for x in range(w):
            spikes[rng.choice(t, size=3, replace=False), 0, y, x] = 1
    spikes[:, 0, 0, :4] = 0  # never-spiking pixels
    steps = np.arange(0, t, 4)
    whole = evaluate_spikes(spikes, scene, "fsm", [400.0], method="tfi", steps=steps)
    got = evaluate_source(array_source(spikes), scene, "fsm", [400.0], method="tfi",
                          steps=steps, chunk_steps=3)
    assert got == whole
