"""RTL-versus-fixed-twin verification: the functions behind ``rvsm verify``.

Everything goes through one stimulus file format (:mod:`rvsm.model.fixed.stimulus`):
:func:`check_stimulus` writes a :class:`Stimulus` into its run folder, builds (cached)
and simulates the Verilog with the cocotb testbench, and returns the testbench's
comparison. On a mismatch without ``waves`` it re-runs the stimulus up to the first
failing step with waves on, so a waveform is always kept. The entry points build the
stimulus three ways: :func:`run_rtl` from a contract, codes and thresholds (the
expectation from :meth:`ArrayContract.run`); :func:`verify` from a scene and a design
point (a :class:`~.run_point.RunPoint`, read once by the command) via the fixed twin;
:func:`replay` from a stimulus file (``rvsm stimulus``). The last three share one
parameter object, :class:`~.run_settings.RunSettings` (simulator, waves, work folder,
architecture and options, harness), given by keyword. The architecture is a value of the
registry; whether it has a long-run harness is its capability
(:attr:`~rvsm.rtl.capabilities.Architecture.long_run_testbench`).
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.stimulus import Stimulus, open_stimulus, save_stimulus
from rvsm.model.fixed.stimulus_chunks import StimulusChunks
from rvsm.model.fixed.widths import unsigned_max
from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.scene import Scene
from rvsm.rtl.architectures.registry import DEFAULT_ARCHITECTURE, get_architecture
from rvsm.rtl.capabilities import Architecture
from rvsm.sim.cosim.builds.build_cache import SimBuild, build, new_run_dir
from rvsm.sim.cosim.builds.testbench_run import run_testbench
from rvsm.sim.cosim.run_point import RunPoint
from rvsm.sim.cosim.run_settings import (
    AUTO_CHUNK_BEATS,
    DEFAULT_WORK,
    HARNESSES,
    RunSettings,
    check_code_coverage,
    check_harness,
    choose_harness,
)

__all__ = ["AUTO_CHUNK_BEATS", "DEFAULT_WORK", "HARNESSES", "RunSettings",
           "check_code_coverage", "check_harness", "check_stimulus", "choose_harness",
           "random_verify", "replay", "run_rtl", "verify"]


def _check_inputs(contract: ArrayContract, codes: np.ndarray, thresholds: np.ndarray) -> None:
    c = contract
    if codes.ndim != 3 or codes.shape[1:] != (c.height, c.width):
        raise RvsmError(f"codes must be (T, {c.height}, {c.width}), got {codes.shape}")
    if codes.min() < 0 or codes.max() > unsigned_max(c.adc_bits):
        raise RvsmError(f"ADC codes must lie in 0..{unsigned_max(c.adc_bits)}")
    if thresholds.shape != (c.num_scales, c.height, c.width):
        raise RvsmError(f"thresholds must be ({c.num_scales}, {c.height}, {c.width}), "
                        f"got {thresholds.shape}")


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
    resolved = RunSettings(arch=a, options=options).resolve(contract)
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


def _per_cycle(s: RunSettings, stim: Stimulus, name: str) -> dict:
    """:func:`check_stimulus` of ``stim`` with the settings ``s`` (per-cycle testbench)."""
    return check_stimulus(stim, s.sim, waves=s.waves, work_dir=s.work_dir, name=name,
                          arch=s.arch, **s.options)


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


def replay(stimulus: str | os.PathLike, sim: str = "icarus", steps: int | None = None,
           recompute_expected: bool = False, **settings: Any) -> dict:
    """Replay a stimulus file (``rvsm stimulus -o FILE``) on the RTL, spike for spike.

    ``settings``: :class:`~.run_settings.RunSettings` by keyword (``waves``, ``work_dir``,
    ``arch``, ``harness``...; the rest architecture options). ``steps`` keeps the first
    steps. The file is checked before the RTL is blamed: when its expected spikes do not
    follow from its own codes, thresholds and contract (a hand-edited or damaged file) it
    is a bad stimulus (:class:`RvsmError`, exit 2, naming the first inconsistent step and
    accumulator), unless ``recompute_expected`` takes the expectation from its codes
    instead. Returns :func:`check_stimulus`'s result plus ``stimulus``, ``height``,
    ``width`` and ``expectation`` (``"file"`` or ``"recomputed"``).
    """
    s = RunSettings.of(sim, **settings)
    stim = open_stimulus(stimulus)  # codes and spikes read a range of steps at a time
    c = stim.contract
    s.resolve(c)
    if steps is not None and steps > stim.num_steps:
        raise RvsmError(f"--steps {steps}: {stimulus} holds {stim.num_steps} steps; ask for "
                        f"at most {stim.num_steps}")
    if steps is not None and steps < stim.num_steps:
        stim = stim.first_steps(steps)
    harness = s.choose(c.height * c.width, stim.num_steps)
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
        result = s.check_chunks(StimulusChunks.from_stimulus(
            stim, str(Path(stimulus).resolve()), recompute=recompute_expected), name)
    else:
        result = _per_cycle(s, stim, name)
    result.update(stimulus=str(stimulus), height=c.height, width=c.width,
                  coverage=with_lane_coverage(_coverage(stim), result),
                  expectation="recomputed" if recompute_expected else "file")
    return result


def _settings_and_point(sim: str, point: RunPoint | str | os.PathLike,
                        size: tuple[int, int] | None, settings: dict[str, Any]
                        ) -> tuple[RunSettings, RunPoint]:
    """What :func:`verify` and :func:`random_verify` start from: the run settings
    resolved against the design point (read once, at ``size`` if given)."""
    s = RunSettings.of(sim, **settings)
    run = RunPoint.coerce(point, size)
    s.resolve(run.contract)
    return s, run


def verify(scene: str | Scene, point: RunPoint | str | os.PathLike, sim: str = "icarus",
           steps: int | None = None, size: tuple[int, int] | None = None,
           **settings: Any) -> dict:
    """Verify the RTL of design ``point`` on ``scene``, spike for spike.

    ``point`` is a :class:`~.run_point.RunPoint` (a command reads its TOML once) or the
    TOML path; ``settings``: :class:`~.run_settings.RunSettings` by keyword (``arch`` and
    its options, ``harness``, ``waves``, ``work_dir``...; the streaming array takes any
    array size).

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

    s, run = _settings_and_point(sim, point, size, settings)
    h, w = run.shape
    if not isinstance(scene, Scene):
        scene = load_scene(scene, size=(h, w))
    harness = s.choose(h * w, scene.num_steps if steps is None else steps,
                       reloadable=scene.source is not None)
    name = scene.name or "scene"
    if harness == "chunk":
        if steps is not None and steps > scene.num_steps:
            raise RvsmError(f"--steps {steps} is more than the {scene.num_steps} steps of "
                            f"scene {scene.name!r}; ask for at most {scene.num_steps}")
        result = s.check_chunks(StimulusChunks.from_scene(scene, run.point, steps), name)
        coverage = result.get("lane_coverage")
    else:
        stim = make_stimulus(scene, run.point, num_steps=steps)
        result = _per_cycle(s, stim, name)
        coverage = _coverage(stim)
    result.update(scene=scene.source or scene.name, point=run.source, height=h, width=w,
                  coverage=coverage)
    return result


def random_verify(point: RunPoint | str | os.PathLike, seed: int, steps: int,
                  sim: str = "icarus", size: tuple[int, int] | None = None,
                  **settings: Any) -> dict:
    """Verify the RTL of design ``point`` (as :func:`verify`, ``settings`` the same) on
    a seeded random and corner stimulus
    (:func:`~rvsm.model.fixed.corner_stimulus.corner_stimulus`, ``steps`` steps).

    Returns :func:`check_stimulus`'s result plus ``seed``, ``point``, ``height``,
    ``width`` and ``coverage`` (per scale, accumulator-steps per bin).
    """
    from rvsm.model.fixed.corner_stimulus import corner_stimulus, coverage

    s, run = _settings_and_point(sim, point, size, settings)
    stim = corner_stimulus(run.contract, seed, steps)
    stim.point = run.point
    h, w = run.shape
    if s.choose(h * w, steps) == "chunk":
        result = s.check_chunks(StimulusChunks.from_stimulus(stim), f"random{seed}")
    else:
        result = _per_cycle(s, stim, f"random{seed}")
    result.update(seed=seed, point=run.source, height=h, width=w,
                  coverage=with_lane_coverage(coverage(stim), result))
    return result


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
