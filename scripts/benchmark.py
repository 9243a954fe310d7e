#!/usr/bin/env python3
"""Throughput of the float samplers at 250x400 on a built-in scene (`make bench`).

Prints pixel-steps/s for FSM and accumulator-steps/s for dog4 (and the other ladders),
with and without noise, beside the naive per-step transcription of the SPEC
(``rvsm.model.reference``) on a short run. Targets (issue 2): FSM >= 3e8 pixel-steps/s,
dog4 >= 1e8 accumulator-steps/s, noiseless. Figures are best-of-``--repeat`` wall time.
"""

from __future__ import annotations

import argparse
import time

from rvsm.model.noise import NoiseParams
from rvsm.model.reference import reference_sample
from rvsm.model.samplers import SamplerConfig, sample
from rvsm.model.scene_library import builtin_scene

TARGETS = {"fsm": 3e8, "dog4": 1e8}


def best_time(fn, repeat: int) -> float:
    """Best wall time of ``repeat`` calls, in seconds."""
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--scene", default="flyball")
    parser.add_argument("--frames", type=int, default=21, help="frames (x10 steps)")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--naive-steps", type=int, default=10)
    args = parser.parse_args()
    scene = builtin_scene(args.scene, num_frames=args.frames)
    h, w = scene.shape
    print(f"scene {scene.name} {h}x{w}, {scene.num_steps} steps; best of {args.repeat}")
    print(f"{'model':8s} {'noise':6s} {'seconds':>8s} {'acc-steps/s':>12s} {'target':>8s}")
    for model in ("fsm", "dog4", "gauss4", "dog1"):
        for noise in (None, NoiseParams()):
            config = SamplerConfig(model=model, noise=noise)
            seconds = best_time(lambda c=config: sample(scene, c), args.repeat)
            rate = scene.num_steps * config.spec.num_scales * h * w / seconds
            target = TARGETS.get(model) if noise is None else None
            verdict = "" if target is None else ("ok" if rate >= target else "MISSED")
            print(f"{model:8s} {'k=1' if noise else 'off':6s} {seconds:8.3f} {rate:12.3g} "
                  f"{verdict:>8s}")
    short = builtin_scene(args.scene, num_frames=2, steps_per_frame=args.naive_steps)
    print(f"\nnaive per-step loop (rvsm.model.reference), {short.num_steps} steps:")
    for model in ("fsm", "dog4"):
        config = SamplerConfig(model=model)
        naive = best_time(lambda c=config: reference_sample(short, c), 1)
        fast = best_time(lambda c=config: sample(short, c), args.repeat)
        rate = short.num_steps * config.spec.num_scales * h * w
        print(f"{model:8s} naive {rate / naive:10.3g}/s   vectorised {rate / fast:10.3g}/s   "
              f"speed-up {naive / fast:5.1f}x")


if __name__ == "__main__":
    main()
