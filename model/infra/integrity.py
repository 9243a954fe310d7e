"""Integrity checks of the files the project writes: damage is reported, never read as data.

* ``.npz`` (spike and stimulus files): every zip member carries a CRC-32 of its bytes;
  :func:`verify_npz` reads each member to its end (1 MiB at a time, so memory stays
  bounded), which makes :mod:`zipfile` check it, and names the first damaged member.
* ``.h5`` spike files: the ``spikes`` dataset carries HDF5's Fletcher-32 checksum per
  chunk (checked by HDF5 on every read) and the root attributes a CRC-32 over their
  canonical JSON (:func:`header_crc32`), checked by the reader.
* The camera's ``.dat`` has no room for a checksum (no header): its reader checks only that
  the size is a whole number of steps (``docs/cli.md``, "Damaged input files").
"""

from __future__ import annotations

import json
import os
import zipfile
import zlib
from pathlib import Path

from rvsm.model.infra.errors import RvsmError

__all__ = ["header_crc32", "verify_npz"]

_BLOCK = 1 << 20


def verify_npz(path: str | os.PathLike, what: str = "file") -> None:
    """Check every member of the ``.npz`` archive ``path`` against its CRC-32.

    :class:`RvsmError` naming the damaged member (or the archive's directory when the
    archive itself cannot be opened); ``what`` names the file kind in the message
    (``"spike file"``)."""
    p = Path(path)
    try:
        archive = zipfile.ZipFile(p)
    except (zipfile.BadZipFile, OSError, ValueError, EOFError, NotImplementedError,
            RuntimeError) as exc:
        raise RvsmError(f"{p} is truncated or corrupt: the {what}'s zip directory "
                        f"cannot be read ({exc})") from None
    with archive:
        try:
            infos = archive.infolist()
        except (zipfile.BadZipFile, ValueError) as exc:  # pragma: no cover - defensive
            raise RvsmError(f"{p} is a damaged {what}: {exc}") from None
        for info in infos:
            try:
                with archive.open(info) as member:
                    while member.read(_BLOCK):
                        pass
            except (zipfile.BadZipFile, zlib.error, OSError, EOFError, ValueError,
                    NotImplementedError, RuntimeError) as exc:
                raise RvsmError(f"{p} is corrupt: member {info.filename!r} of the {what} "
                                f"fails its integrity check ({exc})") from None


def header_crc32(fields: dict) -> str:
    """CRC-32 (8 hex digits) of ``fields`` as canonical JSON (sorted keys): the checksum
    an HDF5 spike file keeps over its header attributes."""
    text = json.dumps(fields, sort_keys=True, default=str).encode()
    return f"{zlib.crc32(text) & 0xFFFFFFFF:08x}"
