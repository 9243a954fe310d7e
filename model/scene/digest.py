"""What a scene argument holds, as a digest: results keyed by content, not by name.

A built-in scene is rendered from its name (and the size and frames a run asks for, which
callers key separately): its digest is ``builtin:<name>``. A scene file (``.npy``, image,
video) or image folder is keyed by the SHA-256 of its bytes (a folder: of each image's
name and bytes, in the loader's order), read 1 MiB at a time, so replacing
``mine.npy`` with different frames changes the digest and every result keyed by it.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.file_frames import IMAGE_SUFFIXES
from rvsm.model.scene.library import SCENE_NAMES

__all__ = ["scene_digest"]

_BLOCK = 1 << 20


def _feed(digest: hashlib._Hash, path: Path) -> None:
    with open(path, "rb") as handle:
        while block := handle.read(_BLOCK):
            digest.update(block)


def scene_digest(scene: str | os.PathLike) -> str:
    """``builtin:<name>`` or ``sha256:<24 hex digits>`` of the file or folder's content;
    :class:`RvsmError` when the path cannot be read."""
    if os.fspath(scene) in SCENE_NAMES:  # a built-in scene (loaders.is_builtin)
        return f"builtin:{os.fspath(scene)}"
    path = Path(scene)
    digest = hashlib.sha256()
    try:
        if path.is_dir():
            for member in sorted(p for p in path.iterdir()
                                 if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES):
                digest.update(member.name.encode() + b"\0")
                _feed(digest, member)
        else:
            _feed(digest, path)
    except OSError as exc:
        raise RvsmError(f"scene {path}: cannot be read ({exc.strerror or exc})") from None
    return f"sha256:{digest.hexdigest()[:24]}"
