"""``rvsm regress``: a plan's runs on an executor (this process or Dask), resumable in
SQLite, with a progress bar, merged coverage, a closure report and JUnit XML.

:func:`run_regression` skips the runs the database already holds with a verdict, runs
the rest (a local Dask cluster by default, a remote scheduler as for sweeps, or in this
process with ``workers=0``), writes each outcome as it arrives, and returns a
:class:`RegressionSummary` of the plan's runs (all of them, from the database).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rvsm.model.infra.progress import progress_bar
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
    """Run what ``db`` does not yet hold of ``plan``; see the module docstring."""
    work = str(Path(work_dir).resolve())
    with RegressionStore(db) as store:
        done = store.done_keys()
        todo = [RegressionWork(spec, work) for spec in plan.runs if spec.key not in done]
        by_key = {w.key: w for w in todo}
        ran = 0
        if todo:
            bar = progress_bar(len(todo), f"regress {plan.name}", progress, unit="run")
            with executor_for(workers, scheduler) as executor:
                for finished in executor.run(todo):
                    work_item = by_key[finished.work.key]
                    record = finished.value if finished.error is None else {
                        "status": "error", "error": f"{type(finished.error).__name__}: "
                        f"{finished.error}"[:500]}
                    store.write(work_item.spec, record)
                    ran += 1
                    bar.update(1)
            bar.close()
        rows = store.rows({s.key for s in plan.runs})
    summary = RegressionSummary(rows, ran, len(plan.runs) - len(todo), closure_lines(rows),
                                merge_code_coverage(rows, Path(db)))
    if junit is not None:
        write_junit(junit, plan.name, rows)
    return summary
