#!/usr/bin/env python3
"""Peak memory against scene length (issue 17): the same 40,000 steps from few or many
frames, and a long stimulus file.

Runs ``rvsm simulate flyball --size 250x400 --model dog4 --noise --frames F
--steps-per-frame M -o long.h5`` in a child process for each ``F:M`` of ``--cases``
(default ``401:100`` and ``4001:10``, both 40,000 steps) and prints each child's peak RSS
(``ru_maxrss`` from ``wait4``) and wall time. Scenes are read a range of frames at a time,
so both cases should peak alike, at most ``--target`` GB. Pass ``--spikes-digest`` to
print a SHA-256 of each file's spikes (compare runs of two trees: same spikes bit for bit).

``--stimulus-steps N`` (0: skip) then runs ``rvsm stimulus flyball --fixed POINT --size
250x400 --frames N/10+1 --steps N -o stim.npz`` (the default design point, dog4) and
prints its peak RSS, wall time and file size: the stimulus is made and written a chunk of
steps at a time, so the peak should not grow with N (``--stimulus-target`` GB).
``--only-stimulus`` skips the ``rvsm simulate`` cases.
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
    return run_child(["simulate", "flyball", "--size", "250x400", "--model", "dog4",
                      "--noise", "--frames", str(frames), "--steps-per-frame", str(spf),
                      "-o", str(out)])


def run_stimulus(steps: int, folder: Path) -> tuple[float, float, int]:
    """``(peak RSS bytes, wall seconds, file bytes)`` of one ``rvsm stimulus`` child of
    ``steps`` steps of 250x400 (10 steps per frame) at the default design point."""
    point, out = folder / "point.toml", folder / "stim.npz"
    subprocess.run([sys.executable, "-m", "rvsm.sim.cli.main", "config", "new", "-o",
                    str(point)], check=True, capture_output=True)
    rss, wall = run_child(["stimulus", "flyball", "--fixed", str(point), "--size",
                           "250x400", "--frames", str(-(-steps // 10) + 1), "--steps",
                           str(steps), "-o", str(out)])
    size = out.stat().st_size
    out.unlink()
    return rss, wall, size


def run_child(args: list[str]) -> tuple[float, float]:
    """``(peak RSS bytes, wall seconds)`` of one ``rvsm ARGS`` child."""
    cmd = [sys.executable, "-m", "rvsm.sim.cli.main", *args]
    start = time.perf_counter()
    # stderr (progress bars) to a file: a pipe read only after wait4 fills up and blocks
    # the child on a long run
    with tempfile.TemporaryFile() as log:
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=log)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - start
        log.seek(0)
        err = log.read().decode(errors="replace")
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
    parser.add_argument("--stimulus-steps", type=int, default=4000,
                        help="steps of the rvsm stimulus case (default %(default)s; 0: skip)")
    parser.add_argument("--stimulus-target", type=float, default=1.0,
                        help="rvsm stimulus peak RSS target, GB")
    parser.add_argument("--only-stimulus", action="store_true",
                        help="skip the rvsm simulate cases")
    args = parser.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.2f}")
    with tempfile.TemporaryDirectory() as tmp:
        for case in [] if args.only_stimulus else args.cases.split(","):
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
        if args.stimulus_steps > 0:
            n = args.stimulus_steps
            rss, wall, size = run_stimulus(n, Path(tmp))
            ok = "met" if rss <= args.stimulus_target * 1e9 else "MISSED"
            print(f"rvsm stimulus, {n} steps of 250x400 dog4: peak RSS {rss / 1e9:.2f} GB "
                  f"(target <= {args.stimulus_target} GB: {ok}), {wall:.0f} s wall, file "
                  f"{size / 1e6:.0f} MB", flush=True)


if __name__ == "__main__":
    main()
