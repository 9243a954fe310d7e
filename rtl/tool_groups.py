"""The process groups of the tools running now, and the interrupt that stops them all.

Every tool :func:`rvsm.rtl.toolchain.run_tool` starts is the leader of its own process
group, recorded here while it runs (:func:`tracked`). A terminal's Ctrl-C reaches only the
``rvsm`` process group, not the tools' groups, and Python delivers a signal to the main
thread alone, while tools may run on worker threads (``rvsm formal -j 2``, ``rvsm fpga
--seeds``). So the interrupt is one mechanism, here, for every tool of every command:

- :func:`interrupt_handlers` (installed once by the CLI) turns SIGINT, SIGTERM and
  SIGHUP into :func:`interrupt` then ``KeyboardInterrupt("SIGTERM")`` in the main thread;
- :func:`interrupt` marks the process as stopping and sends SIGTERM to every tracked
  group at once (a group that outlives :data:`GRACE_SECONDS` gets SIGKILL when its
  thread unwinds, :func:`stop_group`);
- :func:`raise_if_stopping` is asked by ``run_tool`` before a tool starts, while it runs
  and when it ends: a worker thread then raises ``KeyboardInterrupt`` too instead of
  starting its next tool or reading a killed tool as a failure;
- :func:`thread_map` runs work on threads and, when interrupted, starts nothing more and
  joins the threads before the interrupt goes on.

The exit status of an interrupt is ``128 + signal`` (:func:`exit_status`: 130 SIGINT,
143 SIGTERM, 129 SIGHUP). A signal the caller ignores (``nohup``, the SIGINT of a
background job in a script) stays ignored.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import signal
import subprocess
import threading
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from typing import TypeVar

__all__ = ["GRACE_SECONDS", "INTERRUPT_SIGNALS", "exit_status", "interrupt", "kill_group",
           "interrupt_handlers", "kill_all", "live_groups", "raise_if_stopping",
           "stop_group", "stopping", "thread_map", "tracked"]

#: Seconds a tool's group gets between SIGTERM and SIGKILL when the parent is interrupted.
GRACE_SECONDS = 2.0

#: Signals that interrupt a command: the same cleanup, exit status ``128 + signal``.
INTERRUPT_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)

_live: dict[int, subprocess.Popen] = {}  # process-group id -> leader
_lock = threading.Lock()
_stop = threading.Event()
_stopped_by: list[int] = []  # the first interrupting signal


def live_groups() -> list[int]:
    """Process-group ids of the tools running now (for tests and diagnostics)."""
    with _lock:
        return list(_live)


def kill_group(pgid: int, sig: int) -> None:
    try:
        os.killpg(pgid, sig)
    except (ProcessLookupError, PermissionError):
        pass


def stop_group(proc: subprocess.Popen) -> None:
    """SIGTERM the group of ``proc`` (the leader of its own group), SIGKILL it
    after :data:`GRACE_SECONDS`, reap the leader."""
    kill_group(proc.pid, signal.SIGTERM)
    try:
        proc.wait(timeout=GRACE_SECONDS)
    except subprocess.TimeoutExpired:
        pass
    kill_group(proc.pid, signal.SIGKILL)
    proc.wait()


@contextlib.contextmanager
def tracked(proc: subprocess.Popen) -> Iterator[subprocess.Popen]:
    """Record ``proc``'s group as live (:func:`interrupt` and :func:`kill_all` stop it)
    while the block runs; on any exception in the block (``KeyboardInterrupt``, a
    timeout) stop the group before the exception propagates. A process already
    interrupted stops the group at once (the signal may have come just before it was
    recorded)."""
    with _lock:
        _live[proc.pid] = proc
    try:
        raise_if_stopping()  # after recording: interrupt() sees the group or we see it
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


def stopping() -> bool:
    """Whether the process has been interrupted (:func:`interrupt`)."""
    return _stop.is_set()


def _signal_name(number: int) -> str:
    try:
        return signal.Signals(number).name
    except ValueError:
        return f"signal {number}"


def raise_if_stopping() -> None:
    """``KeyboardInterrupt("SIGINT")`` (the interrupting signal's name) once the process
    is interrupted, in any thread: no tool starts or goes on after an interrupt."""
    if _stop.is_set():
        raise KeyboardInterrupt(_signal_name(_stopped_by[0] if _stopped_by
                                             else signal.SIGINT))


def interrupt(signum: int = signal.SIGINT) -> None:
    """Mark the process as interrupted by ``signum`` and send SIGTERM to every tool group
    now (without waiting: safe in a signal handler). Threads running tools notice
    (:func:`raise_if_stopping`) and unwind."""
    if not _stop.is_set():
        _stopped_by[:] = [signum]
        _stop.set()
    for pgid in list(_live):  # a copy: no lock in a signal handler
        kill_group(pgid, signal.SIGTERM)


def _reset() -> None:
    _stop.clear()
    _stopped_by.clear()


def _on_signal(signum: int, frame: object) -> None:
    """The handler of :func:`interrupt_handlers`: later signals are ignored while the
    cleanup runs; the tools are stopped; the main thread unwinds like Ctrl-C."""
    for sig in INTERRUPT_SIGNALS:
        if signal.getsignal(sig) is not signal.SIG_IGN:
            signal.signal(sig, signal.SIG_IGN)
    interrupt(signum)
    raise KeyboardInterrupt(_signal_name(signum))


@contextlib.contextmanager
def interrupt_handlers() -> Iterator[None]:
    """For the block (the main thread of a command): SIGINT, SIGTERM and SIGHUP, unless
    ignored, stop every tool and raise ``KeyboardInterrupt`` named after the signal.
    Afterwards the handlers are as they were and the process is no longer stopping."""
    previous = {sig: signal.getsignal(sig) for sig in INTERRUPT_SIGNALS}
    for sig, handler in previous.items():
        if handler is not signal.SIG_IGN:  # `nohup rvsm ...` keeps ignoring SIGHUP
            signal.signal(sig, _on_signal)
    try:
        yield
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        _reset()


def exit_status(exc: KeyboardInterrupt) -> int:
    """``128 + signal`` for an interrupt named after its signal (``KeyboardInterrupt
    ("SIGTERM")``: 143), else 130 (a plain Ctrl-C)."""
    name = str(exc.args[0]) if exc.args else ""
    try:
        return 128 + int(signal.Signals[name])
    except KeyError:
        return 128 + int(signal.SIGINT)


T = TypeVar("T")
R = TypeVar("R")


def thread_map(fn: Callable[[T], R], items: Iterable[T], jobs: int) -> list[R]:
    """``[fn(x) for x in items]``, ``jobs`` at a time on threads (in order), for work
    that waits on tools. On an exception nothing not yet started starts and the threads
    are joined before it goes on; on an interrupt their tools are stopped first
    (:func:`interrupt`, also for a Ctrl-C without :func:`interrupt_handlers`), so the
    join takes a moment, not the rest of the solver's run."""
    pool = ThreadPoolExecutor(max_workers=max(1, jobs))
    futures = [pool.submit(fn, x) for x in items]
    ours = False
    try:
        return [f.result() for f in futures]
    except BaseException as exc:
        for f in futures:
            f.cancel()
        if isinstance(exc, KeyboardInterrupt) and not stopping():
            ours = True  # a Ctrl-C without the CLI's handlers: stop the threads' tools
            interrupt(signal.SIGINT)
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
        if ours:
            _reset()
