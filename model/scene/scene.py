"""A scene: F video frames plus the per-step brightness the samplers see (SPEC section 1).

Brightness is in 8-bit units (0..255, float). With ``steps_per_frame = m``:

- linear (default): ``T = (F-1) m`` steps; step ``t`` has ``f = t // m``, ``a = (t % m)/m``
  and ``I_t = (1 - a) frames[f] + a frames[f+1]``;
- hold: ``T = F m`` steps and ``I_t = frames[t // m]``.

Ground truth for step ``t`` is ``I_t``.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np

from rvsm.model.infra.errors import RvsmError

DEFAULT_STEPS_PER_FRAME = 10


def validate_frames(frames: np.ndarray, source: str = "scene") -> np.ndarray:
    """Check a frame stack and return it as ``(F, H, W) float64`` brightness.

    Refuses (with :class:`RvsmError`) a wrong number of dimensions, an empty array, NaN or
    infinite values and negative brightness. ``uint8`` input is taken as 8-bit brightness.
    """
    arr = np.asarray(frames)
    if arr.dtype == object or not (
        np.issubdtype(arr.dtype, np.number) or arr.dtype == bool
    ) or np.issubdtype(arr.dtype, np.complexfloating):
        raise RvsmError(f"{source}: frames must be real numeric values, got dtype {arr.dtype}")
    if arr.ndim == 2:
        arr = arr[None]
    if arr.ndim != 3:
        raise RvsmError(
            f"{source}: frames must have shape (F, H, W), got shape {arr.shape}; "
            "convert colour video to grey first"
        )
    if min(arr.shape) == 0:
        raise RvsmError(f"{source}: frames are empty (shape {arr.shape})")
    out = arr.astype(np.float64)
    if not np.all(np.isfinite(out)):
        raise RvsmError(f"{source}: frames contain NaN or infinite values")
    if out.min() < 0:
        raise RvsmError(
            f"{source}: brightness must be >= 0 (8-bit units), found {out.min():g}"
        )
    return out


@dataclass(frozen=True)
class Scene:
    """Frames ``(F, H, W) float64`` in 8-bit brightness units and how they become steps.

    ``source`` is what loads the scene again (a built-in name or a path, as given to
    :func:`rvsm.model.scene.loaders.load_scene`); ``None`` for a scene made in code.
    """

    name: str
    frames: np.ndarray = field(repr=False)
    steps_per_frame: int = DEFAULT_STEPS_PER_FRAME
    hold: bool = False
    source: str | None = None

    def __post_init__(self) -> None:
        frames = validate_frames(self.frames, self.name)
        frames.setflags(write=False)
        object.__setattr__(self, "frames", frames)
        m = self.steps_per_frame
        if isinstance(m, bool) or not isinstance(m, (int, np.integer)) or m < 1:
            raise RvsmError(f"steps_per_frame must be an integer >= 1, got {m!r}")
        object.__setattr__(self, "steps_per_frame", int(m))
        if not self.hold and frames.shape[0] < 2:
            raise RvsmError(
                f"{self.name}: linear interpolation needs at least 2 frames, got 1; "
                "use --hold for a still image"
            )

    @property
    def shape(self) -> tuple[int, int]:
        """``(H, W)`` in pixels."""
        return self.frames.shape[1], self.frames.shape[2]

    @property
    def num_frames(self) -> int:
        """F, the number of video frames."""
        return self.frames.shape[0]

    @property
    def num_steps(self) -> int:
        """T, the number of sampling steps."""
        f, m = self.num_frames, self.steps_per_frame
        return f * m if self.hold else (f - 1) * m

    def frame_weights(self, t0: int, t1: int) -> tuple[np.ndarray, np.ndarray]:
        """For steps ``t0..t1-1``: frame index ``f (B,) int64`` and weight ``a (B,) float64``.

        ``I_t = (1 - a) frames[f] + a frames[f + 1]`` (``a`` is 0 in hold mode).
        """
        t = np.arange(t0, t1, dtype=np.int64)
        m = self.steps_per_frame
        f = t // m
        a = np.zeros(t.shape) if self.hold else (t % m) / m
        return f, a

    def brightness(self, t0: int = 0, t1: int | None = None) -> np.ndarray:
        """Per-step brightness for steps ``t0..t1-1``: ``(B, H, W) float64``."""
        t1 = self.num_steps if t1 is None else t1
        if not 0 <= t0 <= t1 <= self.num_steps:
            raise RvsmError(f"step range {t0}..{t1} outside 0..{self.num_steps}")
        f, a = self.frame_weights(t0, t1)
        return interpolate(self.frames, f, a)

    def blocks(self, block_steps: int) -> Iterator[tuple[int, int]]:
        """Yield ``(t0, t1)`` step ranges of at most ``block_steps`` covering ``0..T``."""
        for t0 in range(0, self.num_steps, block_steps):
            yield t0, min(t0 + block_steps, self.num_steps)

    def meta(self) -> dict:
        """What it takes to load this scene again: goes into spike files' ``meta``.

        ``scene_arg`` (the source, else the name), ``height``, ``width``, ``num_frames``,
        ``steps_per_frame`` and ``hold``.
        """
        h, w = self.shape
        return {
            "scene_arg": self.source if self.source is not None else self.name,
            "height": h,
            "width": w,
            "num_frames": self.num_frames,
            "steps_per_frame": self.steps_per_frame,
            "hold": self.hold,
        }


def interpolate(stack: np.ndarray, f: np.ndarray, a: np.ndarray) -> np.ndarray:
    """``(1 - a) stack[f] + a stack[f+1]`` along axis 0, exactly as SPEC section 1 writes it.

    ``stack`` is ``(F, ...)``; ``f`` and ``a`` are ``(B,)``; returns ``(B, ...) float64``.
    Where ``a == 0`` the result is ``stack[f]`` (no read past the last frame).
    """
    base = stack[f]
    if not np.any(a):
        return base.astype(np.float64, copy=True)
    nxt = stack[np.minimum(f + 1, stack.shape[0] - 1)]
    shape = (-1,) + (1,) * (stack.ndim - 1)
    aa = a.reshape(shape)
    return (1.0 - aa) * base + aa * nxt
