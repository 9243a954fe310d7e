"""A design point through both board links (docs/board.md, "Verification").

    python scripts/links_run.py points/ecp5-85-40khz.toml --steps 100 --sim verilator
    python scripts/links_run.py tests/data/formal-tiny.toml --size 4x8 --lanes 2 --steps 3

Builds the link loopback (:mod:`rvsm.rtl.board.loopback`: a sensor serialiser, the
board front end around the streaming array, a board deserialiser; skew between the
receive pairs and a bit slip) in the long-run harness, runs ``--steps`` random frames
and checks every spike against the fixed twin (:mod:`rvsm.sim.cosim.links_run`).
Prints steps, spikes compared, mismatches, the wall time and the peak memory (``--json``:
the whole result). Exit status: 0 every spike matches, 1 a mismatch (the first named),
2 bad input, 3 a tool failed. Lanes default to the point's ``[rtl] lanes``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

from rvsm.model.fixed.point_toml import load_point_file
from rvsm.model.infra.errors import RvsmError, ToolError
from rvsm.rtl.toolchain import ToolFailure
from rvsm.sim.cosim.links_run import links_verify


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("point", help="design point TOML")
    p.add_argument("--size", help="HxW instead of the point's size")
    p.add_argument("--lanes", type=int, help="lanes (default: the point's [rtl] lanes)")
    p.add_argument("--steps", type=int, default=100)
    p.add_argument("--sim", choices=("icarus", "verilator"), default="verilator")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--work", default="build/links-run", help="work folder")
    p.add_argument("--json", action="store_true", help="print the whole result as JSON")
    a = p.parse_args(argv)
    t0 = time.perf_counter()
    try:
        point, settings = load_point_file(a.point)
        if a.size:
            h, w = (int(v) for v in a.size.lower().split("x"))
            point = point.with_size(h, w)
        lanes = a.lanes or settings.lanes or 1
        r = links_verify(point, lanes, a.steps, a.work, sim=a.sim, seed=a.seed,
                         build_root=f"{a.work}/builds")
    except (ToolError, ToolFailure) as exc:
        print(f"links_run: {exc}", file=sys.stderr)
        return 3
    except (RvsmError, ValueError) as exc:
        print(f"links_run: {exc}", file=sys.stderr)
        return 2
    r["wall_seconds"] = round(time.perf_counter() - t0, 1)
    if a.json:
        print(json.dumps(r, indent=1))
    else:
        print(f"{r['point']} P={r['lanes']} on {r['sim']}: {r['steps']} steps, "
              f"{r['rx_pairs']} receive / {r['tx_pairs']} transmit pairs, "
              f"{r['compared']:,} spikes compared ({r['spikes']:,} non-zero), "
              f"{r['mismatches']} mismatches; {r['core_cycles']:,} core cycles "
              f"({r['cycles']:,} bit clocks); wall {r['wall_seconds']} s (build "
              f"{r['seconds']['build']:.0f} s, simulate {r['seconds']['simulate']:.0f} s); "
              f"peak RSS {r['peak_rss_mb']:.0f} MB")
    if r["mismatches"]:
        print(f"links_run: first mismatch {r['first_mismatch']} (stray {r['stray']}, "
              f"overflow {r['overflow']})", file=sys.stderr)
        if r["waveform"]:
            print(f"links_run: waveform of bit clocks {r['window_cycles'][0]}.."
                  f"{r['window_cycles'][1]}: {r['waveform']}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
