"""State-seeded, sharded long runs: a long run of ``T`` steps split into segments that run
at the same time, on Dask workers, each checked as strictly as one unbroken run.

``rvsm verify ... --harness chunk --shards N --workers W [--scheduler ADDRESS]``.
:func:`check_shards` builds the design once (the build cache, keyed by digest: every
segment then finds it), splits ``0 .. T`` into ``N`` segments ``[t_k, t_{k+1})`` of equal
length, and runs each as :func:`~.long_run.check_chunks` with ``segment=(t_k,
t_{k+1})``, on the executors of :mod:`rvsm.sim.sweep.executors` (what ``rvsm regress``
uses): ``LocalExecutor`` for ``--workers 0``, else a ``DaskExecutor`` on a local
cluster of ``W`` processes or the cluster at ``--scheduler``.

**One segment** (:mod:`.segment_state`, :mod:`.chunk_twin`, :mod:`.tb_stream_chunks`):

1. the twin's process runs the fixed twin over steps ``0 .. t_k - 1`` without
   streaming them (fast-forward) and writes its state at ``t_k`` (accumulators and
   thresholds, as the array's memory words) for the harness;
2. after reset the harness loads that state into the array's memories by hierarchical
   name (``$readmemh``, simulation only: the array has no port for it) and clears its
   fresh-frame flag; the thresholds are then written through the threshold bus as in
   every long run;
3. steps ``t_k .. t_{k+1} - 1`` are streamed and every spike is checked, as in an
   unbroken run;
4. after the flush the harness dumps every memory (``$writememh``) and the twin
   compares it word for word with its own state at ``t_{k+1}``: a differing word is a
   mismatch (exit 1), named by memory, scale, row and column.

**Why the chain is as strong as one unbroken run.** Let ``S_t`` be the state of the
array at the frame boundary before step ``t`` (every accumulator, or reference, and
threshold; the rest of the pipeline holds nothing that outlives a frame: the line
buffer and the window are refilled, and zero-padded at the borders, within each frame,
and after the flush no write of a later position is pending) and ``S'_t`` the twin's.
The array's outputs for steps ``t .. u - 1`` and ``S_u`` are a function of ``S_t`` and
the inputs of those steps only (the RTL is deterministic and its next state depends on
its state and inputs). Segment ``k`` starts from ``S_{t_k} = S'_{t_k}`` (loaded) and
checks every spike of its steps and ``S_{t_{k+1}} = S'_{t_{k+1}}``. The unbroken run
from reset, checked on every spike, is by induction on ``k`` the same chain: before
``t_1`` it is segment 0 exactly (both start from reset, ``S_0 = S'_0``); if the unbroken
run reaches ``t_k`` in state ``S'_{t_k}`` (segment ``k - 1``'s boundary check), its
steps ``t_k .. t_{k+1} - 1`` are segment ``k``'s, with the same spikes and the same end
state. So if every segment passes, the unbroken run would have passed, spike for spike;
and a fault that survives to a boundary is caught there, even one that no spike of the
segment shows (the unbroken run would only see it later, or never). What the argument
needs: the twin's state at ``t`` is a function of the inputs before ``t`` only (the
twin is causal: it is run over ``0 .. t - 1`` to get it), and the inputs of a segment
can be made without the steps before it (the ADC codes come from the scene's frames
and counter-based noise streams keyed by step and pixel, so a segment starts anywhere);
and the boundary compares every bit the array carries across a frame boundary (the
accumulator and threshold memories, dumped whole, and the fresh-frame flag, which is
clear after the first frame of every run). ``boundary_states_compared`` counts the
segments' end states compared: ``N`` when all finish (the last one at ``T``); the
start of segment 0 is the reset state, not loaded.
"""

from __future__ import annotations

import contextlib
import json
import os
import secrets
import shutil
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

from rvsm.model.fixed.stimulus import save_stimulus
from rvsm.model.fixed.stimulus_chunks import StimulusChunks, open_stimulus_chunks
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.architectures.registry import DEFAULT_ARCHITECTURE, get_architecture
from rvsm.rtl.capabilities import Architecture
from rvsm.sim.cosim.builds.build_cache import build
from rvsm.sim.cosim.builds.build_notes import note, still
from rvsm.sim.cosim.builds.chunk_harness import StateMemories, state_memories
from rvsm.sim.cosim.long_runs.long_run import DEFAULT_CHUNK_STEPS, check_chunks

__all__ = ["SegmentWork", "check_shards", "check_state_fault", "segment_bounds"]


def segment_bounds(num_steps: int, shards: int) -> list[tuple[int, int]]:
    """``shards`` consecutive ranges of ``0 .. num_steps`` of (nearly) equal length."""
    if isinstance(shards, bool) or int(shards) < 1:
        raise RvsmError(f"--shards must be >= 1, got {shards}")
    if int(shards) > num_steps:
        raise RvsmError(f"--shards {shards} is more than the {num_steps} steps of the run: "
                        "each segment needs at least one step")
    n = int(shards)
    cuts = [num_steps * k // n for k in range(n + 1)]
    return list(zip(cuts[:-1], cuts[1:], strict=True))


@dataclass(frozen=True)
class SegmentWork:
    """One segment of a sharded run, as an executor's work item (``key``,
    ``priority``, :meth:`run`): the source's spec, the segment's steps and where to
    run it."""

    spec: str
    index: int
    t0: int
    t1: int
    sim: str
    work_dir: str
    build_root: str
    arch: str
    options: dict
    chunk_steps: int
    state_flip: str | None
    token: str
    priority: ClassVar[int] = 0

    @property
    def key(self) -> str:
        """Unique Dask key."""
        return f"segment-{self.index}-{self.t0}-{self.t1}-{self.token}"

    @property
    def run_name(self) -> str:
        """Its run folder's name, ``segment<K>-<token>-<sim>-...``: the run's token tells
        its folders from another run's sharing the work folder."""
        return f"segment{self.index}-{self.token}"

    def run(self) -> dict[str, Any]:
        """Run the segment (:func:`~.long_run.check_chunks` with ``segment``)."""
        t = time.perf_counter()
        source = open_stimulus_chunks(self.spec)
        r = check_chunks(source, self.sim, work_dir=self.work_dir,
                         name=self.run_name, build_root=self.build_root,
                         arch=self.arch, chunk_steps=self.chunk_steps,
                         segment=(self.t0, self.t1), state_flip=self.state_flip,
                         **self.options)
        r["segment_seconds"] = time.perf_counter() - t
        r["segment"] = [self.t0, self.t1]
        r["index"] = self.index
        r["host"] = os.uname().nodename
        return r


def check_state_fault(flip: str, state: StateMemories) -> None:
    """Refuse a ``FILE:WORD:BIT`` seeded fault that names no bank, word or bit of the
    design's state (:class:`RvsmError`, exit 2, naming what it does have) before any
    segment starts: the testbench would otherwise crash on it."""
    parts = flip.split(":")
    if len(parts) != 3:
        raise RvsmError(f"--state-fault must be K:FILE:WORD:BIT, got FILE:WORD:BIT {flip!r}")
    name, word, bit = parts
    banks = {b.file: b for b in state.banks}
    bank = banks.get(name)
    if bank is None:
        raise RvsmError(f"--state-fault: {name!r} is not a state file of this design; its "
                        f"files are {', '.join(sorted(banks))}")
    if not word.isdigit() or int(word) >= bank.depth:
        raise RvsmError(f"--state-fault: word {word!r} of {name} is out of range: it has "
                        f"words 0..{bank.depth - 1}")
    if not bit.isdigit() or int(bit) >= bank.width:
        raise RvsmError(f"--state-fault: bit {bit!r} of {name} is out of range: its words "
                        f"have bits 0..{bank.width - 1}")


def check_shards(
    source: StimulusChunks,
    shards: int,
    sim: str = "verilator",
    workers: int | None = 1,
    scheduler: str | None = None,
    work_dir: str | os.PathLike = Path("build") / "verify",
    name: str = "run",
    build_root: str | os.PathLike | None = None,
    arch: str | Architecture = DEFAULT_ARCHITECTURE,
    chunk_steps: int = DEFAULT_CHUNK_STEPS,
    fault: tuple[int, str] | None = None,
    progress: bool = False,
    **options: int | None,
) -> dict:
    """Run ``source`` as ``shards`` state-seeded segments (module docstring) on
    ``workers`` local Dask processes (0: one after another in this process) or the
    cluster at ``scheduler``. ``fault`` ``(segment, "FILE:WORD:BIT")`` flips a bit of
    that segment's loaded state (a seeded fault). Returns the run as a whole:
    ``shards``, ``boundary_states_compared``, ``mismatches`` (spikes and state words),
    ``compared``, ``steps``, ``mismatch_list`` (earliest first), ``segments`` (each
    one's steps, mismatches, boundary and timings) and ``wall_seconds``."""
    from rvsm.sim.sweep.executors import executor_for

    a = get_architecture(arch)
    resolved = a.resolve(options)
    a.check(source.contract, **resolved)
    if chunk_steps < 1:
        raise RvsmError(f"--chunk-steps must be >= 1, got {chunk_steps}")
    bounds = segment_bounds(source.num_steps, shards)
    if workers is not None and workers < 0:
        raise RvsmError(f"--workers must be >= 0, got {workers}")
    work = Path(work_dir).resolve()
    root = work / "builds" if build_root is None else Path(build_root).resolve()
    t_start = time.perf_counter()
    # one build for every segment, before fanning out (the cache is keyed by digest)
    sb = build(source.contract, sim, root, arch=a, harness=True, **resolved)
    if fault is not None:
        check_state_fault(fault[1], state_memories(sb.verilog.read_text(), sb.top))
    spec = dict(source.spec)
    if not spec:
        if source.stimulus is None:
            raise RvsmError("a sharded run needs a scene it can load again (a built-in "
                            "name or a path), not a scene made in code")
        path = work / f"{name}-stimulus-{secrets.token_hex(4)}.npz"
        work.mkdir(parents=True, exist_ok=True)
        save_stimulus(path, source.stimulus)
        spec = {"kind": "stimulus", "path": str(path)}
    token = secrets.token_hex(4)
    items = [SegmentWork(json.dumps(spec), k, t0, t1, sim, str(work), str(root), a.name,
                         dict(resolved), int(chunk_steps),
                         fault[1] if fault is not None and fault[0] == k else None, token)
             for k, (t0, t1) in enumerate(bounds)]
    if fault is not None and not 0 <= fault[0] < len(bounds):
        raise RvsmError(f"the fault's segment {fault[0]} is not one of 0..{len(bounds) - 1}")
    results: list[dict] = []
    t_fan = time.perf_counter()
    where = scheduler or (f"{workers} worker(s)" if workers else "this process")
    if progress:
        note(f"running {len(items)} segments of about {bounds[0][1] - bounds[0][0]} steps "
             f"on {where}")
    heartbeat = still(lambda: f"running {len(items)} segments: {len(results)} done") \
        if progress else contextlib.nullcontext()
    try:
        with heartbeat, executor_for(workers, scheduler) as ex:
            for done in ex.run(items):
                if done.error is not None:
                    raise done.error
                results.append(done.value)
                if progress:
                    r = done.value
                    note(f"segment {r['index']} (steps {r['segment'][0]}.."
                         f"{r['segment'][1] - 1}) done: {r['mismatches']} mismatches, "
                         f"{r['segment_seconds']:.0f} s")
    except (KeyboardInterrupt, SystemExit):
        # the workers are gone: the segments they ran leave half-made run folders
        _remove_unfinished(work, token, results)
        raise
    _remove_unfinished(work, token, results)  # a segment rerun after its worker died
    wall = time.perf_counter() - t_start
    return _whole(results, sb, source, bounds, wall, time.perf_counter() - t_fan, workers,
                  scheduler, a.name, resolved, chunk_steps, root)


def _remove_unfinished(work: Path, token: str, results: list[dict]) -> None:
    """Remove this run's segment folders (``<work>/runs/segment*-<token>-*``) that no
    finished segment's result names."""
    kept = {Path(r["run_dir"]).resolve() for r in results}
    for folder in (work / "runs").glob(f"segment*-{token}-*"):
        if folder.resolve() not in kept:
            shutil.rmtree(folder, ignore_errors=True)


def _whole(results: list[dict], sb: Any, source: StimulusChunks,
           bounds: list[tuple[int, int]], wall: float, fan_wall: float,
           workers: int | None, scheduler: str | None, arch: str, options: dict,
           chunk_steps: int, root: Path) -> dict:
    """The segments' results as one run's."""
    results.sort(key=lambda r: r["index"])
    listed: list[dict] = []
    for r in results:
        for m in r.get("mismatch_list", []):
            listed.append({"segment": r["index"], **m})
    boundaries = [r.get("boundary") for r in results]
    cycles = sum(int(r.get("cycles") or 0) for r in results)
    segments = [{
        "segment": r["index"], "steps": r["segment"], "mismatches": r["mismatches"],
        "compared": r["compared"], "boundary": r.get("boundary"),
        "stopped_at_step": r.get("stopped_at_step"), "run_dir": r["run_dir"],
        "cycles": r.get("cycles"), "cycles_per_second": r.get("cycles_per_second"),
        "stream_seconds": r.get("stream_seconds"), "segment_seconds": r["segment_seconds"],
        "fast_forward_seconds": (r.get("seconds") or {}).get("fast_forward"),
        "state_compare_seconds": (r.get("seconds") or {}).get("state_compare"),
        "state_loaded_at": (r.get("timeline") or {}).get("state_loaded"),
        "host": r.get("host"),
    } for r in results]
    return {
        "harness": "chunk", "arch": arch, "options": options, "lanes": options.get("lanes"),
        "shards": len(bounds), "workers": workers, "scheduler": scheduler,
        "boundary_states_compared": sum(b is not None for b in boundaries),
        "boundary_mismatches": sum(b["mismatches"] for b in boundaries if b is not None),
        "mismatches": sum(int(r["mismatches"]) for r in results),
        "compared": sum(int(r["compared"]) for r in results),
        "expected_spikes": sum(int(r.get("expected_spikes") or 0) for r in results),
        "accumulators": results[0]["accumulators"] if results else 0,
        "steps": source.num_steps,
        "first_mismatch": listed[0] if listed else None, "mismatch_list": listed,
        "segments": segments, "cycles": cycles,
        "cycles_per_second": cycles / wall if wall else None,
        "wall_seconds": wall, "segments_wall_seconds": fan_wall,
        "build_seconds": sb.build_seconds, "generate_seconds": sb.generate_seconds,
        "build_cached": sb.cached, "verilog": str(sb.verilog), "waves": None,
        "run_dir": str(Path(results[0]["run_dir"]).parent) if results else str(root),
        "chunk_steps": int(chunk_steps),
    }
