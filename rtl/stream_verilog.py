"""Verilog and port map of the streaming array (:mod:`rvsm.rtl.stream_array`).

* :func:`generate_stream_verilog` converts :class:`RvsmStreamArray` with Amaranth's
  bundled yosys (``emit_src=False``) without all-zero memory initialisers: the array
  never relies on memory contents at power-up (accumulators read as zero in the first
  frame after reset or ``clear``; line-buffer rows outside the frame are masked;
  thresholds must be loaded), and at sensor size building those initialisers was most
  of the conversion time and their ``initial`` blocks most of the file.
* :func:`stream_port_map` derives the port list from the component's signature
  (:mod:`rvsm.rtl.ports`: ``codes_payload``, ``thr_we``, ...), with the bit fields of
  the output payload; :func:`write_stream_outputs` writes ``<top>.v``, ``<top>.ports.json``
  (ports, timing properties, state memory) and ``<top>.ports.md``.
* Lint with :func:`rvsm.rtl.verilog.verilator_lint` (the same documented waivers).
"""

from __future__ import annotations

import contextlib
import json
import os
import re
import time
from collections.abc import Iterator
from pathlib import Path

from amaranth.back import verilog as amaranth_verilog

from rvsm.model.fixed.core import ArrayContract
from rvsm.model.infra.atomic import write_text_atomic
from rvsm.rtl.ports import port_map as signature_port_map
from rvsm.rtl.ports import verilog_ports
from rvsm.rtl.stream_array import RvsmStreamArray, StreamGeometry
from rvsm.rtl.verilog import GeneratedVerilog, check_top

__all__ = [
    "STREAM_TOP",
    "generate_stream_verilog",
    "stream_port_map",
    "stream_port_map_markdown",
    "strip_zero_memory_init",
    "write_stream_outputs",
]

STREAM_TOP = "rvsm_stream_array"

_ZERO_INIT = re.compile(
    r"^[ \t]*initial begin\n(?:[ \t]*\\?[\w$.]+ ?\[\d+\] = \d+'h0+;\n)+[ \t]*end\n",
    re.MULTILINE)


def strip_zero_memory_init(text: str) -> tuple[str, int]:
    """Remove ``initial begin mem[i] = N'h0; ... end`` blocks; return text and count.

    Only blocks made entirely of all-zero memory-word assignments are removed, so any
    non-zero initial contents stay.
    """
    return _ZERO_INIT.subn("", text)


@contextlib.contextmanager
def _no_zero_meminit() -> Iterator[None]:
    """Let Amaranth's RTLIL emitter skip the ``$meminit_v2`` cell of all-zero memories.

    Amaranth 0.5 builds that cell bit by bit (about 90 % of the conversion time at
    sensor size) and yosys turns it into ``initial`` blocks; without it the memory is
    uninitialised, which this array allows. Non-zero initial contents are emitted as
    usual. If Amaranth's internals differ, nothing is patched (only slower).
    """
    from amaranth.back import rtlil

    emitter = getattr(rtlil, "ModuleEmitter", None)
    original = getattr(emitter, "emit_memory", None)
    if original is None:
        yield
        return

    def emit_memory(self, cell_idx, cell):  # noqa: ANN001, ANN202 - Amaranth's signature
        if any(cell.init):
            return original(self, cell_idx, cell)
        return None

    emitter.emit_memory = emit_memory
    try:
        yield
    finally:
        emitter.emit_memory = original


def generate_stream_verilog(contract: ArrayContract, lanes: int, top: str = STREAM_TOP,
                            dut: RvsmStreamArray | None = None) -> GeneratedVerilog:
    """Verilog of ``RvsmStreamArray(contract, lanes)`` (or of ``dut``, built from them):
    no src attributes, no zero memory initialisers."""
    t0 = time.perf_counter()
    if dut is None:
        StreamGeometry(contract, lanes)  # validate before building a component
        dut = RvsmStreamArray(contract, lanes)
    with _no_zero_meminit():
        text = amaranth_verilog.convert(dut, name=top, ports=verilog_ports(dut),
                                        emit_src=False)
    text, _ = strip_zero_memory_init(text)
    return GeneratedVerilog(text, top, dut.latency, time.perf_counter() - t0)


_FIELD_DESCRIPTIONS = {
    "row": "row y of the position",
    "group": "column group g of the position (columns g*P .. g*P+P-1)",
    "last": "last beat of a frame",
    "pos": "+1 spikes: bit s*P + i = accumulator (s, y, g*P + i)",
    "neg": "-1 spikes, same ordering (always 0 for unsigned models)",
}


def stream_port_map(contract: ArrayContract, lanes: int) -> list[dict]:
    """Top-level ports from the array's signature (:func:`rvsm.rtl.ports.port_map`, with
    :meth:`RvsmStreamArray.port_docs`); ``spikes_payload`` also lists its bit ``fields``
    (``name, offset, width, desc``) from the payload layout."""
    rows = signature_port_map(RvsmStreamArray.interface(contract, lanes),
                              RvsmStreamArray.port_docs(contract, lanes))
    layout = StreamGeometry(contract, lanes).spike_layout
    for row in rows:
        if row["name"] == "spikes_payload":
            row["fields"] = [{"name": name, "offset": field.offset, "width": field.width,
                              "desc": _FIELD_DESCRIPTIONS[name]} for name, field in layout]
    return rows


def _meta(dut: RvsmStreamArray, top: str) -> dict:
    geo = dut.geometry
    return {"top": top, "arch": "stream", "latency": geo.latency, "timing": geo.timing(),
            "bank_sizes": geo.bank_sizes, "state_bits": geo.state_bits,
            "ports": stream_port_map(dut.contract, geo.lanes)}


def stream_port_map_markdown(dut: RvsmStreamArray, top: str = STREAM_TOP) -> str:
    """The port map as Markdown: design point, timing properties, ports, payload fields."""
    c, geo = dut.contract, dut.geometry
    t = geo.timing()
    lines = [
        f"# `{top}` port map (streaming array)",
        "",
        f"Array {c.height}x{c.width}, {c.num_scales} scale(s), ADC {c.adc_bits} bits, "
        f"accumulator {c.accumulator_bits} bits ({'signed' if c.signed else 'unsigned'}"
        f" model, reset {c.reset}), shift {c.shift}; {geo.lanes} lane(s), "
        f"{geo.groups} beat(s) per row, {geo.beats_per_frame} per frame.",
        "",
        f"Timing (beats): window lag {t['window_lag']}, pipeline depth "
        f"{t['pipeline_depth']} (latency {t['latency']} cycles back to back), lag "
        f"{t['lag']} (output p follows input beat p + lag; flush with lag beats), "
        f"threshold lag {t['threshold_lag']}, read-modify-write depth {t['rmw_depth']}.",
        "",
        "| port | dir | width | meaning |",
        "|---|---|---|---|",
    ]
    ports = stream_port_map(c, geo.lanes)
    lines += [f"| `{p['name']}` | {p['dir']} | {p['width']} | {p['desc']} |" for p in ports]
    for p in ports:
        if "fields" in p:
            lines += ["", f"Fields of `{p['name']}`:", "",
                      "| field | bits | meaning |", "|---|---|---|"]
            lines += [f"| `{f['name']}` | [{f['offset'] + f['width'] - 1}:{f['offset']}] "
                      f"| {f['desc']} |" for f in p["fields"]]
    s = geo.state_bits
    lines += ["", f"State memory: accumulators {s['accumulators']} bits, thresholds "
              f"{s['thresholds']} bits, line buffer {s['line_buffer']} bits; banks of "
              f"{geo.bank_sizes} words per scale and kind."]
    return "\n".join(lines) + "\n"


def write_stream_outputs(
    contract: ArrayContract, lanes: int, out_dir: str | os.PathLike, top: str = STREAM_TOP
) -> tuple[dict[str, Path], GeneratedVerilog]:
    """Write ``<top>.v``, ``<top>.ports.json`` and ``<top>.ports.md`` into ``out_dir``."""
    check_top(top)
    out = Path(out_dir)
    StreamGeometry(contract, lanes)  # validate before building a component
    dut = RvsmStreamArray(contract, lanes)
    gen = generate_stream_verilog(contract, lanes, top, dut)
    paths = {
        "verilog": out / f"{top}.v",
        "ports_json": out / f"{top}.ports.json",
        "ports_md": out / f"{top}.ports.md",
    }
    meta = _meta(dut, top)
    meta["generation_seconds"] = round(gen.seconds, 3)
    write_text_atomic(paths["verilog"], gen.text)
    write_text_atomic(paths["ports_json"], json.dumps(meta, indent=2) + "\n")
    write_text_atomic(paths["ports_md"], stream_port_map_markdown(dut, top))
    return paths, gen
