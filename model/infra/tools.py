"""External tools (iverilog, vvp, verilator, make, g++, yosys) run in their own process group.

Every tool the package starts goes through :func:`run_tool`: the child gets a new session
(so a new process group that holds it and everything it forks: ``make`` -> ``g++`` ->
``cc1plus``), is recorded while it runs, and the whole group is killed when the parent
is interrupted (``KeyboardInterrupt``, which the CLI also raises for SIGTERM and SIGHUP)
or when the tool itself dies (a ``make`` killed by the out-of-memory killer must not leave
its compilers running). A failing tool raises :class:`ToolFailure` (a
:class:`~rvsm.model.infra.errors.ToolError`, exit status 3 in the CLI) whose one-line message
names the tool, its exit status (or the signal that killed it) and its log.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import signal
import subprocess
import threading
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import IO

from rvsm.model.infra.errors import ToolError

__all__ = ["ToolFailure", "describe_status", "kill_all", "live_groups", "run_tool",
           "stop_group", "tracked"]

#: Seconds a tool's group gets between SIGTERM and SIGKILL when the parent is interrupted.
GRACE_SECONDS = 2.0

_live: dict[int, subprocess.Popen] = {}  # process-group id -> leader
_lock = threading.Lock()


class ToolFailure(ToolError):
    """A tool exited non-zero or was killed: ``tool``, ``status`` (negative: signal) and
    ``log`` (path of its output, or None)."""

    def __init__(self, tool: str, status: int, log: str | os.PathLike | None,
                 detail: str = "") -> None:
        self.tool, self.status, self.detail = tool, status, detail
        self.log = None if log is None else Path(log)
        where = f"; log: {self.log}" if self.log is not None else ""
        extra = f": {detail}" if detail else ""
        super().__init__(f"{tool} {describe_status(status)}{extra}{where}")


def describe_status(status: int) -> str:
    """``"exited with status 2"`` or ``"was killed by SIGKILL (status -9)"``."""
    if status < 0:
        try:
            name = signal.Signals(-status).name
        except ValueError:
            name = f"signal {-status}"
        return f"was killed by {name} (status {status})"
    return f"exited with status {status}"


def live_groups() -> list[int]:
    """Process-group ids of the tools running now (for tests and diagnostics)."""
    with _lock:
        return list(_live)


def _kill_group(pgid: int, sig: int) -> None:
    try:
        os.killpg(pgid, sig)
    except (ProcessLookupError, PermissionError):
        pass


def stop_group(proc: subprocess.Popen) -> None:
    """SIGTERM the group of ``proc`` (started with ``start_new_session=True``), SIGKILL it
    after :data:`GRACE_SECONDS`, reap the leader."""
    _kill_group(proc.pid, signal.SIGTERM)
    try:
        proc.wait(timeout=GRACE_SECONDS)
    except subprocess.TimeoutExpired:
        pass
    _kill_group(proc.pid, signal.SIGKILL)
    proc.wait()


@contextlib.contextmanager
def tracked(proc: subprocess.Popen):
    """Record ``proc``'s group as live (:func:`kill_all` stops it) while the block runs;
    on any exception in the block (``KeyboardInterrupt``, a timeout) stop the group before
    the exception propagates. For callers that read a tool's output themselves
    (:func:`rvsm.rtl.fpga.tools.run_tool`)."""
    with _lock:
        _live[proc.pid] = proc
    try:
        yield proc
    except BaseException:
        stop_group(proc)
        raise
    finally:
        with _lock:
            _live.pop(proc.pid, None)


def kill_all() -> None:
    """Stop every tool group still running (called at interpreter exit too)."""
    with _lock:
        procs = list(_live.values())
        _live.clear()
    for proc in procs:
        stop_group(proc)


atexit.register(kill_all)


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
) -> subprocess.CompletedProcess:
    """Run ``cmd`` (an argv list, never a shell string) in its own process group.

    Output goes to ``stdout`` (a file object, stderr merged into it), to the file ``log``
    (created; stderr merged), is captured (``capture``: text in ``.stdout``/``.stderr``)
    or is inherited. ``tool`` names the tool in errors (default: ``cmd[0]``'s name);
    ``log`` is named in them too. With ``check`` a non-zero status raises
    :class:`ToolFailure`. On any exception while it runs (``KeyboardInterrupt``), the
    group is terminated before the exception propagates; after the leader exits, any
    process left in its group is killed.
    """
    argv = [os.fspath(c) for c in cmd]
    name = tool or Path(argv[0]).name
    handle = None
    if log is not None and stdout is None and not capture:
        Path(log).parent.mkdir(parents=True, exist_ok=True)
        handle = open(log, "w", encoding="utf-8")  # noqa: SIM115 (closed below)
        stdout = handle
    kwargs: dict = {"cwd": cwd, "env": None if env is None else dict(env),
                    "start_new_session": True}
    if capture:
        kwargs.update(stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    elif stdout is not None:
        kwargs.update(stdout=stdout, stderr=subprocess.STDOUT)
    try:
        try:
            proc = subprocess.Popen(argv, **kwargs)
        except FileNotFoundError as exc:
            raise ToolFailure(name, 127, log, f"{argv[0]} not found ({exc.strerror})") \
                from exc
        except PermissionError as exc:
            raise ToolFailure(name, 126, log, f"cannot execute {argv[0]}") from exc
        with tracked(proc):
            out, err = proc.communicate()
        _kill_group(proc.pid, signal.SIGKILL)  # stragglers of a tool that died or forked
    finally:
        if handle is not None:
            handle.close()
    result = subprocess.CompletedProcess(argv, proc.returncode, out, err)
    if check and proc.returncode != 0:
        detail = ""
        if capture and log is None:
            lines = (err or out or "").strip().splitlines()
            detail = lines[-1][-300:] if lines else ""
        raise ToolFailure(name, proc.returncode, log, detail)
    return result
