"""The spike camera's ``.dat`` files (FSM spikes only, one bit per pixel).

Layout, as the camera writes it: no header; step after step, each step ``H*W/8`` bytes
holding one bit per pixel, 8 pixels per byte, least significant bit first; the pixels in
row-major order with the image's rows **bottom-up** (the file's first row is the image's
last). That is the layout SpikeCV's reader (``spkData/load_dat.py``, from the camera's
makers) decodes with its default ``flipud=True``: bit ``i % 8`` of byte ``i // 8`` of a
step is file pixel ``i``, file row ``i // W`` is image row ``H - 1 - i // W``.
``flip=True`` writes and reads the rows top-down instead (the image's first row first),
on both export and import. Whole arrays (:func:`export_dat`, :func:`import_dat`), a
chunked writer (:class:`DatWriter`, a spike sink) and a chunked reader
(:func:`dat_source`).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from rvsm.model.infra.atomic import PartialFile, atomic_path
from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.memory import require_memory
from rvsm.model.spikes.arrays import single_scale_spikes
from rvsm.model.spikes.source import SpikeSource


def _file_rows(frames: np.ndarray, flip: bool) -> np.ndarray:
    """Image frames ``(T, H, W)`` in the file's row order (bottom-up unless ``flip``); the
    same map takes file rows back to image rows."""
    return frames if flip else frames[:, ::-1]


def export_dat(path: str | os.PathLike, spikes: np.ndarray, flip: bool = False) -> None:
    """Write FSM spikes ``(T, H, W)`` or ``(T, 1, H, W)`` of 0/1 in the camera's layout
    (rows bottom-up; ``flip``: top-down)."""
    spikes = single_scale_spikes(spikes, ".dat (one bit per pixel)")
    if spikes.size and (spikes.min() < 0 or spikes.max() > 1):
        raise RvsmError(".dat holds only 0/1 spikes; RVSM's -1 spikes cannot be exported")
    t, h, w = spikes.shape
    if (h * w) % 8:
        raise RvsmError(f".dat needs H*W divisible by 8 (8 pixels per byte), got {h}x{w}")
    frames = _file_rows(spikes, flip)
    packed = np.packbits(frames.reshape(t, h * w).astype(bool), axis=1, bitorder="little")
    with atomic_path(path) as tmp:
        packed.tofile(tmp)


def dat_steps(path: str | os.PathLike, height: int, width: int) -> np.ndarray:
    """The steps of a camera ``.dat`` file, checked against ``height x width``, as a
    read-only memory map ``(T, H*W/8) uint8`` (one row of packed bits per step)."""
    path = Path(path)
    if not path.is_file():
        raise RvsmError(f".dat file {path} does not exist")
    if height < 1 or width < 1 or (height * width) % 8:
        raise RvsmError(
            f".dat size {height}x{width} invalid: H*W must be positive and divisible by 8"
        )
    step_bytes = height * width // 8
    size = path.stat().st_size
    if size == 0 or size % step_bytes:
        raise RvsmError(
            f"{path} is truncated or not {height}x{width}: {size} bytes is not a whole "
            f"number of steps of {step_bytes} bytes; check --size"
        )
    return np.memmap(path, dtype=np.uint8, mode="r").reshape(-1, step_bytes)


def unpack_dat(rows: np.ndarray, height: int, width: int, flip: bool = False) -> np.ndarray:
    """Spikes ``(T, 1, H, W) int8`` of ``.dat`` step rows ``(T, H*W/8) uint8`` (rows
    bottom-up in the file; ``flip``: top-down)."""
    bits = np.unpackbits(np.asarray(rows), axis=1, bitorder="little")
    frames = _file_rows(bits.reshape(-1, height, width), flip)
    return np.ascontiguousarray(frames[:, None]).astype(np.int8)


def import_dat(
    path: str | os.PathLike, height: int, width: int, flip: bool = False
) -> np.ndarray:
    """Read a camera ``.dat`` file into spikes ``(T, 1, H, W) int8`` (rows bottom-up in
    the file; ``flip``: top-down)."""
    raw = dat_steps(path, height, width)
    require_memory(9 * raw.size, f"{path} (one int8 per pixel)",
                   "split the .dat file into shorter recordings")
    return unpack_dat(raw, height, width, flip)


class DatWriter:
    """A spike sink writing FSM spikes in the camera's ``.dat`` layout, chunk by chunk,
    atomically (the layout of the module docstring: rows bottom-up; ``flip``: top-down)."""

    def __init__(self, path: str | os.PathLike, flip: bool = False):
        self.path = Path(path)
        self.flip = flip
        self._handle = None
        self._partial: PartialFile | None = None

    def check(self, shape, meta) -> None:
        """Refuse spikes the layout cannot hold (several scales, ``H*W`` not a multiple
        of 8, events) before any file is opened."""
        t, s, h, w = shape
        if meta.get("kind") == "events":
            raise RvsmError(".dat holds the spike camera's one-bit spikes and events have two "
                            "polarities (ON/OFF): write events with rvsm events export "
                            "(HDF5 event list, AEDAT4, EVT or CSV; docs/events.md)")
        if s != 1:
            raise RvsmError(f".dat (one bit per pixel) needs single-scale (FSM) spikes; these "
                            f"have {s} scales")
        if (h * w) % 8:
            raise RvsmError(f".dat needs H*W divisible by 8 (8 pixels per byte), got {h}x{w}")

    def begin(self, shape, meta) -> None:
        self.check(shape, meta)
        self._partial = PartialFile(self.path)
        self._handle = open(self._partial.path, "wb")  # closed in finish / abort

    def write(self, t0, spikes) -> None:
        arr = spikes[:, 0]
        if arr.size and (arr.min() < 0 or arr.max() > 1):
            raise RvsmError(".dat holds only 0/1 spikes; RVSM's -1 spikes cannot be exported")
        arr = _file_rows(arr, self.flip)
        t, h, w = arr.shape
        np.packbits(arr.reshape(t, h * w).astype(bool), axis=1,
                    bitorder="little").tofile(self._handle)

    def finish(self, meta) -> None:
        self._handle.close()
        self._handle = None
        self._partial.commit()
        self._partial = None

    def abort(self) -> None:
        if self._handle is not None:
            self._handle.close()
            self._handle = None
        if self._partial is not None:
            self._partial.abort()
        self._partial = None


def dat_source(path: str | os.PathLike, height: int, width: int,
               flip: bool = False) -> SpikeSource:
    """A camera ``.dat`` file as a :class:`SpikeSource` of ``(T, 1, H, W)`` spikes, read
    step range by step range (memory-mapped)."""
    raw = dat_steps(path, height, width)

    def read(t0: int, t1: int) -> np.ndarray:
        return unpack_dat(raw[t0:t1], height, width, flip)

    return SpikeSource((raw.shape[0], 1, height, width), {}, read, None, str(path))
