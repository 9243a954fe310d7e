"""Run a sweep: compute every missing row, write each as it completes.

:func:`run_sweep` expands the sweep, skips every row already in the database, measures
the hardware cost (logic per lane of the streaming array) of each distinct RTL not yet in
``lane_cost`` once, and runs the rest through one :class:`SweepRun` on the executor
chosen by :func:`~rvsm.sim.sweep.executors.executor_for`: a local Dask cluster of
``workers`` processes (default: one per core), the Dask cluster at ``scheduler``, or,
with ``workers=0``, this process without Dask. Only this (coordinating) process writes
the database, one committed row per finished work item whichever executor ran it, so
Ctrl-C keeps everything finished.
"""

from __future__ import annotations

import os
import sqlite3
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from rvsm.model.infra.errors import RvsmError
from rvsm.sim.sweep.executors import Executor, Finished, executor_for
from rvsm.sim.sweep.spec import SweepSpec
from rvsm.sim.sweep.store import SweepStore, database_error
from rvsm.sim.sweep.work import PointWork, SynthesisWork, hw_digest, hw_record


@dataclass
class SweepSummary:
    """What a run did. Counts are rows (tasks) unless named ``hw_*`` (syntheses)."""

    total: int = 0
    already_done: int = 0
    #: scene -> (rows, reason) of finished rows recomputed because their scene's content
    #: is not what they were computed from.
    recomputed: dict[str, tuple[int, str]] = field(default_factory=dict)
    computed: int = 0
    invalid: int = 0
    errors: list[str] = field(default_factory=list)
    hw_synthesised: int = 0
    hw_cached: int = 0
    seconds: float = 0.0
    workers: int = 0

    def format(self) -> str:
        """One-paragraph summary for the CLI (and one line per scene whose rows were
        recomputed because its content changed)."""
        text = (f"sweep: {self.total} rows: {self.already_done} already done, "
                f"{self.computed} computed, {self.invalid} invalid design(s) recorded, "
                f"{len(self.errors)} failed; RTL: {self.hw_synthesised} synthesised, "
                f"{self.hw_cached} cached; {self.seconds:.1f} s on {self.workers} worker(s)")
        for scene, (rows, reason) in self.recomputed.items():
            text += f"\nsweep: {rows} row(s) recomputed: scene {scene} {reason}"
        return text


@dataclass
class SweepRun:
    """One run of ``spec`` into ``store`` on ``executor``.

    :meth:`plan` registers the sweep, records the invalid designs and fills
    :attr:`syntheses` (one per missing hardware digest x lane count) and :attr:`points`
    (the rows not yet stored); :meth:`execute` runs them and :meth:`record` stores each
    outcome. ``on_result(summary)`` is called after each (tests use it to interrupt).
    """

    spec: SweepSpec
    store: SweepStore
    executor: Executor
    progress: bool = True
    on_result: Callable[[SweepSummary], None] | None = None
    summary: SweepSummary = field(default_factory=SweepSummary)
    #: design_id -> hardware digest of every valid design (``[hardware]`` enabled).
    digests: dict[str, str] = field(default_factory=dict)
    syntheses: list[SynthesisWork] = field(default_factory=list)
    points: list[PointWork] = field(default_factory=list)
    #: digest -> lane count -> synthesis record, until all lane counts are in.
    _halves: dict[str, dict[int, dict[str, Any]]] = field(default_factory=dict, repr=False)
    _failed: set[str] = field(default_factory=set, repr=False)
    #: scene -> its content digest (:func:`~rvsm.model.scene.digest.scene_digest`).
    scene_digests: dict[str, str] = field(default_factory=dict)

    def plan(self) -> None:
        """Work out what is missing; fail early, naming the field, on an unloadable scene."""
        spec, store, hw = self.spec, self.store, self.spec.hardware
        tasks = spec.tasks()
        self.summary.total = len(tasks)
        known = store.known_digests()
        to_synthesise = {}
        if hw.enabled:
            for d in spec.designs:
                if d.point is not None:
                    dig = self.digests[d.design_id] = hw_digest(d.point, hw)
                    if dig not in known:
                        to_synthesise.setdefault(dig, d.point)
            self.summary.hw_cached = len(set(self.digests.values())) - len(to_synthesise)
        self.syntheses = [SynthesisWork(dig, point, hw, lanes)
                          for dig, point in to_synthesise.items() for lanes in hw.lanes]
        store.register(spec, tasks, self.digests)
        store.attach_digests(self.digests)
        done = store.done_keys()
        self.scene_digests = {name: self._scene_digest(name) for name in spec.run.scenes}
        for t in tasks:
            key = (t.point_id, t.scene, int(t.noise), t.seed, t.steps, t.size_text)
            stale = key in done and self._stale(t.scene, done[key])
            if key in done and not stale:
                self.summary.already_done += 1
            elif stale and t.design.point is not None:
                rows, reason = self.summary.recomputed.get(t.scene, (0, stale))
                self.summary.recomputed[t.scene] = (rows + 1, reason)
                self.points.append(PointWork(t, spec.run, self.executor.threads))
            elif t.design.point is None:
                store.write_result(t, None, "invalid", t.design.error,
                                   scene_digest=self.scene_digests[t.scene])
                self.summary.invalid += 1
            else:
                self.points.append(PointWork(t, spec.run, self.executor.threads))
        if self.points:
            self._check_scenes()

    def _scene_digest(self, name: str) -> str:
        from rvsm.model.scene.digest import scene_digest

        try:
            return scene_digest(name)
        except RvsmError as exc:
            raise RvsmError(f"{self.spec.source}: run.scenes: {exc}") from None

    def _stale(self, scene: str, stored: str | None) -> str:
        """Why a finished row of ``scene`` computed from ``stored`` content must be
        recomputed ("" when it need not)."""
        current = self.scene_digests[scene]
        if stored == current or (stored is None and current.startswith("builtin:")):
            return ""
        if stored is None:
            return "was not recorded by content (a database from an older rvsm)"
        return "changed since those rows were computed"

    def _check_scenes(self) -> None:
        from rvsm.model.scene.loaders import load_scene

        run = self.spec.run
        for name in run.scenes:
            try:
                load_scene(name, size=run.size, num_frames=run.frames,
                           steps_per_frame=run.steps_per_frame)
            except RvsmError as exc:
                raise RvsmError(f"{self.spec.source}: run.scenes: {exc}") from None

    def execute(self) -> None:
        """Run the syntheses (the longest, so first) and the points, recording each as it
        finishes, with a progress bar unless ``progress`` is off."""
        if not (self.points or self.syntheses):
            return
        from tqdm import tqdm

        work = [*self.syntheses, *self.points]
        bar = tqdm(total=len(work), desc="sweep", unit="task", disable=not self.progress,
                   smoothing=0.1)
        try:
            with self.executor as executor:
                self.summary.workers = executor.workers
                for finished in executor.run(work):
                    self.record(finished)
                    bar.set_postfix_str(f"{len(work) - bar.n - 1} remaining", refresh=False)
                    bar.update(1)
                    if self.on_result is not None:
                        self.on_result(self.summary)
        finally:
            bar.close()

    def record(self, finished: Finished) -> None:
        """Store one outcome and count it: a point's row (``ok`` or ``error``); a
        synthesis half, the digest's ``lane_cost`` row once all its lane counts are in
        (one error per digest; a failed digest is retried on the next run)."""
        work = finished.work
        if isinstance(work, SynthesisWork):
            self._record_synthesis(work, finished)
        else:
            self._record_point(work, finished)

    def _record_synthesis(self, work: SynthesisWork, finished: Finished) -> None:
        dig, hw = work.digest, self.spec.hardware
        halves = self._halves.setdefault(dig, {})
        if finished.error is not None:
            if dig not in self._failed:
                self.summary.errors.append(f"synthesis of {dig}: {finished.error}")
            self._failed.add(dig)
        else:
            halves[work.lanes] = finished.value
        if dig not in self._failed and len(halves) == len(hw.lanes):
            self.store.write_hw_cost(dig, hw_record(work.point, hw, halves))
            self.summary.hw_synthesised += 1

    def _record_point(self, work: PointWork, finished: Finished) -> None:
        task = work.task
        dig = self.digests.get(task.design.design_id)
        if finished.error is None:
            self.store.write_result(task, finished.value, "ok", hw_digest=dig,
                                    scene_digest=self.scene_digests.get(task.scene))
            self.summary.computed += 1
        else:
            msg = f"{type(finished.error).__name__}: {finished.error}"
            self.store.write_result(task, None, "error", msg, hw_digest=dig,
                                    scene_digest=self.scene_digests.get(task.scene))
            self.summary.errors.append(f"{task.design.design_id} on {task.scene}: {msg}")


def run_sweep(
    spec: SweepSpec,
    db_path: str | os.PathLike,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: bool = True,
    on_result: Callable[[SweepSummary], None] | None = None,
    processes: bool = True,
) -> SweepSummary:
    """Compute every row of ``spec`` missing from ``db_path``; see the module docstring.

    ``on_result(summary)`` is called after each stored row or synthesis (tests use it to
    interrupt). ``processes=False`` runs a local cluster's workers as threads.
    """
    executor = executor_for(workers, scheduler, processes)
    t0 = time.perf_counter()
    try:
        with SweepStore(db_path) as store:
            run = SweepRun(spec, store, executor, progress, on_result)
            run.plan()
            run.execute()
    except sqlite3.Error as exc:  # a full disk or a lost database while writing rows
        raise database_error(exc, db_path) from None
    run.summary.seconds = time.perf_counter() - t0
    return run.summary
