"""``rvsm regress`` under faults: interrupts at each phase and a Dask worker killed.

An interrupt (SIGINT, SIGTERM) ends in exit 130 (143) with one line and no traceback, no tool
or worker left, no ``.tmp`` build, no half run folder, and JUnit of the runs that
finished. Tiny Icarus plans; the full grid of phases and signals under ``-m slow``.
"""

from __future__ import annotations

import signal
import subprocess
import time
from pathlib import Path
from xml.etree import ElementTree as ET

import pytest

from tests.sim.cosim.test_faults import (
    RVSM,
    _assert_no_orphans,
    _children,
    _has,
    _leftovers,
    _signal_at,
)
from tests.sim.regress.conftest import TINY_PLAN, write_plan

#: The tiny plan's seed runs only (two runs).
PLAN = TINY_PLAN.replace('scenes = ["coin"]\n', "")


def _args(tmp_path: Path, workers: int = 2) -> list[str]:
    plan = write_plan(tmp_path, PLAN)
    return ["regress", str(plan), "-o", str(tmp_path / "r.sqlite"), "--work",
            str(tmp_path / "w"), "--junit", str(tmp_path / "r.xml"), "--workers",
            str(workers)]


def _says(word: str):
    return lambda kids, err: word in err


PHASES = {
    "start": _has("spawn_main"),  # the Dask workers are starting
    "generate": _says("rvsm: generating the Verilog"),
    "build": _says("rvsm: building "),
    "simulate": _has("vvp"),
}


def _check_interrupted(tmp_path: Path, status: int, err: str, seen: dict,
                       sig: int = signal.SIGINT) -> None:
    assert status == 128 + sig, err  # 130 SIGINT, 143 SIGTERM
    assert "Traceback" not in err, err
    assert "leaked semaphore" not in err, err
    lines = [ln for ln in err.splitlines() if ln.startswith("rvsm: interrupted")]
    assert len(lines) == 1, err
    _assert_no_orphans(seen)
    assert _leftovers(tmp_path / "w") == []
    runs = tmp_path / "w" / "runs"
    done = ET.parse(tmp_path / "r.xml").getroot().find("testsuite")  # written anyway
    assert done is not None
    kept = {c.find("properties") is not None for c in done.findall("testcase")}
    assert kept <= {True}
    if runs.exists():  # only finished runs' folders are left
        assert len(list(runs.iterdir())) <= int(done.get("tests", "0"))


@pytest.mark.parametrize("phase", ["build"])
def test_interrupt_during_a_build(tmp_path: Path, phase: str) -> None:
    status, err, seen = _signal_at(_args(tmp_path), signal.SIGINT, PHASES[phase])
    _check_interrupted(tmp_path, status, err, seen)


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
@pytest.mark.parametrize("phase", list(PHASES))
def test_interrupt_at_each_phase(tmp_path: Path, phase: str, sig: int) -> None:
    status, err, seen = _signal_at(_args(tmp_path), sig, PHASES[phase])
    _check_interrupted(tmp_path, status, err, seen, sig)


def _rows(tmp_path: Path) -> list[tuple]:
    from rvsm.sim.regress.store import RegressionStore

    with RegressionStore(tmp_path / "r.sqlite") as store:
        return sorted((r["label"], r["status"], r["mismatches"], r["compared"])
                      for r in store.rows())


@pytest.mark.slow
def test_a_worker_killed_mid_run_finishes_elsewhere(tmp_path: Path) -> None:
    """SIGKILL the worker running a simulation: its tools die with it, the run is done
    again on a worker, the verdicts equal an uninterrupted run's, nothing is left."""
    ref = tmp_path / "ref"
    ref.mkdir()
    r = subprocess.run([RVSM, *_args(ref, workers=0), "--quiet"], capture_output=True,
                       text=True, timeout=900)
    assert r.returncode == 0, r.stderr
    proc = subprocess.Popen([RVSM, *_args(tmp_path), "--quiet"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    seen: dict[int, str] = {}
    end = time.monotonic() + 600
    killed = False
    while not killed:
        assert time.monotonic() < end and proc.poll() is None
        kids = _children(proc.pid)
        seen.update(kids)
        for pid, cmd in kids.items():
            if Path(cmd.split(" ")[0]).name == "vvp":  # the simulator, not "-o sim.vvp"
                worker = next((p for p, c in kids.items() if "spawn_main" in c
                               and pid in _children(p)), None)
                if worker is None:  # the simulation ended meanwhile: wait for the next
                    continue
                import os

                os.kill(worker, signal.SIGKILL)
                killed = True
                break
        time.sleep(0.05)
    out, err = proc.communicate(timeout=900)
    assert proc.returncode == 0, err
    assert "Traceback" not in err
    _assert_no_orphans(seen)
    assert _leftovers(tmp_path / "w") == []
    assert [row[1:] for row in _rows(tmp_path)] == [row[1:] for row in _rows(ref)]
