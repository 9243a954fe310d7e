"""The fully parallel array as a registered :class:`~rvsm.rtl.capabilities.Architecture`."""

from __future__ import annotations

import numpy as np

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.capabilities import Architecture, MutationSites
from rvsm.rtl.mutations import mutations_for
from rvsm.rtl.parallel.array import RvsmArray
from rvsm.rtl.parallel.drive import compare_spikes, simulate
from rvsm.rtl.parallel.harnesses import parallel_properties
from rvsm.rtl.ports import port_map

__all__ = ["MAX_SIDE", "PARALLEL", "check_size"]

#: Largest side of a fully parallel array that is built (generation time grows with
#: pixels x taps; a full-resolution sensor needs the streaming array).
MAX_SIDE = 64


def check_size(contract: ArrayContract) -> None:
    """The size rule: at most :data:`MAX_SIDE` pixels on each side (either sensor)."""
    if max(contract.height, contract.width) > MAX_SIDE:
        raise RvsmError(
            f"the fully parallel RTL array is limited to {MAX_SIDE}x{MAX_SIDE} pixels "
            f"(larger ones take hours to generate), the design point is "
            f"{contract.height}x{contract.width}; pass --size, e.g. --size 16x16, or "
            "--arch stream")


def _summary(dut: RvsmArray) -> list[str]:
    c = dut.contract
    return [f"Array {c.height}x{c.width}, {c.num_scales} scale(s), ADC {c.adc_bits} bits, "
            f"accumulator {c.accumulator_bits} bits ({'signed' if c.signed else 'unsigned'}"
            f" model, reset {c.reset}), shift {c.shift}; latency {dut.latency} cycle(s)."]


def _compare(contract: ArrayContract, expected: np.ndarray, got: np.ndarray) -> dict:
    return compare_spikes(expected, got)


_NAME = "parallel"

PARALLEL = Architecture(
    name=_NAME,
    title="fully parallel array",
    default_top="rvsm_array",
    options=(),
    build=RvsmArray,
    check=check_size,
    pixels_per_clock=lambda contract: contract.height * contract.width,
    port_map=lambda contract: port_map(RvsmArray.interface(contract),
                                       RvsmArray.port_docs(contract)),
    describe=lambda dut: {},
    summary=_summary,
    notes=lambda dut: [],
    simulate=simulate,
    compare=_compare,
    testbench="rvsm.sim.cosim.testbenches.tb_parallel",
    formal={"properties": parallel_properties},
    # the formal checks of a mutant run at 2x2 with the point's model
    mutation_sites=MutationSites(tuple(mutations_for(_NAME)), formal_size=(2, 2),
                                 formal_checks=("properties",)),
)
