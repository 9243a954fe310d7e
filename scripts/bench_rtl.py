#!/usr/bin/env python3
"""Co-simulation throughput and memory (`make bench-rtl`, issue 17): every figure with
the command that produced it, against its target.

Each case runs the CLI in a fresh work folder (so the Verilog generation and the
simulator build are included where a target says so) as a child of a small wrapper that
reports the peak resident memory of the largest process it waited for (the simulator,
which runs cocotb and the twin). Cases:

* ``full-1k``: 250x400 dog4 default point, P=40, Verilator, 1,000 steps, long-run
  harness: wall time including generation and build (target <= 5 min), sustained
  cycles/s of the run (target >= 40,000);
* ``medium``: 64x96 dog4, P=8, Verilator, 2,000 steps (target >= 150,000 cycles/s);
* ``icarus``: 64x64 dog4, P=4, Icarus, 200 steps (target >= 5,000 cycles/s), also the
  simulator's share (cycles over the seconds the testbench waited for it) and the same
  run replayed by plain ``vvp`` without cocotb (``scripts/bench_icarus_plain.py``): the
  harness's Icarus build simulates a yosys-rewritten netlist and makes its own clock
  (``sim/cosim/builds/icarus_netlist.py``, ``chunk_harness.py``; docs/long-runs.md);
* ``one-second`` (unless ``--quick``): 250x400, P=40, Verilator, 40,000 steps of a
  4,001-frame scene: wall time including build (target <= 60 min), peak RSS (<= 4 GB);
* ``simulate`` (unless ``--quick``): ``rvsm simulate`` of that scene to ``.h5``: peak
  RSS (target <= 1.5 GB);
* ``stimulus`` (unless ``--quick``): ``rvsm stimulus`` of 4,000 steps of 250x400 (the
  default point) to a file, written a chunk at a time: peak RSS (target <= 1 GB), wall
  time and file size; then ``rvsm verify --stimulus`` of its first 200 steps in the
  long-run harness (P=40, Verilator, build included), reading the file a chunk at a
  time: peak RSS (target <= 1.5 GB);
* ``regress``: ``rvsm regress`` of 64 random seeds (16x16 dog4, P=4, Verilator, 200
  steps) on 1 and then 2 local Dask workers, builds cached first: the speed-up (target
  >= 1.7x);
* ``verilog``: ``rvsm verilog point.toml --lanes 40`` (250x400 dog4, the default point),
  three runs: the fastest wall time and the CPU time (user + system, the bundled yosys
  included) of each (target <= 15 s on a quiet machine; on a loaded one the CPU time is
  the figure to compare).

The exit status is 0 when every case ran (targets missed are printed, not failed: a
benchmark reports, it does not judge) and 3 when a case failed to run.
"""

from __future__ import annotations

import argparse
import json
import shlex
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RVSM = str(Path(sys.executable).with_name("rvsm"))
_WRAP = ("import resource, subprocess, sys; r = subprocess.run(sys.argv[1:]); "
         "u = resource.getrusage(resource.RUSAGE_CHILDREN); "
         "print(u.ru_maxrss, u.ru_utime + u.ru_stime, file=sys.stderr); "
         "sys.exit(r.returncode)")


def run_cpu(argv: list[str], cwd: Path) -> tuple[float, int, str, float]:
    """Run ``argv`` in ``cwd``; wall seconds, peak RSS (kB) of its largest process, stdout,
    CPU seconds (user + system) of it and every process it waited for."""
    t0 = time.perf_counter()
    p = subprocess.run([sys.executable, "-c", _WRAP, *argv], cwd=cwd, capture_output=True,
                       text=True)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        tail = (p.stderr or p.stdout).strip().splitlines()[-3:]
        raise SystemExit(f"bench-rtl: {shlex.join(argv)} failed ({p.returncode}): "
                         + " | ".join(tail))
    rss, cpu = p.stderr.strip().splitlines()[-1].split()
    return wall, int(rss), p.stdout, float(cpu)


def run(argv: list[str], cwd: Path) -> tuple[float, int, str]:
    """Run ``argv`` in ``cwd``; wall seconds, peak RSS (kB) of its largest process, stdout."""
    wall, rss, out, _ = run_cpu(argv, cwd)
    return wall, rss, out


def verify_case(tmp: Path, name: str, size: str, lanes: int, sim: str, steps: int,
                frames: int, steps_per_frame: int = 10) -> dict:
    work = tmp / name
    argv = [RVSM, "verify", "flyball", "--fixed", str(tmp / "point.toml"), "--size", size,
            "--lanes", str(lanes), "--sim", sim, "--harness", "chunk", "--steps",
            str(steps), "--frames", str(frames), "--steps-per-frame", str(steps_per_frame),
            "--work", str(work), "--json"]
    wall, rss, out = run(argv, tmp)
    r = json.loads(out)
    if r["mismatches"]:
        raise SystemExit(f"bench-rtl: {name}: {r['mismatches']} mismatches")
    shown = [a if a != str(tmp / "point.toml") else "point.toml" for a in argv]
    shown = [a if not a.startswith(str(tmp)) else Path(a).name for a in shown]
    return {"case": name, "command": "rvsm " + shlex.join(shown[1:]), "wall": wall,
            "rss_mb": rss / 1024, "cycles_per_second": r["cycles_per_second"],
            "build": r["build_seconds"], "generate": r["generate_seconds"],
            "stream": r["stream_seconds"], "seconds": r["seconds"], "steps": r["steps"],
            "compared": r["compared"], "cycles": r["cycles"],
            "timeline": r.get("timeline")}


def plain_vvp(tmp: Path, size: str, steps: int, frames: int) -> dict:
    """The Icarus case replayed by plain ``vvp`` on its build (scripts/bench_icarus_plain.py)."""
    from rvsm.model.fixed.point_toml import load_design_point
    from rvsm.model.fixed.stimulus_chunks import StimulusChunks
    from rvsm.model.scene.loaders import load_scene

    h, w = (int(v) for v in size.split("x"))
    point = load_design_point(tmp / "point.toml").with_size(h, w)
    scene = load_scene("flyball", size=(h, w), num_frames=frames, steps_per_frame=10)
    spec = json.dumps(StimulusChunks.from_scene(scene, point, steps).spec)
    build_dir = next((tmp / "icarus" / "builds").glob("icarus-*"))
    p = subprocess.run([sys.executable, str(ROOT / "scripts" / "bench_icarus_plain.py"),
                        str(build_dir), spec, "--work", str(tmp / "plain-vvp")],
                       capture_output=True, text=True)
    if p.returncode != 0:
        raise SystemExit(f"bench-rtl: plain vvp failed: {p.stderr.strip()[-300:]}")
    return json.loads(p.stdout.strip().splitlines()[-1])


REGRESS_PLAN = """
[regression]
name = "bench"
[run]
models = ["dog4"]
size = "16x16"
lanes = [4]
simulators = ["verilator"]
harness = "chunk"
steps = 200
seeds = { start = 0, stop = 64 }
"""


def regress_case(tmp: Path) -> tuple[str, str, str, str]:
    """64 seeds on 1 then 2 workers (the build made once before, by a one-seed plan)."""
    plan = tmp / "bench.toml"
    plan.write_text(REGRESS_PLAN)
    warm = tmp / "warm.toml"
    warm.write_text(REGRESS_PLAN.replace("stop = 64", "stop = 1"))
    work = tmp / "regress-work"
    run([RVSM, "regress", str(warm), "-o", str(tmp / "warm.sqlite"), "--workers", "0",
         "--no-progress", "--work", str(work)], tmp)
    walls = {}
    for workers in (1, 2):
        walls[workers], _, _ = run([RVSM, "regress", str(plan), "-o",
                                    str(tmp / f"r{workers}.sqlite"), "--workers",
                                    str(workers), "--no-progress", "--work", str(work)], tmp)
        print(f"regress: rvsm regress bench.toml --workers {workers}  (64 seeds, 16x16 dog4 "
              f"P=4, Verilator, 200 steps)\n  wall {walls[workers]:.0f} s", flush=True)
    speedup = walls[1] / walls[2]
    return ("rvsm regress 64 seeds, 2 workers vs 1", f"{speedup:.2f}x", ">= 1.7x",
            "met" if speedup >= 1.7 else "MISSED")


def stimulus_case(tmp: Path) -> list[tuple[str, str, str, str]]:
    """``rvsm stimulus`` of 4,000 full-sensor steps, then a 200-step replay of the file."""
    stim = tmp / "stim.npz"
    argv = [RVSM, "stimulus", "flyball", "--fixed", str(tmp / "point.toml"), "--size",
            "250x400", "--frames", "401", "--steps", "4000", "-o", str(stim)]
    wall, rss, _ = run(argv, tmp)
    size = stim.stat().st_size
    print(f"stimulus: rvsm stimulus flyball --fixed point.toml --size 250x400 --frames 401 "
          f"--steps 4000 -o stim.npz\n  wall {wall:.0f} s; peak RSS {rss / 1024:,.0f} MB; "
          f"file {size / 1e6:,.0f} MB", flush=True)
    replay = [RVSM, "verify", "--stimulus", str(stim), "--harness", "chunk", "--sim",
              "verilator", "--arch", "stream", "--lanes", "40", "--steps", "200", "--json",
              "--work", str(tmp / "stimulus-work")]
    r_wall, r_rss, out = run(replay, tmp)
    r = json.loads(out)
    if r["mismatches"]:
        raise SystemExit(f"bench-rtl: stimulus replay: {r['mismatches']} mismatches")
    print(f"  rvsm verify --stimulus stim.npz --harness chunk --sim verilator --arch stream "
          f"--lanes 40 --steps 200\n  wall {r_wall:.0f} s (build {r['build_seconds']:.0f} "
          f"s); peak RSS {r_rss / 1024:,.0f} MB; 0 mismatches", flush=True)
    stim.unlink()
    gb, r_gb = rss / 1024 ** 2, r_rss / 1024 ** 2
    return [("rvsm stimulus 4,000 steps 250x400", f"{gb:.2f} GB", "<= 1 GB",
             "met" if gb <= 1 else "MISSED"),
            ("  its replay, 200 steps (chunk)", f"{r_gb:.2f} GB", "<= 1.5 GB",
             "met" if r_gb <= 1.5 else "MISSED")]


def verilog_case(tmp: Path, runs: int = 3) -> tuple[str, str, str, str]:
    """``rvsm verilog`` of the full sensor at P=40, ``runs`` times: wall and CPU seconds."""
    argv = [RVSM, "verilog", str(tmp / "point.toml"), "--lanes", "40", "-o",
            str(tmp / "verilog")]
    times = [run_cpu(argv, tmp) for _ in range(runs)]
    size = (tmp / "verilog" / "rvsm_stream_array.v").stat().st_size
    print("verilog: rvsm verilog point.toml --lanes 40 -o verilog  (250x400 dog4)\n  "
          + "; ".join(f"wall {w:.1f} s, CPU {c:.1f} s" for w, _, _, c in times)
          + f"; peak RSS {max(r for _, r, _, _ in times) / 1024:,.0f} MB; "
          f"rvsm_stream_array.v {size / 1e6:.2f} MB", flush=True)
    wall = min(w for w, _, _, _ in times)
    cpu = min(c for _, _, _, c in times)
    return ("rvsm verilog 250x400 P=40 (wall / CPU)", f"{wall:.1f} s / {cpu:.1f} s",
            "<= 15 s", "met" if wall <= 15 else "MISSED")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true",
                        help="leave out the one-second run and the simulate memory case")
    parser.add_argument("--keep", action="store_true", help="keep the work folders")
    parser.add_argument("--only", nargs="+", metavar="CASE",
                        help="run only these cases: full-1k medium icarus one-second "
                        "simulate stimulus regress verilog")
    args = parser.parse_args()
    tmp = Path(tempfile.mkdtemp(prefix="rvsm-bench-rtl-"))
    rows: list[tuple[str, str, str, str]] = []
    try:
        subprocess.run([RVSM, "config", "new", "-o", str(tmp / "point.toml")], check=True,
                       capture_output=True)
        cases = [("full-1k", "250x400", 40, "verilator", 1000, 101),
                 ("medium", "64x96", 8, "verilator", 2000, 201),
                 ("icarus", "64x64", 4, "icarus", 200, 21)]
        if not args.quick:
            cases.append(("one-second", "250x400", 40, "verilator", 40000, 4001))
        cases = [c for c in cases if not args.only or c[0] in args.only]
        for name, size, lanes, sim, steps, frames in cases:
            r = verify_case(tmp, name, size, lanes, sim, steps, frames)
            print(f"{name}: {r['command']}", flush=True)
            phases = ", ".join(f"{k} {v:.1f} s" for k, v in r["seconds"].items())
            print(f"  wall {r['wall']:.0f} s (generate {r['generate']:.0f} s, build "
                  f"{r['build']:.0f} s, stream {r['stream']:.0f} s: {phases}); "
                  f"{r['cycles_per_second']:,.0f} cycles/s; peak RSS {r['rss_mb']:,.0f} MB; "
                  f"{r['compared']:,} spikes, 0 mismatches", flush=True)
            cps = r["cycles_per_second"]
            if name == "full-1k":
                rows += [("250x400 P=40 Verilator sustained", f"{cps:,.0f} cycles/s",
                          ">= 40,000", "met" if cps >= 40000 else "MISSED"),
                         ("250x400, 1,000 steps incl. build", f"{r['wall'] / 60:.1f} min",
                          "<= 5 min", "met" if r["wall"] <= 300 else "MISSED")]
            elif name == "medium":
                rows.append(("64x96 P=8 Verilator", f"{cps:,.0f} cycles/s", ">= 150,000",
                             "met" if cps >= 150000 else "MISSED"))
            elif name == "icarus":
                sec = r["seconds"]
                alone = r["cycles"] / sec["simulate"]
                cpu = r["cycles"] / sec["simulate_cpu"]
                print(f"  the simulator's share: {alone:,.0f} cycles/s ({r['cycles']:,} cycles "
                      f"in {sec['simulate']:.1f} s), {cpu:,.0f} per second of its thread's "
                      f"CPU time (other jobs barely change it); waiting for the twin "
                      f"{sec['wait_for_twin']:.1f} s; timeline {r['timeline']}", flush=True)
                plain = plain_vvp(tmp, size, steps, frames)
                print(f"  plain vvp (the same run, no cocotb: scripts/bench_icarus_plain.py): "
                      f"{plain['cycles_per_second']:,.0f} cycles/s ({plain['cycles']:,} "
                      f"cycles in {plain['seconds']:.1f} s, {plain['user_seconds']:.1f} s "
                      f"user); the whole run is {cps / plain['cycles_per_second']:.1%} of it",
                      flush=True)
                rows += [("64x64 P=4 Icarus", f"{cps:,.0f} cycles/s", ">= 5,000",
                          "met" if cps >= 5000 else "MISSED"),
                         ("  its simulator's share", f"{alone:,.0f} cycles/s", "", ""),
                         ("  per CPU second", f"{cpu:,.0f} cycles/s", "", ""),
                         ("  plain vvp, same run", f"{plain['cycles_per_second']:,.0f} cycles/s",
                          "", "")]
            else:
                rows += [("250x400, 40,000 steps incl. build", f"{r['wall'] / 60:.1f} min",
                          "<= 60 min", "met" if r["wall"] <= 3600 else "MISSED"),
                         ("  its peak RSS", f"{r['rss_mb'] / 1024:.2f} GB", "<= 4 GB",
                          "met" if r["rss_mb"] <= 4096 else "MISSED")]
        if not args.quick and (not args.only or "simulate" in args.only):
            argv = [RVSM, "simulate", "flyball", "--size", "250x400", "--model", "dog4",
                    "--noise", "--frames", "4001", "--steps-per-frame", "10", "-o",
                    str(tmp / "s.h5")]
            wall, rss, _ = run(argv, tmp)
            print(f"simulate: rvsm {shlex.join(argv[1:-1])} s.h5\n  wall {wall:.0f} s; "
                  f"peak RSS {rss / 1024:,.0f} MB", flush=True)
            rows.append(("rvsm simulate 4,001 frames to .h5", f"{rss / 1024 ** 2:.2f} GB",
                         "<= 1.5 GB", "met" if rss <= 1.5 * 1024 ** 2 else "MISSED"))
        if not args.quick and (not args.only or "stimulus" in args.only):
            rows += stimulus_case(tmp)
        if not args.only or "regress" in args.only:
            rows.append(regress_case(tmp))
        if not args.only or "verilog" in args.only:
            rows.append(verilog_case(tmp))
    finally:
        if not args.keep:
            shutil.rmtree(tmp, ignore_errors=True)
    print()
    width = max(len(r[0]) for r in rows)
    for what, got, target, verdict in rows:
        print(f"{what:<{width}}  {got:>16}  target {target:<12} {verdict}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
