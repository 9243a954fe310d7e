#!/usr/bin/env python3
"""Sweep speed-up from 1 to 2 Dask workers (`make bench-sweep`, issue 10 item 5).

Runs a sweep file (default ``sweeps/example.toml``) into a fresh database with 1 worker,
then with 2, ``--rounds`` times alternating (the machine's speed drifts; alternating
pairs see the same drift), and prints per run: wall seconds, the sum of the tasks' own
seconds (the work, as measured inside the workers), the start-up before the first
result, and the speed-up of each pair against the target (>= 1.7x on a 2-core machine).
The median pair decides.
"""

from __future__ import annotations

import argparse
import os
import sqlite3
import statistics
import sys
import tempfile
import time
from pathlib import Path

TARGET = 1.7
ROOT = Path(__file__).resolve().parents[1]


def one_run(sweep: Path, workers: int, db: Path) -> dict[str, float]:
    """Wall seconds, task seconds and start-up of one fresh sweep run."""
    from rvsm.sim.sweep.run import run_sweep
    from rvsm.sim.sweep.spec import load_sweep

    db.unlink(missing_ok=True)
    spec = load_sweep(sweep)
    t0 = time.perf_counter()
    done: list[float] = []
    summary = run_sweep(spec, db, workers=workers, progress=False,
                        on_result=lambda _s: done.append(time.perf_counter() - t0))
    wall = time.perf_counter() - t0
    if summary.errors:
        raise SystemExit(f"sweep failed: {summary.errors[0]}")
    with sqlite3.connect(db) as con:
        work = sum(r[0] for r in con.execute("SELECT seconds FROM lane_cost"))
        work += sum(r[0] for r in con.execute("SELECT seconds FROM results"))
    return {"wall": wall, "work": work, "first": done[0] if done else wall}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("sweep", nargs="?", default=str(ROOT / "sweeps" / "example.toml"))
    parser.add_argument("--rounds", type=int, default=1, help="1-worker/2-worker pairs")
    args = parser.parse_args()
    sweep = Path(args.sweep)
    from rvsm.sim.sweep.spec import load_sweep

    load_sweep(sweep)  # a bad file fails here, before any run
    print(f"{sweep.name}: fresh database per run; {os.cpu_count()} CPUs; load = 1-min load "
          "average at the start of the run; work = sum of the tasks' own seconds")
    print(f"{'round':>5s} {'workers':>7s} {'wall s':>7s} {'work s':>7s} {'start-up s':>10s} "
          f"{'load':>5s} {'speed-up':>8s}")
    ratios = []
    with tempfile.TemporaryDirectory(prefix="rvsm-bench-sweep-") as tmp:
        for r in range(1, args.rounds + 1):
            walls = {}
            for workers in (1, 2):
                load = os.getloadavg()[0]
                res = one_run(sweep, workers, Path(tmp) / f"r{r}-w{workers}.sqlite")
                walls[workers] = res["wall"]
                ratio = f"{walls[1] / res['wall']:7.2f}x" if workers == 2 else ""
                print(f"{r:5d} {workers:7d} {res['wall']:7.1f} {res['work']:7.1f} "
                      f"{res['first']:10.1f} {load:5.2f} {ratio:>8s}", flush=True)
            ratios.append(walls[1] / walls[2])
    median = statistics.median(ratios)
    verdict = "met" if median >= TARGET else "MISSED"
    print(f"\nspeed-up 1 -> 2 workers: median {median:.2f}x over {len(ratios)} pair(s) "
          f"(target >= {TARGET}x: {verdict})")


if __name__ == "__main__":
    from rvsm.model.infra.errors import RvsmError

    try:
        main()
    except RvsmError as exc:  # a bad sweep file: one line, exit 2 as the CLI does
        print(f"bench_sweep: error: {exc}", file=sys.stderr)
        sys.exit(2)
