"""Read a text input (TOML design points and sweep files) as UTF-8, refusing in one line a
file that is unreadable, not UTF-8, or starts with a byte-order mark."""

from __future__ import annotations

import codecs
import os
from pathlib import Path

from rvsm.model.infra.errors import RvsmError


def read_utf8_text(path: str | os.PathLike, what: str) -> str:
    """The text of ``path`` (``what`` names it in messages, e.g. ``"design point"``)."""
    p = Path(path)
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise RvsmError(f"cannot read {what} {p}: {exc.strerror or exc}") from None
    if raw.startswith(codecs.BOM_UTF8):
        raise RvsmError(f"{p}: starts with a byte-order mark (BOM); save the {what} as plain "
                        "UTF-8 without BOM")
    if raw.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        raise RvsmError(f"{p}: is UTF-16 text; save the {what} as UTF-8")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw[: exc.start].count(b"\n") + 1
        raise RvsmError(f"{p}: not UTF-8 text (byte 0x{raw[exc.start]:02x} on line {line}); "
                        f"save the {what} as UTF-8") from None
