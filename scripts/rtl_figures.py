#!/usr/bin/env python3
"""Verilator build and per-1000-step figures of docs/rtl.md (dog4, default design point).

Usage: ``python scripts/rtl_figures.py 16 32 [--sim verilator|icarus]``. For each array
side N it generates the Verilog, builds it (cached under ``build/rtl-figures``), streams
1000 steps of random ADC codes with random thresholds and checks every spike against the
fixed twin. A 32x32 Verilator build takes ~16 minutes on 2 cores.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rvsm.model.fixed.design_point import default_design_point
from rvsm.sim.cosim.verify import run_rtl


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("sides", type=int, nargs="+", help="array sides, e.g. 16 32")
    parser.add_argument("--sim", default="verilator", choices=("verilator", "icarus"))
    parser.add_argument("--steps", type=int, default=1000)
    args = parser.parse_args()
    for n in args.sides:
        contract = default_design_point().with_size(n, n).contract()
        rng = np.random.default_rng(0)
        top = (1 << contract.threshold_bits) - 1
        codes = rng.integers(0, 1 << contract.adc_bits, (args.steps, n, n))
        thresholds = rng.integers(top // 4, top + 1, (contract.num_scales, n, n))
        start = time.perf_counter()
        r = run_rtl(contract, codes, thresholds, args.sim, work_dir="build/rtl-figures",
                    name=f"{n}x{n}")
        print(f"{n}x{n} {args.sim}: total {time.perf_counter() - start:.1f} s, "
              f"generate {r['generate_seconds']:.1f} s, build {r['build_seconds']:.1f} s "
              f"(cached: {r['build_cached']}), stream {r['stream_seconds']:.2f} s / "
              f"{args.steps} steps, compared {r['compared']}, mismatches {r['mismatches']}")


if __name__ == "__main__":
    main()
