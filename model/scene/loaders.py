"""Load a scene from a built-in name, a ``.npy`` array, an image folder or a video (SPEC §1).

Every scene's frames are ``(F, H, W) float64`` brightness in 8-bit units (0..255), read
on demand a range of frames at a time (:mod:`.frames`, :mod:`.file_frames`), so a long
scene never sits in memory whole:

- built-in name: rendered a batch of frames at a time (:mod:`.library`);
- ``.npy``: ``(F, H, W)`` or ``(H, W)`` (one frame), ``uint8`` or float, taken as 8-bit
  brightness as-is (no rescaling); memory-mapped, checked chunk by chunk;
- image folder: the image files sorted by name, decoded per range; colour is converted
  to grey with the ITU-R 601 luminance (``skimage.color.rgb2gray``) and scaled to 0..255
  (16-bit images are scaled by 255/65535 at full precision, and the scene's ``notes``
  say so; float images in [0, 1] by 255);
- video or animated / multi-page image: decoded in order through ``imageio.v3.imiter``
  (videos need a plugin: ``pip install imageio[ffmpeg]``); a range before the reader's
  position restarts the decoding from the first frame.

Each file is checked once when loaded (one streaming pass), so a bad file is refused
before a run starts; ``--frames`` and ``--size`` take the first frames and a centre crop.

Every user-fixable problem raises :class:`RvsmError` with a one-line message.
"""

from __future__ import annotations

import functools
import os
import re
from pathlib import Path

from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.digest import scene_digest
from rvsm.model.scene.file_frames import IMAGE_SUFFIXES, DecodedStream, ImageFiles, NpyFrames
from rvsm.model.scene.frames import FrameSource, FrameWindow
from rvsm.model.scene.library import SCENE_NAMES, builtin_scene
from rvsm.model.scene.scene import DEFAULT_STEPS_PER_FRAME, Scene

VIDEO_SUFFIXES = (".mp4", ".avi", ".mov", ".mkv", ".webm", ".m4v", ".mpg", ".mpeg", ".wmv")

_SIZE_RE = re.compile(r"^\s*(\d+)\s*[xX*,]\s*(\d+)\s*$")


def parse_size(text: str) -> tuple[int, int]:
    """Parse ``"HxW"`` (e.g. ``"250x400"``) into ``(H, W)`` pixels, both >= 1."""
    m = _SIZE_RE.match(str(text))
    if not m or int(m.group(1)) < 1 or int(m.group(2)) < 1:
        raise RvsmError(f"bad size {text!r}: write HEIGHTxWIDTH in pixels, e.g. 250x400")
    return int(m.group(1)), int(m.group(2))


def is_builtin(arg: str | os.PathLike) -> bool:
    """True if ``arg`` names a built-in scene (rendered at any size), not a file."""
    return os.fspath(arg) in SCENE_NAMES


def _load_npy(path: Path) -> FrameSource:
    """An ``.npy`` file, memory-mapped and checked chunk by chunk (:class:`NpyFrames`)."""
    return NpyFrames(path)


def _load_folder(path: Path) -> FrameSource:
    """An image folder: the image files sorted by name, one per frame (:class:`ImageFiles`)."""
    files = sorted(
        p for p in path.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES
    )
    if not files:
        raise RvsmError(
            f"{path}: folder has no image files ({', '.join(IMAGE_SUFFIXES[:4])} ...); "
            "put one image per frame, named so that they sort in time order"
        )
    return ImageFiles(files, path)


def _video_plugin_installed() -> bool:
    """True if imageio has a reader for common video containers (ffmpeg or PyAV)."""
    import importlib.util

    return any(importlib.util.find_spec(m) for m in ("imageio_ffmpeg", "av"))


def _load_image_file(path: Path) -> FrameSource:
    """A single image file: one frame, or every frame of an animated GIF / multi-page TIFF."""
    return DecodedStream(path, "image")


def _load_video(path: Path) -> FrameSource:
    if not _video_plugin_installed():
        raise RvsmError(
            f"{path}: no video reader is installed; run `pip install imageio[ffmpeg]` "
            "or give an image folder, an animated GIF or a .npy file instead"
        )
    return DecodedStream(path, "video")


def _fit_size(frames: FrameSource, num_frames: int | None, size: tuple[int, int] | None,
              source: str) -> FrameSource:
    """The first ``num_frames`` frames, centre-cropped to ``size``; refuse to enlarge."""
    count, fh, fw = frames.shape
    if num_frames is not None:
        if num_frames > count:
            raise RvsmError(f"{source}: has {count} frames, fewer than the "
                            f"{int(num_frames)} asked for; ask for at most --frames "
                            f"{count}")
        count = int(num_frames)
    h, w = (fh, fw) if size is None else (int(v) for v in size)
    if h > fh or w > fw:
        raise RvsmError(
            f"{source}: frames are {fh}x{fw}, smaller than the requested size {h}x{w}; "
            f"ask for at most --size {fh}x{fw}, or leave --size out to use the file's own "
            "size"
        )
    if (count, h, w) == frames.shape:
        return frames
    return FrameWindow(frames, count, (h, w))


def load_scene(
    arg: str,
    size: tuple[int, int] | None = None,
    num_frames: int | None = None,
    steps_per_frame: int = DEFAULT_STEPS_PER_FRAME,
    hold: bool = False,
) -> Scene:
    """A :class:`Scene` from a built-in scene name or a path (``.npy``, folder, video).

    ``size = (H, W)`` renders a built-in scene at that size, or centre-crops file frames
    (larger than ``size``) to it. ``num_frames`` renders that many built-in frames, or keeps
    the first ``num_frames`` frames of a file. Brightness is in 8-bit units.
    """
    if num_frames is not None and (
        isinstance(num_frames, bool) or int(num_frames) != num_frames or num_frames < 1
    ):
        raise RvsmError(f"number of frames must be an integer >= 1, got {num_frames!r}")
    text = os.fspath(arg)
    if is_builtin(text):
        from rvsm.model.scene.library import DEFAULT_FRAMES, DEFAULT_SIZE

        return builtin_scene(
            text,
            DEFAULT_SIZE if size is None else size,
            DEFAULT_FRAMES if num_frames is None else int(num_frames),
            steps_per_frame,
            hold,
        )
    path = Path(text).expanduser()
    if not path.exists():
        raise RvsmError(
            f"scene {text!r} is neither a built-in scene ({', '.join(SCENE_NAMES)}) nor an "
            "existing .npy file, image folder or video"
        )
    suffix = path.suffix.lower()
    if path.is_dir():
        frames = _load_folder(path)
    elif suffix == ".npy":
        frames = _load_npy(path)
    elif suffix in IMAGE_SUFFIXES:
        frames = _load_image_file(path)
    elif suffix in VIDEO_SUFFIXES:
        frames = _load_video(path)
    else:
        raise RvsmError(
            f"{path}: unknown scene file type {suffix or '(none)'!r}; use a .npy array, an "
            f"image folder or a video ({', '.join(VIDEO_SUFFIXES[:4])} ...)"
        )
    notes = tuple(getattr(frames, "notes", ()))
    frames = _fit_size(frames, num_frames, size, str(path))
    name = path.stem if path.suffix else path.name
    scene = Scene(name, frames, steps_per_frame, hold, source=text).describe_source(
        os.path.abspath(path), functools.partial(scene_digest, path))
    object.__setattr__(scene, "notes", notes)
    return scene
