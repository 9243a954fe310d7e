"""A scene cut to its first steps (``--steps N`` of ``rvsm stimulus``): the same
brightness, fewer steps (:func:`scene_steps`, checked; :func:`first_steps`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.scene import Scene

__all__ = ["first_steps", "scene_steps"]


def scene_steps(scene: Scene, num_steps: int | None) -> Scene:
    """``scene`` cut to its first ``num_steps`` steps (checked)."""
    if num_steps is not None:
        if isinstance(num_steps, bool) or int(num_steps) < 1:
            raise RvsmError(f"number of steps must be an integer >= 1, got {num_steps!r}")
        if num_steps > scene.num_steps:
            raise RvsmError(f"--steps {num_steps} is more than the {scene.num_steps} steps of "
                            f"scene {scene.name!r}; ask for at most {scene.num_steps}")
        if num_steps < scene.num_steps:
            scene = first_steps(scene, int(num_steps))
    return scene


@dataclass(frozen=True)
class _StepFrames:
    """A frame per step: the brightness of ``scene``'s first ``steps`` steps, read on
    demand (a scene of them, held for one step each, has exactly those steps)."""

    scene: Scene
    steps: int

    @property
    def shape(self) -> tuple[int, int, int]:
        return (self.steps, *self.scene.shape)

    def frame_range(self, f0: int, f1: int) -> np.ndarray:
        return self.scene.brightness(f0, f1)


def first_steps(scene: Scene, steps: int) -> Scene:
    """A scene whose steps are the first ``steps`` of ``scene`` (same brightness)."""
    m = scene.steps_per_frame
    if scene.hold:
        frames = scene.frame_range(0, -(-steps // m))
        out = Scene(scene.name, frames, m, True, scene.source)
    else:
        frames = scene.frame_range(0, -(-steps // m) + 1)
        out = Scene(scene.name, frames, m, False, scene.source)
    if out.num_steps == steps:
        return out
    return Scene(scene.name, _StepFrames(out, steps), 1, True, scene.source)
