"""What a regression reports: functional coverage merged over runs with its closure
(the bins never hit), and JUnit XML with one test case per run.

Coverage bins, per scale, are those of :func:`rvsm.model.fixed.corner_stimulus.coverage`
(codes at 0 and full scale, exact threshold hits of both signs, both saturation rails,
spikes of both signs, a clear mid-stream; measured on seed runs and on scene runs with
the per-cycle testbench) and, for runs in the long-run harness, the lanes at the image
borders (the beat stream's ``border_coverage``, ``rtl/stream/coverage.py``:
``top_lane<i>``, ...; a bin is named by its lane, so plans with several lane counts
close each). Bins a contract
cannot reach (``None`` in every run) are left out of the closure.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any
from xml.etree import ElementTree as ET

from rvsm.model.infra.atomic import write_text_atomic

__all__ = ["closure_lines", "merged_coverage", "write_junit"]


def merged_coverage(rows: Sequence[dict[str, Any]]) -> dict[str, list[dict[str, int | None]]]:
    """Per model, per scale, accumulator-steps per bin summed over the runs that
    measured coverage (``None`` where no run could reach a bin)."""
    merged: dict[str, list[dict[str, int | None]]] = {}
    for row in rows:
        cov = row.get("coverage")
        if not cov:
            continue
        into = merged.setdefault(row["model"], [{} for _ in cov])
        for scale, bins in enumerate(cov):
            for name, n in bins.items():
                into[scale].setdefault(name, None)
                if n is not None:
                    into[scale][name] = (into[scale][name] or 0) + int(n)
    return merged


def closure_lines(rows: Sequence[dict[str, Any]]) -> list[str]:
    """The closure report: per model and scale, bins hit of the reachable ones and the
    bins never hit; the runs without coverage counted."""
    merged = merged_coverage(rows)
    lines = []
    for model, scales in sorted(merged.items()):
        runs = sum(1 for r in rows if r["model"] == model and r.get("coverage"))
        lines.append(f"{model} ({runs} run(s) with coverage):")
        for scale, bins in enumerate(scales):
            live = {b: n for b, n in bins.items() if n is not None}
            missing = [b for b, n in live.items() if not n]
            hit = len(live) - len(missing)
            tail = f"; never hit: {', '.join(missing)}" if missing else "; closed"
            lines.append(f"  scale {scale}: {hit}/{len(live)} bins hit{tail}")
    without = sum(1 for r in rows if not r.get("coverage"))
    if without:
        lines.append(f"{without} run(s) measured no functional coverage (scene runs in the "
                     "long-run harness)")
    return lines


def write_junit(path: str | os.PathLike, plan: str, rows: Sequence[dict[str, Any]]) -> None:
    """JUnit XML (atomically): one ``testcase`` per run, a ``failure`` for a mismatch
    (the first one named), an ``error`` for a tool failure."""
    suite = ET.Element("testsuite", name=plan, tests=str(len(rows)),
                       failures=str(sum(r["status"] == "fail" for r in rows)),
                       errors=str(sum(r["status"] == "error" for r in rows)),
                       time=f"{sum(r.get('seconds') or 0 for r in rows):.3f}")
    for r in rows:
        case = ET.SubElement(suite, "testcase", classname=f"rvsm.regress.{plan}",
                             name=r["label"], time=f"{r.get('seconds') or 0:.3f}")
        if r["status"] == "fail":
            first = r.get("first_mismatch") or {}
            text = ", ".join(f"{k}={v}" for k, v in first.items())
            fail = ET.SubElement(case, "failure", type="mismatch",
                                 message=f"{r['mismatches']} mismatch(es); first: {text}")
            fail.text = f"run folder: {r.get('run_dir')}\nwaveform: {r.get('waves')}"
        elif r["status"] == "error":
            ET.SubElement(case, "error", type="tool", message=r.get("error") or "")
        props = ET.SubElement(case, "properties")
        for k in ("key", "compared", "cycles_per_second", "run_dir"):
            ET.SubElement(props, "property", name=k, value=str(r.get(k)))
    tree = ET.ElementTree(ET.Element("testsuites"))
    tree.getroot().append(suite)
    ET.indent(tree)
    write_text_atomic(Path(path), ET.tostring(tree.getroot(), encoding="unicode",
                                              xml_declaration=True) + "\n")
