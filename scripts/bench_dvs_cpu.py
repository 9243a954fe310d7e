#!/usr/bin/env python3
"""CPU time of the fused RVSM-DVS engine on one thread: ns per pixel and step.

A figure that a loaded machine does not distort much (CPU time of one thread, best of
``--repeat``; the wall rates of ``scripts/benchmark.py --only dvs`` need a quiet machine).
Runs ``FusedEventSampler`` alone (no sink) on the built-in ``flyball`` at 250x400 for
``--steps`` steps, noise off and on, and prints ns per pixel-step and what that is as
accumulator-steps per second of one core (``S / ns``). Two cores at the same CPU time
per pixel give twice the rate (``docs/events.md``, section "Speed").

    .venv/bin/python scripts/bench_dvs_cpu.py --model dog4 --steps 200 --repeat 5
"""

from __future__ import annotations

import argparse
import os
import time

from rvsm.model.events.config import EventConfig, contrast_thresholds
from rvsm.model.events.fused import FusedEventSampler
from rvsm.model.noise.sensor import NoiseParams
from rvsm.model.scene.library import builtin_scene


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--model", default="dog4")
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    import numba  # after rvsm.model, which chooses the vector width before numba loads

    numba.set_num_threads(1)
    wide = os.environ.get("NUMBA_CPU_FEATURES", "").endswith("-prefer-256-bit")
    print(f"fused RVSM-DVS {args.model}, flyball 250x400, {args.steps} steps, one thread, "
          f"best of {args.repeat}; {'512' if wide else 'default'}-bit vectors; "
          f"load {os.getloadavg()[0]:.2f}")
    for noise in (False, True):
        scene = builtin_scene("flyball", num_frames=args.steps // 10 + 1, steps_per_frame=10)
        cfg = EventConfig(model=args.model, noise=NoiseParams() if noise else None)
        thr = contrast_thresholds(cfg, scene.shape)
        best = float("inf")
        for i in range(args.repeat + 1):  # the first run compiles or loads the kernels
            sampler = FusedEventSampler(scene, cfg, thr)
            start = time.process_time()
            sampler.run(0, scene.num_steps)
            if i:
                best = min(best, time.process_time() - start)
        ns = best / (scene.num_steps * scene.shape[0] * scene.shape[1]) * 1e9
        scales = cfg.spec.num_scales
        print(f"noise {'on ' if noise else 'off'}: {ns:6.2f} CPU ns per pixel-step = "
              f"{scales / ns * 1e9:.3g} accumulator-steps per CPU second", flush=True)


if __name__ == "__main__":
    main()
