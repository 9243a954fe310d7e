"""Write the timing diagrams of the guides, recorded from ``amaranth.sim``: the bare
streaming array's (:mod:`rvsm.rtl.stream.timing_diagrams`, ``docs/diagrams/``,
docs/integration.md) and the AXI IP's (:mod:`rvsm.rtl.ip.waves`, ``docs/ip/``, docs/ip.md),
each as ``<name>.json`` (WaveJSON) and ``<name>.svg``.

Usage: ``python scripts/timing_diagrams.py`` (``make diagrams``).
``tests/rtl/stream/test_timing_diagrams.py`` and ``tests/rtl/ip/test_waves.py`` check the
committed JSON is what the RTL does today.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import wavedrom

from rvsm.model.infra.atomic import write_text_atomic
from rvsm.rtl.ip.waves import write_diagrams
from rvsm.rtl.stream.timing_diagrams import SCENARIOS, scenario_wavejson


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="docs/diagrams",
                        help="output folder of the bare array's diagrams")
    parser.add_argument("--ip-out", default="docs/ip", help="output folder of the IP's")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for name in SCENARIOS:
        diagram = scenario_wavejson(name)
        text = json.dumps(diagram, indent=1) + "\n"
        write_text_atomic(out / f"{name}.json", text)
        svg = wavedrom.render(json.dumps(diagram))
        write_text_atomic(out / f"{name}.svg", svg.tostring() + "\n")
        print(f"wrote {out / name}.json and .svg")
    for path in write_diagrams(args.ip_out):
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
