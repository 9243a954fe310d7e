"""The response-time threshold rule: hand-computed uniform scene, oracle against the
sampler's first spikes, and the refused cases."""

import numpy as np
import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.receptive_fields import model_spec
from rvsm.model.sampling.config import SamplerConfig
from rvsm.model.sampling.thresholds import (
    calibration_thresholds,
    first_spike_steps,
    fsm_response_time,
    median_levels,
    response_thresholds,
    response_time,
    rule_thresholds,
)
from rvsm.model.sampling.twin import sample
from rvsm.model.scene.library import builtin_scene
from rvsm.model.scene.scene import Scene

# SPEC section 2 check values: sums of the normalised DoG kernels.
DOG_SUMS = (0.842416, 0.326844, 0.036321, 0.000367)


def _uniform(value=100.0, size=40, steps=20):
    return Scene("flat", np.full((1, size, size), value), steps_per_frame=steps, hold=True)


def test_uniform_scene_by_hand():
    # FSM: 100 per step reaches 400 after exactly 4 steps on every pixel -> R_FSM = 4,
    # m_FSM = 400. Interior pixels (32x32 of 40x40, the majority) of DoG scale s reach
    # 4 * 100 * sum(K_s), so phi_s = 400 * sum(K_s); Gauss kernels sum to 1 -> 400.
    scene = _uniform()
    assert fsm_response_time(scene) == 4
    dog = np.array(response_thresholds(scene, "dog4"))
    np.testing.assert_allclose(dog / 400.0, DOG_SUMS, rtol=0, atol=5e-7)  # 6-digit values
    kernel_sums = [k.sum() for k in model_spec("dog4").kernels()]
    np.testing.assert_allclose(dog, 400.0 * np.array(kernel_sums), rtol=1e-12)
    np.testing.assert_allclose(response_thresholds(scene, "gauss4"), [400.0] * 4, rtol=1e-12)
    assert response_thresholds(scene, "fsm") == (400.0,)
    assert rule_thresholds("equal", scene, "dog4") is None


def test_first_spike_steps_match_the_sampler():
    scene = builtin_scene("coin", size=(24, 32), num_frames=3, steps_per_frame=8)
    phis = response_thresholds(scene, "dog3")
    spikes = sample(scene, SamplerConfig(model="dog3", scale_phi=phis)).spikes
    fired = spikes != 0
    direct = np.where(fired.any(axis=0), fired.argmax(axis=0) + 1, scene.num_steps + 1)
    np.testing.assert_array_equal(first_spike_steps(scene, "dog3", phis), direct)


@pytest.mark.parametrize("model", ["dog4", "gauss2"])
def test_response_time_not_later_than_fsm(model):
    scene = builtin_scene("driving", size=(30, 40), num_frames=3, steps_per_frame=10)
    r_fsm = fsm_response_time(scene)
    assert response_time(first_spike_steps(scene, "fsm", [400.0]))[0] == r_fsm
    phis = np.array(response_thresholds(scene, model))
    assert np.all(response_time(first_spike_steps(scene, model, phis)) <= r_fsm)
    # m_s is the largest threshold that still responds by R_FSM on half the pixels
    levels = median_levels(scene, model, r_fsm)
    assert np.all(response_time(first_spike_steps(scene, model, levels)) <= r_fsm)
    later = response_time(first_spike_steps(scene, model, levels * (1 + 1e-9)))
    assert np.all(later > r_fsm)
    np.testing.assert_allclose(phis, 400.0 * levels / median_levels(scene, "fsm", r_fsm)[0])


def test_flat_black_and_dark_scenes_are_refused():
    black = Scene("black", np.zeros((1, 16, 16)), steps_per_frame=50, hold=True)
    with pytest.raises(RvsmError, match="fewer than half"):
        response_thresholds(black, "dog2")
    # bright enough for FSM but a DoG scale sees nothing: a kernel of zero sum would;
    # here a scene that is black on more than half the pixels gives zero DoG drive there
    frames = np.zeros((1, 20, 20))
    frames[0, :, :11] = 200.0  # FSM: 11/20 of the pixels fire -> R_FSM defined
    half_dark = Scene("half", frames, steps_per_frame=10, hold=True)
    assert fsm_response_time(half_dark) == 2
    thr = response_thresholds(half_dark, "dog1")
    assert thr[0] > 0
    with pytest.raises(RvsmError, match="unknown threshold rule"):
        rule_thresholds("fastest", half_dark, "dog1")


def test_zero_response_is_refused():
    frames = np.zeros((1, 20, 20))
    frames[0, :, :9] = 200.0  # FSM fires on 9/20 of the columns only: under half
    with pytest.raises(RvsmError, match="no response time"):
        fsm_response_time(Scene("dim", frames, steps_per_frame=10, hold=True))


def test_calibration_thresholds_cached_and_validated():
    a = calibration_thresholds("character", "dog2", 400.0, (24, 32))
    assert a == calibration_thresholds("character", "dog2", 400.0, (24, 32))
    assert len(a) == model_spec("dog2").num_scales
    with pytest.raises(RvsmError, match="not a built-in scene"):
        calibration_thresholds("moon", "dog2", 400.0, (24, 32))
