"""What a followed tool reports (:func:`rvsm.rtl.toolchain.run_tool` with ``follow``).

:class:`ProgressFollower` says how a long tool is followed (its phases, recognised from
its log lines, a detail for heartbeats, the expected duration) and :class:`Progress` is
one report of it; :class:`Tail` reads the new lines of a log a tool writes itself.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

__all__ = ["HEARTBEAT_SECONDS", "Progress", "ProgressFollower", "Tail"]

#: Seconds between two heartbeats of a followed tool: a command never sits silent on
#: stderr for more than 10 s (issue 42).
HEARTBEAT_SECONDS = 8.0


@dataclass(frozen=True)
class Progress:
    """One progress report: which step, its phase, seconds elapsed and expected."""

    step: str
    phase: str
    elapsed: float
    expected: float | None
    done: bool = False

    def line(self) -> str:
        """``"place & route: routing -- 1:05 elapsed, about 4:00 expected"``."""
        text = f"{self.step}: {self.phase} -- {_mmss(self.elapsed)} elapsed"
        if self.done:
            return f"{self.step}: done in {_mmss(self.elapsed)}"
        if self.expected:
            text += f", about {_mmss(self.expected)} expected"
        return text


def _mmss(seconds: float) -> str:
    s = int(round(seconds))
    return f"{s // 3600}:{s % 3600 // 60:02d}:{s % 60:02d}" if s >= 3600 \
        else f"{s // 60}:{s % 60:02d}"


@dataclass(frozen=True)
class ProgressFollower:
    """How :func:`run_tool` follows a long tool: the ``step`` it reports to
    ``on_progress``, its ``phases`` (log-line regex, phase name; in order, phases only move
    forward), an optional ``detail`` (regex with one integer group, format such as
    ``"{:,} arcs left"``) shown in heartbeats every ``heartbeat`` s, the ``expected``
    duration (s) and ``log_file``: a log the tool writes and flushes itself (relative to
    the tool's folder), read instead of its console, whose pipe may arrive in blocks of
    kilobytes (WebAssembly tools)."""

    step: str
    on_progress: Callable[[Progress], None] | None = None
    phases: tuple[tuple[re.Pattern[str], str], ...] = ()
    detail: tuple[re.Pattern[str], str] | None = None
    expected: float | None = None
    heartbeat: float = HEARTBEAT_SECONDS
    log_file: str | os.PathLike | None = None

    def report(self, phase: str, elapsed: float, done: bool = False) -> None:
        """Send one :class:`Progress` to ``on_progress`` (if any)."""
        if self.on_progress is not None:
            self.on_progress(Progress(self.step, phase, elapsed, self.expected, done))



class Tail:
    """Complete new lines of a growing text file (which may not exist yet)."""

    def __init__(self, path: Path):
        self.path, self.handle, self.partial, self.last = path, None, "", ""

    def read_lines(self) -> list[str]:
        if self.handle is None:
            try:
                self.handle = open(self.path, encoding="utf-8", errors="replace")  # noqa: SIM115
            except OSError:
                return []
        text = self.partial + self.handle.read()
        *done, self.partial = text.split("\n")
        for line in reversed(done):
            if line.strip():
                self.last = line.strip()
                break
        return done

    def close(self) -> None:
        if self.handle is not None:
            self.handle.close()
