"""The long fuzzing campaign (``make fuzz``): every ``fuzz``-marked test with the ``fuzz``
hypothesis profile and a total case budget split evenly over the tests.

Prints, per reader (test file), the cases hypothesis ran, the failures and the wall time,
and writes the same as JSON (``--json``). Exit status: pytest's (0 every case held, 1 a
case failed: its minimal example and traceback are in the output above the table).

    python scripts/fuzz.py [--cases 100000] [--workers 2] [--json out/fuzz.json]
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import subprocess
import sys
import time
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STATS_KEY = "_hypothesis_stats"
COUNTS = re.compile(r"(\d+) passing, (\d+) failing, and (\d+) invalid")


def fuzz_tests() -> list[str]:
    """Node ids of every ``fuzz``-marked test."""
    out = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q", "-m",
                          "fuzz", "-p", "no:cacheprovider"], cwd=ROOT, capture_output=True,
                         text=True, check=False)
    return [line for line in out.stdout.splitlines() if "::" in line]


class Tally:
    """A pytest plugin adding up hypothesis' case counts per test file."""

    def __init__(self) -> None:
        self.files: dict[str, dict[str, float]] = defaultdict(
            lambda: {"tests": 0, "cases": 0, "failing": 0, "invalid": 0, "seconds": 0.0,
                     "failed_tests": 0})

    def pytest_runtest_logreport(self, report) -> None:
        row = self.files[report.nodeid.split("::")[0]]
        row["seconds"] += report.duration
        if report.when == "call":
            row["tests"] += 1
            row["failed_tests"] += int(report.failed)
        stats = report.__dict__.get(STATS_KEY)
        if report.when == "teardown" and stats:
            for passing, failing, invalid in COUNTS.findall(stats):
                row["cases"] += int(passing) + int(failing)
                row["failing"] += int(failing)
                row["invalid"] += int(invalid)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=100_000,
                        help="total case budget over every fuzz test (default 100000)")
    parser.add_argument("--workers", type=int, default=2, help="pytest-xdist workers")
    parser.add_argument("--json", type=Path, default=ROOT / "out" / "fuzz.json",
                        help="where to write the summary (default out/fuzz.json)")
    args = parser.parse_args()
    tests = fuzz_tests()
    if not tests:
        print("fuzz: no fuzz-marked tests collected", file=sys.stderr)
        return 2
    per_test = max(1, math.ceil(args.cases / len(tests)))
    os.environ.update(RVSM_FUZZ_PROFILE="fuzz", RVSM_FUZZ_CASES=str(per_test))
    print(f"fuzz: {len(tests)} tests x {per_test} cases = {len(tests) * per_test} cases "
          f"on {args.workers} worker(s)", flush=True)
    import pytest

    tally = Tally()
    t0 = time.perf_counter()
    status = pytest.main(["-m", "fuzz", "-q", "-p", "no:cacheprovider",
                          "--hypothesis-show-statistics", "-n", str(args.workers),
                          "--hypothesis-seed", str(int(time.time()))], plugins=[tally])
    wall = time.perf_counter() - t0
    total = {"cases": 0, "failing": 0, "invalid": 0}
    print(f"\n{'reader tests':58} {'tests':>5} {'cases':>8} {'failed':>6} {'seconds':>8}")
    for name, row in sorted(tally.files.items()):
        print(f"{name:58} {row['tests']:5.0f} {row['cases']:8.0f} {row['failing']:6.0f} "
              f"{row['seconds']:8.1f}")
        for k in total:
            total[k] += int(row[k])
    print(f"fuzz: {total['cases']} cases run ({total['invalid']} generated inputs "
          f"rejected as invalid), {total['failing']} failing, {wall:.0f} s wall time, "
          f"pytest status {int(status)}")
    args.json.parent.mkdir(parents=True, exist_ok=True)
    tmp = args.json.with_suffix(".tmp")
    tmp.write_text(json.dumps({"cases": total["cases"], "failing": total["failing"],
                               "invalid": total["invalid"], "wall_seconds": round(wall, 1),
                               "cases_per_test": per_test, "status": int(status),
                               "readers": tally.files}, indent=1))
    os.replace(tmp, args.json)
    return int(status)


if __name__ == "__main__":
    sys.exit(main())
