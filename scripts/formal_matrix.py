"""The streaming array's bounded equivalence for every model, lane count and reset mode.

``python scripts/formal_matrix.py [--jobs N] [--models ...] [--configs 3x4:2 ...]``
runs ``rvsm formal POINT --arch stream --size HxW --lanes P --model M --check
equivalence`` for each combination (the two tiny points: reset subtract and zero), N at
a time, prints one line per run and a table (wall time of each), writes
``build/formal/equivalence-matrix.json`` and exits with the worst status (0 every run
passed, 1 a counterexample, 3 a tool failed). ``make formal`` runs it. The runs whose
direct miter gives no verdict within an hour (:data:`COMPOSED`) run in the compositional
form (``--check window sums composed``, docs/formal.md, "The compositional proof").
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
POINTS = {"subtract": ROOT / "tests/data/formal-tiny.toml",
          "zero": ROOT / "tests/data/formal-tiny-zero.toml"}
MODELS = ("fsm", "gauss1", "gauss2", "gauss3", "gauss4", "dog1", "dog2", "dog3", "dog4")
CONFIGS = ("3x4:2", "3x3:1", "3x6:3")
#: Runs proven in the compositional form (:data:`COMPOSED_CHECKS`): dog4's widest kernels
#: with 2 and 3 lanes, whose direct miter reached only step 17 of 28 in an hour's pace
#: (docs/formal.md, the equivalence matrix).
COMPOSED = {("dog4", "3x4:2"), ("dog4", "3x6:3")}
COMPOSED_CHECKS = ("window", "sums", "composed")


def run_one(model: str, config: str, reset: str, out: Path, timeout: float) -> dict:
    size, lanes = config.split(":")
    folder = out / f"equivalence-{model}-{size}-p{lanes}-{reset}"
    checks = COMPOSED_CHECKS if (model, config) in COMPOSED else ("equivalence",)
    cmd = [str(Path(sys.executable).parent / "rvsm"), "formal", str(POINTS[reset]),
           "--arch", "stream", "--size", size, "--lanes", lanes, "--model", model,
           "--check", *checks, "--timeout", str(timeout), "--json", "-o",
           str(folder)]
    started = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True)
    seconds = time.perf_counter() - started
    depth = None
    if proc.stdout.strip().startswith("{"):
        report = json.loads(proc.stdout)
        depth = max((c["depth"] for c in report["checks"]), default=None)
    return {"model": model, "size": size, "lanes": int(lanes), "reset": reset,
            "status": proc.returncode, "depth": depth, "seconds": round(seconds, 1),
            "folder": str(folder),
            "error": proc.stderr.strip().splitlines()[-1] if proc.returncode else ""}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--models", nargs="+", default=list(MODELS), choices=MODELS)
    parser.add_argument("--configs", nargs="+", default=list(CONFIGS), metavar="HxW:P")
    parser.add_argument("--resets", nargs="+", default=list(POINTS), choices=list(POINTS))
    parser.add_argument("--timeout", type=float, default=3600.0,
                        help="seconds per run before it counts as a tool failure")
    parser.add_argument("-o", "--out", type=Path, default=ROOT / "build/formal")
    args = parser.parse_args(argv)
    runs = [(m, c, r) for c in args.configs for m in args.models for r in args.resets]
    started = time.perf_counter()
    results = []
    with ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = [pool.submit(run_one, m, c, r, args.out, args.timeout) for m, c, r in runs]
        for i, future in enumerate(futures, 1):
            r = future.result()
            results.append(r)
            verdict = {0: "pass", 1: "COUNTEREXAMPLE"}.get(r["status"], "TOOL FAILED")
            print(f"[{i}/{len(runs)}] {r['model']:7} {r['size']} P={r['lanes']} "
                  f"{r['reset']:8} depth {r['depth']}: {verdict} ({r['seconds']} s)"
                  + (f" {r['error']}" if r["error"] else ""), flush=True)
    wall = time.perf_counter() - started
    args.out.mkdir(parents=True, exist_ok=True)
    summary = {"wall_seconds": round(wall, 1), "jobs": args.jobs, "runs": results}
    (args.out / "equivalence-matrix.json").write_text(json.dumps(summary, indent=2) + "\n")
    print(f"\nequivalence matrix: {sum(r['status'] == 0 for r in results)}/{len(results)} "
          f"passed, wall {wall:.0f} s with {args.jobs} jobs "
          f"(sum of run times {sum(r['seconds'] for r in results):.0f} s)")
    worst = max((r["status"] for r in results), default=0)
    return 0 if worst == 0 else (1 if worst == 1 else 3)


if __name__ == "__main__":
    sys.exit(main())
