"""What a build says on stderr while it works: one line as each phase starts
(:func:`note`) and, while a phase lasts, a line every :data:`HEARTBEAT_SECONDS`
(:func:`still`), so a minutes-long generation or compile (the full sensor's) is never a
silent wait. Lines go above any progress bar."""

from __future__ import annotations

import contextlib
import sys
import threading
import time
from collections.abc import Iterator

__all__ = ["HEARTBEAT_SECONDS", "note", "still"]

#: Seconds between two "still ..." lines of a phase.
HEARTBEAT_SECONDS = 30.0


def note(text: str) -> None:
    """One progress line ``rvsm: text`` on stderr (above any progress bar)."""
    from tqdm import tqdm

    tqdm.write(f"rvsm: {text}", file=sys.stderr)


@contextlib.contextmanager
def still(text: str, every: float | None = None) -> Iterator[None]:
    """While the block runs, say ``rvsm: still TEXT (M:SS elapsed)`` every ``every`` s
    (default :data:`HEARTBEAT_SECONDS`)."""
    period = HEARTBEAT_SECONDS if every is None else every
    done = threading.Event()
    t0 = time.monotonic()

    def beat() -> None:
        while not done.wait(period):
            s = int(time.monotonic() - t0)
            note(f"still {text} ({s // 60}:{s % 60:02d} elapsed)")

    thread = threading.Thread(target=beat, name="rvsm-build-heartbeat", daemon=True)
    thread.start()
    try:
        yield
    finally:
        done.set()
        thread.join()
