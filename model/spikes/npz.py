"""Spike files: the project's ``.npz`` format and the spike camera's ``.dat`` layout.

``.npz``: ``spikes`` -- ``(T, S, H, W) int8`` in {-1, 0, 1} (S = 1 for FSM) -- and
``meta`` -- a JSON string with every parameter needed to reproduce the file.

``.dat`` (FSM only, as the camera writes it): no header; step after step, each step
``H*W/8`` bytes holding one bit per pixel in row-major order, 8 pixels per byte, least
significant bit first. The camera stores rows bottom-up; ``flip=True`` flips vertically on
both export and import (SpikeCV's loaders do).
"""

from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path

import numpy as np

from rvsm.model.infra.atomic import atomic_path
from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.memory import require_memory
from rvsm.model.infra.npy_guard import check_npz_members
from rvsm.model.infra.versions import with_versions


def save_spikes(path: str | os.PathLike, spikes: np.ndarray, meta: dict) -> None:
    """Write ``spikes (T, S, H, W) int8`` and ``meta`` to an ``.npz`` file, atomically;
    ``meta`` gains ``versions`` (rvsm, numpy, Python: :func:`~.versions.with_versions`)."""
    spikes = _check_spikes(np.asarray(spikes), str(path))
    text = json.dumps(with_versions(meta), sort_keys=True)
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        np.savez_compressed(handle, spikes=spikes, meta=np.array(text))


def load_spikes(path: str | os.PathLike) -> tuple[np.ndarray, dict]:
    """Read an ``.npz`` spike file: ``(spikes (T, S, H, W) int8, meta dict)``."""
    path = Path(path)
    if not path.is_file():
        raise RvsmError(f"spike file {path} does not exist")
    check_npz_members(path, {"spikes": 4, "meta": 0})
    try:
        with np.load(path, allow_pickle=False) as data:
            missing = {"spikes", "meta"} - set(data.files)
            if missing:
                raise RvsmError(
                    f"{path} is not an rvsm spike file: missing {', '.join(sorted(missing))}"
                )
            spikes = data["spikes"]
            meta_text = str(data["meta"])
    except RvsmError:
        raise
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as exc:
        raise RvsmError(
            f"{path} is not a readable .npz spike file (truncated or corrupt?): {exc}"
        ) from None
    try:
        meta = json.loads(meta_text)
    except json.JSONDecodeError as exc:
        raise RvsmError(f"{path}: 'meta' is not valid JSON ({exc})") from None
    if not isinstance(meta, dict):
        raise RvsmError(f"{path}: 'meta' must be a JSON object")
    return _check_spikes(spikes, str(path)), meta


def _check_spikes(spikes: np.ndarray, source: str) -> np.ndarray:
    if spikes.ndim != 4:
        raise RvsmError(f"{source}: spikes must have shape (T, S, H, W), got {spikes.shape}")
    if not np.issubdtype(spikes.dtype, np.integer):
        raise RvsmError(f"{source}: spikes must be integers, got dtype {spikes.dtype}")
    if spikes.size and (spikes.min() < -1 or spikes.max() > 1):
        raise RvsmError(f"{source}: spikes must hold only -1, 0 and 1")
    return spikes.astype(np.int8, copy=False)


def single_scale_spikes(spikes: np.ndarray, purpose: str) -> np.ndarray:
    """``(T, H, W)`` or ``(T, 1, H, W)`` spikes -> ``(T, H, W)``; refuses several scales.

    ``purpose`` names what needs one bit per pixel, for the error message.
    """
    arr = np.asarray(spikes)
    if arr.ndim == 4:
        if arr.shape[1] != 1:
            raise RvsmError(
                f"{purpose} needs single-scale (FSM) spikes; these have {arr.shape[1]} scales"
            )
        arr = arr[:, 0]
    if arr.ndim != 3:
        raise RvsmError(
            f"{purpose} needs spikes (T, H, W) or (T, 1, H, W), got shape {arr.shape}"
        )
    return arr


def export_dat(path: str | os.PathLike, spikes: np.ndarray, flip: bool = False) -> None:
    """Write FSM spikes ``(T, H, W)`` or ``(T, 1, H, W)`` of 0/1 in the camera's layout."""
    spikes = single_scale_spikes(spikes, ".dat (one bit per pixel)")
    if spikes.size and (spikes.min() < 0 or spikes.max() > 1):
        raise RvsmError(".dat holds only 0/1 spikes; RVSM's -1 spikes cannot be exported")
    t, h, w = spikes.shape
    if (h * w) % 8:
        raise RvsmError(f".dat needs H*W divisible by 8 (8 pixels per byte), got {h}x{w}")
    frames = spikes[:, ::-1] if flip else spikes
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
    """Spikes ``(T, 1, H, W) int8`` of ``.dat`` step rows ``(T, H*W/8) uint8``."""
    bits = np.unpackbits(np.asarray(rows), axis=1, bitorder="little")
    frames = bits.reshape(-1, height, width)
    if flip:
        frames = frames[:, ::-1]
    return np.ascontiguousarray(frames[:, None]).astype(np.int8)


def import_dat(
    path: str | os.PathLike, height: int, width: int, flip: bool = False
) -> np.ndarray:
    """Read a camera ``.dat`` file into spikes ``(T, 1, H, W) int8``."""
    raw = dat_steps(path, height, width)
    require_memory(9 * raw.size, f"{path} (one int8 per pixel)",
                   "split the .dat file into shorter recordings")
    return unpack_dat(raw, height, width, flip)
