#!/usr/bin/env python3
"""Peak memory against scene length (issue 17): the same 40,000 steps from few or many
frames.

Runs ``rvsm simulate flyball --size 250x400 --model dog4 --noise --frames F
--steps-per-frame M -o long.h5`` in a child process for each ``F:M`` of ``--cases``
(default ``401:100`` and ``4001:10``, both 40,000 steps) and prints each child's peak RSS
(``ru_maxrss`` from ``wait4``) and wall time. Scenes are read a range of frames at a time,
so both cases should peak alike, at most ``--target`` GB. Pass ``--spikes-digest`` to
print a SHA-256 of each file's spikes (compare runs of two trees: same spikes bit for bit).
"""

from __future__ import annotations

import argparse
import hashlib
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def run_case(frames: int, spf: int, out: Path) -> tuple[float, float]:
    """``(peak RSS bytes, wall seconds)`` of one ``rvsm simulate`` child."""
    cmd = [sys.executable, "-m", "rvsm.sim.cli.main", "simulate", "flyball", "--size",
           "250x400", "--model", "dog4", "--noise", "--frames", str(frames),
           "--steps-per-frame", str(spf), "-o", str(out)]
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    err = proc.stderr.read().decode(errors="replace") if proc.stderr else ""
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        raise SystemExit(f"run failed ({proc.returncode}): {err.strip()[-500:]}")
    return usage.ru_maxrss * 1024.0, wall


def spikes_digest(path: Path) -> str:
    """SHA-256 (first 16 hex digits) of a spike file's ``spikes`` dataset, chunk by chunk."""
    import h5py

    digest = hashlib.sha256()
    with h5py.File(path, "r") as f:
        data = f["spikes"]
        for t in range(0, data.shape[0], 1024):
            digest.update(data[t:t + 1024].tobytes())
    return digest.hexdigest()[:16]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", default="401:100,4001:10",
                        help="comma-separated FRAMES:STEPS_PER_FRAME (default %(default)s)")
    parser.add_argument("--target", type=float, default=1.5, help="peak RSS target, GB")
    parser.add_argument("--spikes-digest", action="store_true",
                        help="also print a digest of each run's spikes")
    args = parser.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.2f}")
    with tempfile.TemporaryDirectory() as tmp:
        for case in args.cases.split(","):
            frames, spf = (int(v) for v in case.split(":"))
            out = Path(tmp) / "long.h5"
            rss, wall = run_case(frames, spf, out)
            ok = "met" if rss <= args.target * 1e9 else "MISSED"
            line = (f"--frames {frames} --steps-per-frame {spf} ({(frames - 1) * spf} steps): "
                    f"peak RSS {rss / 1e9:.2f} GB (target <= {args.target} GB: {ok}), "
                    f"{wall:.0f} s wall")
            if args.spikes_digest:
                line += f", spikes sha256 {spikes_digest(out)}"
            print(line, flush=True)
            out.unlink()


if __name__ == "__main__":
    main()
