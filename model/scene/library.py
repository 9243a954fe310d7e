"""Built-in synthetic high-speed scenes in the spirit of the paper's HMD dataset (SPEC §1).

Every scene is rendered from real photographs that scikit-image ships inside its wheel
(``skimage.data``: text, coffee, brick, coins, gravel, chelsea, grass, moon, camera, rocket),
never from noise, and is fully deterministic (no random numbers at all).

Conventions
-----------
- Frames are ``(F, H, W) float64`` brightness in 8-bit units.
- Brightness is mapped to ``[16, 240]``: the dark floor of 16 means that, at the default
  FSM threshold ``phi = 400``, every pixel spikes at least once every ``400 / 16 = 25``
  steps, so reconstructions have no never-spiking pixels; the ceiling keeps headroom
  below 255.
- Motion is defined per *frame* in "reference pixels" (pixels of the default 250 x 400
  canvas) and is at most a few pixels per frame, so with the default 10 steps per frame the
  motion per sampling step is sub-pixel (high-speed sampling). Other sizes render the same
  view, scaled (uniform scale ``s = max(250 / H, 400 / W)``); textures are low-pass filtered
  before minification to avoid aliasing. Motions are bounded or periodic, so any number of
  frames works; the per-frame motion does not depend on ``num_frames``.
- Scenes are rendered on demand, a batch of frames at a time (:class:`RenderedFrames`);
  batches are cached up to a byte budget and returned as read-only arrays.
"""

from __future__ import annotations

import functools
import threading
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.renderers import DEFAULT_SIZE, RENDERERS, Grid, to_brightness
from rvsm.model.scene.scene import DEFAULT_STEPS_PER_FRAME, Scene

DEFAULT_FRAMES: int = 41

_DESCRIPTIONS: dict[str, str] = {
    "character": "a page of printed characters (skimage 'text') rotating uniformly about "
    "the image centre",
    "teapot": "a shaded 3-D sphere wrapped with the 'coffee' photo, spinning about a tilted "
    "axis in front of a brick wall",
    "coin": "a real coin (from 'coins') spinning in-plane while flipping (foreshortening) "
    "and drifting over gravel",
    "grasshopper": "a small textured body (cat fur from 'chelsea') making parabolic jumps, "
    "tilting with its velocity, over grass",
    "flyball": "a fast shaded ball textured with the 'moon' flying along a curve while "
    "spinning and changing depth over the 'camera' photo",
    "driving": "driving: a perspective road (brick) moving toward the viewer under a "
    "panning, slowly zooming skyline ('rocket'), parallax between near and far",
}

SCENE_NAMES: tuple[str, ...] = tuple(_DESCRIPTIONS)


def scene_descriptions() -> dict[str, str]:
    """One-line description of every built-in scene, keyed by name."""
    return dict(_DESCRIPTIONS)


def _check_name(name: str) -> None:
    if name not in RENDERERS:
        raise RvsmError(
            f"unknown scene {name!r}; built-in scenes are: {', '.join(SCENE_NAMES)} "
            "(or give a .npy file, an image folder or a video)"
        )


def _check_size(size: tuple[int, int], num_frames: int) -> tuple[tuple[int, int], int]:
    try:
        h, w = (int(v) for v in size)
    except (TypeError, ValueError):
        raise RvsmError(f"scene size must be (H, W) integers, got {size!r}") from None
    if h < 4 or w < 4 or h > 4096 or w > 4096:
        raise RvsmError(f"scene size must be between 4x4 and 4096x4096, got {h}x{w}")
    if isinstance(num_frames, bool) or int(num_frames) != num_frames or num_frames < 1:
        raise RvsmError(f"number of frames must be an integer >= 1, got {num_frames!r}")
    return (h, w), int(num_frames)


#: Frames rendered per batch: every renderer works frame by frame, so batches bound the
#: rendering's temporary memory (about a dozen batch-sized arrays) without changing a value.
#: Batches always start at multiples of ``RENDER_BATCH``, whether a scene is rendered whole
#: or a range at a time, so both give the same frames bit for bit.
RENDER_BATCH = 16

#: Batch-sized float64 arrays a renderer holds at once, at most (its temporaries).
RENDER_WORKING_ARRAYS = 12

#: Bytes of rendered batches kept for reuse (least recently used dropped first).
RENDER_CACHE_BYTES = 96 << 20


class _BatchCache:
    """Rendered batches ``(n, H, W) float64`` (read-only) keyed by ``(name, size, first
    frame, n)``, at most ``limit`` bytes, least recently used dropped first; thread-safe."""

    def __init__(self, limit: int) -> None:
        self.limit = limit
        self._items: OrderedDict[tuple, np.ndarray] = OrderedDict()
        self._bytes = 0
        self._lock = threading.Lock()

    def get(self, key: tuple, make: Callable[[], np.ndarray]) -> np.ndarray:
        with self._lock:
            hit = self._items.get(key)
            if hit is not None:
                self._items.move_to_end(key)
                return hit
        value = make()
        with self._lock:
            if key not in self._items:
                self._items[key] = value
                self._bytes += value.nbytes
            while self._bytes > self.limit and len(self._items) > 1:
                _, old = self._items.popitem(last=False)
                self._bytes -= old.nbytes
        return value

    def clear(self) -> None:
        with self._lock:
            self._items.clear()
            self._bytes = 0


_BATCHES = _BatchCache(RENDER_CACHE_BYTES)


def _render_batch(name: str, size: tuple[int, int], f0: int, n: int) -> np.ndarray:
    """Frames ``f0 .. f0 + n - 1`` of scene ``name``: ``(n, H, W) float64``, read-only."""
    def make() -> np.ndarray:
        g = Grid(size, n, first=f0)
        out = np.ascontiguousarray(
            to_brightness(np.broadcast_to(RENDERERS[name](g), (n, *size))),
            dtype=np.float64)
        out.setflags(write=False)
        return out

    return _BATCHES.get((name, size, f0, n), make)


@dataclass(frozen=True)
class RenderedFrames:
    """Built-in scene ``name`` at ``size = (H, W)`` with ``num_frames`` frames, rendered a
    range at a time (whole batches of :data:`RENDER_BATCH` frames, cached up to
    :data:`RENDER_CACHE_BYTES`): a :class:`~.frames.FrameSource`. Compares by its fields.
    """

    name: str
    size: tuple[int, int]
    num_frames: int

    #: A range within ``[k B, (k + 1) B)`` is a view of one cached batch (no copy); a
    #: range crossing a multiple of ``B`` is copied. Read by
    #: :meth:`rvsm.model.sampling.fused.FusedFloatSampler.run`.
    block_frames = RENDER_BATCH

    @property
    def shape(self) -> tuple[int, int, int]:
        """``(F, H, W)``."""
        return (self.num_frames, *self.size)

    def frame_range(self, f0: int, f1: int) -> np.ndarray:
        """Frames ``f0 .. f1 - 1``: ``(f1 - f0, H, W) float64`` brightness in [16, 240],
        read-only when it is one batch's view."""
        if f1 <= f0:
            return np.empty((0, *self.size))
        b0 = f0 // RENDER_BATCH * RENDER_BATCH
        parts = [
            _render_batch(self.name, self.size, b, min(RENDER_BATCH, self.num_frames - b))
            [max(f0 - b, 0):f1 - b]
            for b in range(b0, f1, RENDER_BATCH)
        ]
        return parts[0] if len(parts) == 1 else np.concatenate(parts)  # only frames asked for


def render_frames(
    name: str, size: tuple[int, int] = DEFAULT_SIZE, num_frames: int = DEFAULT_FRAMES
) -> np.ndarray:
    """Render built-in scene ``name``: ``(num_frames, H, W) float64`` brightness in 8-bit
    units within [16, 240]. Deterministic and cached; the returned array is read-only. The
    whole stack at once: runs use :func:`builtin_scene`, which renders a range at a time."""
    from rvsm.model.infra.memory import require_memory

    _check_name(name)
    size, num_frames = _check_size(size, num_frames)
    require_memory(2 * 8 * num_frames * size[0] * size[1],  # frames and a working copy
                   f"scene {name!r} with {num_frames} frames of {size[0]}x{size[1]}",
                   "ask for fewer --frames or a smaller --size")
    return _render_cached(name, size, num_frames)


@functools.lru_cache(maxsize=32)
def _render_cached(name: str, size: tuple[int, int], num_frames: int) -> np.ndarray:
    out = np.array(RenderedFrames(name, size, num_frames).frame_range(0, num_frames))
    out.setflags(write=False)
    return out


def builtin_scene(
    name: str,
    size: tuple[int, int] = DEFAULT_SIZE,
    num_frames: int = DEFAULT_FRAMES,
    steps_per_frame: int = DEFAULT_STEPS_PER_FRAME,
    hold: bool = False,
) -> Scene:
    """Built-in scene ``name`` as a :class:`Scene` (``size`` is ``(H, W)`` pixels) whose
    frames are rendered on demand, a range at a time (:class:`RenderedFrames`)."""
    from rvsm.model.infra.memory import require_memory

    _check_name(name)
    size, num_frames = _check_size(size, num_frames)
    require_memory(RENDER_WORKING_ARRAYS * 8 * min(RENDER_BATCH, num_frames) * size[0] * size[1],
                   f"rendering scene {name!r} at {size[0]}x{size[1]}", "ask for a smaller --size")
    return Scene(name, RenderedFrames(name, size, num_frames), steps_per_frame, hold,
                 source=name).describe_source(name, f"builtin:{name}")


def black_scene(size: tuple[int, int], num_steps: int) -> Scene:
    """A black scene (brightness 0) of ``size = (H, W)`` lasting ``num_steps`` steps: one
    frame held for ``num_steps`` steps (the robustness experiment, SPEC §4)."""
    size, _ = _check_size(size, 1)
    if isinstance(num_steps, bool) or int(num_steps) != num_steps or num_steps < 1:
        raise RvsmError(f"number of steps must be an integer >= 1, got {num_steps!r}")
    return Scene("black", np.zeros((1, *size)), int(num_steps), hold=True)
