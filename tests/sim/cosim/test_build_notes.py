"""Progress of ``rvsm verify --harness chunk`` (issue 34, finding 5: nothing printed for
minutes during generation and build): each phase (generation, build, simulation) prints
its first line as it starts, and a long phase says every so often that it is still at
work (:mod:`rvsm.sim.cosim.builds.build_notes`)."""

from __future__ import annotations

import subprocess
import threading
import time
from pathlib import Path

import pytest

from rvsm.sim.cosim.builds import build_notes
from rvsm.sim.cosim.builds.build_cache import build
from tests.sim.cosim.test_faults import RVSM
from tests.sim.cosim.test_long_run_faults import STEPS, _args


def _timed_lines(cmd: list[str]) -> tuple[int, list[tuple[float, str]]]:
    """Run ``cmd``; its exit status and each stderr line (``\\r`` ends a line too, as a
    progress bar's redraws) with the seconds since the start at which it was complete."""
    t0 = time.monotonic()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    lines: list[tuple[float, str]] = []

    def pump() -> None:
        buf = b""
        assert proc.stderr is not None
        while chunk := proc.stderr.read1(4096):
            for byte in chunk:
                if byte in b"\r\n":
                    if buf.strip():
                        lines.append((time.monotonic() - t0, buf.decode(errors="replace")))
                    buf = b""
                else:
                    buf += bytes([byte])
        if buf.strip():
            lines.append((time.monotonic() - t0, buf.decode(errors="replace")))

    reader = threading.Thread(target=pump)
    reader.start()
    status = proc.wait(timeout=900)
    reader.join()
    return status, lines


def _first(lines: list[tuple[float, str]], text: str) -> int:
    found = [k for k, (_, line) in enumerate(lines) if text in line]
    assert found, (text, lines)
    return found[0]


def test_each_phase_prints_a_line_as_it_starts(tmp_path: Path) -> None:
    status, lines = _timed_lines([RVSM, *_args(tmp_path)])
    assert status == 0, lines
    generating = _first(lines, "rvsm: generating the Verilog")
    building = _first(lines, "rvsm: building ")
    built = _first(lines, "rvsm: built ")
    bar = _first(lines, f" 0/{STEPS} ")  # the simulation's bar, before any step is done
    done = _first(lines, f" {STEPS}/{STEPS} ")
    assert generating < building < built < bar < done, lines


def test_a_long_phase_says_it_is_still_at_work(small_contract, tmp_path: Path,
                                               capsys: pytest.CaptureFixture,
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(build_notes, "HEARTBEAT_SECONDS", 0.02)
    build(small_contract("dog2", 4, 6), "icarus", tmp_path / "builds", arch="stream",
          harness=True, lanes=2)
    err = capsys.readouterr().err
    assert "rvsm: still generating the Verilog of icarus-" in err, err
    assert "rvsm: still building icarus-" in err and " elapsed)" in err, err
    assert err.index("rvsm: still building") < err.index("rvsm: built ")
