"""Short lines for a device constraint's verdicts, and the one line when nothing fits.

:func:`short_verdict` is a design's verdict on one device in a line a terminal shows
(``"breaks fmax 1,000 / 115.7 MHz (+764 %); memory ..."``: the figures without the
details, which ``report.md`` and ``--json`` keep). :func:`nothing_fits` is the error line
``rvsm sweep report`` and ``rvsm datasheet`` exit with when no design meets the request:
per device the budget the nearest design breaks and by how much.
"""

from __future__ import annotations

from rvsm.rtl.fpga.build_budget import lane_clocks
from rvsm.rtl.fpga.feasibility import Check, Feasibility

__all__ = ["check_text", "nothing_fits", "prime_width_note", "short_verdict"]


def check_text(c: Check) -> str:
    """``"fmax 1,000 / 115.7 MHz (+764 %)"``: a check's figures without its detail."""
    return c.text().split("; ")[0].replace(" BREAKS:", "").replace(" unknown:", " ?")


def short_verdict(f: Feasibility) -> str:
    """``"P = 40 at 100.0 MHz: breaks fmax ...; memory ..."`` in one short line."""
    head = f"P = {f.lanes} at {f.clock_needed_hz / 1e6:,.1f} MHz"
    if f.feasible:
        return f"{head}: fits"
    bad = f.broken or f.unknown
    word = "breaks" if f.broken else "unverified"
    return f"{head}: {word} " + "; ".join(check_text(c) for c in bad)


def _worst(f: Feasibility) -> float:
    """How far the verdict is from fitting: the largest excess of a broken check."""
    return max((c.over_by for c in f.broken if c.over_by is not None), default=0.0)


def prime_width_note(height: int, width: int, rate_hz: float) -> str:
    """For a prime width (only 1 and ``width`` lanes divide it): say so, with the clock
    each needs; else ``""``."""
    if width < 4 or any(width % p == 0 for p in range(2, int(width ** 0.5) + 1)):
        return ""
    return (f"; the width {width} is prime, so only {lane_clocks(height, width, rate_hz)} "
            "lanes divide it: choose a width with more divisors")


def nothing_fits(verdicts: dict[str, list[Feasibility]], subject: str = "no design meets",
                 product: str = "the report") -> str:
    """The one line: ``subject`` (e.g. ``"dog2 cannot meet"``) the camera; per device, the nearest
    design's broken budgets and by how much; ``--allow-infeasible`` writes ``product``."""
    parts = []
    for device, fs in verdicts.items():
        if not fs:
            continue
        near = min(fs, key=_worst)
        best = f" ({len(fs)} designs) at best" if len(fs) > 1 else ""
        parts.append(f"{device}{best} {short_verdict(near)}")
    cam = next(iter(f for fs in verdicts.values() for f in fs), None)
    what = "" if cam is None else f" {cam.camera.text()}"
    note = "" if cam is None else prime_width_note(cam.camera.height, cam.camera.width,
                                                   cam.camera.rate_hz)
    return (f"{subject}{what}: on " + " | ".join(parts) + note
            + f" (--allow-infeasible writes {product} anyway)")
