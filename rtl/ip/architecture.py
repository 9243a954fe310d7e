"""The AXI IP as an :class:`~rvsm.rtl.capabilities.Architecture` value: a wrapper.

:data:`STREAM_AXIS` is what ``rvsm verilog --interface axis`` generates: the streaming
array inside :class:`~rvsm.rtl.ip.wrapper.RvsmAxisIp`, options ``lanes`` and
``fifo_depth``, its port map derived from the IP's signature (with the bit fields of
both ``tdata`` s), and the register-map files beside the Verilog
(:attr:`Architecture.extra_outputs`: ``<top>.regs.md``, ``.regs.json``, ``.regs.h``).
Its beats are the streaming array's (:data:`~rvsm.rtl.stream.architecture.STREAM_BEATS`);
its testbench drives them through cocotbext-axi. The registry offers it as the ``axis``
interface of the streaming array (``get_architecture("stream", "axis")``), not as an
``--arch`` choice: the IP is an interface around an architecture, not an array of its
own.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.capabilities import Architecture, Option
from rvsm.rtl.ip.axi_lite import AxiLiteSignature
from rvsm.rtl.ip.axis import spike_tdata_layout, video_lane_bits
from rvsm.rtl.ip.drive import decode_output, simulate_ip
from rvsm.rtl.ip.register_harness import ip_registers
from rvsm.rtl.ip.register_map import regs_c_header, regs_json, regs_markdown
from rvsm.rtl.ip.wrapper import IP_ARCH, RvsmAxisIp, ip_regmap
from rvsm.rtl.ports import port_map
from rvsm.rtl.stream.architecture import STREAM_BEATS, array_sentence
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.schedule import OutputBeats, check_beats

__all__ = ["STREAM_AXIS", "ip_port_map"]

_AXIL = {
    "awaddr": "write address (byte address; registers are 32-bit words)",
    "awprot": "write protection type (ignored)",
    "awvalid": "write address valid", "awready": "write address ready",
    "wdata": "write data", "wstrb": "write strobes (0xF: a partial write answers SLVERR)",
    "wvalid": "write data valid", "wready": "write data ready",
    "bresp": "write response: OKAY (0) or SLVERR (2)", "bvalid": "write response valid",
    "bready": "write response ready",
    "araddr": "read address (byte address)", "arprot": "read protection type (ignored)",
    "arvalid": "read address valid", "arready": "read address ready",
    "rdata": "read data", "rresp": "read response: OKAY (0) or SLVERR (2)",
    "rvalid": "read data valid", "rready": "read data ready",
}

_OUT_FIELDS = {
    "pos": "+1 spikes: bit s*P + i = accumulator (s, y, g*P + i)",
    "neg": "-1 spikes, same ordering (always 0 for unsigned models)",
    "row": "row y of the position",
    "group": "column group g of the position (columns g*P .. g*P+P-1)",
    "eof": "last beat of a frame",
    "pad": "zero padding to a byte multiple",
}


def _port_docs(contract: ArrayContract, lanes: int) -> dict[str, str]:
    c, geo = contract, StreamGeometry(contract, lanes)
    p, b, g = geo.lanes, video_lane_bits(c.adc_bits), geo.groups
    docs = {
        "clk": "clock (rising edge); every port is synchronous to it",
        "rst": "synchronous reset, active high: then the thresholds are set to "
               + ("their nominal values" if geo.shared_thresholds else "the top rail")
               + " (STATUS.init) before the input opens",
        "s_axis_tdata": f"{p} ADC codes: lane i = pixel (y, g*{p} + i) at bits "
                        f"[i*{b} +: {c.adc_bits}] (each padded to {b} bits); beats in "
                        f"raster order (frame, row y, group g = 0..{g - 1})",
        "s_axis_tvalid": "input beat valid", "s_axis_tready": "the IP takes the beat",
        "s_axis_tuser": "start of frame (first beat of a frame); checked: STATUS.framing",
        "s_axis_tlast": "end of line (beat g = G-1 of a row); checked: STATUS.framing",
        "m_axis_tdata": "one output beat (fields below): spikes of the beat's S*P "
                        "accumulators and its position",
        "m_axis_tvalid": "output beat valid", "m_axis_tready": "the sink takes the beat",
        "m_axis_tuser": "start of frame (position row 0, group 0)",
        "m_axis_tlast": "end of line (group G-1)",
    }
    docs.update({f"s_axil_{k}": v for k, v in _AXIL.items()})
    return docs


def ip_port_map(contract: ArrayContract, lanes: int,
                fifo_depth: int = RvsmAxisIp.FIFO_DEPTH) -> list[dict]:
    """Top-level ports from the IP's signature (:func:`rvsm.rtl.ports.port_map`); both
    ``tdata`` s list their bit ``fields``."""
    c, geo = contract, StreamGeometry(contract, lanes)
    rows = port_map(RvsmAxisIp.interface(contract, lanes), _port_docs(contract, lanes))
    b = video_lane_bits(c.adc_bits)
    layout = spike_tdata_layout(c.num_scales, geo.lanes, c.height, geo.groups)
    for row in rows:
        if row["name"] == "s_axis_tdata":
            row["fields"] = [{"name": f"code{i}", "offset": i * b, "width": c.adc_bits,
                              "desc": f"ADC code of lane {i}"} for i in range(geo.lanes)]
        elif row["name"] == "m_axis_tdata":
            row["fields"] = [{"name": name, "offset": f.offset, "width": f.shape.width,
                              "desc": _OUT_FIELDS[name]} for name, f in layout]
    return rows


def _check(contract: ArrayContract, lanes: int, fifo_depth: int) -> None:
    StreamGeometry(contract, lanes)
    if not RvsmAxisIp.MIN_FIFO_DEPTH <= fifo_depth < 1 << 16:
        raise RvsmError(f"--fifo-depth must be from {RvsmAxisIp.MIN_FIFO_DEPTH} to 65535, "
                        f"got {fifo_depth}")


def _describe(dut: RvsmAxisIp) -> dict:
    geo = dut.geometry
    # one latency: the IP's (the top-level "latency" of ports.json); the array's inside it
    # keeps its own name
    array = geo.timing()
    timing = {**array, "latency": dut.latency, "array_latency": array["latency"],
              "fifo_depth": dut.fifo_depth,
              "release_cycles": dut.RELEASE_CYCLES, "init_cycles": dut.init_cycles,
              "full_rate_depth": dut.FULL_RATE_DEPTH}
    return {"timing": timing, "bank_sizes": geo.bank_sizes, "state_bits": geo.state_bits,
            "axil_addr_bits": AxiLiteSignature(dut.regmap.addr_bits).addr_bits}


def _summary(dut: RvsmAxisIp) -> list[str]:
    t = dut.geometry.timing()
    return [
        f"AXI IP around the streaming array: {array_sentence(dut)}; output FIFO "
        f"{dut.fifo_depth} beats.",
        "",
        f"Timing: lag {t['lag']} beats (output p follows input beat p + lag; flush with "
        f"CONTROL.flush), offered on m_axis {dut.RELEASE_CYCLES} cycles after the "
        f"releasing beat is accepted (FIFO empty); latency {dut.latency} cycles back to "
        f"back; {dut.init_cycles} cycles of threshold initialisation after rst. Register "
        "map: <top>.regs.md; guide: docs/ip.md.",
    ]


def _notes(dut: RvsmAxisIp) -> list[str]:
    return [f"Policies (CONTROL.drop): stall (0, reset value) holds s_axis_tready low "
            f"when the FIFO has no room for the beats in flight, so no beat is lost; drop "
            f"(1) keeps s_axis_tready high and drops whole output beats that find the "
            f"FIFO full (STATUS.overflow, DROPPED). One beat per cycle needs a FIFO of at "
            f"least {dut.FULL_RATE_DEPTH} beats."]


def _extra_outputs(dut: RvsmAxisIp, prov: Mapping) -> dict[str, str]:
    from rvsm.rtl.flow_files import header

    top = prov["top"]
    return {".regs.md": header(prov, "<!--") + regs_markdown(dut.regmap, top),
            ".regs.json": regs_json(dut.regmap, {"top": top, "provenance": dict(prov)}),
            ".regs.h": header(prov, "/*") + regs_c_header(dut.regmap, top)}


def simulate_axis(contract: ArrayContract, codes: np.ndarray, thresholds: np.ndarray,
                  clear_before: Sequence[int] = (), lanes: int = 1,
                  fifo_depth: int = RvsmAxisIp.FIFO_DEPTH) -> OutputBeats:
    """The IP in ``amaranth.sim`` (stall policy, sink always ready): every beat
    delivered, for :meth:`Architecture.run`."""
    run = simulate_ip(contract, lanes, codes, thresholds, fifo_depth=fifo_depth,
                      flush="control", clear_before=clear_before)
    return decode_output(run.dut, run.out)[0]


def _compare(contract: ArrayContract, expected: np.ndarray, got: OutputBeats, lanes: int,
             fifo_depth: int) -> dict:
    return check_beats(StreamGeometry(contract, lanes).schedule, expected, got)


STREAM_AXIS = Architecture(
    name=IP_ARCH,
    title="streaming array, AXI4-Stream/AXI4-Lite IP",
    default_top="rvsm_axis_ip",
    options=(Option("lanes", 1, "pixels per beat of the streaming array (divides the "
                    "width)"),
             Option("fifo_depth", RvsmAxisIp.FIFO_DEPTH, "output FIFO depth in beats",
                    metavar="BEATS")),
    build=RvsmAxisIp,
    check=_check,
    pixels_per_clock=lambda contract, lanes, fifo_depth: lanes,
    port_map=ip_port_map,
    describe=_describe,
    summary=_summary,
    notes=_notes,
    simulate=simulate_axis,
    compare=_compare,
    testbench="rvsm.sim.cosim.testbenches.tb_axis",
    register_testbench="rvsm.sim.cosim.testbenches.tb_register_map",
    register_map=ip_regmap,
    extra_outputs=_extra_outputs,
    extra_suffixes=(".regs.md", ".regs.json", ".regs.h"),
    beats=STREAM_BEATS,
    formal={"registers": ip_registers},
)
