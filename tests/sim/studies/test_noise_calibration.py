"""The ``paper`` noise preset: the calibration rule on synthetic drops and tiny scenes, and
that the preset reaches the samplers."""

import numpy as np
import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.model.noise.presets import NOISE_PRESETS, PAPER_K, preset_noise
from rvsm.model.noise.sensor import NoiseParams
from rvsm.model.scene.library import builtin_scene
from rvsm.sim.studies.noise_calibration import (
    PAPER_FSM_SSIM_CLEAN,
    PAPER_FSM_SSIM_NOISY,
    calibrate_k,
    closest_k,
    fsm_ssim_drop,
    paper_fsm_ssim_drop,
)


def test_paper_target_from_table_1():
    assert len(PAPER_FSM_SSIM_CLEAN) == len(PAPER_FSM_SSIM_NOISY) == 6
    # (0.749+0.837+0.881+0.943+0.770+0.801)/6 - (0.346+0.524+0.362+0.438+0.266+0.581)/6
    assert paper_fsm_ssim_drop() == pytest.approx(4.981 / 6 - 2.517 / 6, abs=1e-12)


def test_closest_k_and_ties():
    assert closest_k({1.0: 0.1, 2.0: 0.3, 4.0: 0.5}, 0.32) == 2.0
    assert closest_k({2.0: 0.3, 1.0: 0.5}, 0.4) == 1.0  # tie -> smaller k
    with pytest.raises(RvsmError):
        closest_k({}, 0.4)


def test_calibrate_k_bisects_the_bracket():
    calls = []

    def drop(k):  # monotone, D(k) = 0.05 k: target 0.41 at k = 8.2
        calls.append(k)
        return 0.05 * k

    k, drops = calibrate_k(drop, 0.41, grid=(1, 4, 16), refine=3)
    assert calls[:3] == [1.0, 4.0, 16.0]
    assert calls[3:] == [10.0, 7.0, 8.5]  # bisection of the bracket (4, 16)
    assert k == 8.5 and set(drops) == set(calls)
    # no bracket: the closest grid point, no refinement
    k, drops = calibrate_k(lambda k: 0.01 * k, 0.41, grid=(1, 2), refine=5)
    assert k == 2.0 and len(drops) == 2


def test_measured_drop_grows_with_k_on_tiny_scenes():
    scenes = [builtin_scene(n, size=(24, 32), num_frames=4, steps_per_frame=10)
              for n in ("teapot", "coin")]
    d1 = fsm_ssim_drop(scenes, 1.0)
    d8 = fsm_ssim_drop(scenes, 8.0)
    assert 0 < d1 < d8 < 1
    k, drops = calibrate_k(lambda k: fsm_ssim_drop(scenes, k), d8 - 1e-9, grid=(1.0, 8.0),
                           refine=0)
    assert k == 8.0 and drops[8.0] == pytest.approx(d8)


def test_presets():
    assert preset_noise("spec", seed=3) == NoiseParams(k=1.0, seed=3)
    assert preset_noise("paper") == NoiseParams(k=PAPER_K, seed=0)
    assert NOISE_PRESETS["paper"] == PAPER_K > 1
    with pytest.raises(RvsmError, match="unknown noise preset"):
        preset_noise("loud")
    assert np.isfinite(PAPER_K)
