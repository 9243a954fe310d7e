"""A scene cut to its first steps (model/scene/scene_steps.py): the same brightness step
for step, whether the cut falls on a frame boundary or inside a frame, held or
interpolated; a step count out of range is a one-line refusal."""

from __future__ import annotations

import numpy as np
import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.scene import Scene
from rvsm.model.scene.scene_steps import first_steps, scene_steps


def _scene(hold: bool) -> Scene:
    frames = np.arange(5 * 2 * 3, dtype=np.float64).reshape(5, 2, 3) / 30.0
    return Scene("ramp", frames, 4, hold)


@pytest.mark.parametrize("hold", [True, False])
@pytest.mark.parametrize("steps", [1, 4, 7, 8])
def test_first_steps_keep_the_brightness(hold: bool, steps: int) -> None:
    scene = _scene(hold)
    cut = first_steps(scene, steps)
    assert cut.num_steps == steps
    np.testing.assert_array_equal(cut.brightness(0, steps), scene.brightness(0, steps))


def test_scene_steps_checks_the_count() -> None:
    scene = _scene(True)
    assert scene_steps(scene, None) is scene
    assert scene_steps(scene, scene.num_steps) is scene
    assert scene_steps(scene, 3).num_steps == 3
    for bad in (0, True, scene.num_steps + 1):
        with pytest.raises(RvsmError):
            scene_steps(scene, bad)
