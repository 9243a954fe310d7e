"""Check ``.npy`` headers before loading: the shape a file claims is checked against the
bytes it holds and the memory available, so a hostile or corrupt header is refused in one
line instead of allocating ``(100000, 4, 250, 400)`` first."""

from __future__ import annotations

import math
import os
import tokenize
import zipfile
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

import numpy as np
import numpy.lib.format as npformat

from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.memory import require_memory

#: Largest ratio of uncompressed to compressed size deflate can reach (about 1032:1).
MAX_DEFLATE_RATIO = 1100


#: Largest ``.npy`` header read (bytes); numpy writes a few hundred.
MAX_HEADER_BYTES = 1 << 16


def _header(handle: BinaryIO, source: str, available: int | None = None
            ) -> tuple[tuple[int, ...], np.dtype, int, bool]:
    """``(shape, dtype, header bytes, fortran order)`` of the ``.npy`` stream at ``handle``
    (seekable),
    ``available`` bytes long; a header length beyond the data (or over
    :data:`MAX_HEADER_BYTES`) is refused before numpy reads it."""
    try:
        head = handle.read(12)
        handle.seek(0)
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
        raise RvsmError(f"{source}: cannot load .npy data ({exc})") from None
    if len(head) >= 10 and head[:6] == b"\x93NUMPY":
        size = (int.from_bytes(head[8:10], "little") if head[6] == 1
                else int.from_bytes(head[8:12], "little"))
        if size > MAX_HEADER_BYTES or (available is not None and size > available):
            raise RvsmError(f"{source}: cannot load .npy data, its header claims {size} "
                            f"bytes; the file is truncated or corrupt")
    try:
        version = npformat.read_magic(handle)
        if version == (1, 0):
            shape, fortran, dtype = npformat.read_array_header_1_0(handle)
        else:
            shape, fortran, dtype = npformat.read_array_header_2_0(handle)
    except (ValueError, OSError, EOFError, SyntaxError, tokenize.TokenError, TypeError,
            KeyError, zipfile.BadZipFile, zlib.error) as exc:
        raise RvsmError(f"{source}: cannot load .npy data, bad array header ({exc})") from None
    return tuple(int(v) for v in shape), np.dtype(dtype), handle.tell(), bool(fortran)


def _check_size(shape: tuple[int, ...], dtype: np.dtype, data_bytes: int, source: str) -> int:
    """Refuse pickles and a shape larger than the bytes that follow the header; returns
    the array's bytes."""
    if dtype.hasobject:
        raise RvsmError(f"{source}: holds Python objects (pickles), which rvsm never loads")
    nbytes = math.prod(shape) * dtype.itemsize
    if nbytes > data_bytes:
        raise RvsmError(f"{source}: header claims shape {shape} ({nbytes} bytes) but only "
                        f"{data_bytes} bytes follow; the file is truncated or corrupt")
    return nbytes


def _check(shape: tuple[int, ...], dtype: np.dtype, data_bytes: int, source: str) -> int:
    nbytes = _check_size(shape, dtype, data_bytes, source)
    require_memory(nbytes, f"{source} (shape {shape}, {dtype})",
                   "use a smaller file or a machine with more memory")
    return nbytes


def check_npy_file(path: str | os.PathLike) -> tuple[int, ...]:
    """Check an ``.npy`` file's header against its size and the memory; returns the shape."""
    p = Path(path)
    with open(p, "rb") as handle:
        shape, dtype, offset, _ = _header(handle, str(p), p.stat().st_size)
    _check(shape, dtype, p.stat().st_size - offset, str(p))
    return shape


@dataclass(frozen=True)
class NpyLayout:
    """Where an ``.npy`` file's array lies: ``shape``, ``dtype``, the data's byte
    ``offset`` and ``fortran_order``."""

    shape: tuple[int, ...]
    dtype: np.dtype
    offset: int
    fortran_order: bool


def npy_layout(path: str | os.PathLike) -> NpyLayout:
    """Check an ``.npy`` file's header against its size (not against the memory: for a
    file that is memory-mapped, not loaded) and return its :class:`NpyLayout`."""
    p = Path(path)
    try:
        with open(p, "rb") as handle:
            shape, dtype, offset, fortran = _header(handle, str(p), p.stat().st_size)
    except OSError as exc:
        raise RvsmError(f"{p}: cannot load .npy data ({exc.strerror or exc})") from None
    _check_size(shape, dtype, p.stat().st_size - offset, str(p))
    return NpyLayout(shape, dtype, offset, fortran)


def check_npz_members(path: str | os.PathLike, ndims: dict[str, int | None],
                      lazy: tuple[str, ...] = ()) -> None:
    """Check the headers of the members ``ndims`` names (``name -> ndim``, None = any) of
    an ``.npz`` file before :func:`numpy.load` allocates them; missing members and
    unreadable archives are left to the loader's own messages. Members named in
    ``lazy`` are read a range at a time, never whole: checked against the bytes they
    hold, not against the memory."""
    p = Path(path)
    try:
        zf = zipfile.ZipFile(p)
    except (zipfile.BadZipFile, OSError, ValueError, EOFError, NotImplementedError,
            RuntimeError):
        return
    with zf:
        names = set(zf.namelist())
        for name, ndim in ndims.items():
            member = f"{name}.npy"
            if member not in names:
                continue
            info = zf.getinfo(member)
            source = f"{p}: {name!r}"
            if info.compress_type != zipfile.ZIP_STORED and \
                    info.file_size > MAX_DEFLATE_RATIO * max(info.compress_size, 1) + 4096:
                raise RvsmError(f"{source} claims {info.file_size} bytes from "
                                f"{info.compress_size} compressed; the archive is corrupt")
            try:
                with zf.open(info) as handle:
                    shape, dtype, offset, _ = _header(handle, source, info.file_size)
            except (zipfile.BadZipFile, zlib.error, OSError, EOFError, ValueError,
                    NotImplementedError, RuntimeError) as exc:
                raise RvsmError(f"{source}: unreadable member, the archive is damaged "
                                f"({exc})") from None
            if ndim is not None and len(shape) != ndim:
                raise RvsmError(f"{source} must have {ndim} dimensions, got shape {shape}")
            if name in lazy:
                _check_size(shape, dtype, info.file_size - offset, source)
            else:
                _check(shape, dtype, info.file_size - offset, source)


def npz_member_layout(archive: zipfile.ZipFile, info: zipfile.ZipInfo, source: str
                      ) -> NpyLayout:
    """The :class:`NpyLayout` of the ``.npy`` member ``info`` of an open archive
    (``offset``: the data's offset inside the member's uncompressed bytes), its header
    checked against the member's size (not against the memory)."""
    try:
        with archive.open(info) as handle:
            shape, dtype, offset, fortran = _header(handle, source, info.file_size)
    except (zipfile.BadZipFile, zlib.error, OSError, EOFError, ValueError,
            NotImplementedError, RuntimeError) as exc:
        raise RvsmError(f"{source}: unreadable member, the archive is damaged "
                        f"({exc})") from None
    _check_size(shape, dtype, info.file_size - offset, source)
    return NpyLayout(shape, dtype, offset, fortran)
