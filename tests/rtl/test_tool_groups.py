"""One interrupt for every tool: tools on worker threads stop with the main thread."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from rvsm.rtl.tool_groups import exit_status, stopping
from tests.conftest import default_signals
from tests.rtl.test_toolchain import _alive, _wait_dead


def test_exit_status_is_128_plus_the_signal() -> None:
    assert exit_status(KeyboardInterrupt("SIGTERM")) == 143
    assert exit_status(KeyboardInterrupt("SIGHUP")) == 129
    assert exit_status(KeyboardInterrupt("SIGINT")) == 130
    assert exit_status(KeyboardInterrupt()) == 130  # a plain Ctrl-C
    assert not stopping()


@pytest.mark.parametrize("handlers", [True, False], ids=["cli-handlers", "plain-ctrl-c"])
def test_tools_on_worker_threads_stop_on_an_interrupt(tmp_path: Path, handlers: bool
                                                      ) -> None:
    """Two tools on :func:`thread_map`'s threads and a third queued: SIGINT to the
    process ends it within 5 s, both tools' children die, the third never starts (with
    the CLI's handlers, and with Python's plain Ctrl-C too)."""
    pids = [tmp_path / f"pid{i}" for i in range(3)]
    script = textwrap.dedent(f"""
        import contextlib, sys
        from rvsm.rtl.tool_groups import interrupt_handlers, thread_map
        from rvsm.rtl.toolchain import run_tool
        pids = {[str(p) for p in pids]!r}
        def tool(i):
            run_tool(["sh", "-c", f"sleep 60 & echo $! > {{pids[i]}}; wait"])
        with interrupt_handlers() if {handlers} else contextlib.nullcontext():
            try:
                thread_map(tool, range(3), 2)
            except KeyboardInterrupt:
                sys.exit(130)
    """)
    proc = subprocess.Popen([sys.executable, "-c", script], preexec_fn=default_signals)
    end = time.monotonic() + 30
    while not all(p.exists() and p.read_text().strip() for p in pids[:2]):
        assert time.monotonic() < end and proc.poll() is None
        time.sleep(0.05)
    children = [int(p.read_text()) for p in pids[:2]]
    assert all(_alive(c) for c in children)
    t0 = time.monotonic()
    os.kill(proc.pid, signal.SIGINT)
    assert proc.wait(timeout=30) == 130
    assert time.monotonic() - t0 < 5.0
    assert all(_wait_dead(c, 2.0) for c in children)
    assert not pids[2].exists()  # the queued tool never started
