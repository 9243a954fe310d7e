"""One build per key across processes: an advisory lock beside each cached build.

Two processes (two Dask workers, two ``rvsm verify`` runs) asking for the same build key
at once would both compile it (minutes of Verilator each, on the same cores). Before
building ``<build_root>/<name>``, :func:`build_lock` takes ``fcntl.flock`` on
``<build_root>/<name>.lock``: the first process builds, the others wait (saying so on
stderr) and then find the finished build in the cache. The kernel releases the lock when
its holder dies (SIGKILL included), so a crashed builder never blocks the others; its
half-made ``<name>.tmp<pid>`` folder is stale by then, and :func:`remove_stale` (called
under the lock, where no other process can be building that name) removes it. The holder
removes the ``.lock`` file before it lets go, so none is left behind; a waiter that then
gets the lock of a removed file sees that the path no longer names its file and takes
the lock again on the new one (:func:`_acquire`), so two processes never both hold it.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import shutil
import sys
import time
from collections.abc import Iterator
from pathlib import Path

__all__ = ["build_lock", "lock_path", "remove_stale", "sweep_stale"]


def lock_path(final: Path) -> Path:
    """The lock file of the build folder ``final``."""
    return final.with_name(f"{final.name}.lock")


def _acquire(path: Path, wait: bool, on_wait=None) -> int | None:
    """A descriptor of ``path`` holding its exclusive lock (None when busy and not
    ``wait``); ``on_wait()`` is called once before waiting."""
    waited = False
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
        try:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                if not wait:
                    os.close(fd)
                    return None
                if not waited and on_wait is not None:
                    on_wait()
                waited = True
                fcntl.flock(fd, fcntl.LOCK_EX)  # a signal's KeyboardInterrupt ends the wait
            mine = os.fstat(fd)
            try:
                now = os.stat(path)
            except FileNotFoundError:
                now = None
            if now is not None and (now.st_ino, now.st_dev) == (mine.st_ino, mine.st_dev):
                return fd
            os.close(fd)  # its holder removed that file: lock the one there now
        except BaseException:
            os.close(fd)
            raise


def _release(path: Path, fd: int) -> None:
    """Remove the lock file (while still holding it), then let go."""
    try:
        with contextlib.suppress(OSError):
            os.unlink(path)
    finally:
        os.close(fd)


@contextlib.contextmanager
def build_lock(final: Path, note: bool = True) -> Iterator[bool]:
    """Hold the lock of build folder ``final`` for the block; yields True when another
    process held it first (so the build may be in the cache now). With ``note``, a wait
    is announced on stderr."""
    final.parent.mkdir(parents=True, exist_ok=True)
    path = lock_path(final)
    waited: list[float] = []

    def say() -> None:
        waited.append(time.monotonic())
        if note:
            print(f"rvsm: another process is building {final.name}; waiting for it "
                  "(one build per design)", file=sys.stderr, flush=True)

    fd = _acquire(path, True, say)
    assert fd is not None
    try:
        if waited and note:
            print(f"rvsm: waited {time.monotonic() - waited[0]:.0f} s for {final.name}",
                  file=sys.stderr, flush=True)
        yield bool(waited)
    finally:
        _release(path, fd)


def remove_stale(final: Path) -> list[Path]:
    """Remove the half-made ``<final>.tmp<pid>`` folders of dead builders (call it
    holding :func:`build_lock` of ``final``); the folders removed."""
    gone = []
    for tmp in final.parent.glob(f"{final.name}.tmp*"):
        shutil.rmtree(tmp, ignore_errors=True)
        gone.append(tmp)
    return gone


def sweep_stale(build_root: str | os.PathLike) -> list[Path]:
    """Remove every half-made build folder in ``build_root`` that no live process is
    building (its lock is free): what a killed worker left. The folders removed."""
    root = Path(build_root)
    gone: list[Path] = []
    if not root.is_dir():
        return gone
    finals = {p.with_name(p.name.rsplit(".tmp", 1)[0]) for p in root.glob("*.tmp*")
              if p.is_dir()}
    for final in sorted(finals):
        fd = _acquire(lock_path(final), False)
        if fd is None:
            continue  # being built now
        try:
            gone += remove_stale(final)
        finally:
            _release(lock_path(final), fd)
    return gone
