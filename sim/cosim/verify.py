"""RTL-versus-fixed-twin verification: the function behind ``rvsm verify``.

:func:`run_rtl` is the core: given a contract, per-step ADC codes and thresholds, it
computes the expectation with :meth:`ArrayContract.run` (the bit-accurate model beside
the RTL), writes a stimulus ``.npz``, builds (cached) and simulates the Verilog, and
returns the testbench's comparison. On a mismatch without ``waves`` it re-runs the
stimulus up to the first failing step with waves on, so a waveform is always kept.
:func:`verify` does the same for a scene and a design-point TOML via the fixed twin's
stimulus (:func:`rvsm.model.fixed.stimulus.make_stimulus`).
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from rvsm.model.errors import RvsmError
from rvsm.model.fixed.core import ArrayContract

from .runner import build, check_simulator, run_testbench

__all__ = ["MAX_PARALLEL_SIDE", "expected_spikes", "run_rtl", "verify", "write_stimulus"]

#: Largest side of a fully parallel array ``verify`` will build (generation time grows
#: with pixels x taps; a full-resolution sensor needs the streaming array).
MAX_PARALLEL_SIDE = 64
DEFAULT_WORK = Path("build") / "verify"


def expected_spikes(
    contract: ArrayContract, codes: np.ndarray, thresholds: np.ndarray,
    clear_before: Sequence[int] = (),
) -> np.ndarray:
    """``contract.run`` per segment, restarting from zero at every ``clear_before`` step."""
    cuts = sorted({int(t) for t in clear_before if 0 < int(t) < len(codes)})
    bounds = [0, *cuts, len(codes)]
    parts = [contract.run(codes[a:b], thresholds) for a, b in zip(bounds, bounds[1:],
                                                                    strict=False)]
    return np.concatenate(parts, axis=0)


def write_stimulus(
    path: str | os.PathLike, contract: ArrayContract, codes: np.ndarray,
    thresholds: np.ndarray, expected: np.ndarray, clear_before: Sequence[int] = (),
) -> Path:
    """Write the testbench's ``.npz`` (codes, thresholds, expected, clear_before)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez(path, codes=np.asarray(codes, dtype=np.int64),
             thresholds=np.asarray(thresholds, dtype=np.int64),
             expected=np.asarray(expected, dtype=np.int8),
             clear_before=np.asarray(sorted(clear_before), dtype=np.int64),
             adc_bits=np.int64(contract.adc_bits))
    return path


def _check_inputs(contract: ArrayContract, codes: np.ndarray, thresholds: np.ndarray) -> None:
    c = contract
    if codes.ndim != 3 or codes.shape[1:] != (c.height, c.width):
        raise RvsmError(f"codes must be (T, {c.height}, {c.width}), got {codes.shape}")
    if codes.min() < 0 or codes.max() >= (1 << c.adc_bits):
        raise RvsmError(f"ADC codes must lie in 0..{(1 << c.adc_bits) - 1}")
    if thresholds.shape != (c.num_scales, c.height, c.width):
        raise RvsmError(f"thresholds must be ({c.num_scales}, {c.height}, {c.width}), "
                        f"got {thresholds.shape}")


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
) -> dict:
    """Simulate the RTL on ``codes``/``thresholds`` and compare with the expectation.

    ``expected`` defaults to :func:`expected_spikes` (pass one to test the checker).
    Returns the testbench result: ``compared``, ``mismatches``, ``first_mismatch``,
    ``simulator``, ``waves`` (path or None), ``build_seconds``, ``stream_seconds``...
    """
    codes = np.asarray(codes, dtype=np.int64)
    thresholds = np.asarray(thresholds, dtype=np.int64)
    _check_inputs(contract, codes, thresholds)
    if expected is None:
        expected = expected_spikes(contract, codes, thresholds, clear_before)
    work = Path(work_dir)
    root = work / "builds" if build_root is None else Path(build_root)
    sb = build(contract, sim, root, waves=waves)
    run_dir = work / sim / name
    stim = write_stimulus(run_dir / "stimulus.npz", contract, codes, thresholds, expected,
                          clear_before)
    result = run_testbench(sb, stim, run_dir, waves=waves)
    if result["mismatches"] and not result["waves"]:
        first = result["first_mismatch"] or {}
        upto = min(len(codes), int(first.get("step", len(codes) - 1)) + 1)
        again_dir = run_dir / "failure"
        stim2 = write_stimulus(again_dir / "stimulus.npz", contract, codes[:upto],
                               thresholds, expected[:upto],
                               [t for t in clear_before if t < upto])
        sbw = build(contract, sim, root, waves=True)
        result["waves"] = run_testbench(sbw, stim2, again_dir, waves=True)["waves"]
    result.update(
        build_seconds=sb.build_seconds, generate_seconds=sb.generate_seconds,
        build_cached=sb.cached, verilog=str(sb.verilog), run_dir=str(run_dir),
    )
    return result


def verify(
    scene: str,
    fixed: str | os.PathLike,
    sim: str = "icarus",
    steps: int | None = None,
    waves: bool = False,
    size: tuple[int, int] | None = None,
    work_dir: str | os.PathLike = DEFAULT_WORK,
) -> dict:
    """Verify the RTL of design point ``fixed`` (TOML) on ``scene``, spike for spike.

    ``size = (H, W)`` overrides the point's array size (the scene is rendered or cropped
    to it); ``steps`` keeps the first steps. Returns :func:`run_rtl`'s result plus
    ``scene`` and ``point``. Raises :class:`RvsmError` on user errors (not on
    mismatches: check ``result["mismatches"]``).
    """
    from rvsm.model.fixed.config import load_design_point
    from rvsm.model.fixed.stimulus import make_stimulus
    from rvsm.model.scene_io import load_scene

    check_simulator(sim)
    point = load_design_point(fixed)
    if size is not None:
        point = point.with_size(*size)
    h, w = point.height, point.width
    if max(h, w) > MAX_PARALLEL_SIDE:
        raise RvsmError(
            f"the fully parallel RTL array is limited to {MAX_PARALLEL_SIDE}x"
            f"{MAX_PARALLEL_SIDE} pixels, the design point is {h}x{w}; pass --size, "
            "e.g. --size 16x16")
    stim = make_stimulus(load_scene(scene, size=(h, w)), point, num_steps=steps)
    result = run_rtl(stim.contract, stim.codes, stim.thresholds, sim,
                     expected=stim.spikes, waves=waves, work_dir=work_dir,
                     name=Path(str(scene)).stem or "scene")
    result.update(scene=str(scene), point=str(fixed), height=h, width=w)
    return result
