"""What the cocotb testbenches (:mod:`.tb_parallel`, :mod:`.tb_stream`,
:mod:`.tb_stream_protocol`) share: their inputs, reading logic vectors with X/Z, the
clock-and-reset sequence, the beat stream of the build's architecture (from the registry,
by the name its port map records), reading output beats into their fields, and writing the
result."""

from __future__ import annotations

import json
import os
from typing import Any

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge

from rvsm.model.fixed.contract import ArrayContract
from rvsm.rtl.architectures.registry import get_architecture
from rvsm.rtl.capabilities import BeatStream
from rvsm.rtl.ports import load_ports_json

#: Clock period of both testbenches (ns); inputs are driven on the falling edge.
CLOCK_NS = 10


def testbench_arg(name: str) -> str:
    """Environment variable ``RVSM_<NAME>`` or plusarg ``+rvsm_<name>=``."""
    plus = cocotb.plusargs.get(f"rvsm_{name}")
    value = plus if isinstance(plus, str) else os.environ.get(f"RVSM_{name.upper()}")
    if not value:
        raise RuntimeError(f"set RVSM_{name.upper()} or +rvsm_{name}=")
    return value


def build_ports() -> dict:
    """The build's port map (``<top>.ports.json``, input ``ports``): its architecture,
    lanes, timing properties and payload bit fields."""
    return load_ports_json(testbench_arg("ports"))


def logic_bits(value: object) -> tuple[int, int]:
    """A logic vector as ``(int with X/Z as 0, mask of X/Z bits)``."""
    s = str(value)
    if set(s) <= {"0", "1"}:
        return int(s, 2), 0
    clean = "".join(ch if ch in "01" else "0" for ch in s)
    xmask = "".join("0" if ch in "01" else "1" for ch in s)
    return int(clean, 2), int(xmask, 2)


async def clock_and_reset(dut: object, idle: tuple[str, ...], clock: bool = True) -> None:
    """Start ``dut.clk`` (unless not ``clock``: a design that makes its own), hold ``rst``
    high with every input in ``idle`` at 0 for two cycles, release ``rst`` on a falling
    edge."""
    clk = dut.clk  # type: ignore[attr-defined]
    if clock:
        cocotb.start_soon(Clock(clk, CLOCK_NS, unit="ns").start())
    dut.rst.value = 1  # type: ignore[attr-defined]
    for name in idle:
        getattr(dut, name).value = 0
    await FallingEdge(clk)
    await FallingEdge(clk)
    dut.rst.value = 0  # type: ignore[attr-defined]


def beat_stream(ports: dict) -> BeatStream:
    """The :class:`~rvsm.rtl.capabilities.BeatStream` of the architecture that made the
    build whose port map is ``ports`` (its ``arch``, looked up in the registry)."""
    arch = get_architecture(ports["arch"])
    if arch.beats is None:
        raise RuntimeError(f"the {arch.name} architecture does not stream beats")
    return arch.beats


def stream_geometry(contract: ArrayContract, ports: dict) -> Any:
    """The beat stream's geometry for ``contract`` with the lanes of the build's port
    map ``ports``; refuses a build whose timing is not this contract's."""
    geo = beat_stream(ports).geometry(contract, int(ports["timing"]["lanes"]))
    if geo.timing() != ports["timing"]:
        raise RuntimeError(f"the build's timing {ports['timing']} is not this contract's "
                           f"{geo.timing()}")
    return geo


class OutputBeats:
    """The output beats a stream testbench reads from ``spikes_payload``, split into the
    payload fields of the build's port map ``ports`` (``row``, ``group``, ``last``,
    ``pos``, ``neg``), and the indices of beats that held X/Z."""

    def __init__(self, ports: dict) -> None:
        by_name = {p["name"]: p for p in ports["ports"]}
        self.fields = {f["name"]: (f["offset"], f["width"])
                       for f in by_name["spikes_payload"]["fields"]}
        self.got: dict[str, list[int]] = {k: [] for k in self.fields}
        self.x_beats: list[int] = []

    def __len__(self) -> int:
        return len(self.got["row"])

    def read(self, payload: object) -> None:
        """Record the beat whose ``spikes_payload`` value is ``payload``."""
        value, xmask = logic_bits(payload)
        if xmask:
            self.x_beats.append(len(self))
        for name, (off, width) in self.fields.items():
            self.got[name].append((value >> off) & ((1 << width) - 1))

    def decoded(self, stream: BeatStream, scales: int, lanes: int) -> Any:
        """The beats as the beat stream's output beats (its ``output_beats.from_words``)."""
        g = self.got
        return stream.output_beats.from_words(g["row"], g["group"], g["last"], g["pos"],
                                              g["neg"], scales, lanes)

    def count_x(self, result: dict, cycles: list[int] | None = None) -> None:
        """Count the beats with X/Z as mismatches of ``result`` (a checker's dict), the
        first of them first (with its cycle, given each beat's cycle ``cycles``)."""
        if not self.x_beats:
            return
        first = self.x_beats[0]
        where = {} if cycles is None else {"cycle": cycles[first]}
        result["mismatches"] += len(self.x_beats)
        result["mismatch_list"].insert(0, {"beat": first, **where, "error":
                                           f"X/Z in {len(self.x_beats)} output beat(s)"})
        result["first_mismatch"] = result["mismatch_list"][0]


def write_result(result: dict, path: str) -> None:
    """Write ``result`` as JSON to ``path``; fail the cocotb test if it has mismatches."""
    with open(path, "w", encoding="utf-8") as f:
        json.dump(result, f)
    assert result["mismatches"] == 0, \
        f"{result['mismatches']} mismatches; first {result['first_mismatch']}"
