"""Commands that start tools, interrupted while their tools run (issue 42).

SIGINT to the ``rvsm`` process, SIGINT to its whole process group (what a terminal's
Ctrl-C sends) and SIGTERM, sent as soon as the tools run: ``rvsm`` ends within 5 s with
exit status 130 (143 for SIGTERM), one ``rvsm:`` line on stderr (the interrupt) and no
traceback, no process left (not one of its descendants, nor anything in its tools'
process groups), and its ``-o`` folder absent (it was made by the run) or complete.
``formal -j 2`` once kept both solvers running for minutes: the signal reached the main
thread only (:mod:`rvsm.rtl.tool_groups`). Real solvers for ``formal`` and ``mutate``;
stand-in tools for the synthesis of ``fpga`` and the Icarus lint of ``verilog --lint``.
"""

from __future__ import annotations

import os
import signal
import subprocess
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from tests.conftest import FORMAL_POINT, default_signals
from tests.sim.cosim.test_faults import RVSM, _alive, _children, _fake_tools, _leftovers

#: How an interrupt is sent: (signal, to the whole process group).
HOW = {"SIGINT": (signal.SIGINT, False), "SIGINT-group": (signal.SIGINT, True),
       "SIGTERM": (signal.SIGTERM, False)}

#: Seconds from the signal to the end of ``rvsm`` (the issue's bound).
WITHIN = 5.0


def _pgid(pid: int) -> int | None:
    try:
        return os.getpgid(pid)
    except ProcessLookupError:
        return None


def _in_groups(groups: set[int]) -> list[int]:
    """Live processes whose process group is one of ``groups``."""
    found = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit() and _pgid(int(d.name)) in groups and _alive(int(d.name)):
            found.append(int(d.name))
    return found


def interrupt(cmd: list[str], how: str, ready: Callable[[dict[int, str]], bool],
              env: dict | None = None, timeout: float = 240) -> tuple[int, str, float, dict]:
    """Start ``rvsm cmd`` in a process group of its own, interrupt it ``how`` once
    ``ready(descendants)``; return (exit status, stderr, seconds to exit, descendants
    seen). Fails when it does not end within :data:`WITHIN` s or leaves a process."""
    sig, group = HOW[how]
    with tempfile.TemporaryDirectory() as folder:
        log = Path(folder) / "stderr"
        with open(log, "a") as errf:  # appends: reading it does not move the writer
            proc = subprocess.Popen([RVSM, *cmd], stdout=subprocess.DEVNULL, stderr=errf,
                                    env=env, preexec_fn=default_signals, process_group=0)
        seen: dict[int, str] = {}
        groups: set[int] = set()
        try:
            end = time.monotonic() + timeout
            while True:
                kids = _children(proc.pid)
                seen.update(kids)
                if ready(kids):
                    break
                assert proc.poll() is None, f"rvsm ended too soon: {log.read_text()}"
                assert time.monotonic() < end, "the tools never ran"
                time.sleep(0.05)
            seen.update(_children(proc.pid))
            groups = {g for g in map(_pgid, seen) if g is not None} - {proc.pid}
            t0 = time.monotonic()
            if group:
                os.killpg(proc.pid, sig)
            else:
                proc.send_signal(sig)
            try:
                status = proc.wait(timeout=60)
            except subprocess.TimeoutExpired:
                status = None
            seconds = time.monotonic() - t0
            # looked at before the clean-up below kills what a failing run left
            left = [cmd for pid, cmd in seen.items() if _alive(pid)]
            stray = _in_groups(groups)
        finally:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
            for g in groups:  # a test that fails must not leave solvers to the next
                try:
                    os.killpg(g, signal.SIGKILL)
                except ProcessLookupError:
                    pass
        err = log.read_text()
    assert status is not None, f"rvsm still ran 60 s after {how}: {err[-2000:]}"
    assert left == [] and stray == [], f"left running after {how}: {left} {stray}"
    return status, err, seconds, seen


def check_interrupted(how: str, status: int, err: str, seconds: float) -> None:
    """Exit 130 (143 for SIGTERM) within :data:`WITHIN` s, one ``rvsm:`` line: the
    interrupt; no traceback."""
    sig, _ = HOW[how]
    assert status == 128 + sig, err
    assert seconds <= WITHIN, f"{seconds:.1f} s after {how}"
    assert "Traceback" not in err, err
    lines = [ln for ln in err.splitlines() if ln.startswith("rvsm:")]
    assert lines == [f"rvsm: interrupted by {signal.Signals(sig).name}; finished results "
                     "are kept, partial files removed"], err


def _count(word: str, n: int) -> Callable[[dict[int, str]], bool]:
    """Ready once ``n`` descendants' command lines hold ``word``."""
    return lambda kids: sum(word in cmd for cmd in kids.values()) >= n


@pytest.mark.parametrize("how", list(HOW))
def test_formal_with_two_jobs_ends_on_an_interrupt(tmp_path: Path, how: str) -> None:
    """Two sby runs on worker threads (``-j 2``): both stopped, no work folder left."""
    out = tmp_path / "formal"
    cmd = ["formal", str(FORMAL_POINT), "--arch", "stream", "--size", "3x4", "--lanes",
           "2", "-j", "2", "-o", str(out)]
    status, err, seconds, seen = interrupt(cmd, how, _count("yowasp-sby", 2))
    assert sum("yowasp-sby" in c for c in seen.values()) == 2
    check_interrupted(how, status, err, seconds)
    assert not out.exists()


@pytest.mark.parametrize("how", list(HOW))
def test_mutate_ends_on_an_interrupt(tmp_path: Path, how: str) -> None:
    """``mutate`` while its first solver runs: stopped, no work folder, no report."""
    out = tmp_path / "mutate"
    cmd = ["mutate", str(FORMAL_POINT), "--arch", "stream", "--checks", "formal",
           "--mutation", "stream.no_saturation", "--json", "-o", str(out)]
    status, err, seconds, _ = interrupt(cmd, how, _count("yowasp-sby", 1))
    check_interrupted(how, status, err, seconds)
    assert "mutate: stream: checking the shipped RTL first" in err  # it spoke meanwhile
    assert not out.exists()


def test_fpga_ends_on_an_interrupt(tmp_path: Path, fake_tool) -> None:
    """``fpga`` while its synthesis (a stand-in yosys that forks) runs."""
    from dataclasses import replace

    from rvsm.model.fixed.design_point import default_design_point
    from rvsm.model.fixed.point_toml import save_design_point

    point = tmp_path / "p.toml"
    save_design_point(point, replace(default_design_point().with_size(4, 4), model="fsm"))
    yosys = fake_tool(tmp_path / "slow-yosys", "sleep 120 & sleep 120\nwait\n")
    env = dict(os.environ, RVSM_YOSYS=str(yosys))
    out = tmp_path / "fpga"
    status, err, seconds, _ = interrupt(["fpga", str(point), "--synth-only", "-o",
                                         str(out)], "SIGINT-group", _count("sleep 120", 2),
                                        env=env)
    check_interrupted("SIGINT-group", status, err, seconds)
    assert not out.exists()


def test_verilog_lint_ends_on_an_interrupt(tmp_path: Path) -> None:
    """``verilog --lint`` while Icarus (a stand-in that forks) lints: the Verilog,
    written before the lint, is whole."""

    from rvsm.model.fixed.design_point import default_design_point
    from rvsm.model.fixed.point_toml import save_design_point

    point = tmp_path / "p.toml"
    save_design_point(point, default_design_point().with_size(6, 8))
    env = _fake_tools(tmp_path / "bin", iverilog="sleep 120 & sleep 120; wait")
    out = tmp_path / "v"
    status, err, seconds, _ = interrupt(["verilog", str(point), "--lint", "-o", str(out)],
                                        "SIGTERM", _count("sleep 120", 2), env=env)
    check_interrupted("SIGTERM", status, err, seconds)
    verilog = next(out.glob("*.v"))
    assert verilog.read_text().rstrip().endswith("endmodule")
    assert _leftovers(out) == []
