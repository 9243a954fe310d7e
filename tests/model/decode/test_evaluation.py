"""The shared evaluation API: warm-up, scored steps, evaluate_spikes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rvsm.model.decode.evaluation import (
    evaluate_spikes,
    reconstruct_for_display,
    scored_steps,
    warmup_steps,
)
from rvsm.model.infra.errors import RvsmError
from rvsm.model.sampling.config import SamplerConfig
from rvsm.model.sampling.twin import sample
from rvsm.model.scene.scene import Scene


def _ramp_scene(num_frames=6, m=10, shape=(20, 24)) -> Scene:
    base = np.linspace(40, 200, shape[1])[None, :] * np.ones(shape)
    frames = np.stack([np.roll(base, i, axis=1) for i in range(num_frames)])
    return Scene("ramp", frames, steps_per_frame=m)


def test_warmup_and_scored_steps():
    scene = _ramp_scene()
    b = np.percentile(scene.frames[0], 5)
    assert warmup_steps(scene, 400.0) == min(2 * math.ceil(400 / b), scene.num_steps // 2)
    assert warmup_steps(scene, [100.0, 400.0]) == warmup_steps(scene, 400.0)
    steps = scored_steps(scene, 400.0)
    assert np.all(steps % scene.steps_per_frame == 0)
    assert steps.min() >= warmup_steps(scene, 400.0)
    dark = Scene("dark", np.zeros((3, 8, 8)), steps_per_frame=4)
    assert warmup_steps(dark, 400.0) == dark.num_steps // 2  # capped
    assert scored_steps(dark, 400.0, stride=100).tolist() == [dark.num_steps - 1]
    truth = scene.brightness()
    assert warmup_steps(truth, 400.0) == warmup_steps(scene, 400.0)


def test_evaluate_spikes_keys_and_quality():
    scene = _ramp_scene()
    for model in ("fsm", "dog2", "gauss3"):
        train = sample(scene, SamplerConfig(model=model))
        res = evaluate_spikes(train, scene, model, train.config.phis)
        assert set(res) == {"mse", "psnr", "ssim", "num_scored", "warmup", "method"}
        assert res["method"] == ("tfi" if model == "fsm" else "rvsm")
        assert res["num_scored"] == len(scored_steps(scene, 400.0))
        assert res["psnr"] > 15 and 0 < res["ssim"] <= 1
    res = evaluate_spikes(train.spikes, scene, "gauss3", train.config.phis, match="affine",
                          steps=[30, 40])
    assert res["num_scored"] == 2


def test_fsm_on_constant_scene_is_near_exact():
    scene = Scene("flat", np.full((1, 16, 16), 100.0), steps_per_frame=80, hold=True)
    train = sample(scene, SamplerConfig(model="fsm"))
    res = evaluate_spikes(train.spikes, scene, "fsm", 400.0)
    assert res["mse"] == pytest.approx(0.0, abs=1e-9)
    truth, recon = reconstruct_for_display(train.spikes, scene, "fsm", 400.0, [10, 70])
    assert truth.shape == recon.shape == (2, 16, 16)


def test_shape_mismatch_is_a_user_error():
    scene = _ramp_scene()
    spikes = np.zeros((scene.num_steps, 2) + scene.shape, dtype=np.int8)
    with pytest.raises(RvsmError):
        evaluate_spikes(spikes, scene, "dog3", 400.0)
    with pytest.raises(RvsmError):
        evaluate_spikes(spikes[:-1], scene, "dog2", 400.0)
