"""The streaming array as a registered :class:`~rvsm.rtl.capabilities.Architecture`.

Besides the component and its port map, :data:`STREAM` states the streaming array's
capabilities: its beat stream (:data:`STREAM_BEATS`), its three cocotb testbenches (per
cycle, the long-run harness's, the protocol scripts'), what its ``amaranth.sim`` driver
takes (stalls, paused and running threshold writes), its mutation sites and its formal
harnesses.
"""

from __future__ import annotations

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.rtl.capabilities import (
    Architecture,
    BeatStream,
    MutationSites,
    Option,
    ProtocolScripts,
)
from rvsm.rtl.mutations import mutations_for
from rvsm.rtl.ports import port_map
from rvsm.rtl.stream.array import RvsmStreamArray
from rvsm.rtl.stream.coverage import BorderCoverage
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.rtl.stream.drive import (
    colliding_threshold_writes,
    simulate,
    simulate_with_threshold_writes,
    threshold_writes,
)
from rvsm.rtl.stream.formal_lemmas import composed_equivalence, sum_lemma, window_lemma
from rvsm.rtl.stream.harnesses import PROPERTY_GROUPS, stream_check, stream_equivalence
from rvsm.rtl.stream.protocol import (
    check_script,
    load_script,
    protocol_summary,
    random_script,
    save_script,
    script_coverage,
)
from rvsm.rtl.stream.schedule import OutputBeats, StreamChecker, check_beats, pack_lanes

__all__ = ["STREAM", "STREAM_BEATS", "array_sentence", "stream_port_map"]

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


def array_sentence(dut: RvsmStreamArray | object) -> str:
    """The summary's first sentence of a streaming array (or of a wrapper with its
    ``contract`` and ``geometry``): size, scales, widths, lanes and beats, no full stop."""
    c, geo = dut.contract, dut.geometry
    return (f"{c.height}x{c.width}, {c.num_scales} scale(s), ADC {c.adc_bits} bits, "
            f"accumulator {c.accumulator_bits} bits ({'signed' if c.signed else 'unsigned'}"
            f" model, reset {c.reset}), shift {c.shift}; {geo.lanes} lane(s), "
            f"{geo.groups} beat(s) per row, {geo.beats_per_frame} per frame")


def _summary(dut: RvsmStreamArray) -> list[str]:
    t = dut.geometry.timing()
    return [
        f"Array {array_sentence(dut)}.",
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


def _running_threshold_writes(contract: ArrayContract, codes: np.ndarray,
                              thresholds: np.ndarray, seed: int, top: int,
                              mutation: str | None = None, lanes: int = 1
                              ) -> tuple[np.ndarray, OutputBeats]:
    """Threshold writes below ``top`` while ``codes`` stream back to back, many at the
    edge reading their own word (:func:`~rvsm.rtl.stream.drive.colliding_threshold_writes`,
    seeded): the thresholds each frame reads under the documented rule ``(T, S, H, W)``
    and the output beats."""
    geo = StreamGeometry(contract, lanes)
    writes, frames, _, _ = colliding_threshold_writes(geo, thresholds, len(codes), seed, top)
    got = simulate_with_threshold_writes(contract, lanes, codes, thresholds, writes,
                                         mutation=mutation)
    shape = (contract.num_scales, contract.height, contract.width)
    return np.stack([f.reshape(shape) for f in frames]), got  # words (S, H*G, P) -> pixels


#: The streaming array's beats: input beats of ``lanes`` codes, one output beat per
#: position (the AXI IP around it streams the same beats).
STREAM_BEATS = BeatStream(
    geometry=StreamGeometry,
    threshold_writes=threshold_writes,
    pack_lanes=pack_lanes,
    output_beats=OutputBeats,
    check_beats=check_beats,
    checker=StreamChecker,
    border_coverage=BorderCoverage,
)

#: The formal checks a mutant faces, cheapest first; the compositional proof (window,
#: sums, composed) re-proves what equivalence checks end to end and is not run again.
_MUTANT_CHECKS = ("tail", "protocol", "equivalence", "state", "thresholds")

_NAME = "stream"

STREAM = Architecture(
    name=_NAME,
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
    long_run_testbench="rvsm.sim.cosim.long_runs.tb_stream_chunks",
    beats=STREAM_BEATS,
    protocol=ProtocolScripts(
        testbench="rvsm.sim.cosim.testbenches.tb_stream_protocol",
        random_script=random_script, save=save_script, load=load_script,
        check=check_script, coverage=script_coverage, summary=protocol_summary),
    simulate_keywords=frozenset({"idle_every", "threshold_updates"}),
    running_threshold_writes=_running_threshold_writes,
    # dog2: two signed scales with a surround, so every kernel, padding, sign, lane and
    # reset bug shows at 3x4, and each check takes seconds
    mutation_sites=MutationSites(tuple(mutations_for(_NAME)), formal_size=(3, 4),
                                 formal_model="dog2", formal_checks=_MUTANT_CHECKS),
    # the threshold memories' words and forwarding; shared registers are checked end to
    # end by "equivalence" (every threshold the reference's)
    formal_storage={"thresholds": "per-pixel"},
)
