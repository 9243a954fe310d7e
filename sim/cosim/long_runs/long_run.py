"""Long co-simulation runs: an array that streams (the streaming array) in the long-run
harness, chunk by chunk, in bounded memory, with a waveform window around the first
mismatch.

:func:`check_chunks` builds (cached) the array inside :mod:`.chunk_harness` and runs the
long-run testbench (the architecture's
:attr:`~rvsm.rtl.capabilities.Architecture.long_run_testbench`, :mod:`.tb_stream_chunks`
for the streaming array) on a :class:`StimulusChunks`: the twin's
codes and expectation are produced in the simulator's process a chunk at a time, so a
one-second run (40,000 steps of 250x400) never holds more than a chunk. A progress bar
follows the steps done.

**The waveform window.** A full trace of a long run is too large (gigabytes per
thousand steps at sensor size), so a failing run is simulated a second time from the
start (on Verilator, with a second build that can trace: tracing is 11 of the 18 MB of
C++ of the full sensor, so only failing runs pay for it) with the harness's dump
switched on only for clock cycles ``C - before .. C +
after`` around the cycle ``C`` of the first mismatching output beat; ``before``
defaults to two frames of beats plus the lag (:func:`window_cycles`), so the window holds
the two earlier updates of every accumulator on the mismatching row, and the re-run
stops at the end of the window. ``waves=True`` dumps the whole run instead. Both
simulators write FST.
"""

from __future__ import annotations

import json
import os
import shutil
import threading
from pathlib import Path
from typing import Any

from rvsm.model.fixed.stimulus import save_stimulus
from rvsm.model.fixed.stimulus_chunks import StimulusChunks
from rvsm.model.infra.errors import RvsmError
from rvsm.model.infra.progress import progress_bar
from rvsm.rtl.architectures.registry import DEFAULT_ARCHITECTURE, get_architecture
from rvsm.rtl.capabilities import Architecture
from rvsm.sim.cosim.builds.build_cache import SimBuild, build, new_run_dir
from rvsm.sim.cosim.builds.chunk_harness import DEFAULT_DEPTH, clock_inside
from rvsm.sim.cosim.builds.code_coverage import read_coverage, summary
from rvsm.sim.cosim.builds.testbench_run import run_cocotb
from rvsm.sim.cosim.long_runs.chunk_twin import start_twin

__all__ = ["DEFAULT_CHUNK_STEPS", "check_chunks", "window_cycles"]

#: Steps the testbench produces and streams at a time.
DEFAULT_CHUNK_STEPS = 8
#: Cycles the waveform window runs past the first mismatching beat.
WINDOW_AFTER = 64


def window_cycles(geo: Any) -> int:
    """Cycles the waveform window reaches back before the first mismatch: two frames of
    beats plus the lag (each accumulator of the row is updated twice in it)."""
    return 2 * geo.beats_per_frame + geo.lag


WHOLE_RUN_WAVES = "waves.fst"
WINDOW_WAVES = "window.fst"


def _source_inputs(source: StimulusChunks, run_dir: Path, chunk_steps: int) -> dict:
    spec = source.spec
    if not spec:
        if source.stimulus is None:  # a scene made in code
            raise RvsmError("a long run needs a scene it can load again (a built-in name or "
                            "a path), not a scene made in code")
        path = run_dir / "stimulus.npz"
        save_stimulus(path, source.stimulus)
        spec = {"kind": "stimulus", "path": str(path)}
    return {"RVSM_SOURCE": json.dumps(spec), "RVSM_CHUNK_STEPS": str(int(chunk_steps))}


def _run(sb: SimBuild, inputs: dict, run_dir: Path, plusargs: list[str],
         hdl_dumps: bool) -> dict:
    """One testbench run, the twin's process (:mod:`.chunk_twin`) started first: its
    first chunk is made while the simulator starts."""
    segment = json.loads(inputs.get("RVSM_SEGMENT", "null"))
    twin = start_twin(inputs["RVSM_SOURCE"], sb.ports_json.resolve(), run_dir,
                      int(inputs["RVSM_CHUNK_STEPS"]), DEFAULT_DEPTH,
                      stop_on_mismatch="RVSM_STOP_AFTER_CYCLE" not in inputs,
                      segment=segment)
    try:
        return run_cocotb(sb, {**inputs, **twin.env()}, run_dir, plusargs=plusargs,
                          hdl_dumps=hdl_dumps)
    finally:
        twin.close()


def _run_with_progress(sb: SimBuild, inputs: dict, run_dir: Path, total: int, desc: str,
                       progress: bool, plusargs: list[str], waves: bool) -> dict:
    """One testbench run; a thread follows ``progress.txt`` into a progress bar."""
    progress_file = run_dir / "progress.txt"
    inputs = {**inputs, "RVSM_PROGRESS": str(progress_file)}
    stop = threading.Event()
    bar = progress_bar(total, desc, progress)

    done = [0]

    def catch_up() -> None:
        try:
            now = int(progress_file.read_text().split("/")[0])
        except (OSError, ValueError):
            return
        if now > done[0]:
            bar.update(now - done[0])
            done[0] = now

    def follow() -> None:
        while not stop.wait(0.5):
            catch_up()

    thread = threading.Thread(target=follow, daemon=True) if progress else None
    if thread is not None:
        thread.start()
    try:
        return _run(sb, inputs, run_dir, plusargs, waves)
    finally:
        stop.set()
        if thread is not None:
            thread.join()
            catch_up()  # the last steps, which a poll every 0.5 s may not have seen
            bar.refresh()
        bar.close()


def check_chunks(
    source: StimulusChunks,
    sim: str = "verilator",
    work_dir: str | os.PathLike = Path("build") / "verify",
    name: str = "run",
    build_root: str | os.PathLike | None = None,
    arch: str | Architecture = DEFAULT_ARCHITECTURE,
    chunk_steps: int = DEFAULT_CHUNK_STEPS,
    waves: bool = False,
    progress: bool = False,
    code_coverage: bool = False,
    segment: tuple[int, int] | None = None,
    state_flip: str | None = None,
    **options: int | None,
) -> dict:
    """Run ``source`` through the RTL in the long-run harness; compare every spike.

    Returns the testbench result (:func:`~.simulation.run_testbench`'s keys, plus
    ``harness``, ``chunks``, ``beats_streamed``, ``seconds`` per phase of the
    testbench: ``twin``, ``encode``, ``simulate``, ``decode``, ``check``) with
    ``build_seconds``, ``run_dir`` and ``waves``: on a mismatch, the window around it
    (module docstring); with ``waves``, the whole run. ``code_coverage`` (Verilator)
    builds line and toggle coverage in and gives ``code_coverage``, the run's
    ``coverage.dat`` (:mod:`.code_coverage`), and its ``code_coverage_summary``.
    ``segment`` ``(t0, t1)``: only steps ``t0 .. t1 - 1``, the RTL started from the
    twin's state at ``t0`` and its state at ``t1`` compared (``boundary``; a segment of
    :func:`~.shards.check_shards`); ``state_flip`` (``FILE:WORD:BIT``) flips a bit of
    the state loaded: a seeded fault.
    """
    a = get_architecture(arch)
    resolved = a.resolve(options)
    a.check(source.contract, **resolved)
    if chunk_steps < 1:
        raise RvsmError(f"--chunk-steps must be >= 1, got {chunk_steps}")
    work = Path(work_dir)
    root = work / "builds" if build_root is None else Path(build_root)
    sb = build(source.contract, sim, root, arch=a, harness=True,
               waves=waves and sim == "verilator", coverage=code_coverage, **resolved)
    run_dir = new_run_dir(work, f"{name}-{sim}")
    geo = a.beats.geometry(source.contract, int(resolved["lanes"]))
    try:
        inputs = {**_source_inputs(source, run_dir, chunk_steps),
                  "RVSM_HARNESS_CLOCK": "inside" if clock_inside(sim) else "outside"}
        if segment is not None:
            inputs["RVSM_SEGMENT"] = json.dumps([int(t) for t in segment])
            if state_flip:
                inputs["RVSM_STATE_FLIP"] = state_flip
        total = source.num_steps if segment is None else segment[1] - segment[0]
        plusargs = []
        if waves:
            plusargs = [f"+rvsm_dump_file={run_dir / WHOLE_RUN_WAVES}", "+rvsm_dump_from=0",
                        f"+rvsm_dump_to={2**62}"]
        result = _run_with_progress(sb, inputs, run_dir, total,
                                    f"{sim} {a.name} {name}", progress, plusargs, waves)
        result["waves"] = str(run_dir / WHOLE_RUN_WAVES) if waves else None
        dat = run_dir / "coverage.dat"
        result["code_coverage"] = str(dat) if code_coverage and dat.exists() else None
        if result["code_coverage"]:
            result["code_coverage_summary"] = summary(read_coverage(dat))
        first = result.get("first_mismatch") or {}
        if result["mismatches"] and not waves and "cycle" in first:
            traced = sb if sim == "icarus" else build(
                source.contract, sim, root, arch=a, harness=True, waves=True, **resolved)
            result.update(_window(traced, inputs, run_dir, int(first["cycle"]), geo))
    except KeyboardInterrupt:  # an interrupted run leaves no half-written run folder
        shutil.rmtree(run_dir, ignore_errors=True)
        raise
    result.update(build_seconds=sb.build_seconds, generate_seconds=sb.generate_seconds,
                  build_cached=sb.cached, verilog=str(sb.verilog), run_dir=str(run_dir),
                  arch=a.name, options=resolved, lanes=resolved.get("lanes"),
                  chunk_steps=int(chunk_steps))
    return result


def _window(sb: SimBuild, inputs: dict, run_dir: Path, cycle: int, geo: Any) -> dict:
    """Re-run up to the window's end with the dump on for the window only."""
    lo = max(0, cycle - window_cycles(geo))
    hi = cycle + WINDOW_AFTER
    again = run_dir / "failure"
    wave = again / WINDOW_WAVES
    plusargs = [f"+rvsm_dump_file={wave}", f"+rvsm_dump_from={lo}", f"+rvsm_dump_to={hi}"]
    inputs = {**inputs, "RVSM_STOP_AFTER_CYCLE": str(hi)}
    _run(sb, inputs, again, plusargs, hdl_dumps=True)
    return {"waves": str(wave) if wave.exists() else None,
            "wave_window_cycles": [lo, hi]}
