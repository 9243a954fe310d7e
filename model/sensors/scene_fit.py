"""Does a scene fit a file's spikes or events, and if not, which options make it fit.

A scene of ``F`` frames and ``m`` steps a frame has ``T = (F - 1) m`` steps (``F m``
held); a file of ``T`` steps fits the scene shaped by ``--frames`` and
``--steps-per-frame`` values that give ``T``: :func:`matching_options` names them,
keeping one of the two where it can. :func:`check_scene_fits` refuses a scene that does
not fit, naming them.
"""

from __future__ import annotations

from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.scene import Scene

__all__ = ["check_scene_fits", "matching_options"]


def matching_options(num_steps: int, scene: Scene) -> list[str]:
    """``--frames`` / ``--steps-per-frame`` settings giving ``num_steps`` steps for
    ``scene`` (its hold mode kept): the frames for its steps a frame, the steps a frame
    for its frames, else both (the divisor of ``T`` nearest its steps a frame)."""
    t, f, m = int(num_steps), scene.num_frames, scene.steps_per_frame
    extra = 0 if scene.hold else 1  # T = (F - extra) m
    if t < 1:
        return []
    found = []
    if t % m == 0:
        found.append(f"--frames {t // m + extra}")
    if f - extra >= 1 and t % (f - extra) == 0:
        found.append(f"--steps-per-frame {t // (f - extra)}")
    if not found:  # both: the divisor of T nearest the scene's steps a frame
        near = min((d for d in range(1, t + 1) if t % d == 0), key=lambda d: abs(d - m))
        found.append(f"--frames {t // near + extra} --steps-per-frame {near}")
    return found


def check_scene_fits(scene: Scene, shape: tuple[int, int, int, int],
                     what: str = "spikes", imported: bool = False) -> None:
    """Refuse, naming the options that fix it, a scene shaped unlike the file's
    ``(T, S, H, W)`` ``what`` (``"spikes"`` or ``"events"``); ``imported``: the file
    came from another tool, whose step count ends at its last event (``--steps`` of
    ``rvsm events import`` sets it)."""
    t, _, h, w = (int(v) for v in shape)
    if scene.shape == (h, w) and scene.num_steps == t:
        return
    if scene.shape != (h, w):
        fix = f"pass --size {h}x{w}"
    else:
        options = matching_options(t, scene)
        rule = "frames x steps" if scene.hold else "(frames - 1) x steps"
        fix = f"pass {' or '.join(options)} ({rule} per frame = {t} steps)"
        if imported and scene.num_steps > t:
            fix += (f", or import it again with --steps {scene.num_steps} if the recording "
                    "ran on after its last event")
    raise RvsmError(f"{what} {tuple(int(v) for v in shape)} do not match scene "
                    f"{scene.name!r} ({scene.num_steps} steps of {scene.shape[0]}x"
                    f"{scene.shape[1]}: {scene.num_frames} frames, {scene.steps_per_frame} "
                    f"steps per frame{', held' if scene.hold else ''}); {fix}")
