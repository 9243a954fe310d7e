"""Load a scene from a built-in name, a ``.npy`` array, an image folder or a video (SPEC §1).

All loaders return frames as ``(F, H, W) float64`` brightness in 8-bit units (0..255):

- ``.npy``: ``(F, H, W)`` or ``(H, W)`` (one frame), ``uint8`` or float, taken as 8-bit
  brightness as-is (no rescaling);
- image folder: the image files sorted by name; colour is converted to grey with the
  ITU-R 601 luminance (``skimage.color.rgb2gray``) and scaled to 0..255 (16-bit images
  are scaled by 255/65535, float images in [0, 1] by 255);
- video: read with ``imageio.v3`` (needs a video plugin: ``pip install imageio[ffmpeg]``).

Every user-fixable problem raises :class:`RvsmError` with a one-line message.
"""

from __future__ import annotations

import os
import re
import warnings
from pathlib import Path

import numpy as np

from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.library import SCENE_NAMES, builtin_scene
from rvsm.model.scene.scene import DEFAULT_STEPS_PER_FRAME, Scene, validate_frames

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".gif", ".webp", ".pgm",
                  ".ppm")
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


def _to_grey(img: np.ndarray, source: str) -> np.ndarray:
    """One image (H, W) / (H, W, C) of any dtype as grey ``(H, W) float64`` in 0..255."""
    from skimage.color import rgb2gray

    img = np.asarray(img)
    if img.ndim == 3 and img.shape[-1] in (1, 2, 3, 4):
        if img.shape[-1] in (1, 2):  # grey (+ alpha)
            img = img[..., 0]
        else:
            kind = img.dtype
            img = rgb2gray(img[..., :3])  # float in [0, 1] for integer input
            if np.issubdtype(kind, np.floating):
                return _float_to_8bit(img)
            return img * 255.0
    if img.ndim != 2:
        raise RvsmError(f"{source}: expected a grey or colour image, got shape {img.shape}")
    if img.dtype == np.uint8:
        return img.astype(np.float64)
    if img.dtype == np.uint16:
        return img.astype(np.float64) * (255.0 / 65535.0)
    if img.dtype == bool:
        return img.astype(np.float64) * 255.0
    if np.issubdtype(img.dtype, np.floating):
        return _float_to_8bit(img.astype(np.float64))
    return img.astype(np.float64)


def _float_to_8bit(img: np.ndarray) -> np.ndarray:
    """Float images in [0, 1] are scaled to 0..255; larger ranges are taken as 8-bit."""
    finite = img[np.isfinite(img)]
    if finite.size and finite.max() <= 1.0:
        return img * 255.0
    return img


def _load_npy(path: Path) -> np.ndarray:
    from rvsm.model.infra.npy_guard import check_npy_file

    check_npy_file(path)
    try:
        arr = np.load(path, allow_pickle=False)
    except Exception as exc:  # truncated, corrupt, pickled object arrays ...
        raise RvsmError(
            f"{path}: cannot load .npy file ({type(exc).__name__}: "
            f"{str(exc).splitlines()[0] if str(exc) else 'unreadable'}); re-save it with "
            "numpy.save"
        ) from None
    if isinstance(arr, np.lib.npyio.NpzFile):  # pragma: no cover - .npz named .npy
        raise RvsmError(f"{path}: is an .npz archive; save one (F, H, W) array with numpy.save")
    return arr


def _read_image(path: Path) -> np.ndarray:
    import imageio.v3 as iio

    try:
        with warnings.catch_warnings():  # imageio's plugin probing warns on bad files
            warnings.simplefilter("ignore")
            img = iio.imread(path)
    except Exception as exc:
        raise RvsmError(f"{path}: cannot read image ({type(exc).__name__}); "
                        "use PNG/JPEG/TIFF files") from None
    if img.ndim == 4 or (img.ndim == 3 and img.shape[-1] not in (1, 2, 3, 4)):
        img = img[0]  # multi-page / animated: first page
    return _to_grey(img, str(path))


def _load_folder(path: Path) -> np.ndarray:
    files = sorted(
        p for p in path.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES
    )
    if not files:
        raise RvsmError(
            f"{path}: folder has no image files ({', '.join(IMAGE_SUFFIXES[:4])} ...); "
            "put one image per frame, named so that they sort in time order"
        )
    frames = []
    for f in files:
        img = _read_image(f)
        if frames and img.shape != frames[0].shape:
            raise RvsmError(
                f"{path}: images have different sizes ({files[0].name} is "
                f"{frames[0].shape[0]}x{frames[0].shape[1]}, {f.name} is "
                f"{img.shape[0]}x{img.shape[1]}); resize them to one size"
            )
        frames.append(img)
    return np.stack(frames)


def _video_plugin_installed() -> bool:
    """True if imageio has a reader for common video containers (ffmpeg or PyAV)."""
    import importlib.util

    return any(importlib.util.find_spec(m) for m in ("imageio_ffmpeg", "av"))


def _read_frames(path: Path, what: str) -> list[np.ndarray]:
    """Every frame (page) of ``path`` through ``imageio.v3.imiter``, as grey ``(H, W)``."""
    import imageio.v3 as iio

    try:
        with warnings.catch_warnings():  # imageio's plugin probing warns on bad files
            warnings.simplefilter("ignore")
            return [_to_grey(fr, str(path)) for fr in iio.imiter(path)]
    except RvsmError:
        raise
    except Exception as exc:
        reason = str(exc).strip().splitlines()[0] if str(exc).strip() else "unreadable"
        raise RvsmError(
            f"{path}: cannot read this {what} ({type(exc).__name__}: {reason}); the file may "
            "be corrupt or truncated"
        ) from None


def _load_image_file(path: Path) -> np.ndarray:
    """A single image file: one frame, or every frame of an animated GIF / multi-page TIFF."""
    frames = _read_frames(path, "image")
    if not frames:
        raise RvsmError(f"{path}: image file has no frames")
    return np.stack(frames)


def _load_video(path: Path) -> np.ndarray:
    if not _video_plugin_installed():
        raise RvsmError(
            f"{path}: no video reader is installed; run `pip install imageio[ffmpeg]` "
            "or give an image folder, an animated GIF or a .npy file instead"
        )
    frames = _read_frames(path, "video")
    if not frames:
        raise RvsmError(f"{path}: video has no frames")
    return np.stack(frames)


def _fit_size(frames: np.ndarray, size: tuple[int, int] | None, source: str) -> np.ndarray:
    """Centre-crop ``(F, H, W)`` frames to ``size``; refuse to enlarge."""
    if size is None:
        return frames
    h, w = (int(v) for v in size)
    fh, fw = frames.shape[1:]
    if (h, w) == (fh, fw):
        return frames
    if h > fh or w > fw:
        raise RvsmError(
            f"{source}: frames are {fh}x{fw}, smaller than the requested size {h}x{w}; "
            f"ask for at most --size {fh}x{fw}, or leave --size out to use the file's own "
            "size"
        )
    y0, x0 = (fh - h) // 2, (fw - w) // 2
    return frames[:, y0 : y0 + h, x0 : x0 + w]


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
    frames = validate_frames(frames, str(path))
    if num_frames is not None:
        if num_frames > frames.shape[0]:
            raise RvsmError(f"{path}: has {frames.shape[0]} frames, fewer than the "
                            f"{int(num_frames)} asked for; ask for at most --frames "
                            f"{frames.shape[0]}")
        frames = frames[: int(num_frames)]
    frames = _fit_size(frames, size, str(path))
    name = path.stem if path.suffix else path.name
    return Scene(name, frames, steps_per_frame, hold, source=text)
