"""Write the integration guide's timing diagrams: ``docs/diagrams/<name>.json`` (WaveJSON)
and ``<name>.svg``, recorded from ``amaranth.sim`` (:mod:`rvsm.rtl.stream.timing_diagrams`).

Usage: ``python scripts/timing_diagrams.py [--out docs/diagrams]`` (``make diagrams``).
``tests/rtl/stream/test_timing_diagrams.py`` checks the committed JSON is what the RTL
does today.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import wavedrom

from rvsm.model.infra.atomic import write_text_atomic
from rvsm.rtl.stream.timing_diagrams import SCENARIOS, scenario_wavejson


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="docs/diagrams", help="output folder")
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


if __name__ == "__main__":
    main()
