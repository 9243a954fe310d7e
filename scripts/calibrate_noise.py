"""Reproduce the ``paper`` noise preset: calibrate ``k`` on FSM against Table 1.

Usage: ``.venv/bin/python scripts/calibrate_noise.py [--size 250x400] [--frames 41]
[--steps-per-frame 10] [--seed 0] [-o docs/reproduction/noise-calibration.json]``.
Prints ``D(k)`` for every evaluated ``k`` and the chosen ``k``; the rule is in
:mod:`rvsm.sim.studies.noise_calibration`. Defaults are those of ``rvsm table``.
"""

from __future__ import annotations

import argparse
import json
import time

from rvsm.model.infra.atomic import write_text_atomic
from rvsm.sim.cli.studies import TABLE_FRAMES, TABLE_STEPS_PER_FRAME, scored_size
from rvsm.sim.studies.noise_calibration import (
    DEFAULT_GRID,
    DEFAULT_REFINE,
    calibrate_k,
    fsm_ssim,
    fsm_ssim_drop,
    paper_fsm_ssim_drop,
)
from rvsm.sim.studies.table import load_scenes


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--size", default="250x400")
    ap.add_argument("--frames", type=int, default=TABLE_FRAMES)
    ap.add_argument("--steps-per-frame", type=int, default=TABLE_STEPS_PER_FRAME)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("-o", "--output", default=None, help="write the evaluations as JSON")
    args = ap.parse_args()
    start = time.perf_counter()
    scenes = load_scenes(None, scored_size(args.size), args.frames, args.steps_per_frame)
    clean = [fsm_ssim(s, None) for s in scenes]
    target = paper_fsm_ssim_drop()
    print(f"target D* = {target:.4f}; FSM clean SSIM " +
          ", ".join(f"{s.name} {c:.4f}" for s, c in zip(scenes, clean, strict=True)))

    def drop(k: float) -> float:
        d = fsm_ssim_drop(scenes, k, seed=args.seed, clean=clean)
        print(f"k = {k:g}: D = {d:.4f} ({time.perf_counter() - start:.0f} s)", flush=True)
        return d

    k, drops = calibrate_k(drop, target, DEFAULT_GRID, DEFAULT_REFINE)
    print(f"chosen k = {k:g} (D = {drops[k]:.4f}, target {target:.4f})")
    if args.output:
        write_text_atomic(args.output, json.dumps({
            "target": target, "k": k, "drops": {f"{kk:g}": v for kk, v in drops.items()},
            "clean_ssim": {s.name: c for s, c in zip(scenes, clean, strict=True)},
            "size": args.size, "frames": args.frames,
            "steps_per_frame": args.steps_per_frame, "seed": args.seed,
        }, indent=1) + "\n")


if __name__ == "__main__":
    main()
