"""The datasheet's "Verification" section: what the saved results say was checked.

One row per check (``rvsm verify`` at full size, the ``rvsm regress`` plan, ``rvsm
formal``, ``rvsm mutate``), each naming its saved result and counting what it counts:
accumulator-steps compared (``S*H*W`` accumulators x steps) and the spikes among them,
test cases, properties, mutations. A check without a saved result says "not run". The
commands are in the page's Reproduce section.
"""

from __future__ import annotations

from typing import Any

from rvsm.sim.studies.datasheet_inputs import DatasheetInputs

__all__ = ["verification_lines", "verify_counts"]


def verify_counts(v: dict[str, Any]) -> str:
    """``8,000,000,000 accumulator-steps compared (200,000 accumulators x 40,000 steps),
    1,190,471,833 of them spikes``: what an ``rvsm verify --json`` result compared."""
    text = f"{v['compared']:,} accumulator-steps compared"
    acc, steps = v.get("accumulators"), v.get("steps")
    if isinstance(acc, int) and isinstance(steps, int) and acc * steps == v["compared"]:
        text += f" ({acc:,} accumulators x {steps:,} steps)"
    if isinstance(v.get("expected_spikes"), int):
        text += f", {v['expected_spikes']:,} of them spikes"
    return text


def verification_lines(inputs: DatasheetInputs, title: str) -> list[str]:
    """The section (module docstring)."""
    lines = [f"## {title}", "", "| check | saved result | result |", "|---|---|---|"]
    v = inputs.verify
    if v is None:
        lines.append("| RTL against the twin | - | not run |")
    else:
        verdict = "PASS: 0 mismatches" if v["mismatches"] == 0 else \
            f"FAIL: {v['mismatches']:,} mismatches"
        what = ", ".join(f"{k} {v[key]}" for k, key in (
            ("simulator", "simulator"), ("arch", "arch"), ("harness", "harness"))
            if v.get(key))
        size = f" at {v['height']}x{v['width']}" if v.get("height") else ""
        lines.append(f"| RTL against the twin{size}, scene {v.get('scene', '?')} | "
                     f"`{inputs.verify_path}` | {verdict} in {verify_counts(v)}"
                     f"{'; ' + what if what else ''} |")
    r = inputs.regress
    if r is None:
        lines.append("| regression plan | - | not run |")
    else:
        lines.append(f"| regression {', '.join(r.suites)} | `{inputs.regress_path}` | "
                     f"{r.count('pass')} of {len(r.cases)} test cases pass, "
                     f"{r.count('fail')} fail, {r.count('error')} error |")
        bad = [c for c in r.cases if c[2] in ("fail", "error")]
        lines += [f"| - {c[1]} | | {c[2]} |" for c in bad[:20]]
    f = inputs.formal
    if f is None:
        lines.append("| formal checks (tiny size) | - | not run |")
    else:
        h, w = f["size"]
        lanes = (f.get("options") or {}).get("lanes")
        done = "; ".join(f"{c['check']} {c['status']} ({c.get('mode', '?')}, depth "
                         f"{c.get('depth', '?')})" for c in f["checks"])
        n_ok = sum(c["status"] == "pass" for c in f["checks"])
        lines.append(f"| formal checks, {f.get('model', '?')} {h}x{w}"
                     f"{f', P = {lanes}' if lanes else ''} | `{inputs.formal_path}` | "
                     f"{'PASS' if f.get('ok') else 'FAIL'}: {n_ok} of {len(f['checks'])} "
                     f"checks pass: {done} |")
    m = inputs.mutate
    if m is None:
        lines.append("| mutation testing (tiny size) | - | not run |")
    else:
        survivors = ", ".join(m["survivors"]) or "none"
        size = f" at {m['size'][0]}x{m['size'][1]}" if m.get("size") else ""
        lines.append(f"| mutation testing{size} ({', '.join(m.get('checks', []))}) | "
                     f"`{inputs.mutate_path}` | {m['killed']} of {m['mutations']} "
                     f"mutations killed; survivors: {survivors} |")
    lines += ["", "Sources: the saved results named above; a check without one says "
              "\"not run\"; commands: [Reproduce](#reproduce).", ""]
    return lines
