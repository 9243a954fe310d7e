"""Run a sweep on Dask: compute every missing row, write each as it completes.

:func:`run_sweep` expands the sweep, skips every row already in the database, measures
the hardware cost (logic per lane of the streaming array) of each distinct RTL not yet in
``lane_cost`` once, and runs the rest on a Dask cluster: a
:class:`~dask.distributed.LocalCluster` of ``workers`` processes (default: one per core),
``scheduler=ADDRESS`` for an existing cluster, or ``workers=0`` in this process without
Dask. A local cluster listens on 127.0.0.1 only (:func:`local_cluster`);
``scheduler`` trusts that cluster completely: Dask runs unauthenticated pickled tasks, so
a remote scheduler must be on a trusted network or use ``tls://`` with certificates
(``dask.distributed.Security``). Only this (coordinating) process writes the database,
one committed row per finished future, so Ctrl-C keeps everything finished. The task
functions :func:`evaluate_task` and :func:`synthesise_task` are top-level so distributed
workers can import them.
"""

from __future__ import annotations

import logging
import os
import sqlite3
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.infra.errors import RvsmError
from rvsm.sim.sweep.spec import HardwareSettings, SweepSpec, SweepTask
from rvsm.sim.sweep.store import SweepStore, database_error


@dataclass
class SweepSummary:
    """What a run did. Counts are rows (tasks) unless named ``hw_*`` (syntheses)."""

    total: int = 0
    already_done: int = 0
    computed: int = 0
    invalid: int = 0
    errors: list[str] = field(default_factory=list)
    hw_synthesised: int = 0
    hw_cached: int = 0
    seconds: float = 0.0
    workers: int = 0

    def format(self) -> str:
        """One-paragraph summary for the CLI."""
        return (f"sweep: {self.total} rows: {self.already_done} already done, "
                f"{self.computed} computed, {self.invalid} invalid design(s) recorded, "
                f"{len(self.errors)} failed; RTL: {self.hw_synthesised} synthesised, "
                f"{self.hw_cached} cached; {self.seconds:.1f} s on {self.workers} worker(s)")


def evaluate_task(task: SweepTask, frames: int, steps_per_frame: int, method: str = "auto",
                  match: str = "gain", threads: int | None = None) -> dict[str, Any]:
    """Fixed vs float on one scene: :func:`~rvsm.model.fixed.cost.quantisation_cost` plus
    ``mse_cost`` (fixed minus float, 8-bit units squared), ``saturation_rate`` (per scale,
    saturated accumulator-steps / (steps * H * W)), ``max_saturation_rate`` and
    ``seconds`` (wall time). ``threads`` caps the numba threads of the twins' fused kernels
    in this process (a local cluster gives each of its ``n`` worker processes
    ``cores // n``, so workers x threads never oversubscribe the cores)."""
    from rvsm.model.fixed.cost import quantisation_cost
    from rvsm.model.scene.loaders import load_scene

    if threads is not None:
        import numba

        numba.set_num_threads(max(1, min(int(threads), numba.config.NUMBA_NUM_THREADS)))

    t0 = time.perf_counter()
    scene = load_scene(task.scene, size=task.size, num_frames=frames,
                       steps_per_frame=steps_per_frame)
    rec = quantisation_cost(scene, task.run_point(), method=method, match=match)
    denom = max(1, rec["steps"] * rec["height"] * rec["width"])
    rec["saturation_rate"] = [s / denom for s in rec["saturated"]]
    rec["max_saturation_rate"] = max(rec["saturation_rate"], default=0.0)
    rec["mse_cost"] = rec["mse_fixed"] - rec["mse_float"]
    rec["noise"] = task.noise
    rec["seed"] = task.seed
    rec["seconds"] = time.perf_counter() - t0
    return rec


def hw_point(point: DesignPoint, size: tuple[int, int]) -> DesignPoint:
    """The small array whose RTL is synthesised for ``point`` (noise does not change RTL)."""
    return point.with_size(*size)


def hw_digest(point: DesignPoint, hardware: HardwareSettings) -> str:
    """Cache key of a design's hardware cost: the digest of its RTL contract at
    ``hardware.size`` (RTL sources included), the FPGA flow's sources, the lane counts
    and whether Fmax is measured."""
    from rvsm.rtl.digest import rtl_digest

    return rtl_digest(hw_point(point, hardware.size).contract(), "stream",
                      extra={"lane_counts": list(hardware.lanes), "fmax": hardware.fmax})


def synthesise_task(point: DesignPoint, hardware: HardwareSettings, lanes: int
                    ) -> dict[str, Any]:
    """One of the two syntheses of :func:`~rvsm.rtl.fpga.lane_cost.lane_cost`: the
    streaming array of ``point`` at ``hardware.size`` with ``lanes`` lanes (placed and
    routed for Fmax when ``hardware.fmax`` and ``lanes`` is the first lane count). A
    sweep submits the two lane counts as two tasks, so they run on two workers."""
    from dataclasses import asdict

    from rvsm.rtl.fpga.lane_cost import lane_synthesis

    fmax = hardware.fmax and lanes == hardware.lanes[0]
    return asdict(lane_synthesis(point, lanes, size=hardware.size, fmax=fmax))


def hw_record(point: DesignPoint, hardware: HardwareSettings,
              syntheses: dict[int, dict[str, Any]]) -> dict[str, Any]:
    """The ``lane_cost`` row of ``point`` from its two :func:`synthesise_task` results:
    ``lut4_per_lane``, ``ff_per_lane``, ``lut4_base``, ``fmax_mhz`` (or None), the memory
    bits, ``size`` ("HxW"), ``lanes``, ``contract`` (repr) and ``seconds`` (both
    syntheses)."""
    from rvsm.rtl.fpga.lane_cost import LaneSynthesis, combine_lanes

    p1, p2 = hardware.lanes
    cost = combine_lanes(point, hardware.size, LaneSynthesis(**syntheses[p1]),
                         LaneSynthesis(**syntheses[p2]))
    rec = cost.to_dict()
    rec.update(size=f"{hardware.size[0]}x{hardware.size[1]}", lanes=list(hardware.lanes),
               contract=repr(hw_point(point, hardware.size).contract()))
    return rec


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
    try:
        return _run_sweep(spec, db_path, workers, scheduler, progress, on_result, processes)
    except sqlite3.Error as exc:  # a full disk or a lost database while writing rows
        raise database_error(exc, db_path) from None


def _run_sweep(spec, db_path, workers, scheduler, progress, on_result, processes
               ) -> SweepSummary:
    t0 = time.perf_counter()
    summary = SweepSummary()
    tasks = spec.tasks()
    summary.total = len(tasks)
    with SweepStore(db_path) as store:
        hw = spec.hardware
        digests: dict[str, str] = {}
        hw_todo: dict[str, DesignPoint] = {}
        known = store.known_digests()
        if hw.enabled:
            for d in spec.designs:
                if d.point is not None:
                    digests[d.design_id] = hw_digest(d.point, hw)
            for did, dig in digests.items():
                if dig in known:
                    continue
                hw_todo.setdefault(dig, next(x.point for x in spec.designs if x.design_id == did))
            summary.hw_cached = len(set(digests.values())) - len(hw_todo)
        store.register(spec, tasks, digests)
        store.attach_digests(digests)
        done = store.done_keys()
        pending: list[SweepTask] = []
        for t in tasks:
            key = (t.point_id, t.scene, int(t.noise), t.seed, t.steps, t.size_text)
            if key in done:
                summary.already_done += 1
            elif t.design.point is None:
                store.write_result(t, None, "invalid", t.design.error)
                summary.invalid += 1
            else:
                pending.append(t)
        if pending:
            _check_scenes(spec)
        if pending or hw_todo:
            _execute(spec, store, pending, hw_todo, digests, summary, workers, scheduler,
                     progress, on_result, processes)
    summary.seconds = time.perf_counter() - t0
    return summary


def _check_scenes(spec: SweepSpec) -> None:
    """Fail early, naming the field, if a scene cannot be loaded."""
    from rvsm.model.scene.loaders import load_scene

    for name in spec.run.scenes:
        try:
            load_scene(name, size=spec.run.size, num_frames=spec.run.frames,
                       steps_per_frame=spec.run.steps_per_frame)
        except RvsmError as exc:
            raise RvsmError(f"{spec.source}: run.scenes: {exc}") from None


def _execute(spec, store, pending, hw_todo, digests, summary, workers, scheduler, progress,
             on_result, processes) -> None:
    from tqdm import tqdm

    run = spec.run
    args = (run.frames, run.steps_per_frame, run.method, run.match)
    hw = spec.hardware
    # one synthesis task per (design digest, lane count); a digest's row is written when
    # all of its lane counts are in
    syntheses = [((dig, lanes), point) for dig, point in hw_todo.items() for lanes in hw.lanes]
    total = len(pending) + len(syntheses)
    bar = tqdm(total=total, desc="sweep", unit="task", disable=not progress, smoothing=0.1)
    halves: dict[str, dict[int, dict[str, Any]]] = {dig: {} for dig in hw_todo}
    failed: set[str] = set()

    def finished(kind: str, item: Any, value: Any, exc: BaseException | None) -> None:
        if kind == "hw":
            dig, lanes = item
            if exc is not None:
                if dig not in failed:
                    summary.errors.append(f"synthesis of {dig}: {exc}")
                failed.add(dig)
            else:
                halves[dig][lanes] = value
            if dig not in failed and len(halves[dig]) == len(hw.lanes):
                store.write_hw_cost(dig, hw_record(hw_todo[dig], hw, halves[dig]))
                summary.hw_synthesised += 1
        else:
            dig = digests.get(item.design.design_id)
            if exc is None:
                store.write_result(item, value, "ok", hw_digest=dig)
                summary.computed += 1
            else:
                msg = f"{type(exc).__name__}: {exc}"
                store.write_result(item, None, "error", msg, hw_digest=dig)
                summary.errors.append(f"{item.design.design_id} on {item.scene}: {msg}")
        bar.set_postfix_str(f"{total - bar.n - 1} remaining", refresh=False)
        bar.update(1)
        if on_result is not None:
            on_result(summary)

    try:
        if workers == 0 and scheduler is None:
            summary.workers = 0
            for (dig, lanes), point in syntheses:
                _call(finished, "hw", (dig, lanes), synthesise_task, point, hw, lanes)
            for t in pending:
                _call(finished, "pt", t, evaluate_task, t, *args)
        else:
            _dask(spec, pending, syntheses, args, finished, summary, workers, scheduler,
                  processes)
    finally:
        bar.close()


def _call(finished, kind, item, fn, *args) -> None:
    try:
        value = fn(*args)
    except Exception as exc:  # a failed row is recorded and retried next run
        finished(kind, item, None, exc)
        return
    finished(kind, item, value, None)


#: Where a local cluster listens: the loopback interface only (its scheduler accepts
#: pickled tasks without authentication, so it must never be reachable from the network).
LOCAL_HOST = "127.0.0.1"


def local_cluster(workers: int, processes: bool = True):
    """A :class:`~dask.distributed.LocalCluster` of ``workers`` single-threaded workers
    whose scheduler, workers, nannies and HTTP pages (workers, logs, call stacks: Dask
    always serves them, even without a dashboard) listen on :data:`LOCAL_HOST` only, on
    random ports (threaded workers talk in-process)."""
    from dask.distributed import LocalCluster

    where = {"host": LOCAL_HOST} if processes else {}  # threads talk in-process (inproc://)
    return LocalCluster(n_workers=workers, threads_per_worker=1, processes=processes,
                        **where, dashboard_address=f"{LOCAL_HOST}:0",
                        worker_dashboard_address=f"{LOCAL_HOST}:0", silence_logs=logging.ERROR)


def _dask(spec, pending, syntheses, args, finished, summary, workers, scheduler,
          processes) -> None:
    from dask.distributed import Client, as_completed

    cluster = None
    if scheduler is not None:
        try:
            client = Client(scheduler, timeout="15s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise RvsmError(f"cannot connect to the Dask scheduler {scheduler}: {exc}; "
                            "check --scheduler (e.g. tcp://host:8786)") from None
    else:
        n = workers if workers is not None else (os.cpu_count() or 1)
        if n < 1:
            raise RvsmError(f"--workers must be >= 0, got {n}")
        cluster = local_cluster(n, processes)
        client = Client(cluster)
        # numba threads per worker: the cores shared out, never oversubscribed.
        args = (*args, max(1, (os.cpu_count() or 1) // n))
    futures = []
    try:
        summary.workers = len(client.scheduler_info().get("workers", {}))
        items = {}
        # The longest tasks first (syntheses, one per lane count), the short evaluations
        # last, so they fill the workers' tails.
        for (dig, lanes), point in syntheses:
            f = client.submit(synthesise_task, point, spec.hardware, lanes,
                              key=f"hw-{dig}-p{lanes}", priority=10)
            items[f.key] = ("hw", (dig, lanes))
            futures.append(f)
        for t in pending:
            f = client.submit(evaluate_task, t, *args, key=f"pt-{t.point_id}")
            items[f.key] = ("pt", t)
            futures.append(f)
        for fut in as_completed(futures):
            kind, item = items[fut.key]
            try:
                value = fut.result()
            except Exception as exc:  # recorded and retried next run
                finished(kind, item, None, exc)
            else:
                finished(kind, item, value, None)
            fut.release()
    finally:
        if futures:
            client.cancel([f for f in futures if not f.done()])
        client.close()
        if cluster is not None:
            cluster.close()
