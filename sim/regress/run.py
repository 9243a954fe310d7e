"""``rvsm regress``: a plan's runs on an executor (this process or Dask), resumable in
SQLite, with a progress bar, merged coverage, a closure report and JUnit XML.

:func:`run_regression` skips the runs the database already holds with a verdict, runs
the rest (a local Dask cluster by default, a remote scheduler as for sweeps, or in this
process with ``workers=0``), writes each outcome as it arrives, and returns a
:class:`RegressionSummary` of the plan's runs (all of them, from the database).
"""

from __future__ import annotations

import gc
import os
import shutil
import signal
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rvsm.model.infra.progress import progress_bar
from rvsm.sim.cosim.builds.build_lock import sweep_stale
from rvsm.sim.cosim.builds.code_coverage import merge, summary, write_coverage, write_lcov
from rvsm.sim.regress.plan import RegressionPlan
from rvsm.sim.regress.report import closure_lines, write_junit
from rvsm.sim.regress.store import RegressionStore
from rvsm.sim.regress.work import RegressionWork
from rvsm.sim.sweep.executors import executor_for

__all__ = ["RegressionSummary", "run_regression"]


@dataclass
class RegressionSummary:
    """The plan's runs as recorded (``rows``), how many ran now (``ran``) and were
    skipped as already done (``skipped``)."""

    rows: list[dict[str, Any]]
    ran: int = 0
    skipped: int = 0
    closure: list[str] = field(default_factory=list)
    code_coverage: list[str] = field(default_factory=list)  # lines: merged files, summary

    def count(self, status: str) -> int:
        """Runs with ``status`` (``pass``, ``fail``, ``error``)."""
        return sum(r["status"] == status for r in self.rows)

    @property
    def exit_status(self) -> int:
        """1 if a run mismatched, else 3 if a run failed to complete, else 0."""
        return 1 if self.count("fail") else 3 if self.count("error") else 0


def merge_code_coverage(rows: list[dict[str, Any]], db: Path) -> list[str]:
    """Merge the runs' Verilator ``coverage.dat`` into ``<db>-coverage/merged.dat`` and
    ``lcov.info``; the report's lines (empty when no run has code coverage)."""
    files = [r["code_coverage"] for r in rows
             if r.get("code_coverage") and Path(r["code_coverage"]).exists()]
    if not files:
        return []
    out = db.with_name(f"{db.stem}-coverage")
    out.mkdir(parents=True, exist_ok=True)
    points = merge(files)
    write_coverage(points, out / "merged.dat")
    write_lcov(points, out / "lcov.info")
    kinds = ", ".join(f"{k} {hit}/{n} ({100 * hit / max(n, 1):.1f}%)"
                      for k, (hit, n) in summary(points).items())
    return [f"{len(files)} run(s) merged: {kinds} points hit",
            f"{out / 'merged.dat'} (verilator_coverage format), {out / 'lcov.info'} "
            "(genhtml makes HTML of it)"]


def run_regression(plan: RegressionPlan, db: str | os.PathLike,
                   work_dir: str | os.PathLike, workers: int | None = None,
                   scheduler: str | None = None, junit: str | os.PathLike | None = None,
                   progress: bool = True) -> RegressionSummary:
    """Run what ``db`` does not yet hold of ``plan``; see the module docstring.

    Interrupted (``KeyboardInterrupt``: SIGINT, or SIGTERM/SIGHUP through the CLI), it
    stops the workers (their tools die with them), removes what they left half-made
    (``builds/*.tmp<pid>``, run folders of unfinished runs), writes the coverage report
    and JUnit of the runs that finished, then raises the interrupt again, saying how far
    it got."""
    work = str(Path(work_dir).resolve())
    started = time.time()
    interrupted: KeyboardInterrupt | None = None
    pids: set[int] = {os.getpid()}
    with RegressionStore(db) as store:
        done = store.done_keys()
        todo = [RegressionWork(spec, work) for spec in plan.runs if spec.key not in done]
        by_key = {w.key: w for w in todo}
        ran = 0
        if todo:
            bar = progress_bar(len(todo), f"regress {plan.name}", progress, unit="run")
            try:
                with executor_for(workers, scheduler) as executor:
                    pids = executor.pids
                    bar.set_postfix_str(f"{max(executor.workers, 1)} worker(s) building and "
                                        "simulating", refresh=True)
                    for finished in executor.run(todo):
                        work_item = by_key[finished.work.key]
                        record = finished.value if finished.error is None else {
                            "status": "error", "error": f"{type(finished.error).__name__}: "
                            f"{finished.error}"[:500]}
                        store.write(work_item.spec, record)
                        ran += 1
                        bar.update(1)
            except KeyboardInterrupt as exc:
                interrupted = KeyboardInterrupt(*exc.args)  # not its traceback's frames
                _ignore_interrupts()  # a second Ctrl-C must not cut the clean-up short
            finally:
                bar.close()
            if interrupted is not None:  # the cluster's queues and semaphores, freed now
                gc.collect()
        rows = store.rows({s.key for s in plan.runs})
    if interrupted is not None:
        remove_half_made(Path(work), pids, started, rows)
    summary = RegressionSummary(rows, ran, len(plan.runs) - len(todo), closure_lines(rows),
                                merge_code_coverage(rows, Path(db)))
    if junit is not None:
        write_junit(junit, plan.name, rows)
    if interrupted is not None:
        why = interrupted.args[0] if interrupted.args else "SIGINT"
        wrote = f", JUnit of them in {junit}" if junit is not None else ""
        raise KeyboardInterrupt(f"{why} with {len(rows)} of {len(plan.runs)} run(s) "
                                f"done{wrote}; rerun the same command to resume")
    return summary


def _ignore_interrupts() -> None:
    """Ignore SIGINT, SIGTERM and SIGHUP from now on (main thread only; the CLI restores
    its handlers when the command returns)."""
    if threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
            signal.signal(sig, signal.SIG_IGN)


def remove_half_made(work: Path, pids: set[int], since: float,
                     rows: list[dict[str, Any]]) -> list[Path]:
    """After an interrupted regression: remove the half-made builds in ``work/builds``
    that no live process is building, and the run folders in ``work/runs`` made since
    ``since`` (epoch s) by one of ``pids`` (the workers; all ended now) that no
    recorded run names (its ``run_dir``, or the log named by its error). The paths
    removed."""
    gone = sweep_stale(work / "builds")
    runs = work / "runs"
    if not runs.is_dir():
        return gone
    named = " ".join(str(r.get("run_dir") or "") + " " + str(r.get("error") or "")
                     for r in rows)
    for folder in runs.iterdir():
        pid = folder.name.rsplit("-", 2)[-2] if folder.name.count("-") >= 2 else ""
        try:
            made = folder.stat().st_mtime
        except OSError:
            continue
        if (folder.is_dir() and pid.isdigit() and int(pid) in pids and made >= since - 1
                and str(folder) not in named and not _alive(int(pid), own=True)):
            shutil.rmtree(folder, ignore_errors=True)
            gone.append(folder)
    return gone


def _alive(pid: int, own: bool = False) -> bool:
    """Whether process ``pid`` runs (``own``: this process counts as ended, its runs
    having unwound)."""
    if own and pid == os.getpid():
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True
