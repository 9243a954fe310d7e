"""Frame sources read from files a range of frames at a time (:mod:`.frames` protocol).

- :class:`NpyFrames`: an ``.npy`` array, memory-mapped; each range maps only its own
  frames and unmaps them after the copy, so pages read do not pile up in the resident
  set. (A Fortran-order file maps the whole array per range: correct, not page-thrifty.)
- :class:`ImageFiles`: one image file per frame (a folder), decoded per range.
- :class:`DecodedStream`: the frames of a video or an animated / multi-page image through
  ``imageio.v3.imiter``, decoded in order. A range before the reader's position restarts
  it from the first frame (videos have no cheap random access); runs read forward, so
  each frame is decoded once per pass.

Every source is checked when made, by one streaming pass over its frames (the layout,
equal image sizes, then NaN/infinity and negative brightness with the same one-line
:class:`RvsmError` as a whole stack), so a bad file is refused before a run starts; the
frames are then decoded again when a run reads them. Grey conversion (:func:`to_grey`):
colour through the ITU-R 601 luminance (``skimage.color.rgb2gray``) scaled to 0..255,
16-bit images scaled by 255/65535, float images in [0, 1] by 255.

**16-bit images keep their precision**: the brightness is a float, so a 16-bit value
``v`` becomes ``v * 255 / 65535`` in the model's 8-bit units, fractions kept (no rounding
to 256 levels). Pillow, imageio's PNG reader, decodes a 16-bit *colour* PNG (or grey
with alpha) to 8 bits; such files are decoded with ``pypng`` instead
(:func:`read_raw_image`). A source made of 16-bit images says so in :attr:`notes`, which
the command line prints.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np

from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.frames import CHUNK_BYTES, ContentCheck, check_layout

#: File suffixes read as images (an image folder's frames, a single image).
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".gif", ".webp", ".pgm",
                  ".ppm")


def to_grey(img: np.ndarray, source: str) -> np.ndarray:
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


def png16_planes(path: Path) -> int:
    """The planes of a 16-bit colour or grey-with-alpha PNG (2, 3 or 4), which Pillow
    would decode to 8 bits; 0 for any other file."""
    try:
        with open(path, "rb") as handle:
            head = handle.read(26)
    except OSError:
        return 0
    if len(head) < 26 or not head.startswith(b"\x89PNG\r\n\x1a\n") or head[24] != 16:
        return 0
    return {2: 3, 4: 2, 6: 4}.get(head[25], 0)


def _read_png16(path: Path, planes: int) -> np.ndarray:
    """A 16-bit colour PNG as ``(H, W, planes) uint16``, through ``pypng``."""
    try:
        import png
    except ImportError:  # pragma: no cover - a declared dependency
        raise RvsmError(f"{path}: a 16-bit colour PNG needs pypng (pip install pypng); "
                        "Pillow would read it as 8-bit") from None
    try:
        width, height, rows, _ = png.Reader(filename=str(path)).asDirect()
        img = np.vstack([np.asarray(row, dtype=np.uint16) for row in rows])
    except Exception as exc:  # noqa: BLE001 - any decoder failure is a bad file
        raise RvsmError(f"{path}: cannot read image ({type(exc).__name__}); "
                        "use PNG/JPEG/TIFF files") from None
    return img.reshape(height, width, planes)


def read_raw_image(path: Path) -> np.ndarray:
    """One image file's pixels as decoded (any dtype; the first page of a multi-page one):
    16-bit colour PNGs at 16 bits (:func:`png16_planes`), the rest through imageio."""
    import imageio.v3 as iio

    planes = png16_planes(path)
    if planes:
        return _read_png16(path, planes)
    try:
        with warnings.catch_warnings():  # imageio's plugin probing warns on bad files
            warnings.simplefilter("ignore")
            img = iio.imread(path)
    except Exception as exc:
        raise RvsmError(f"{path}: cannot read image ({type(exc).__name__}); "
                        "use PNG/JPEG/TIFF files") from None
    if img.ndim == 4 or (img.ndim == 3 and img.shape[-1] not in (1, 2, 3, 4)):
        img = img[0]  # multi-page / animated: first page
    return img


def read_image(path: Path) -> np.ndarray:
    """One image file as grey ``(H, W) float64`` (the first page of a multi-page one)."""
    return to_grey(read_raw_image(path), str(path))


def depth_note(dtype: np.dtype, source: str) -> tuple[str, ...]:
    """The note a source of images of ``dtype`` gives (16-bit: how they are read)."""
    if np.dtype(dtype) != np.uint16:
        return ()
    return (f"{source}: 16-bit images, read at full precision: brightness = value x "
            "255/65535 in the model's 8-bit units, fractions kept",)


def _frames_per_chunk(frame_shape: tuple[int, int, int], itemsize: int) -> int:
    return max(1, CHUNK_BYTES // (frame_shape[1] * frame_shape[2] * max(itemsize, 8)))


class NpyFrames:
    """The frames of an ``.npy`` file ``(F, H, W)`` or ``(H, W)``, any real dtype, taken as
    8-bit brightness as they are; memory-mapped, never loaded whole. Compares by identity.
    """

    def __init__(self, path: Path) -> None:
        from rvsm.model.infra.npy_guard import npy_layout

        self.path = Path(path)
        layout = npy_layout(self.path)
        self._shape = check_layout(layout.shape, layout.dtype, str(self.path))
        self._dtype = layout.dtype
        self._offset = layout.offset
        self._fortran = layout.fortran_order
        check = ContentCheck(str(self.path))
        step = _frames_per_chunk(self._shape, self._dtype.itemsize)
        for f0 in range(0, self._shape[0], step):
            check.update(self.frame_range(f0, min(f0 + step, self._shape[0])))
        check.finish()

    @property
    def shape(self) -> tuple[int, int, int]:
        """``(F, H, W)``."""
        return self._shape

    def frame_range(self, f0: int, f1: int) -> np.ndarray:
        """Frames ``f0 .. f1 - 1`` as a fresh ``(f1 - f0, H, W) float64`` array."""
        _, h, w = self._shape
        if f1 <= f0:
            return np.empty((0, h, w))
        try:
            if self._fortran:
                whole = np.memmap(self.path, self._dtype, "r", self._offset,
                                  self._shape, order="F")
                part = whole[f0:f1]
            else:
                start = self._offset + f0 * h * w * self._dtype.itemsize
                part = np.memmap(self.path, self._dtype, "r", start, (f1 - f0, h, w))
            out = part.astype(np.float64)
        except (OSError, ValueError) as exc:
            raise RvsmError(f"{self.path}: cannot read frames {f0}..{f1 - 1} "
                            f"({type(exc).__name__}: {exc}); the file changed or is "
                            "truncated") from None
        del part
        return out


class ImageFiles:
    """One image file per frame, in the given order, decoded a range at a time.

    Made by checking every image once: readable, all of one size, finite, not negative.
    Compares by identity.
    """

    def __init__(self, files: Sequence[Path], folder: Path) -> None:
        self.files = list(files)
        raw = read_raw_image(self.files[0])
        #: what the command line says about these frames (16-bit images)
        self.notes = depth_note(raw.dtype, str(folder))
        first = to_grey(raw, str(self.files[0]))
        check = ContentCheck(str(folder))
        check.update(first)
        for f in self.files[1:]:
            img = read_image(f)
            if img.shape != first.shape:
                raise RvsmError(
                    f"{folder}: images have different sizes ({self.files[0].name} is "
                    f"{first.shape[0]}x{first.shape[1]}, {f.name} is "
                    f"{img.shape[0]}x{img.shape[1]}); resize them to one size"
                )
            check.update(img)
        check.finish()
        self._shape = (len(self.files), *first.shape)

    @property
    def shape(self) -> tuple[int, int, int]:
        """``(F, H, W)``."""
        return self._shape  # type: ignore[return-value]

    def frame_range(self, f0: int, f1: int) -> np.ndarray:
        """Frames ``f0 .. f1 - 1`` decoded: ``(f1 - f0, H, W) float64``."""
        out = np.empty((max(f1 - f0, 0), *self._shape[1:]))
        for i, f in enumerate(self.files[f0:f1]):
            img = read_image(f)
            if img.shape != self._shape[1:]:
                raise RvsmError(f"{f}: changed size since the scene was loaded")
            out[i] = img
        return out


class DecodedStream:
    """The frames of a video or animated / multi-page image (``what`` names it in errors),
    decoded in order through ``imageio.v3.imiter``. Compares by identity.

    Made by decoding every frame once (count, sizes, content); a range then reads forward
    from the reader's position, restarting it only for a range that begins before it.
    The last two frames read are kept, so consecutive ranges that share their boundary
    frame, or a per-step reader asking for the same pair again, decode nothing twice.
    """

    def __init__(self, path: Path, what: str) -> None:
        self.path = Path(path)
        self.what = what
        check = ContentCheck(str(self.path))
        shape: tuple[int, ...] | None = None
        count = 0
        #: what the command line says about these frames (16-bit images)
        self.notes: tuple[str, ...] = ()
        for frame in self._frames(first_dtype=True):
            if shape is None:
                shape = frame.shape
            elif frame.shape != shape:
                raise RvsmError(f"{self.path}: frames have different sizes "
                                f"({shape[0]}x{shape[1]} and {frame.shape[0]}x"
                                f"{frame.shape[1]}); this {what} cannot be a scene")
            check.update(frame)
            count += 1
        if shape is None:
            noun = "image file" if what == "image" else what
            raise RvsmError(f"{self.path}: {noun} has no frames")
        check.finish()
        self._shape = (count, *shape)
        self._reader: Iterator[np.ndarray] | None = None
        self._position = 0  # index of the frame the reader yields next
        self._last: tuple[int, np.ndarray] = (0, np.empty((0, *shape)))

    @property
    def shape(self) -> tuple[int, int, int]:
        """``(F, H, W)``."""
        return self._shape  # type: ignore[return-value]

    def _frames(self, first_dtype: bool = False) -> Iterator[np.ndarray]:
        """Every frame of the file as grey ``(H, W) float64``; one-line errors. With
        ``first_dtype``, the first frame's depth sets :attr:`notes`."""
        import imageio.v3 as iio

        planes = png16_planes(self.path)
        if planes:  # a 16-bit colour PNG: one frame, at 16 bits
            if first_dtype:
                self.notes = depth_note(np.uint16, str(self.path))
            yield to_grey(_read_png16(self.path, planes), str(self.path))
            return
        try:
            with warnings.catch_warnings():  # imageio's plugin probing warns on bad files
                warnings.simplefilter("ignore")
                for frame in iio.imiter(self.path):
                    if first_dtype:
                        self.notes = depth_note(np.asarray(frame).dtype, str(self.path))
                        first_dtype = False
                    yield to_grey(frame, str(self.path))
        except RvsmError:
            raise
        except Exception as exc:
            reason = str(exc).strip().splitlines()[0] if str(exc).strip() else "unreadable"
            raise RvsmError(
                f"{self.path}: cannot read this {self.what} ({type(exc).__name__}: {reason}); "
                "the file may be corrupt or truncated"
            ) from None

    def _next(self) -> np.ndarray:
        assert self._reader is not None
        frame = next(self._reader, None)
        if frame is None or frame.shape != self._shape[1:]:
            raise RvsmError(f"{self.path}: {self.what} changed since the scene was loaded")
        self._position += 1
        return frame

    def frame_range(self, f0: int, f1: int) -> np.ndarray:
        """Frames ``f0 .. f1 - 1`` decoded: a fresh ``(f1 - f0, H, W) float64`` array."""
        out = np.empty((max(f1 - f0, 0), *self._shape[1:]))
        start, last = self._last
        f = f0
        while f < f1 and start <= f < start + len(last):
            out[f - f0] = last[f - start]
            f += 1
        if f < f1:
            if self._reader is None or f < self._position:
                self.close()
                self._reader = self._frames()
                self._position = 0
            while self._position < f:
                self._next()
            while f < f1:
                out[f - f0] = self._next()
                f += 1
        if len(out):
            keep = min(len(out), 2)
            self._last = (f1 - keep, out[-keep:].copy())
        return out

    def close(self) -> None:
        """Close the reader (reopened by the next :meth:`frame_range`)."""
        if self._reader is not None:
            self._reader.close()  # type: ignore[attr-defined]
            self._reader = None

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state.update(_reader=None, _position=0, _last=(0, self._last[1][:0]))
        return state
