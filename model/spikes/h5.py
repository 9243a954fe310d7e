"""HDF5 spike files: written chunk by chunk (:class:`H5SpikeWriter`), read lazily
(:func:`open_h5`).

Layout (``.h5``): dataset ``spikes``, chunked along time (about 1 MiB per chunk, one
scale per chunk) and compressed (LZF by default, gzip or none as options); root
attributes ``meta`` (the same JSON text as in ``.npz`` files), ``format =
"rvsm-spikes"``, ``format_version = 2``, ``encoding``, ``shape`` (``T, S, H, W``),
``complete`` (True only once every step was written) and ``header_crc32`` (CRC-32 of the
other attributes, :func:`~rvsm.model.infra.integrity.header_crc32`).
``encoding = "2bit"`` (default):
``spikes`` is ``(T, S, H, ceil(W / 4)) uint8``, four spikes per byte
(:mod:`.packing`: 0 -> 00, 1 -> 01, -1 -> 11, pixel ``x`` at bits ``2 (x mod 4)``);
``encoding = "int8"``: ``spikes`` is ``(T, S, H, W) int8`` in {-1, 0, 1}, readable by any
HDF5 tool as is. Packing first makes the file smaller and the compression 4x cheaper.

Integrity (format version 2): ``spikes`` carries HDF5's Fletcher-32 checksum per chunk and
the attributes their CRC-32; a damaged chunk or attribute is an :class:`RvsmError` naming
it, never different spikes. Version-1 files (written before the checksums) are read
without them.

Atomicity: :class:`H5SpikeWriter` writes to a temporary ``.NAME.*.partial.h5`` beside the
target, sets ``complete`` and renames it onto the target only after the last chunk, so a
killed run never leaves a file under the target's name, and a partial file (if one were
renamed by hand) is refused by :func:`open_h5`.
"""

from __future__ import annotations

import contextlib
import json
import os
from pathlib import Path

import numpy as np

from rvsm.model.infra.atomic import PartialFile
from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.integrity import header_crc32
from rvsm.model.infra.versions import with_versions
from rvsm.model.spikes.packing import pack_spikes, packed_width, unpack_spikes
from rvsm.model.spikes.source import SpikeSource

FORMAT = "rvsm-spikes"
FORMAT_VERSION = 2
#: Versions this reader takes (1: before the checksums).
READABLE_VERSIONS = (1, 2)
H5_SUFFIXES = (".h5", ".hdf5")
CHUNK_BYTES = 1 << 20
COMPRESSIONS = ("lzf", "gzip", "none")
ENCODINGS = ("2bit", "int8")


def is_h5_path(path: str | os.PathLike) -> bool:
    """True when ``path`` names an HDF5 spike file (``.h5`` / ``.hdf5``)."""
    return Path(path).suffix.lower() in H5_SUFFIXES


def _h5py():
    try:
        import h5py
    except ImportError as exc:  # pragma: no cover - a declared dependency
        raise RvsmError(f"HDF5 spike files need h5py ({exc}); pip install h5py") from None
    return h5py


class H5SpikeWriter:
    """A spike sink (:mod:`.sinks`) writing an HDF5 spike file atomically."""

    def __init__(self, path: str | os.PathLike, compression: str = "lzf",
                 encoding: str = "2bit"):
        if compression not in COMPRESSIONS:
            raise RvsmError(f"compression must be one of {COMPRESSIONS}, got {compression!r}")
        if encoding not in ENCODINGS:
            raise RvsmError(f"encoding must be one of {ENCODINGS}, got {encoding!r}")
        self.encoding = encoding
        self.path = Path(path)
        self.compression = None if compression == "none" else compression
        self._file = None
        self._partial: PartialFile | None = None
        self._dset = None
        self.steps_written = 0

    def begin(self, shape, meta) -> None:
        h5py = _h5py()
        t, s, h, w = (int(v) for v in shape)
        self._partial = PartialFile(self.path)
        self._file = h5py.File(self._partial.path, "w", libver=("v110", "latest"))
        wb, dtype = (packed_width(w), np.uint8) if self.encoding == "2bit" else (w, np.int8)
        chunk_t = max(1, min(max(t, 1), CHUNK_BYTES // max(h * wb, 1)))
        opts = {"compression": self.compression} if self.compression else {}
        if self.compression == "gzip":
            opts["compression_opts"] = 1
        self._dset = self._file.create_dataset(
            "spikes", shape=(t, s, h, wb), dtype=dtype,
            chunks=(chunk_t, 1, h, wb) if t else None, shuffle=False,
            fletcher32=bool(t), **opts,
        )
        self._file.attrs["encoding"] = _fixed(self.encoding)
        self._file.attrs["shape"] = np.array([t, s, h, w], dtype=np.int64)
        self._file.attrs["format"] = _fixed(FORMAT)
        self._file.attrs["format_version"] = FORMAT_VERSION
        self._file.attrs["complete"] = False
        self._file.attrs["meta"] = _fixed(json.dumps(with_versions(meta), sort_keys=True))
        self._seal()

    def _seal(self) -> None:
        """Set ``header_crc32`` over the other root attributes."""
        self._file.attrs["header_crc32"] = _fixed(header_crc32(_header_fields(self._file.attrs)))

    def write(self, t0, spikes) -> None:
        b = spikes.shape[0]
        self._dset[t0:t0 + b] = pack_spikes(spikes) if self.encoding == "2bit" else spikes
        self.steps_written = t0 + b

    def finish(self, meta) -> None:
        expected = self._dset.shape[0]
        if self.steps_written != expected:
            self.abort()
            raise RvsmError(
                f"{self.path}: only {self.steps_written} of {expected} steps written"
            )
        self._file.attrs["meta"] = _fixed(json.dumps(with_versions(meta), sort_keys=True))
        self._file.attrs["complete"] = True
        self._seal()
        self._file.close()
        self._file = None
        self._partial.commit()
        self._partial = None

    def abort(self) -> None:
        self._file, self._partial = abort_partial(self._file, self._partial)


def abort_partial(handle, partial: PartialFile | None) -> tuple[None, None]:
    """Close an open HDF5 ``handle`` (errors ignored: it is being thrown away) and remove
    its :class:`PartialFile`; returns ``(None, None)`` for the writer's two fields."""
    if handle is not None:
        with contextlib.suppress(Exception):
            handle.close()
    if partial is not None:
        partial.abort()
    return None, None


def _fixed(text: str) -> np.bytes_:
    """``text`` as a fixed-length HDF5 string attribute: it lives in the (checksummed)
    object header, where a variable-length string lives in the unchecked global heap
    (a damaged global heap can make HDF5 loop forever)."""
    return np.bytes_(text.encode())


def _text(value) -> str:
    """An attribute's text, whether stored fixed-length (bytes) or variable-length."""
    if isinstance(value, bytes | np.bytes_):
        return bytes(value).decode("utf-8", errors="replace")
    return str(value)


def _header_fields(attrs) -> dict:
    """The root attributes the header checksum covers, as JSON-able values."""
    fields = {}
    for key in ("format", "format_version", "encoding", "shape", "complete", "meta"):
        if key in attrs:
            value = attrs[key]
            if isinstance(value, bytes | np.bytes_ | str):
                fields[key] = _text(value)
            else:
                fields[key] = value.tolist() if hasattr(value, "tolist") else value
    return fields


def open_h5(path: str | os.PathLike) -> SpikeSource:
    """Open an HDF5 spike file lazily; refuses foreign, incomplete, inconsistent or
    damaged files (checksums: module docstring)."""
    path = Path(path)
    if not path.is_file():
        raise RvsmError(f"spike file {path} does not exist")
    h5py = _h5py()
    try:
        handle = h5py.File(path, "r")
    except (OSError, ValueError, RuntimeError) as exc:
        raise RvsmError(f"{path} is not a readable HDF5 spike file (damaged or not HDF5): "
                        f"{exc}") from None
    try:
        try:
            dset, shape, encoding, meta = _open_checked(handle, path)
        except RvsmError:
            raise
        except (OSError, KeyError, ValueError, TypeError, RuntimeError) as exc:
            raise RvsmError(f"{path} is a damaged HDF5 spike file: its header cannot be "
                            f"read ({exc})") from None
    except BaseException:
        handle.close()
        raise

    def read(t0: int, t1: int) -> np.ndarray:
        try:
            block = dset[t0:t1]
        except (OSError, ValueError, RuntimeError) as exc:
            raise RvsmError(f"{path} is damaged: dataset 'spikes' steps {t0}-{t1 - 1} fail "
                            f"their integrity check ({exc})") from None
        if encoding == "2bit":
            return unpack_spikes(block, shape[3])
        return block
    return SpikeSource(shape, meta, read, handle.close, str(path))


def _open_checked(handle, path: Path) -> tuple:
    """``(dataset, shape, encoding, meta)`` of an open spike file, after every check."""
    attrs = handle.attrs
    if _text(attrs.get("format", "")) != FORMAT or "spikes" not in handle:
        raise RvsmError(f"{path} is not an rvsm spike file (no 'spikes' / format)")
    version = int(attrs.get("format_version", 1))
    if version not in READABLE_VERSIONS:
        raise RvsmError(f"{path}: spike file format version {version} is not one this rvsm "
                        f"reads ({', '.join(map(str, READABLE_VERSIONS))}); the file is "
                        f"damaged or from a newer rvsm")
    if version >= 2:
        stored = attrs.get("header_crc32")
        if stored is None or _text(stored) != header_crc32(_header_fields(attrs)):
            raise RvsmError(f"{path} is damaged: its header attributes fail their CRC-32 "
                            f"check")
    if not bool(attrs.get("complete", False)):
        raise RvsmError(f"{path} is incomplete (the run that wrote it did not finish)")
    try:
        meta = json.loads(_text(attrs["meta"]))
    except (KeyError, json.JSONDecodeError) as exc:
        raise RvsmError(f"{path}: 'meta' missing or not valid JSON ({exc})") from None
    if not isinstance(meta, dict):
        raise RvsmError(f"{path}: 'meta' must be a JSON object")
    dset = handle["spikes"]
    if not isinstance(dset, _h5py().Dataset):
        raise RvsmError(f"{path}: 'spikes' is not a dataset")
    encoding = _text(attrs.get("encoding", "int8"))
    raw_shape = np.asarray(attrs.get("shape", dset.shape)).reshape(-1)
    if raw_shape.size != 4 or not np.issubdtype(raw_shape.dtype, np.integer) \
            or (raw_shape < 0).any():
        raise RvsmError(f"{path}: attribute 'shape' {raw_shape.tolist()} is not 4 "
                        f"non-negative integers")
    shape = tuple(int(v) for v in raw_shape)
    if encoding == "2bit":
        ok = dset.dtype == np.uint8 and dset.shape == shape[:3] + (packed_width(shape[3]),)
    else:
        ok = encoding == "int8" and dset.dtype == np.int8 and dset.shape == shape
    if dset.ndim != 4 or not ok:
        raise RvsmError(f"{path}: spikes dataset {dset.shape} {dset.dtype} does not match "
                        f"encoding {encoding!r} and shape {shape}")
    if version >= 2 and shape[0] and not dset.fletcher32:
        raise RvsmError(f"{path} is damaged: dataset 'spikes' lost its Fletcher-32 checksum")
    return dset, shape, encoding, meta
