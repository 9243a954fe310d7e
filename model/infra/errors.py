"""The one exception type users see: a message that says what is wrong and how to fix it."""

from __future__ import annotations

import errno
import os


class RvsmError(Exception):
    """A user-facing error (bad input, bad configuration, missing tool).

    The CLI prints ``rvsm: error: <message>`` on one line and exits non-zero; the message
    must name what is wrong and, where possible, how to fix it. Line breaks a message
    quotes from its input (a TOML key, a file name, a library's own message) are shown
    escaped (``\\n``), so a message is always one line.
    """

    def __init__(self, *args: object) -> None:
        if args and isinstance(args[0], str):
            args = (_one_line(args[0]), *args[1:])
        super().__init__(*args)


def _one_line(message: str) -> str:
    return message.replace("\r\n", "\\n").replace("\n", "\\n").replace("\r", "\\r")


def shown(text: object) -> str:
    """``text`` as a message may quote it: as is when printable, else Python-escaped
    (a TOML key ``"\\n"`` or a file name with a newline must not break the one-line
    message)."""
    text = str(text)
    return text if text.isprintable() else repr(text)


class ToolError(RvsmError):
    """An external tool (synthesis, place-and-route, simulator) failed or is missing.

    The CLI prints it like :class:`RvsmError` but exits with status 3 (tool/environment
    failure) instead of 2 (bad input).
    """

def os_error(exc: OSError, target: str | os.PathLike, what: str = "write") -> RvsmError:
    """The user-facing error for an ``OSError`` met writing ``target``: a full disk or an
    I/O error, a read-only or forbidden location is a :class:`ToolError` (exit 3: the
    environment cannot take the output); a missing or malformed path an
    :class:`RvsmError` (exit 2) saying what to fix."""
    code = exc.errno
    reason = os.strerror(code) if code else str(exc)
    if code in (errno.ENOSPC, errno.EDQUOT):
        return ToolError(f"cannot {what} {target}: {reason} (disk full); free space or "
                         "choose another location; no partial file was left")
    if code in (errno.EROFS, errno.EACCES, errno.EPERM):
        return ToolError(f"cannot {what} {target}: {reason}; choose a writable location")
    if code in (errno.ENOENT, errno.ENOTDIR, errno.EISDIR, errno.ENAMETOOLONG):
        return RvsmError(f"cannot {what} {target}: {reason}; check the path")
    return ToolError(f"cannot {what} {target}: {reason}")


def interrupt_behind(exc: BaseException) -> KeyboardInterrupt | None:
    """The ``KeyboardInterrupt`` that is ``exc`` or caused it (``__cause__``/``__context__``).

    Python wraps an exception raised while a class is set up (``__set_name__``, e.g. during
    a lazy import) in a ``RuntimeError``; a signal arriving then must still exit 130.
    """
    seen: set[int] = set()
    current: BaseException | None = exc
    while current is not None and id(current) not in seen:
        if isinstance(current, KeyboardInterrupt):
            return current
        seen.add(id(current))
        current = current.__cause__ or current.__context__
    return None
