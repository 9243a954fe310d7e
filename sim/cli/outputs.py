"""Check output locations before the work: writable, not an input, not another kind of file.

Every ``rvsm`` command that writes calls :func:`check_outputs` right after parsing, so a
bad ``-o`` is refused in one line before minutes or hours of computation:

- a file output must not be a folder, and its parent folder must be writable (checked
  with ``os.access`` and a probe file, so a read-only file system is caught too) or, when
  missing, creatable: its nearest existing ancestor is a writable folder (the writers
  create missing folders, as :mod:`.atomic` does);
- a folder output is likewise an existing writable folder or one that can be created;
- no output may be one of the inputs (same resolved path or same inode), lie inside an
  input folder (an image-folder scene), or hold an input when it is a folder;
- an existing file of a different kind (e.g. a ``.npy`` scene where a spike file would
  go) is only replaced with ``--force``; the same kind (re-running a command) is fine.

Refusals are :class:`~rvsm.model.infra.errors.RvsmError` (exit status 2) except a full
disk found by the
probe, which is a :class:`~rvsm.model.infra.errors.ToolError` (exit status 3), as at write time
(:mod:`rvsm.model.infra.atomic` maps ``OSError`` the same way, through
:func:`rvsm.model.infra.errors.os_error`).
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import tempfile
import zipfile
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

from rvsm.model.infra.errors import RvsmError, os_error

__all__ = ["FOLDER", "Output", "check_outputs", "existing_kind", "kind_for_suffix", "os_error",
           "removed_if_interrupted"]

#: The kind of a folder output.
FOLDER = "folder"
#: Kind of files with no recognised signature (text, ``.dat``, Verilog, CSV...).
PLAIN = "plain file"

_SIGNATURES: tuple[tuple[bytes, str], ...] = (
    (b"\x93NUMPY", "numpy array (.npy)"),
    (b"\x89PNG\r\n\x1a\n", "PNG image"),
    (b"\xff\xd8\xff", "JPEG image"),
    (b"GIF8", "GIF image"),
    (b"II*\x00", "TIFF image"),
    (b"MM\x00*", "TIFF image"),
    (b"%PDF", "PDF document"),
    (b"SQLite format 3\x00", "SQLite database"),
    (b"\x89HDF\r\n\x1a\n", "HDF5 file"),
)
_SUFFIX_KINDS = {
    ".npy": "numpy array (.npy)", ".png": "PNG image", ".jpg": "JPEG image",
    ".jpeg": "JPEG image", ".gif": "GIF image", ".tif": "TIFF image", ".tiff": "TIFF image",
    ".pdf": "PDF document", ".sqlite": "SQLite database", ".db": "SQLite database",
    ".h5": "HDF5 file", ".hdf5": "HDF5 file",
}
_STIMULUS_MEMBERS = {"codes.npy", "thresholds.npy", "spikes.npy", "contract.npy"}


@dataclass(frozen=True)
class Output:
    """One output of a command: its ``path``, ``kind`` (what it holds, e.g. ``"spike
    file"``, :data:`FOLDER`, or ``None`` for "from the suffix") and the ``option`` that
    named it (for messages), plus, for a folder, the ``files`` it will hold (name, kind)."""

    path: str | os.PathLike
    option: str = "-o"
    kind: str | None = None
    files: tuple[tuple[str, str | None], ...] = ()


def kind_for_suffix(path: str | os.PathLike) -> str:
    """The kind a file of this suffix holds when written (``.npz`` -> numpy archive)."""
    suffix = Path(path).suffix.lower()
    if suffix == ".npz":
        return "numpy archive (.npz)"
    return _SUFFIX_KINDS.get(suffix, PLAIN)


def existing_kind(path: str | os.PathLike) -> str:
    """What an existing ``path`` holds, from its first bytes (and an ``.npz``'s members):
    ``"folder"``, ``"empty file"``, ``"spike file"``, ``"stimulus file"``, ``"numpy
    archive (.npz)"``, a signature kind (``"PNG image"``...) or :data:`PLAIN`."""
    p = Path(path)
    if p.is_dir():
        return FOLDER
    try:
        with open(p, "rb") as handle:
            head = handle.read(64)
    except OSError:
        return PLAIN
    if not head:
        return "empty file"
    if head.startswith(b"PK"):
        try:
            with zipfile.ZipFile(p) as zf:
                names = set(zf.namelist())
        except (zipfile.BadZipFile, OSError):
            return "zip archive"
        if _STIMULUS_MEMBERS <= names:
            return "stimulus file"
        if {"spikes.npy", "meta.npy"} <= names:
            return "spike file"
        return "numpy archive (.npz)"
    for magic, kind in _SIGNATURES:
        if head.startswith(magic):
            if kind == "HDF5 file":
                return _hdf5_kind(p)
            return kind
    return PLAIN


def _hdf5_kind(path: Path) -> str:
    try:
        import h5py
    except ImportError:
        return "HDF5 file"
    try:
        with h5py.File(path, "r") as f:
            if "spikes" in f:
                return "spike file"
            fmt = f.attrs.get("format", b"")
            fmt = fmt.decode() if isinstance(fmt, bytes) else str(fmt)
            return "event list" if fmt == "rvsm-events" else "HDF5 file"
    except Exception:  # unreadable HDF5: still an HDF5 file, not ours to judge here
        return "HDF5 file"


def _compatible(existing: str, writing: str) -> bool:
    if existing in ("empty file", writing):
        return True
    archives = ("numpy archive (.npz)", "spike file", "stimulus file")
    return writing == "numpy archive (.npz)" and existing in archives




def _probe(folder: Path, option: str, target: Path) -> None:
    """Refuse unless ``folder`` is an existing folder where a file can be created."""
    if not folder.is_dir():
        raise RvsmError(f"{option} {target}: {folder} is not a folder")
    if not os.access(folder, os.W_OK | os.X_OK):
        code = errno.EROFS if _read_only(folder) else errno.EACCES
        raise os_error(OSError(code, os.strerror(code)), folder,
                       f"write into {option} {target}: folder")
    try:
        fd, tmp = tempfile.mkstemp(prefix=".rvsm-probe-", dir=folder)
    except OSError as exc:
        raise os_error(exc, folder, f"write into {option} {target}: folder") from None
    os.close(fd)
    os.unlink(tmp)


def _read_only(folder: Path) -> bool:
    try:
        return bool(os.statvfs(folder).f_flag & os.ST_RDONLY)
    except (OSError, AttributeError):  # pragma: no cover - no statvfs
        return False


def _nearest_existing(path: Path) -> Path:
    p = path
    while not p.exists():
        if p.parent == p:
            break
        p = p.parent
    return p


def _same(a: Path, b: Path) -> bool:
    if a.resolve() == b.resolve():
        return True
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def _inside(path: Path, folder: Path) -> bool:
    try:
        path.resolve().relative_to(folder.resolve())
    except ValueError:
        return False
    return True


def _check_not_input(target: Path, option: str, inputs: Sequence[Path]) -> None:
    for src in inputs:
        if _same(target, src):
            raise RvsmError(f"{option} {target} is also an input ({src}); refusing to "
                            "overwrite an input: choose another output")
        if src.is_dir() and _inside(target, src):
            raise RvsmError(f"{option} {target} lies inside the input folder {src}; "
                            "choose an output outside it")


def _check_replace(target: Path, option: str, kind: str, force: bool) -> None:
    if not target.exists():
        return
    have = existing_kind(target)
    if have == FOLDER:
        raise RvsmError(f"{option} {target} is a folder; give a file name")
    if not force and not _compatible(have, kind):
        raise RvsmError(f"{option} {target} exists and holds {_a(have)}, not {_a(kind)}; "
                        "choose another name, or pass --force to replace it")


def _a(kind: str) -> str:
    """``kind`` with its indefinite article, by sound ("an HDF5 file", "an event list")."""
    return f"{'an' if kind[:1].lower() in 'aeio' or kind.startswith(('HDF', 'SQL')) else 'a'}" \
        f" {kind}"


def _check_file(out: Output, inputs: Sequence[Path], force: bool) -> None:
    target = Path(out.path)
    kind = out.kind or kind_for_suffix(target)
    _check_not_input(target, out.option, inputs)
    _check_replace(target, out.option, kind, force)
    parent = target.parent if str(target.parent) else Path(".")
    if parent.exists():
        _probe(parent, out.option, target)
        return
    base = _nearest_existing(parent)  # missing folders are created when writing
    if not base.is_dir():
        raise RvsmError(f"{out.option} {target}: cannot create folder {parent}, {base} is "
                        "not a folder")
    _probe(base, out.option, target)


def _check_folder(out: Output, inputs: Sequence[Path], force: bool) -> None:
    folder = Path(out.path)
    _check_not_input(folder, out.option, inputs)
    for src in inputs:
        if _inside(src, folder) and src.is_dir():
            raise RvsmError(f"{out.option} {folder} holds the input folder {src}; "
                            "choose another output folder")
    if folder.exists():
        if not folder.is_dir():
            raise RvsmError(f"{out.option} {folder} exists and is not a folder")
        _probe(folder, out.option, folder)
        for name, kind in out.files:
            sub = folder / name
            _check_not_input(sub, out.option, inputs)
            if kind == FOLDER:
                if sub.exists() and not sub.is_dir():
                    raise RvsmError(f"{out.option} {folder}: {sub} exists and is not a folder")
            else:
                _check_replace(sub, out.option, kind or kind_for_suffix(name), force)
        return
    base = _nearest_existing(folder)
    if not base.is_dir():
        raise RvsmError(f"{out.option} {folder}: cannot create it, {base} is not a folder")
    _probe(base, out.option, folder)


def check_outputs(outputs: Iterable[Output | None | str], inputs: Iterable[str | os.PathLike | None]
                  = (), force: bool = False) -> None:
    """Refuse (one line) any output that cannot be written or must not be; see the
    module docstring. Empty entries (``None``, ``""``: options not given) are skipped;
    ``inputs`` that are not existing paths (built-in scene names) are ignored."""
    srcs = [Path(p) for p in inputs if p is not None and Path(p).exists()]
    outs = [o for o in outputs if o and o.path not in (None, "")]
    for out in outs:
        if out.kind == FOLDER:
            _check_folder(out, srcs, force)
        else:
            _check_file(out, srcs, force)
    seen: dict[Path, str] = {}
    for out in outs:
        key = Path(out.path).resolve()
        if key in seen:
            raise RvsmError(f"{out.option} and {seen[key]} name the same file {out.path}")
        seen[key] = out.option


def default_results(plan: str | os.PathLike) -> Path:
    """Where a plan's or sweep's results database goes when ``-o`` is not given:
    ``build/<plan name>.sqlite`` in the current folder, never beside the plan (which may
    sit in the source tree); its coverage folder goes beside the database."""
    return Path("build") / f"{Path(plan).stem}.sqlite"


@contextlib.contextmanager
def removed_if_interrupted(folder: str | os.PathLike) -> Iterator[None]:
    """A command's output folder that is complete or absent: when the block is
    interrupted, ``folder`` is removed if the command made it, else the empty folders
    left in it (what an interrupted step made and emptied again) are. The steps inside
    remove their own half-made work (e.g. :func:`rvsm.sim.formal.sby.run_sby`)."""
    root = Path(folder)
    existed = root.exists()
    try:
        yield
    except KeyboardInterrupt:
        if not existed:
            shutil.rmtree(root, ignore_errors=True)
        elif root.is_dir():
            for sub in sorted((p for p in root.rglob("*") if p.is_dir()),
                              key=lambda p: len(p.parts), reverse=True):
                with contextlib.suppress(OSError):
                    sub.rmdir()  # only an empty folder goes
        raise
