"""Write result files atomically: a failed or interrupted run never leaves a partial file."""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from rvsm.model.infra.errors import os_error

_UMASK = os.umask(0)
os.umask(_UMASK)


class PartialFile:
    """A hidden temporary file beside ``target`` (same suffix, so writers that infer a
    format still work) for a writer that fills it over several calls: write to
    :attr:`path`, then :meth:`commit` renames it onto ``target`` with a normal file mode,
    or :meth:`abort` removes it; ``target`` is untouched until the commit. An ``OSError``
    becomes a one-line error (:func:`~rvsm.model.infra.errors.os_error`): a full disk a
    ``ToolError`` (exit 3), a read-only or forbidden location an ``RvsmError`` (exit 2).
    """

    def __init__(self, target: str | os.PathLike) -> None:
        self.target = Path(target)
        #: folders this file created, innermost first (removed again by an abort)
        self._made: list[Path] = []
        folder = self.target.parent
        while not folder.exists() and folder != folder.parent:
            self._made.append(folder)
            folder = folder.parent
        try:
            self.target.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(prefix=f".{self.target.stem}.",
                                       suffix=f".partial{self.target.suffix}",
                                       dir=self.target.parent)
        except OSError as exc:
            raise os_error(exc, self.target) from None
        os.close(fd)
        self.path: Path | None = Path(tmp)

    def commit(self) -> None:
        """Give the file a normal mode (``mkstemp`` makes 0600) and rename it onto the
        target."""
        try:
            os.chmod(self.path, 0o666 & ~_UMASK)
            os.replace(self.path, self.target)
        except OSError as exc:
            self.abort()
            raise os_error(exc, self.target) from None
        self.path = None

    def abort(self) -> None:
        """Remove the temporary file and the folders it created, when empty (nothing
        happens after a commit)."""
        if self.path is not None:
            self.path.unlink(missing_ok=True)
            for folder in self._made:
                try:
                    folder.rmdir()
                except OSError:  # not empty (another output went there) or gone
                    break
        self.path = None


@contextlib.contextmanager
def atomic_path(target: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``target``; rename it onto ``target`` on success
    (:class:`PartialFile`). On any exception the temporary file is removed and ``target``
    is left untouched; an ``OSError`` is mapped as by :class:`PartialFile`.
    """
    partial = PartialFile(target)
    try:
        yield partial.path
        partial.commit()
    except OSError as exc:  # a full disk while writing is one line too
        raise os_error(exc, partial.target) from None
    finally:
        partial.abort()


def write_text_atomic(target: str | os.PathLike, text: str) -> None:
    """Write ``text`` to ``target`` atomically (UTF-8)."""
    with atomic_path(target) as tmp:
        tmp.write_text(text, encoding="utf-8")
