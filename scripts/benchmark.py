#!/usr/bin/env python3
"""Twin throughput and long-run memory at 250x400 (`make bench`, issue 10), in one run.

Rates: accumulator-steps per second (pixels x scales x steps / wall seconds; pixel-steps
for FSM) of the fused numba engine (all numba threads) and, beside each, of the numpy
reference engine, on the built-in scene ``flyball`` (best of ``--repeat``; the numpy
path on fewer steps, ``--numpy-steps``). The fixed twin runs the default design point as
``rvsm simulate --fixed`` does (min/max statistics off). Memory: peak RSS of
``rvsm simulate flyball --size 250x400 --model dog4 --noise`` for ``--long-steps`` steps
(``--frames 401 --steps-per-frame 100`` for 40,000) to an ``.h5`` file, measured as the
child's ``ru_maxrss``. Every figure is printed with the load average at its start; the
targets are issue 10's (the ``dvs`` rows, RVSM-DVS: issue 19's), for a 2-core machine.
``fused/cpu-s`` is the same work per CPU second of all threads: the rate a core delivers,
less sensitive to other jobs' load (on an idle 2-core machine the wall rate approaches
twice it).

``api/s`` is the same work through the public whole-array API with its defaults, as a
user calls it: ``sample(scene, SamplerConfig(model=...))`` and ``simulate_fixed(scene,
DesignPoint(model=...))`` (the spikes collected into one ``(T, S, H, W)`` array; the fixed
twin's min/max statistics off, their default; ``ranges cost`` prints what turning them on
costs); ``api/fused`` is its rate over the fused row's (wall), and
``api/fused cpu`` the same per CPU second. The two are timed alternately in one process
(best of ``--repeat`` each), so load drifts hit both.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.fixed.twin import simulate_fixed, stream_fixed
from rvsm.model.noise.sensor import NoiseParams
from rvsm.model.sampling.config import SamplerConfig
from rvsm.model.sampling.twin import sample, stream_float
from rvsm.model.scene.library import builtin_scene

#: (label, kind, model, noise) -> target acc-steps/s (None: no target)
CASES = [
    ("float fsm", "float", "fsm", False, 2e9),
    ("float fsm", "float", "fsm", True, None),
    ("float dog4", "float", "dog4", False, 1e9),
    ("float dog4", "float", "dog4", True, 2e8),
    ("float gauss4", "float", "gauss4", False, None),
    ("float gauss4", "float", "gauss4", True, None),
    ("fixed dog4", "fixed", "dog4", False, 5e8),
    ("fixed dog4", "fixed", "dog4", True, 1.5e8),
    ("dvs fsm", "dvs", "fsm", False, None),
    ("dvs dog4", "dvs", "dog4", False, 1e9),
    ("dvs dog4", "dvs", "dog4", True, 2e8),
]
RSS_TARGET_BYTES = 1.5e9


class NullSink:
    """Discards spikes (the rates measure the twins, not a file format)."""

    def begin(self, shape, meta):
        pass

    def write(self, t0, spikes):
        pass

    def finish(self, meta):
        pass

    def abort(self):
        pass


def load() -> str:
    """The 1-minute load average, as `uptime` prints it."""
    return f"{os.getloadavg()[0]:.2f}"


def vector_bits() -> str:
    """``512`` when :mod:`rvsm.model` chose 512-bit vectors for numba, else ``default``."""
    wide = os.environ.get("NUMBA_CPU_FEATURES", "").endswith("-prefer-256-bit")
    return "512" if wide else "default"


def best_times(fns, repeat: int) -> list[tuple[float, float]]:
    """Per function of ``fns``: best wall time and best CPU time (all threads) of
    ``repeat`` calls, in seconds; the functions are called in turn, ``repeat`` rounds."""
    best = [[float("inf"), float("inf")] for _ in fns]
    for _ in range(repeat):
        for fn, b in zip(fns, best, strict=True):
            start, cpu = time.perf_counter(), time.process_time()
            fn()
            b[0] = min(b[0], time.perf_counter() - start)
            b[1] = min(b[1], time.process_time() - cpu)
    return [(wall, cpu) for wall, cpu in best]


def best_time(fn, repeat: int) -> tuple[float, float]:
    """Best wall time and best CPU time (all threads) of ``repeat`` calls, in seconds."""
    return best_times([fn], repeat)[0]


def run_case(kind: str, model: str, noise: bool, scene, engine: str):
    if kind == "dvs":  # RVSM-DVS, the event sensor (issue 19's targets)
        from rvsm.model.events.config import EventConfig
        from rvsm.model.events.twin import stream_events

        config = EventConfig(model=model, noise=NoiseParams() if noise else None)
        return (lambda: stream_events(scene, config, NullSink(), engine=engine),
                config.spec.num_scales)
    if kind == "float":
        config = SamplerConfig(model=model, noise=NoiseParams() if noise else None)
        return (lambda: stream_float(scene, config, NullSink(), engine=engine),
                config.spec.num_scales)
    point = DesignPoint(model=model, noise=noise)
    return (lambda: stream_fixed(scene, point, NullSink(), engine=engine, ranges=False),
            point.num_scales)


def api_case(kind: str, model: str, noise: bool, scene):
    """The public whole-array call of the same work, with its defaults (None: no such
    call in this table, the event sensor)."""
    if kind == "float":
        config = SamplerConfig(model=model, noise=NoiseParams() if noise else None)
        return lambda: sample(scene, config)
    if kind == "fixed":
        point = DesignPoint(model=model, noise=noise)
        return lambda: simulate_fixed(scene, point)
    return None


def api_text(fused: tuple[float, float], api: tuple[float, float] | None, rate: float) -> str:
    """The ``api/s``, ``api/fused`` and ``api/fused cpu`` columns from the best ``(wall,
    cpu)`` seconds of the fused and API runs (``-`` without an API row)."""
    if api is None:
        return f"{'-':>10s} {'-':>9s} {'-':>13s}"
    return (f"{rate * fused[0] / api[0]:10.3g} {fused[0] / api[0]:9.2f} "
            f"{fused[1] / api[1]:13.2f}")


def verdict(rate: float, target: float | None) -> str:
    if target is None:
        return "-"
    return "met" if rate >= target else "MISSED"


def print_ranges_cost(scene, repeat: int) -> None:
    """The cost of the fixed twin's min/max datapath statistics (``ranges=True``, off by
    default): fixed dog4 noise off with and without them, alternated, best of ``repeat``."""
    point = DesignPoint(model="dog4")
    runs = [lambda r=r: stream_fixed(scene, point, NullSink(), ranges=r) for r in (False, True)]
    ld = load()
    (off, _), (on, _) = best_times(runs, repeat)
    print(f"\nranges cost: fixed dog4 off with ranges=True {on:.3f} s against {off:.3f} s "
          f"without: {on / off:.2f}x the time (load {ld})")


def peak_rss(steps: int, out_dir: Path) -> tuple[float, float, str]:
    """``(peak RSS bytes, wall seconds, command)`` of the long dog4 run."""
    spf = 100
    frames = steps // spf + 1
    out = out_dir / "long.h5"
    cmd = [sys.executable, "-m", "rvsm.sim.cli.main", "simulate", "flyball", "--size", "250x400",
           "--model", "dog4", "--noise", "--frames", str(frames), "--steps-per-frame",
           str(spf), "-o", str(out)]
    start = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        raise SystemExit(f"long run failed: {proc.stderr.strip()[-500:]}")
    rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * 1024.0
    size = out.stat().st_size
    shown = "rvsm simulate " + " ".join(cmd[4:-2]) + " -o long.h5"
    return rss, wall, f"{shown}  ({size / 1e6:.0f} MB file)"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=1000, help="steps per fused run")
    parser.add_argument("--numpy-steps", type=int, default=60, help="steps per numpy run")
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--long-steps", type=int, default=40000,
                        help="steps of the peak-RSS run (0 to skip)")
    parser.add_argument("--only", default="", metavar="TEXT",
                        help="run only the cases whose label contains TEXT (e.g. dvs)")
    args = parser.parse_args()
    import numba  # after rvsm.model, which chooses the vector width before numba loads

    m = 10
    scene = builtin_scene("flyball", num_frames=args.steps // m + 1, steps_per_frame=m)
    short = builtin_scene("flyball", num_frames=args.numpy_steps // m + 1, steps_per_frame=m)
    h, w = scene.shape
    print(f"flyball {h}x{w}; fused: {scene.num_steps} steps, numba threads "
          f"{numba.get_num_threads()}; numpy: {short.num_steps} steps; best of {args.repeat}; "
          f"{os.cpu_count()} CPUs; {vector_bits()}-bit vectors; "
          "load = 1-min load average at the start of each row")
    head = (f"{'twin':13s} {'noise':5s} {'fused/s':>10s} {'numpy/s':>10s} {'speed-up':>8s} "
            f"{'target':>8s} {'met':>6s} {'load':>5s} {'fused/cpu-s':>11s} {'api/s':>10s} "
            f"{'api/fused':>9s} {'api/fused cpu':>13s}")
    print(head)
    print("-" * len(head))
    for label, kind, model, noise, target in CASES:
        if args.only not in label:
            continue
        ld = load()
        fused, scales = run_case(kind, model, noise, scene, "fused")
        api = api_case(kind, model, noise, scene)
        fused()  # compile / warm the caches
        api_times = None
        if api is not None:
            api()
            (t_fused, cpu_fused), api_times = best_times([fused, api], args.repeat)
        else:
            t_fused, cpu_fused = best_time(fused, args.repeat)
        rate = scene.num_steps * scales * h * w / t_fused
        cpu_rate = scene.num_steps * scales * h * w / cpu_fused
        ref, _ = run_case(kind, model, noise, short, "numpy")
        t_ref, _ = best_time(ref, 1 if args.repeat < 3 else 2)
        ref_rate = short.num_steps * scales * h * w / t_ref
        tgt = f"{target:.1e}" if target else "-"
        print(f"{label:13s} {'on' if noise else 'off':5s} {rate:10.3g} {ref_rate:10.3g} "
              f"{rate / ref_rate:7.1f}x {tgt:>8s} {verdict(rate, target):>6s} {ld:>5s} "
              f"{cpu_rate:11.3g} {api_text((t_fused, cpu_fused), api_times, rate)}",
              flush=True)
    if args.only in "fixed dog4":  # the ranges line goes with the fixed dog4 rows
        print_ranges_cost(scene, args.repeat)
    if args.long_steps:
        ld = load()
        with tempfile.TemporaryDirectory() as tmp:
            rss, wall, cmd = peak_rss(args.long_steps, Path(tmp))
        ok = "met" if rss <= RSS_TARGET_BYTES else "MISSED"
        print(f"\npeak RSS {rss / 1e9:.2f} GB (target <= 1.5 GB: {ok}), {wall:.0f} s wall, "
              f"load {ld}: {cmd}")


if __name__ == "__main__":
    main()
