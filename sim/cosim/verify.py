"""RTL-versus-fixed-twin verification: the functions behind ``rvsm verify``.

Everything goes through one stimulus file format (:mod:`rvsm.model.fixed.stimulus`):
:func:`check_stimulus` writes a :class:`Stimulus` into its run folder, builds (cached)
and simulates the Verilog with the cocotb testbench, and returns the testbench's
comparison. On a mismatch without ``waves`` it re-runs the stimulus up to the first
failing step with waves on, so a waveform is always kept. The entry points build the
stimulus three ways: :func:`run_rtl` from a contract, codes and thresholds (the
expectation from :meth:`ArrayContract.run`); :func:`verify` from a scene and a design
point (a :class:`~.run_point.RunPoint`, read once by the command) via the fixed twin;
:func:`replay` from a stimulus file (``rvsm stimulus``). The architecture is a value of
the registry; whether it has a long-run harness is its capability
(:attr:`~rvsm.rtl.capabilities.Architecture.long_run_testbench`).
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.stimulus import Stimulus, open_stimulus, save_stimulus
from rvsm.model.fixed.stimulus_chunks import StimulusChunks
from rvsm.model.fixed.widths import unsigned_max
from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.scene import Scene
from rvsm.rtl.architectures.registry import (
    DEFAULT_ARCHITECTURE,
    architectures_with,
    get_architecture,
)
from rvsm.rtl.capabilities import Architecture
from rvsm.sim.cosim.builds.build_cache import SimBuild, build, new_run_dir
from rvsm.sim.cosim.builds.cocotb_adapter import check_simulator
from rvsm.sim.cosim.builds.testbench_run import run_testbench
from rvsm.sim.cosim.long_runs.long_run import DEFAULT_CHUNK_STEPS, check_chunks
from rvsm.sim.cosim.run_point import RunPoint

#: The testbenches ``rvsm verify --harness`` chooses: per cycle from Python, or the
#: long-run harness (the simulator runs the cycles; streaming array only); ``auto``
#: picks the long-run harness for a streaming run of more than :data:`AUTO_CHUNK_BEATS`
#: input beats, else the per-cycle testbench (:func:`choose_harness`).
HARNESSES = ("auto", "cycle", "chunk")
#: Beats above which ``auto`` takes the long-run harness: the per-cycle testbench runs
#: about 600-15,000 cycles/s, so beyond this a run takes seconds to minutes in it.
AUTO_CHUNK_BEATS = 100_000

__all__ = ["AUTO_CHUNK_BEATS", "HARNESSES", "check_code_coverage", "check_harness",
           "check_stimulus", "choose_harness", "random_verify", "replay", "run_rtl",
           "verify"]

DEFAULT_WORK = Path("build") / "verify"


def _check_inputs(contract: ArrayContract, codes: np.ndarray, thresholds: np.ndarray) -> None:
    c = contract
    if codes.ndim != 3 or codes.shape[1:] != (c.height, c.width):
        raise RvsmError(f"codes must be (T, {c.height}, {c.width}), got {codes.shape}")
    if codes.min() < 0 or codes.max() > unsigned_max(c.adc_bits):
        raise RvsmError(f"ADC codes must lie in 0..{unsigned_max(c.adc_bits)}")
    if thresholds.shape != (c.num_scales, c.height, c.width):
        raise RvsmError(f"thresholds must be ({c.num_scales}, {c.height}, {c.width}), "
                        f"got {thresholds.shape}")


def _resolve(a: Architecture, options: dict[str, int | None],
             contract: ArrayContract) -> dict[str, int]:
    """The options of ``a`` (defaults filled in), after its size rule."""
    resolved = a.resolve(options)
    a.check(contract, **resolved)
    return resolved


def check_stimulus(
    stim: Stimulus,
    sim: str = "icarus",
    waves: bool = False,
    work_dir: str | os.PathLike = DEFAULT_WORK,
    name: str = "run",
    build_root: str | os.PathLike | None = None,
    arch: str | Architecture = DEFAULT_ARCHITECTURE,
    **options: int | None,
) -> dict:
    """Drive the RTL of ``stim.contract`` with ``stim`` and compare every spike.

    ``arch`` names the architecture (:mod:`rvsm.rtl.architectures.registry`, default the
    streaming array), ``options`` its options (e.g. ``lanes``).

    Each call gets its own run folder ``work_dir/runs/<name>-<sim>-<time>-<pid>-<random>``
    (:func:`~.build_cache.new_run_dir`) holding ``stimulus.npz`` (the testbench's input), the
    result, the log and waves; builds are shared in ``build_root`` (default
    ``work_dir/builds``). Returns the testbench result: ``compared``, ``mismatches``,
    ``first_mismatch``, ``first_mismatch_time_ns``, ``simulator``, ``waves`` (path or
    None), ``build_seconds``, ``stream_seconds``, ``run_dir``...
    """
    contract = stim.contract
    a = get_architecture(arch)
    resolved = _resolve(a, options, contract)
    _check_inputs(contract, stim.codes, stim.thresholds)
    want = (stim.num_steps, contract.num_scales, contract.height, contract.width)
    if stim.spikes.shape != want:
        raise RvsmError(f"expected spikes must be {want}, got {stim.spikes.shape}")
    work = Path(work_dir)
    root = work / "builds" if build_root is None else Path(build_root)
    sb = build(contract, sim, root, waves=waves, arch=a, **resolved)
    run_dir = new_run_dir(work, f"{name}-{sim}")
    try:
        result = _run_and_keep_waves(stim, sb, run_dir, root, waves)
    except KeyboardInterrupt:  # an interrupted run leaves no half-written run folder
        shutil.rmtree(run_dir, ignore_errors=True)
        raise
    result.update(
        build_seconds=sb.build_seconds, generate_seconds=sb.generate_seconds,
        build_cached=sb.cached, verilog=str(sb.verilog), run_dir=str(run_dir),
        arch=a.name, options=resolved, lanes=resolved.get("lanes"),
    )
    return result


def _run_and_keep_waves(stim: Stimulus, sb: SimBuild, run_dir: Path, root: Path,
                        waves: bool) -> dict:
    """Run ``stim`` in ``run_dir``; on a mismatch without ``waves``, re-run it up to the
    first failing step with waves on (``run_dir/failure``) so a waveform is kept."""
    path = run_dir / "stimulus.npz"
    save_stimulus(path, stim)
    result = run_testbench(sb, path, run_dir, waves=waves)
    if result["mismatches"] and not result["waves"]:
        first = result["first_mismatch"] or {}
        upto = min(stim.num_steps, int(first.get("step", stim.num_steps - 1)) + 1)
        again_dir = run_dir / "failure"
        again = again_dir / "stimulus.npz"
        save_stimulus(again, stim.first_steps(upto))
        sbw = build(stim.contract, sb.sim, root, top=sb.top, waves=True, arch=sb.arch,
                    **sb.options)
        result["waves"] = run_testbench(sbw, again, again_dir, waves=True)["waves"]
    return result


def run_rtl(
    contract: ArrayContract,
    codes: np.ndarray,
    thresholds: np.ndarray,
    sim: str = "icarus",
    expected: np.ndarray | None = None,
    clear_before: Sequence[int] = (),
    waves: bool = False,
    work_dir: str | os.PathLike = DEFAULT_WORK,
    name: str = "run",
    build_root: str | os.PathLike | None = None,
    arch: str | Architecture = DEFAULT_ARCHITECTURE,
    **options: int | None,
) -> dict:
    """Simulate the RTL on ``codes``/``thresholds`` and compare with the expectation.

    ``expected`` defaults to ``contract.run(codes, thresholds, clear_before)`` (pass one
    to test the checker); ``arch`` and ``options`` as :func:`check_stimulus`. Returns
    :func:`check_stimulus`'s result.
    """
    codes = np.asarray(codes, dtype=np.int64)
    thresholds = np.asarray(thresholds, dtype=np.int64)
    _check_inputs(contract, codes, thresholds)
    if expected is None:
        expected = contract.run(codes, thresholds, clear_before)
    stim = Stimulus(codes, thresholds, np.asarray(expected, dtype=np.int8), contract,
                    clear_before=tuple(clear_before))
    return check_stimulus(stim, sim, waves=waves, work_dir=work_dir, name=name,
                          build_root=build_root, arch=arch, **options)


def replay(
    stimulus: str | os.PathLike,
    sim: str = "icarus",
    steps: int | None = None,
    waves: bool = False,
    work_dir: str | os.PathLike = DEFAULT_WORK,
    arch: str | Architecture = DEFAULT_ARCHITECTURE,
    recompute_expected: bool = False,
    harness: str = "cycle",
    progress: bool = False,
    chunk_steps: int = DEFAULT_CHUNK_STEPS,
    code_coverage: bool = False,
    **options: int | None,
) -> dict:
    """Replay a stimulus file (``rvsm stimulus -o FILE``) on the RTL, spike for spike.

    ``steps`` keeps the first steps. The file is checked before the RTL is blamed: when
    its expected spikes do not follow from its own codes, thresholds and contract
    (a hand-edited or damaged file) it is a bad stimulus (:class:`RvsmError`, exit 2,
    naming the first inconsistent step and accumulator), unless ``recompute_expected``
    takes the expectation from its codes instead. ``harness`` and ``progress`` as
    :func:`verify`. Returns :func:`check_stimulus`'s result plus ``stimulus``,
    ``height``, ``width`` and ``expectation`` (``"file"`` or ``"recomputed"``).
    """
    check_simulator(sim)
    a = get_architecture(arch)
    check_harness(harness, a)
    stim = open_stimulus(stimulus)  # codes and spikes read a range of steps at a time
    c = stim.contract
    _resolve(a, options, c)
    if steps is not None and steps > stim.num_steps:
        raise RvsmError(f"--steps {steps}: {stimulus} holds {stim.num_steps} steps; ask for "
                        f"at most {stim.num_steps}")
    if steps is not None and steps < stim.num_steps:
        stim = stim.first_steps(steps)
    harness = choose_harness(harness, a, c.height * c.width, stim.num_steps, options)
    check_code_coverage(code_coverage, harness, sim)
    if harness != "chunk":  # the per-cycle testbench takes the stimulus whole
        stim = stim.loaded()
    if recompute_expected:
        if harness != "chunk":
            stim = stim.with_recomputed_expectation()
    else:
        problem = stim.first_inconsistency()  # chunk by chunk
        if problem:
            raise RvsmError(f"{stimulus} is a bad stimulus, not an RTL failure: {problem}; "
                            f"fix the file, or replay it with --recompute-expected to take "
                            f"the expectation from its codes")
    name = Path(stimulus).stem or "stimulus"
    if harness == "chunk":
        # the testbench opens the file again and reads it a chunk at a time
        source = StimulusChunks.from_stimulus(stim, str(Path(stimulus).resolve()),
                                              recompute=recompute_expected)
        result = check_chunks(source, sim, work_dir=work_dir, name=name, arch=a,
                              waves=waves, progress=progress, chunk_steps=chunk_steps,
                              code_coverage=code_coverage,
                              **options)
    else:
        result = check_stimulus(stim, sim, waves=waves, work_dir=work_dir, name=name,
                                arch=a, **options)
    result.update(stimulus=str(stimulus), height=c.height, width=c.width,
                  coverage=with_lane_coverage(_coverage(stim), result),
                  expectation="recomputed" if recompute_expected else "file")
    return result


def verify(
    scene: str | Scene,
    point: RunPoint | str | os.PathLike,
    sim: str = "icarus",
    steps: int | None = None,
    waves: bool = False,
    size: tuple[int, int] | None = None,
    work_dir: str | os.PathLike = DEFAULT_WORK,
    arch: str | Architecture = DEFAULT_ARCHITECTURE,
    harness: str = "cycle",
    progress: bool = False,
    chunk_steps: int = DEFAULT_CHUNK_STEPS,
    code_coverage: bool = False,
    **options: int | None,
) -> dict:
    """Verify the RTL of design ``point`` on ``scene``, spike for spike.

    ``point`` is a :class:`~.run_point.RunPoint` (a command reads its TOML once) or the
    TOML path; ``arch`` and ``options`` as :func:`check_stimulus` (the streaming array
    takes any array size).

    ``size = (H, W)`` overrides the point's array size (a scene name or path is rendered
    or cropped to it; a :class:`Scene`, shaped by the caller, must have it); ``steps``
    keeps the first steps. ``harness``: ``"cycle"``, the per-cycle testbench
    (:func:`check_stimulus`), or ``"chunk"``, the long-run harness
    (:func:`~.long_run.check_chunks`: streaming array only, the twin run chunk by
    chunk, bounded memory, no coverage for scene runs; ``progress`` shows a bar).
    Returns :func:`check_stimulus`'s result plus ``scene`` and ``point``. Raises
    :class:`RvsmError` on user errors (not on mismatches: check
    ``result["mismatches"]``).
    """
    from rvsm.model.fixed.stimulus import make_stimulus
    from rvsm.model.scene.loaders import load_scene

    check_simulator(sim)
    a = get_architecture(arch)
    check_harness(harness, a)
    run = RunPoint.coerce(point, size)
    h, w = run.shape
    _resolve(a, options, run.contract)
    if not isinstance(scene, Scene):
        scene = load_scene(scene, size=(h, w))
    harness = choose_harness(harness, a, h * w,
                             scene.num_steps if steps is None else steps, options,
                             reloadable=scene.source is not None)
    check_code_coverage(code_coverage, harness, sim)
    if harness == "chunk":
        if steps is not None and steps > scene.num_steps:
            raise RvsmError(f"--steps {steps} is more than the {scene.num_steps} steps of "
                            f"scene {scene.name!r}; ask for at most {scene.num_steps}")
        source = StimulusChunks.from_scene(scene, run.point, steps)
        result = check_chunks(source, sim, work_dir=work_dir, name=scene.name or "scene",
                              arch=a, waves=waves, progress=progress, chunk_steps=chunk_steps,
                              code_coverage=code_coverage,
                              **options)
        result.update(scene=scene.source or scene.name, point=run.source, height=h,
                      width=w, coverage=result.get("lane_coverage"))
        return result
    stim = make_stimulus(scene, run.point, num_steps=steps)
    result = check_stimulus(stim, sim, waves=waves, work_dir=work_dir,
                            name=scene.name or "scene", arch=a, **options)
    result.update(scene=scene.source or scene.name, point=run.source, height=h, width=w,
                  coverage=_coverage(stim))
    return result


def random_verify(
    point: RunPoint | str | os.PathLike,
    seed: int,
    steps: int,
    sim: str = "icarus",
    waves: bool = False,
    size: tuple[int, int] | None = None,
    work_dir: str | os.PathLike = DEFAULT_WORK,
    arch: str | Architecture = DEFAULT_ARCHITECTURE,
    harness: str = "cycle",
    progress: bool = False,
    chunk_steps: int = DEFAULT_CHUNK_STEPS,
    code_coverage: bool = False,
    **options: int | None,
) -> dict:
    """Verify the RTL of design ``point`` (as :func:`verify`) on a seeded random and
    corner stimulus (:func:`~rvsm.model.fixed.corner_stimulus.corner_stimulus`,
    ``steps`` steps); ``arch`` and ``options`` as :func:`check_stimulus`.

    Returns :func:`check_stimulus`'s result plus ``seed``, ``point``, ``height``,
    ``width`` and ``coverage`` (per scale, accumulator-steps per bin).
    """
    from rvsm.model.fixed.corner_stimulus import corner_stimulus, coverage

    check_simulator(sim)
    a = get_architecture(arch)
    check_harness(harness, a)
    run = RunPoint.coerce(point, size)
    _resolve(a, options, run.contract)
    stim = corner_stimulus(run.contract, seed, steps)
    stim.point = run.point
    h, w = run.shape
    harness = choose_harness(harness, a, h * w, steps, options)
    check_code_coverage(code_coverage, harness, sim)
    if harness == "chunk":
        result = check_chunks(StimulusChunks.from_stimulus(stim), sim, work_dir=work_dir,
                              name=f"random{seed}", arch=a, waves=waves,
                              progress=progress, chunk_steps=chunk_steps,
                              code_coverage=code_coverage,
                              **options)
    else:
        result = check_stimulus(stim, sim, waves=waves, work_dir=work_dir,
                                name=f"random{seed}", arch=a, **options)
    result.update(seed=seed, point=run.source, height=h, width=w,
                  coverage=with_lane_coverage(coverage(stim), result))
    return result


def choose_harness(harness: str, arch: str | Architecture, pixels: int, steps: int,
                   options: dict, reloadable: bool = True) -> str:
    """``harness``, with ``"auto"`` resolved: ``"chunk"`` for an architecture with a
    long-run harness (the streaming array) when ``pixels * steps / lanes`` (input beats)
    exceeds :data:`AUTO_CHUNK_BEATS` and the stimulus can be opened again in the
    simulator (``reloadable``), else ``"cycle"``."""
    if harness != "auto":
        return harness
    long_run = get_architecture(arch).long_run_testbench is not None
    lanes = int(options.get("lanes") or 1)
    if long_run and reloadable and pixels * steps // lanes > AUTO_CHUNK_BEATS:
        return "chunk"
    return "cycle"


def check_code_coverage(code_coverage: bool, harness: str, sim: str) -> None:
    """Refuse code coverage outside the long-run harness on Verilator."""
    if code_coverage and (harness != "chunk" or sim != "verilator"):
        raise RvsmError("code coverage is built for Verilator runs in the long-run harness: "
                        "use --sim verilator --harness chunk")


def check_harness(harness: str, arch: str | Architecture) -> None:
    """Refuse (:class:`RvsmError`) an unknown harness, or the long-run one for an
    architecture it does not drive."""
    if harness not in HARNESSES:
        raise RvsmError(f"unknown harness {harness!r}; choose one of {', '.join(HARNESSES)}")
    a = get_architecture(arch)
    if harness == "chunk" and a.long_run_testbench is None:
        names = architectures_with(lambda x: x.long_run_testbench)
        raise RvsmError(f"--harness chunk drives the {', '.join(names)} "
                        f"architecture only; use --harness cycle for --arch {a.name}")


def with_lane_coverage(bins: list[dict], result: dict) -> list[dict]:
    """The stimulus's coverage ``bins`` per scale plus, for a long run, the lanes'
    border bins it measured (``lane_coverage``, the beat stream's ``border_coverage``;
    its spike counts are already among ``bins``)."""
    lanes = result.get("lane_coverage")
    if not lanes:
        return bins
    return [{**b, **{k: v for k, v in extra.items() if k not in b}}
            for b, extra in zip(bins, lanes, strict=True)]


def _coverage(stim: Stimulus) -> list[dict]:
    from rvsm.model.fixed.corner_stimulus import coverage

    return coverage(stim)
