"""What a build says on stderr while it works: one line as each phase starts
(:func:`note`) and, while a phase lasts, a line every :data:`HEARTBEAT_SECONDS`
(:func:`still`), so a minutes-long generation or compile (the full sensor's) is never a
silent wait. Lines go above any progress bar."""

from __future__ import annotations

import contextlib
import sys
import threading
import time
from collections.abc import Callable, Iterator

__all__ = ["HEARTBEAT_SECONDS", "note", "still"]

#: Seconds between two "still ..." lines of a phase: a fresh clone's ``make demo`` may not
#: sit silent for more than 10 s (issue 33); 8 s leaves room for a thread that numba's
#: compiler keeps from the GIL (at 10 s a warm-up gap measured 10.4 s).
HEARTBEAT_SECONDS = 8.0


def note(text: str) -> None:
    """One progress line ``rvsm: text`` on stderr (above any progress bar)."""
    from tqdm import tqdm

    tqdm.write(f"rvsm: {text}", file=sys.stderr)


@contextlib.contextmanager
def still(text: str | Callable[[], str], every: float | None = None,
          echo: Callable[[str], None] | None = None) -> Iterator[None]:
    """While the block runs, say ``rvsm: still TEXT (M:SS elapsed)`` every ``every`` s
    (default :data:`HEARTBEAT_SECONDS`). ``text`` may be a callable, asked at each line
    (a count that moves); ``echo`` writes the line (default :func:`note`'s stderr, as it
    is when the line is said: give one bound to a stream to say it past a redirection)."""
    period = HEARTBEAT_SECONDS if every is None else every
    done = threading.Event()
    t0 = time.monotonic()

    def beat() -> None:
        while not done.wait(period):
            s = int(time.monotonic() - t0)
            line = f"still {text() if callable(text) else text} ({s // 60}:{s % 60:02d} elapsed)"
            if echo is None:
                note(line)
            else:
                echo(f"rvsm: {line}")

    thread = threading.Thread(target=beat, name="rvsm-build-heartbeat", daemon=True)
    thread.start()
    try:
        yield
    finally:
        done.set()
        thread.join()
