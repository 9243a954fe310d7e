"""What the cocotb testbenches (:mod:`.tb_parallel`, :mod:`.tb_stream`) share: their inputs,
reading logic vectors with X/Z, the clock-and-reset sequence, and the beat stream of the
build's architecture (from the registry, by the name its port map records)."""

from __future__ import annotations

import os
from typing import Any

import cocotb
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge

from rvsm.model.fixed.contract import ArrayContract
from rvsm.rtl.architectures.registry import get_architecture
from rvsm.rtl.capabilities import BeatStream

#: Clock period of both testbenches (ns); inputs are driven on the falling edge.
CLOCK_NS = 10


def testbench_arg(name: str) -> str:
    """Environment variable ``RVSM_<NAME>`` or plusarg ``+rvsm_<name>=``."""
    plus = cocotb.plusargs.get(f"rvsm_{name}")
    value = plus if isinstance(plus, str) else os.environ.get(f"RVSM_{name.upper()}")
    if not value:
        raise RuntimeError(f"set RVSM_{name.upper()} or +rvsm_{name}=")
    return value


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
