"""The datasheet's "Memory map and interfaces" section: everything an integrator wires up.

For the design point at ``P`` lanes: the state memories, the ports of the bare streaming
array (``--interface native``) and of the AXI IP (``--interface axis``) with a bit-range
table of every payload (``codes_payload``, ``spikes_payload``, ``s_axis_tdata``,
``m_axis_tdata``), the AXI4-Lite registers with every bit field
(:func:`~rvsm.rtl.ip.register_map.ip_register_map`), and the reset, initialisation and
flush sequence of both interfaces with this point's cycle counts. The two payloads pack
differently and the section says so first. Everything comes through the architecture
registry (:func:`interfaces_of`): the streaming array's beat geometry and port map, the
IP's register map, port map and timing.
"""

from __future__ import annotations

import gc
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from amaranth.hdl import UnusedElaboratable

from rvsm.model.fixed.contract import ArrayContract

__all__ = ["Interfaces", "field_rows", "interfaces_lines", "interfaces_of", "lane_field_rows"]

#: Fields listed one by one up to this many; a longer run of lanes is shown as a
#: formula with its first and last lane.
MAX_LISTED = 6


def _bits(lsb: int, width: int) -> str:
    return f"[{lsb + width - 1}:{lsb}]" if width > 1 else f"[{lsb}]"


def field_rows(fields: Sequence[dict[str, Any]]) -> list[str]:
    """Markdown rows ``| bits | field | width | meaning |`` of payload ``fields`` (each
    ``name``, ``offset``, ``width``, ``desc``), lowest bit first."""
    return [f"| {_bits(f['offset'], f['width'])} | `{f['name']}` | {f['width']} | "
            f"{f['desc']} |" for f in sorted(fields, key=lambda f: f["offset"])]


def lane_field_rows(lanes: int, stride: int, width: int, what: str) -> list[str]:
    """Rows of ``lanes`` equal fields of ``width`` bits every ``stride`` bits (lane
    ``i`` at ``[i*stride +: width]``): each lane if few, else the formula, the first and
    the last lane."""
    def row(i: int) -> str:
        return f"| {_bits(i * stride, width)} | `code{i}` | {width} | {what} of lane {i} |"

    if lanes <= MAX_LISTED:
        rows = [row(i) for i in range(lanes)]
    else:
        rows = [row(0), f"| [{stride}i+{width - 1}:{stride}i] | `code<i>`, i = 0..{lanes - 1} "
                f"| {width} | {what} of lane i: pixel (y, g*{lanes} + i) |", row(lanes - 1)]
    if stride > width:
        pad = f"[{stride}i+{stride - 1}]" if stride - width == 1 else \
            f"[{stride}i+{stride - 1}:{stride}i+{width}]"
        rows.append(f"| {pad} | padding of each lane | "
                    f"{stride - width} | ignored (each code padded to {stride} bits) |")
    return rows


@dataclass(frozen=True)
class Interfaces:
    """Both interfaces of a point at ``P`` lanes: ``geometry`` the streaming array's
    beat geometry (lag, groups, beats per frame, pixel-to-spike cycles, threshold
    words), ``ip_timing`` the IP's timing (its ``ports.json`` ``timing``:
    ``release_cycles``, ``init_cycles``, ...), ``regmap`` its register map and the
    two port maps (with the payloads' bit ``fields``)."""

    geometry: Any
    ip_timing: dict[str, int]
    regmap: Any
    native_ports: list[dict[str, Any]]
    axi_ports: list[dict[str, Any]]

    @property
    def axi_pixel_to_spike(self) -> int:
        """Cycles from a pixel's beat on ``s_axis`` to its spikes on ``m_axis`` (back to
        back, FIFO empty): ``lag + release_cycles``."""
        return self.geometry.lag + self.ip_timing["release_cycles"]


def interfaces_of(contract: ArrayContract, lanes: int, fifo_depth: int) -> Interfaces:
    """:class:`Interfaces` of the streaming array and its AXI IP, from the registry."""
    from rvsm.rtl.architectures.registry import get_architecture

    stream, ip = get_architecture("stream"), get_architecture("stream", "axis")
    opts = ip.resolve({"lanes": lanes, "fifo_depth": fifo_depth})
    with warnings.catch_warnings():  # built to be described, never elaborated
        warnings.simplefilter("ignore", UnusedElaboratable)
        dut = ip.build(contract, **opts)
        timing = ip.describe(dut)["timing"]
        del dut
        gc.collect()
    return Interfaces(stream.beats.geometry(contract, lanes), timing,
                      ip.register_map(contract, **opts),
                      stream.port_map(contract, lanes=lanes), ip.port_map(contract, **opts))


def _port_table(rows: list[dict[str, Any]]) -> list[str]:
    return ["| port | dir | width | meaning |", "|---|---|---|---|",
            *[f"| `{r['name']}` | {r['dir']} | {r['width']} | "
              f"{r['desc'].replace('(fields below)', '(fields in the table below)')} |"
              for r in rows]]


def _payload(title: str, rows: list[str]) -> list[str]:
    return ["", f"{title}:", "", "| bits | field | width | meaning |", "|---|---|---|---|",
            *rows]


def _ports_by_name(rows: list[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    return {r["name"]: r for r in rows}


def _packing_note(native: dict[str, Any], axi: dict[str, Any], c: ArrayContract,
                  axi_code_bits: int) -> str:
    def at(fields: list[dict[str, Any]], name: str) -> str:
        f = next(f for f in fields if f["name"] == name)
        return _bits(f["offset"], f["width"])

    nf, af = native["fields"], axi["fields"]
    return ("**The native and the AXI payloads pack differently.** The native "
            f"`spikes_payload` ({native['width']} bits) has the position first (`row` at "
            f"{at(nf, 'row')}, `group` {at(nf, 'group')}, `last` {at(nf, 'last')}) and "
            f"the spikes above it (`pos` {at(nf, 'pos')}, `neg` {at(nf, 'neg')}); the AXI "
            f"`m_axis_tdata` ({axi['width']} bits) has the spikes first (`pos` "
            f"{at(af, 'pos')}, `neg` {at(af, 'neg')}), then `row` {at(af, 'row')}, "
            f"`group` {at(af, 'group')}, `eof` {at(af, 'eof')}, padded to a byte "
            f"multiple. The input codes differ too: {c.adc_bits} bits a lane natively, "
            f"{axi_code_bits} bits a lane (each code padded) in `s_axis_tdata`.")


def _register_lines(regmap: Any, fifo: int) -> list[str]:
    lines = [f"AXI4-Lite registers of the IP (`--interface axis`, P = {regmap.lanes}, "
             f"output FIFO {fifo} beats; 32-bit, byte offsets, {1 << regmap.addr_bits} B "
             "window; SLVERR for an unmapped address, a partial write, a write to a "
             "read-only field or above a field's maximum):", "",
             "| offset | register | access | reset | meaning |", "|---|---|---|---|---|"]
    lines += [f"| 0x{r.offset:03X} | `{r.name}` | {r.access} | 0x{r.reset:08X} | {r.desc} |"
              for r in regmap.registers]
    lines += ["", "Every register's bit fields (access: `RO` read-only, `RW` read/write, "
              "`W1C` sticky, write 1 to clear, `WO` write 1 to act, reads 0):", "",
              "| register | bits | field | access | reset | meaning |",
              "|---|---|---|---|---|---|"]
    lines += [f"| `{r.name}` | {_bits(f.lsb, f.width)} | `{f.name}` | {f.access} | "
              f"{f.reset if f.reset < 10 else f'0x{f.reset:X}'} | {f.desc} |"
              for r in regmap.registers for f in r.fields]
    return lines


def _sequence_lines(c: ArrayContract, io: Interfaces, clock_hz: float) -> list[str]:
    us, geo = 1e6 / clock_hz, io.geometry
    shared = geo.shared_thresholds
    init = io.ip_timing["init_cycles"]
    thr = (f"one register per scale, configured to {', '.join(map(str, c.shared_thresholds))}"
           if shared else f"{init:,} threshold words, at the top rail "
           f"{(1 << c.threshold_bits) - 1} until written")
    write = ("`thr_addr` = scale s, `thr_data` = its threshold" if shared else
             f"`thr_addr` = (s << word bits) | (y*{geo.groups} + g), `thr_data` = "
             f"{geo.lanes} thresholds")
    return [
        "", "Reset, initialisation and flush (the figures at this point, clock "
        f"{clock_hz / 1e6:.1f} MHz):", "",
        "Native array:", "",
        "1. `rst` (synchronous, active high) is the same as `clear`: the stream restarts "
        "at position 0 and the first frame reads every accumulator as zero; neither "
        f"reloads the thresholds ({thr}).",
        f"2. To change thresholds, write them before the first beat, one per cycle with "
        f"`thr_we` high: {write}.",
        f"3. Stream frames back to back ({geo.beats_per_frame:,} beats a frame). To end a "
        f"recording, send `lag` = {geo.lag} flush beats (any codes; {geo.lag * us:.2f} us), "
        "wait one cycle, then pulse `clear`.",
        "", "AXI IP:", "",
        "1. After `rst` the IP sets the thresholds to "
        + ("their nominal values" if shared else "the top rail")
        + f", one word a cycle: {init:,} cycles ({init * us:.2f} us), with `STATUS.init` "
        "and `STATUS.busy` high and `s_axis_tready` low.",
        "2. Poll `STATUS` until `busy` is 0; check `ID`, `VERSION`, `DIGEST_RTL` and "
        "`DIGEST_POINT` against the `.regs.h` built with the Verilog.",
        "3. Load thresholds if they differ from the nominal ones (`THR_ADDR`, then the "
        "`THR_DATA` registers; the last one commits), set `CONTROL.drop` = 1 for a live "
        "sensor (drop whole output beats rather than stall it), start the video.",
        f"4. To end a stream write `CONTROL` = 0x3 (`clear` | `flush`): the IP inserts "
        f"{geo.lag} zero beats ({geo.lag * us:.2f} us; `STATUS.flushing`, `s_axis_tready` "
        "low) so every accepted beat's output comes out, then clears: the next beat is "
        "frame 0 again."]


def interfaces_lines(contract: ArrayContract, io: Interfaces, fifo_depth: int,
                     clock_hz: float, docs: str) -> list[str]:
    """The section's body (after its title and the state memories); ``docs`` the
    relative path from the page to the project's ``docs/`` folder."""
    c, geo = contract, io.geometry
    native, axi = _ports_by_name(io.native_ports), _ports_by_name(io.axi_ports)
    b = axi["s_axis_tdata"]["width"] // geo.lanes  # each code padded to a byte multiple
    lines = [f"Guides: [integration guide]({docs}/integration.md) (the native interface, "
             f"timing diagrams) and [IP guide]({docs}/ip.md) (the AXI IP, its driver "
             "sequence in C).", "",
             _packing_note(native["spikes_payload"], axi["m_axis_tdata"], c, b), ""]
    lines += _register_lines(io.regmap, fifo_depth)
    lines += ["", "Ports of the bare streaming array (`--interface native`):", "",
              *_port_table(io.native_ports)]
    lines += _payload(f"`codes_payload` ({native['codes_payload']['width']} bits; beats in "
                      f"raster order: frame, row y, group g = 0..{geo.groups - 1})",
                      lane_field_rows(geo.lanes, c.adc_bits, c.adc_bits, "ADC code"))
    lines += _payload(f"`spikes_payload` ({native['spikes_payload']['width']} bits)",
                      field_rows(native["spikes_payload"]["fields"]))
    lines += ["", "Ports of the AXI IP (`--interface axis`):", "",
              *_port_table(io.axi_ports)]
    lines += _payload(f"`s_axis_tdata` ({axi['s_axis_tdata']['width']} bits)",
                      lane_field_rows(geo.lanes, b, c.adc_bits, "ADC code"))
    lines += _payload(f"`m_axis_tdata` ({axi['m_axis_tdata']['width']} bits)",
                      field_rows(axi["m_axis_tdata"]["fields"]))
    lines += _sequence_lines(c, io, clock_hz)
    return lines
