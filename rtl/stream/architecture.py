"""The streaming array as a registered :class:`~rvsm.rtl.capabilities.Architecture`."""

from __future__ import annotations

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.rtl.capabilities import Architecture, Option
from rvsm.rtl.ports import port_map
from rvsm.rtl.stream.array import RvsmStreamArray
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.drive import simulate
from rvsm.rtl.stream.formal_lemmas import composed_equivalence, sum_lemma, window_lemma
from rvsm.rtl.stream.harnesses import PROPERTY_GROUPS, stream_check, stream_equivalence
from rvsm.rtl.stream.schedule import OutputBeats, check_beats

__all__ = ["STREAM", "stream_port_map"]

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
    rows = port_map(RvsmStreamArray.interface(contract, lanes),
                    RvsmStreamArray.port_docs(contract, lanes))
    layout = StreamGeometry(contract, lanes).spike_layout
    for row in rows:
        if row["name"] == "spikes_payload":
            row["fields"] = [{"name": name, "offset": field.offset, "width": field.width,
                              "desc": _FIELD_DESCRIPTIONS[name]} for name, field in layout]
    return rows


def _describe(dut: RvsmStreamArray) -> dict:
    geo = dut.geometry
    return {"timing": geo.timing(), "bank_sizes": geo.bank_sizes,
            "state_bits": geo.state_bits}


def _summary(dut: RvsmStreamArray) -> list[str]:
    c, geo = dut.contract, dut.geometry
    t = geo.timing()
    return [
        f"Array {c.height}x{c.width}, {c.num_scales} scale(s), ADC {c.adc_bits} bits, "
        f"accumulator {c.accumulator_bits} bits ({'signed' if c.signed else 'unsigned'}"
        f" model, reset {c.reset}), shift {c.shift}; {geo.lanes} lane(s), "
        f"{geo.groups} beat(s) per row, {geo.beats_per_frame} per frame.",
        "",
        f"Timing (beats): window lag {t['window_lag']}, pipeline depth "
        f"{t['pipeline_depth']} (latency {t['latency']} cycles back to back), lag "
        f"{t['lag']} (output p follows input beat p + lag; flush with lag beats), "
        f"threshold lag {t['threshold_lag']}, read-modify-write depth {t['rmw_depth']}.",
    ]


def _notes(dut: RvsmStreamArray) -> list[str]:
    geo = dut.geometry
    s = geo.state_bits
    return [f"State memory: accumulators {s['accumulators']} bits, thresholds "
            f"{s['thresholds']} bits, line buffer {s['line_buffer']} bits; banks of "
            f"{geo.bank_sizes} words per scale and kind.",
            "",
            f"Pixel to spike: output p is presented in the second cycle after input beat "
            f"p + {geo.lag} is accepted ({geo.lag + 1} cycles after the edge accepting "
            f"beat p when beats come back to back). To end a stream send {geo.lag} flush "
            f"beats (any codes), wait one cycle, then clear. Timing diagrams, formulas, "
            f"reset and instantiation: docs/integration.md (the rvsm integration guide)."]


def _check(contract: ArrayContract, lanes: int) -> None:
    StreamGeometry(contract, lanes)  # both sensors: the spike camera and the event sensor


def _compare(contract: ArrayContract, expected: np.ndarray, got: OutputBeats,
             lanes: int) -> dict:
    return check_beats(StreamGeometry(contract, lanes).schedule, expected, got)


STREAM = Architecture(
    name="stream",
    title="streaming array",
    default_top="rvsm_stream_array",
    options=(Option("lanes", 1, "pixels per beat of the streaming array (divides the "
                    "width)"),),
    build=RvsmStreamArray,
    check=_check,
    pixels_per_clock=lambda contract, lanes: lanes,
    port_map=stream_port_map,
    describe=_describe,
    summary=_summary,
    notes=_notes,
    simulate=simulate,
    compare=_compare,
    testbench="rvsm.sim.cosim.testbenches.tb_stream",
    formal={**{group: stream_check(group) for group in PROPERTY_GROUPS},
            "equivalence": stream_equivalence, "window": window_lemma, "sums": sum_lemma,
            "composed": composed_equivalence},
)
