"""Run a formal plan (:mod:`.plan`): its runs ``jobs`` at a time, one line per run, a
summary and ``<out>/<name>-matrix.json``.

Each run is :func:`~.runner.run_checks` of its checks (one after the other) in
``<out>/<run folder>``; runs go ``jobs`` at a time on threads that wait for their sby
processes. The record of a run: ``model``, ``size`` ("HxW"), the architecture's options
(``lanes``...), ``reset``, ``checks``, ``status`` (the run's exit status: 0 every
property holds, 1 a counterexample, 3 a tool failed or gave no verdict), ``depth`` (the
deepest check), ``seconds``, ``folder`` and ``error`` (the first failing check's
message). The plan's exit status is the worst: 3 over 1 over 0.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rvsm.model.infra.atomic import write_text_atomic
from rvsm.model.infra.errors import ToolError
from rvsm.sim.formal.plan import FormalPlan, FormalRun
from rvsm.sim.formal.runner import run_checks

__all__ = ["PlanSummary", "run_formal_plan"]

_VERDICTS = {0: "pass", 1: "COUNTEREXAMPLE"}


@dataclass
class PlanSummary:
    """The records of a plan's runs (in plan order), the wall time (s), the jobs and the
    JSON file written."""

    runs: list[dict[str, Any]] = field(default_factory=list)
    wall_seconds: float = 0.0
    jobs: int = 1
    json_path: Path | None = None

    @property
    def exit_status(self) -> int:
        """0 every run passed, 1 a counterexample, 3 a tool failed (3 wins)."""
        worst = max((r["status"] for r in self.runs), default=0)
        return 0 if worst == 0 else (1 if worst == 1 else 3)

    def line(self) -> str:
        """The summary line."""
        passed = sum(r["status"] == 0 for r in self.runs)
        return (f"{passed}/{len(self.runs)} passed, wall {self.wall_seconds:.0f} s with "
                f"{self.jobs} jobs (sum of run times "
                f"{sum(r['seconds'] for r in self.runs):.0f} s)")

    def to_json(self) -> dict[str, Any]:
        return {"wall_seconds": round(self.wall_seconds, 1), "jobs": self.jobs,
                "runs": self.runs}


def _run_one(plan: FormalPlan, run: FormalRun, out: Path, mode: str | None,
             depth: int | None, timeout: float | None, solver: str) -> dict[str, Any]:
    folder = out / run.folder(plan.name)
    started = time.perf_counter()
    try:
        report = run_checks(run.contract, plan.arch, run.options, checks=list(run.checks),
                            mode=mode, depth=depth, workdir=folder, timeout=timeout,
                            solver=solver)
        status = report.exit_status
        depths = [r.depth for r in report.results]
        errors = [r.message for r in report.results if r.status != "pass" and r.message]
        write_text_atomic(folder / "report.json", json.dumps(report.to_json(), indent=2)
                          + "\n")
    except ToolError as exc:  # a tool missing: no verdict
        status, depths, errors = 3, [], [str(exc)]
    return {"model": run.model, "size": f"{run.size[0]}x{run.size[1]}", **run.options,
            "reset": run.reset, "checks": list(run.checks), "status": status,
            "depth": max(depths, default=None),
            "seconds": round(time.perf_counter() - started, 1), "folder": str(folder),
            "error": errors[0].splitlines()[0] if errors else ""}


def run_formal_plan(plan: FormalPlan, out: str | os.PathLike, jobs: int = 1,
                    mode: str | None = None, depth: int | None = None,
                    timeout: float | None = None, solver: str = "yices",
                    progress: Callable[[str], None] | None = None) -> PlanSummary:
    """Run every run of ``plan`` into ``out``, ``jobs`` at a time; ``mode``, ``depth``
    and ``solver`` as :func:`~.runner.run_checks`, ``timeout`` per check (default the
    plan's); ``progress`` gets one line per finished run. Writes
    ``out/<name>-matrix.json`` and returns the :class:`PlanSummary`."""
    root = Path(out)
    timeout = plan.timeout if timeout is None else timeout
    summary = PlanSummary(jobs=jobs)
    started = time.perf_counter()
    pool = ThreadPoolExecutor(max_workers=jobs)
    try:
        futures = [pool.submit(_run_one, plan, run, root, mode, depth, timeout, solver)
                   for run in plan.runs]
        for i, (run, future) in enumerate(zip(plan.runs, futures, strict=True), 1):
            r = future.result()
            summary.runs.append(r)
            if progress:
                verdict = _VERDICTS.get(r["status"], "TOOL FAILED")
                progress(f"[{i}/{len(plan.runs)}] {run.label} depth {r['depth']}: "
                         f"{verdict} ({r['seconds']} s)"
                         + (f" {r['error']}" if r["error"] else ""))
    finally:  # interrupted: no run not yet started starts
        pool.shutdown(wait=True, cancel_futures=True)
    summary.wall_seconds = time.perf_counter() - started
    summary.json_path = root / f"{plan.name}-matrix.json"
    write_text_atomic(summary.json_path, json.dumps(summary.to_json(), indent=2) + "\n")
    return summary
