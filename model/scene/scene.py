"""A scene: F video frames plus the per-step brightness the samplers see (SPEC section 1).

Brightness is in 8-bit units (0..255, float). With ``steps_per_frame = m``:

- linear (default): ``T = (F-1) m`` steps; step ``t`` has ``f = t // m``, ``a = (t % m)/m``
  and ``I_t = (1 - a) frames[f] + a frames[f+1]``;
- hold: ``T = F m`` steps and ``I_t = frames[t // m]``.

Ground truth for step ``t`` is ``I_t``. A scene's frames come from a
:class:`~rvsm.model.scene.frames.FrameSource`, read a range at a time.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.frames import ArrayFrames, FrameSource, validate_frames

__all__ = ["DEFAULT_STEPS_PER_FRAME", "Scene", "interpolate", "validate_frames"]

DEFAULT_STEPS_PER_FRAME = 10


@dataclass(frozen=True, init=False)
class Scene:
    """Frames ``(F, H, W)`` in 8-bit brightness units and how they become steps.

    ``frames`` given to the constructor is either a stack (validated and kept in memory
    as ``float64``, read-only) or a :class:`~.frames.FrameSource` read on demand (a file,
    a rendered built-in scene). Runs read only the frames a chunk of steps touches
    (:meth:`frame_range`, :meth:`brightness`); :attr:`frames` is the whole stack.
    ``source`` is what loads the scene again (a built-in name or a path, as given to
    :func:`rvsm.model.scene.loaders.load_scene`); ``None`` for a scene made in code.
    Compares field by field, the frames as their source does (an in-memory stack as a
    numpy array).
    """

    name: str
    frame_source: FrameSource = field(repr=False)
    steps_per_frame: int = DEFAULT_STEPS_PER_FRAME
    hold: bool = False
    source: str | None = None
    #: what a command says about how the frames were read (16-bit images), one line each
    notes: ClassVar[tuple[str, ...]] = ()

    def __init__(self, name: str, frames: np.ndarray | FrameSource,
                 steps_per_frame: int = DEFAULT_STEPS_PER_FRAME, hold: bool = False,
                 source: str | None = None) -> None:
        if not isinstance(frames, FrameSource) or isinstance(frames, np.ndarray):
            stack = validate_frames(frames, name)
            stack.setflags(write=False)
            frames = ArrayFrames(stack)
        m = steps_per_frame
        if isinstance(m, bool) or not isinstance(m, (int, np.integer)) or m < 1:
            raise RvsmError(f"steps_per_frame must be an integer >= 1, got {m!r}")
        if not hold and frames.shape[0] < 2:
            raise RvsmError(
                f"{name if source is None else source}: linear interpolation needs at "
                "least 2 frames, got 1; "
                "use --hold for a still image"
            )
        for key, value in (("name", name), ("frame_source", frames),
                           ("steps_per_frame", int(m)), ("hold", hold), ("source", source)):
            object.__setattr__(self, key, value)

    @property
    def frames(self) -> np.ndarray:
        """Every frame ``(F, H, W) float64``, read-only: an in-memory scene's own stack; a
        lazy scene's frames all read at once (refused when they would not fit in memory).
        Runs use :meth:`frame_range` and :meth:`brightness` instead."""
        src = self.frame_source
        if isinstance(src, ArrayFrames):
            return src.array
        from rvsm.model.infra.memory import require_memory

        f, h, w = src.shape
        require_memory(8 * f * h * w, f"all {f} frames of scene {self.name!r} ({h}x{w})",
                       "read them a range at a time (Scene.frame_range)")
        out = np.array(src.frame_range(0, f), dtype=np.float64)
        out.setflags(write=False)
        return out

    def frame_range(self, f0: int, f1: int) -> np.ndarray:
        """Frames ``f0 .. f1 - 1``: ``(f1 - f0, H, W) float64``, possibly a read-only view
        (never write into it)."""
        if not 0 <= f0 <= f1 <= self.num_frames:
            raise RvsmError(f"frame range {f0}..{f1} outside 0..{self.num_frames}")
        if f0 == f1:
            return np.empty((0, *self.shape))
        return self.frame_source.frame_range(int(f0), int(f1))

    @property
    def shape(self) -> tuple[int, int]:
        """``(H, W)`` in pixels."""
        return self.frame_source.shape[1], self.frame_source.shape[2]

    @property
    def num_frames(self) -> int:
        """F, the number of video frames."""
        return self.frame_source.shape[0]

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

    def frame_span(self, t0: int, t1: int) -> tuple[int, int]:
        """The frames steps ``t0..t1-1`` (``t0 < t1``) read: ``(first, last + 1)``, the
        frame after the last step's included (clamped to ``F``)."""
        m = self.steps_per_frame
        first, last = t0 // m, (t1 - 1) // m
        return first, min(last + 2, self.num_frames)

    def brightness(self, t0: int = 0, t1: int | None = None) -> np.ndarray:
        """Per-step brightness for steps ``t0..t1-1``: ``(B, H, W) float64``; reads only
        the frames those steps touch."""
        t1 = self.num_steps if t1 is None else t1
        if not 0 <= t0 <= t1 <= self.num_steps:
            raise RvsmError(f"step range {t0}..{t1} outside 0..{self.num_steps}")
        if t0 == t1:
            return np.empty((0, *self.shape))
        f, a = self.frame_weights(t0, t1)
        first, end = self.frame_span(t0, t1)
        return interpolate(self.frame_range(first, end), f - first, a)

    def blocks(self, block_steps: int) -> Iterator[tuple[int, int]]:
        """Yield ``(t0, t1)`` step ranges of at most ``block_steps`` covering ``0..T``."""
        for t0 in range(0, self.num_steps, block_steps):
            yield t0, min(t0 + block_steps, self.num_steps)

    def digest(self) -> str | None:
        """The content digest of :attr:`source`
        (:func:`rvsm.model.scene.digest.scene_digest`: ``builtin:<name>`` or
        ``sha256:...`` of the file or folder), computed once, when the loader that made
        the scene gave one (:meth:`describe_source`); ``None`` for a scene made in code."""
        digest = self.__dict__.get("_digest")
        if callable(digest):
            digest = digest()
            object.__setattr__(self, "_digest", digest)
        return digest

    def describe_source(self, stored: str, digest: str | Callable[[], str]) -> Scene:
        """Set what a file's meta keeps of the source: ``stored`` (a built-in name, a
        file's absolute path) and its ``digest`` (or a function computing it on first
        use); returns the scene. Called by the loaders, which know what the source is."""
        object.__setattr__(self, "_stored_source", stored)
        object.__setattr__(self, "_digest", digest)
        return self

    def meta(self) -> dict:
        """What it takes to load this scene again: goes into spike files' ``meta``.

        ``scene_arg`` (a built-in name, a scene file's or folder's absolute path, else the
        name), ``scene_digest`` (:meth:`digest`, when the scene has a source),
        ``height``, ``width``, ``num_frames``, ``steps_per_frame`` and ``hold``.
        """
        h, w = self.shape
        out = {
            "scene_arg": self.__dict__.get("_stored_source",
                                           self.name if self.source is None else self.source),
            "height": h,
            "width": w,
            "num_frames": self.num_frames,
            "steps_per_frame": self.steps_per_frame,
            "hold": self.hold,
        }
        digest = self.digest()
        if digest is not None:
            out["scene_digest"] = digest
        return out

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
