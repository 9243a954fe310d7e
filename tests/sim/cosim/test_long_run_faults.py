"""``rvsm verify --harness chunk`` under interrupts: during the generation of the Verilog,
during the simulator build and during the simulation (the simulator and the twin's
process both running).

Each interrupt (SIGINT, SIGTERM) ends in exit 130 (143) with one ``rvsm: interrupted`` line,
no traceback, no process left (the cocotb job, ``vvp``, the twin's process), no
``.tmp`` build folder, lock or partial file, no run folder; rerunning the same command
gives the result of an uninterrupted run. Each phase prints its first progress line at
once. A tiny streaming array on Icarus; the full grid under ``-m slow``.
"""

from __future__ import annotations

import json
import signal
import subprocess
from pathlib import Path

import pytest

from tests.sim.cosim.test_faults import (
    RVSM,
    _assert_no_orphans,
    _leftovers,
    _point,
    _signal_at,
)

STEPS = 24
#: The result's fields that an interrupted-then-rerun run must share with an
#: uninterrupted one (not its timings or folders).
SAME = ("compared", "mismatches", "beats", "steps", "accumulators", "expected_spikes",
        "lane_coverage", "cycles", "coverage", "harness", "lanes")


def _args(folder: Path, *extra: str) -> list[str]:
    point = folder / "p.toml"
    if not point.exists():
        _point(point, 4, 6, "dog2")
    return ["verify", "coin", "--fixed", str(point), "--size", "4x6", "--steps", str(STEPS),
            "--arch", "stream", "--lanes", "2", "--harness", "chunk", "--work",
            str(folder / "w"), *extra]


def _result(folder: Path) -> dict:
    r = subprocess.run([RVSM, *_args(folder, "--json")], capture_output=True, text=True,
                       timeout=900)
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["mismatches"] == 0 and out["harness"] == "chunk"
    return {k: out.get(k) for k in SAME}


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> dict:
    """An uninterrupted run's result."""
    return _result(tmp_path_factory.mktemp("reference"))


def _says(text: str):
    return lambda kids, err: text in err


def _simulating(kids: dict[int, str], err: str) -> bool:
    """Ready once the simulator (``vvp``, not the build's ``-o sim.vvp``) and the twin's
    process both run."""
    return (any(Path(cmd.split(" ")[0]).name == "vvp" for cmd in kids.values())
            and any("chunk_twin" in cmd for cmd in kids.values()))


PHASES = {
    "generate": _says("rvsm: generating the Verilog"),
    "build": _says("rvsm: building "),
    "simulate": _simulating,
}


def _interrupt_case(folder: Path, phase: str, sig: int, reference: dict) -> None:
    status, err, seen = _signal_at(_args(folder), sig, PHASES[phase])
    assert status == 128 + sig, err  # 130 SIGINT, 143 SIGTERM
    assert "Traceback" not in err, err
    lines = [ln for ln in err.replace("\r", "\n").splitlines() if ln.startswith("rvsm: ")
             and not ln.startswith(("rvsm: generating", "rvsm: building", "rvsm: built"))]
    assert len(lines) == 1 and lines[0].startswith("rvsm: interrupted"), err
    _assert_no_orphans(seen)
    work = folder / "w"
    assert _leftovers(work) == []
    assert not list(work.rglob("*.lock"))
    runs = work / "runs"
    assert not runs.exists() or list(runs.iterdir()) == []  # no half run folder
    builds = list((work / "builds").iterdir()) if (work / "builds").exists() else []
    if phase != "simulate":  # no half-made build
        assert builds == [], builds
    assert _result(folder) == reference


QUICK = [("build", signal.SIGINT), ("simulate", signal.SIGTERM)]
GRID = [(p, s) for p in PHASES for s in (signal.SIGINT, signal.SIGTERM)
        if (p, s) not in QUICK]


@pytest.mark.parametrize(("phase", "sig"), QUICK, ids=[f"{p}-{s.name}" for p, s in QUICK])
def test_interrupt_at_a_phase(tmp_path: Path, reference: dict, phase: str,
                              sig: int) -> None:
    _interrupt_case(tmp_path, phase, sig, reference)


@pytest.mark.slow
@pytest.mark.parametrize(("phase", "sig"), GRID, ids=[f"{p}-{s.name}" for p, s in GRID])
def test_interrupt_at_each_phase(tmp_path: Path, reference: dict, phase: str,
                                 sig: int) -> None:
    _interrupt_case(tmp_path, phase, sig, reference)


def test_interrupting_a_sharded_run_on_workers_leaves_nothing(tmp_path: Path) -> None:
    """SIGINT while 2 Dask workers run a sharded run's segments (each with its simulator
    and twin): exit 130 with one line, no process left, and no half-made segment run
    folder (the workers die before their segments can clean up: the run removes them;
    it once left both)."""
    args = _args(tmp_path, "--frames", "201", "--steps-per-frame", "10", "--shards", "2",
                 "--workers", "2")
    args[args.index("--steps") + 1] = "2000"  # long enough to be interrupted mid-segment
    status, err, seen = _signal_at(args, signal.SIGINT, lambda kids, err: sum(
        Path(cmd.split(" ")[0]).name == "vvp" for cmd in kids.values()) >= 1)
    assert status == 130, err
    assert "Traceback" not in err, err
    lines = [ln for ln in err.replace("\r", "\n").splitlines() if ln.startswith("rvsm: ")
             and not ln.startswith(("rvsm: generating", "rvsm: building", "rvsm: built",
                                    "rvsm: running", "rvsm: still"))]
    assert len(lines) == 1 and lines[0].startswith("rvsm: interrupted"), err
    _assert_no_orphans(seen)
    work = tmp_path / "w"
    assert _leftovers(work) == []
    runs = work / "runs"
    assert not runs.exists() or [p.name for p in runs.iterdir()] == []
