"""``rvsm sweep`` under interrupts: while the Dask workers start, while a worker runs a
twin, and while the results are written.

Each interrupt (SIGINT, SIGTERM) ends in exit 130 (143) with one ``rvsm: interrupted`` line on
stderr, no traceback and no ``leaked semaphore`` warning, no worker or tool left, no
partial file; the rows finished stay, and rerunning the same command fills in the rest
with rows identical to an uninterrupted run's. Tiny sweeps; the full grid under
``-m slow``.
"""

from __future__ import annotations

import os
import signal
import sqlite3
import subprocess
from pathlib import Path

import pytest

from tests.sim.cosim.test_faults import (
    RVSM,
    _assert_no_orphans,
    _children,
    _has,
    _leftovers,
    _signal_at,
)

#: Six designs on a 48x64 scene: each twin takes a moment, so that once one row is
#: done the other worker is still computing.
SWEEP = """
[axes]
"adc.bits" = [6, 7, 8]
"weights.frac_bits" = [7, 9]
[run]
scenes = ["coin"]
size = "48x64"
frames = 6
[hardware]
enabled = false
"""

#: The columns that must not depend on how (or in how many goes) a sweep ran.
COLUMNS = ("point_id, scene, noise, seed, steps, size, status, error, agreement, "
           "psnr_float, psnr_fixed, psnr_cost, ssim_fixed, ssim_cost, mse_fixed, mse_cost, "
           "max_saturation_rate, design_toml")


def _args(folder: Path, workers: int = 2) -> list[str]:
    sweep = folder / "s.toml"
    sweep.write_text(SWEEP)
    return ["sweep", str(sweep), "-o", str(folder / "r.sqlite"), "--workers", str(workers)]


def _rows(db: Path) -> list[tuple]:
    with sqlite3.connect(db) as con:
        return list(con.execute(f"SELECT {COLUMNS} FROM results ORDER BY point_id"))


def _computed(db: Path) -> int:
    """Rows computed by a worker (not the invalid designs recorded up front)."""
    return sum(row[6] == "ok" for row in _rows(db))


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> list[tuple]:
    """The rows of an uninterrupted run (in one process)."""
    folder = tmp_path_factory.mktemp("reference")
    r = subprocess.run([RVSM, *_args(folder, workers=0), "--quiet"], capture_output=True,
                       text=True, timeout=900)
    assert r.returncode == 0, r.stderr
    return _rows(folder / "r.sqlite")


def _one_row_done(kids: dict[int, str], err: str) -> bool:
    """Ready once a row is stored (the bar moved) while a worker still computes."""
    return any(f"| {n}/" in err for n in range(1, 5))


PHASES = {"start": _has("spawn_main"), "twin": _one_row_done}


def _check_interrupted(folder: Path, status: int, err: str, seen: dict,
                       sig: int = signal.SIGINT) -> None:
    assert status == 128 + sig, err  # 130 SIGINT, 143 SIGTERM
    assert "Traceback" not in err, err
    assert "leaked semaphore" not in err, err
    lines = [ln for ln in err.replace("\r", "\n").splitlines() if ln.startswith("rvsm")]
    assert len(lines) == 1 and lines[0].startswith("rvsm: interrupted"), err
    _assert_no_orphans(seen)
    assert _leftovers(folder) == []
    assert not list(folder.glob("*-journal"))  # no transaction left half-done


def _resumes_to(folder: Path, reference: list[tuple]) -> None:
    """Rerunning the same command finishes the sweep; its rows are the reference's."""
    done = len(_rows(folder / "r.sqlite")) if (folder / "r.sqlite").exists() else 0
    r = subprocess.run([RVSM, *_args(folder), "--quiet"], capture_output=True, text=True,
                       timeout=900)
    assert r.returncode == 0, r.stderr
    assert f"{done} already done" in r.stdout, r.stdout
    assert _rows(folder / "r.sqlite") == reference


def test_interrupt_while_a_worker_runs_a_twin(tmp_path: Path, reference: list) -> None:
    status, err, seen = _signal_at(_args(tmp_path), signal.SIGINT, PHASES["twin"])
    assert any("spawn_main" in cmd for cmd in seen.values())  # Dask workers did run
    _check_interrupted(tmp_path, status, err, seen)
    assert 1 <= _computed(tmp_path / "r.sqlite") < sum(row[6] == "ok" for row in reference)
    _resumes_to(tmp_path, reference)


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM],
                         ids=lambda s: signal.Signals(s).name)
@pytest.mark.parametrize("phase", list(PHASES))
def test_interrupt_at_each_phase(tmp_path: Path, reference: list, phase: str,
                                 sig: int) -> None:
    status, err, seen = _signal_at(_args(tmp_path), sig, PHASES[phase])
    _check_interrupted(tmp_path, status, err, seen, sig)
    _resumes_to(tmp_path, reference)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM],
                         ids=lambda s: signal.Signals(s).name)
def test_interrupt_while_writing_results(tmp_path: Path, reference: list, sig: int,
                                         capsys: pytest.CaptureFixture,
                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """The signal lands while the coordinating process stores the second row (Dask
    workers computing the others): exit 130, the first row kept whole, the second not
    half-written, the workers gone; a rerun completes it."""
    from rvsm.sim.cli import main
    from rvsm.sim.sweep.store import SweepStore

    real = SweepStore.write_result
    writes: list[int] = []
    seen: dict[int, str] = {}

    def write_then_signal(self, task, record, status, *args, **kwargs):  # noqa: ANN001
        if status == "ok":
            writes.append(1)
            if len(writes) == 2:
                seen.update({pid: cmd for pid, cmd in _children(os.getpid()).items()
                             if "resource_tracker" not in cmd})  # this process's own
                os.kill(os.getpid(), sig)  # delivered inside this write
        return real(self, task, record, status, *args, **kwargs)

    monkeypatch.setattr(SweepStore, "write_result", write_then_signal)
    assert main(_args(tmp_path)) == 128 + sig
    err = capsys.readouterr().err
    assert any("spawn_main" in cmd for cmd in seen.values())
    _check_interrupted(tmp_path, 128 + sig, err, seen, sig)
    assert _computed(tmp_path / "r.sqlite") == 1
    monkeypatch.setattr(SweepStore, "write_result", real)
    _resumes_to(tmp_path, reference)


def test_an_interrupt_during_a_cluster_start_lands_after_it() -> None:
    """:func:`interrupts_deferred`: the block runs to its end, then the interrupt is
    raised (or dropped with ``swallow``); the handlers are as they were."""
    import time

    from rvsm.sim.sweep.executors import interrupts_deferred

    before = signal.getsignal(signal.SIGINT)
    reached = []
    with pytest.raises(KeyboardInterrupt), interrupts_deferred():
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.2)
        reached.append("end of block")
    assert reached == ["end of block"]
    with interrupts_deferred(swallow=True):
        os.kill(os.getpid(), signal.SIGINT)
        time.sleep(0.2)
    assert signal.getsignal(signal.SIGINT) is before
