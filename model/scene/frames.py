"""Frame sources: where a scene's frames come from, read a range of frames at a time.

A :class:`FrameSource` has ``shape = (F, H, W)`` and ``frame_range(f0, f1)``, frames
``f0 .. f1 - 1`` as ``(f1 - f0, H, W) float64`` brightness in 8-bit units. A scene reads
only the frames a chunk of steps touches, so a run's memory does not grow with ``F``.
What a source returns may be a read-only view of a cache: never write into it.

This module holds the protocol, the in-memory source :class:`ArrayFrames`, the window
:class:`FrameWindow` (first frames, centre crop) and the frame checks every source shares
(:func:`check_layout`, :class:`ContentCheck`, :func:`validate_frames`): one wording of
each refusal whether a stack is checked whole or streamed chunk by chunk.
File sources live in :mod:`.file_frames`, rendered built-in scenes in :mod:`.library`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from rvsm.model.infra.errors import RvsmError

#: Raw bytes of frames a streaming check or copy handles at once.
CHUNK_BYTES = 32 << 20


@runtime_checkable
class FrameSource(Protocol):
    """Frames read on demand: ``shape (F, H, W)`` and ``frame_range(f0, f1)`` giving
    ``(f1 - f0, H, W) float64`` (``0 <= f0 <= f1 <= F``, checked by the caller)."""

    @property
    def shape(self) -> tuple[int, int, int]: ...

    def frame_range(self, f0: int, f1: int) -> np.ndarray: ...


def check_layout(shape: tuple[int, ...], dtype: np.dtype, source: str) -> tuple[int, int, int]:
    """The ``(F, H, W)`` a stack of ``shape`` and ``dtype`` holds (``(H, W)`` is one frame);
    :class:`RvsmError` for a non-real dtype, a wrong number of dimensions or no data."""
    dtype = np.dtype(dtype)
    if dtype.kind not in "biufm":  # bool, integers (timedelta too), floats: no objects,
        # text or complex
        raise RvsmError(f"{source}: frames must be real numeric values, got dtype {dtype}")
    shape = tuple(int(v) for v in shape)
    if len(shape) == 2:
        shape = (1, *shape)
    if len(shape) != 3:
        raise RvsmError(
            f"{source}: frames must have shape (F, H, W), got shape {shape}; "
            "convert colour video to grey first"
        )
    if min(shape) == 0:
        raise RvsmError(f"{source}: frames are empty (shape {shape})")
    return shape  # type: ignore[return-value]


@dataclass
class ContentCheck:
    """NaN/infinity and negative brightness, checked over chunks of a stack as if whole.

    :meth:`update` each ``(B, H, W) float64`` chunk (stops at the first non-finite value),
    then :meth:`finish`: the refusal names the smallest value of the whole stack.
    """

    source: str
    low: float = field(default=np.inf)

    def update(self, chunk: np.ndarray) -> None:
        """Take one chunk ``(B, H, W) float64`` into the check."""
        if not np.all(np.isfinite(chunk)):
            raise RvsmError(f"{self.source}: frames contain NaN or infinite values")
        if chunk.size:
            self.low = min(self.low, float(chunk.min()))

    def finish(self) -> None:
        """Refuse negative brightness seen in any chunk."""
        if self.low < 0:
            raise RvsmError(
                f"{self.source}: brightness must be >= 0 (8-bit units), found {self.low:g}"
            )


def validate_frames(frames: np.ndarray, source: str = "scene") -> np.ndarray:
    """Check a frame stack and return it as ``(F, H, W) float64`` brightness.

    Refuses (with :class:`RvsmError`) a wrong number of dimensions, an empty array, NaN or
    infinite values and negative brightness. ``uint8`` input is taken as 8-bit brightness.
    """
    arr = np.asarray(frames)
    shape = check_layout(arr.shape, arr.dtype, source)
    out = arr.astype(np.float64).reshape(shape)
    check = ContentCheck(source)
    check.update(out)
    check.finish()
    return out


@dataclass(frozen=True)
class ArrayFrames:
    """A whole stack in memory: ``array (F, H, W) float64``, validated and read-only.

    Compares as its array does (as :class:`~.scene.Scene` always compared its frames).
    """

    array: np.ndarray

    @property
    def shape(self) -> tuple[int, int, int]:
        """``(F, H, W)``."""
        return self.array.shape  # type: ignore[return-value]

    def frame_range(self, f0: int, f1: int) -> np.ndarray:
        """Frames ``f0 .. f1 - 1``: a read-only view ``(f1 - f0, H, W) float64``."""
        return self.array[f0:f1]


@dataclass(frozen=True)
class FrameWindow:
    """The first ``num_frames`` frames of ``inner``, centre-cropped to ``size = (H, W)``
    (``size`` at most ``inner``'s; the crop starts at ``(fh - H) // 2, (fw - W) // 2``)."""

    inner: FrameSource
    num_frames: int
    size: tuple[int, int]

    @property
    def shape(self) -> tuple[int, int, int]:
        """``(F, H, W)``."""
        return (self.num_frames, *self.size)

    def frame_range(self, f0: int, f1: int) -> np.ndarray:
        """Frames ``f0 .. f1 - 1`` of the window ``(f1 - f0, H, W) float64``."""
        _, fh, fw = self.inner.shape
        h, w = self.size
        y0, x0 = (fh - h) // 2, (fw - w) // 2
        return self.inner.frame_range(f0, f1)[:, y0:y0 + h, x0:x0 + w]
