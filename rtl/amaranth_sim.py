"""The one ``amaranth.sim`` harness: a component, a clock on ``sync``, a test bench.

Every ``amaranth.sim`` driver of the arrays (:mod:`rvsm.rtl.parallel.drive`,
:mod:`rvsm.rtl.stream.drive`) and the RTL unit tests run through
:func:`run_simulation`, so the clock and the waveform option are set in one place.
"""

from __future__ import annotations

import os
from collections.abc import Awaitable, Callable

from amaranth.hdl import Elaboratable
from amaranth.sim import Simulator

__all__ = ["CLOCK_PERIOD_S", "run_simulation"]

#: Clock period of the ``sync`` domain in simulation (s): 1 MHz.
CLOCK_PERIOD_S = 1e-6


def run_simulation(
    dut: Elaboratable,
    bench: Callable[..., Awaitable[None]],
    vcd_path: str | os.PathLike | None = None,
) -> None:
    """Simulate ``dut`` with ``bench(ctx)`` (an ``async`` amaranth test bench taking the
    ``SimulatorContext``) until the bench returns, with a :data:`CLOCK_PERIOD_S` clock on
    ``sync`` when the design has that domain; with ``vcd_path`` the waveform is written
    there."""
    sim = Simulator(dut)
    sim.add_clock(CLOCK_PERIOD_S, if_exists=True)  # none for combinational designs
    sim.add_testbench(bench)
    if vcd_path is None:
        sim.run()
    else:
        with sim.write_vcd(str(vcd_path)):
            sim.run()
