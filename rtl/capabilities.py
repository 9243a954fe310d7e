"""What an RTL architecture provides: :class:`Architecture`, filled in by each package.

An architecture (the fully parallel array :mod:`rvsm.rtl.parallel`, the streaming array
:mod:`rvsm.rtl.stream`) is one :class:`Architecture` value: how to build its component
from an :class:`~rvsm.model.fixed.contract.ArrayContract` and its options, its default top
name, its size rule, its options, its port documentation, its expected-output check, its
``amaranth.sim`` driver and the name of its cocotb testbench module. The registry
(:mod:`rvsm.rtl.registry`) lists them; every command, the co-simulation and the
FPGA flow look an architecture up there instead of testing its options.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from amaranth.lib import wiring

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.errors import RvsmError
from rvsm.model.kinds.sensor_kind import Output

__all__ = ["Architecture", "Option", "require_spike_sensor"]


@dataclass(frozen=True)
class Option:
    """An integer option of an architecture (a command-line ``--<name>``)."""

    name: str
    default: int
    help: str


@dataclass(frozen=True)
class Architecture:
    """One RTL architecture. Callables take the contract and the options as keywords.

    * ``build(contract, **options)``: the ``wiring.Component`` (call :meth:`component`,
      which applies the size rule first);
    * ``check(contract, **options)``: the size rule, :class:`RvsmError` when the array
      cannot be built (too big, options that do not fit the contract);
    * ``pixels_per_clock(contract, **options)``: pixels the array takes per clock;
    * ``port_map(contract, **options)``: ports in Verilog order (``name, dir, width,
      desc`` and optional bit ``fields``), see :func:`rvsm.rtl.ports.port_map`;
    * ``describe(component)``: extra ``ports.json`` entries (timing, memories);
    * ``summary(component)`` / ``notes(component)``: Markdown lines before / after the
      port table;
    * ``simulate(contract, codes, thresholds, clear_before=(), **options)``: run the
      component in ``amaranth.sim``; its output goes to ``compare``;
    * ``compare(contract, expected, output, **options)``: the expected-output model: the
      contract's spikes ``(T, S, H, W)`` against what the RTL produced; returns
      ``compared``, ``mismatches``, ``first_mismatch``, ``mismatch_list``;
    * ``testbench``: the cocotb testbench module (a name: rtl does not import sim);
    * ``formal``: formal harness factories by check name (``"properties"``,
      ``"equivalence"``): ``factory(contract, mutation=None, **options)`` returns a
      :class:`~rvsm.rtl.formal_harness.FormalHarness` (``rvsm formal``);
    * ``extra_outputs(component, provenance)``: more files for ``rvsm verilog`` beside
      the Verilog, ``{suffix: text}`` with the suffixes of ``extra_suffixes`` (the IP's
      register map, :mod:`rvsm.rtl.ip.architecture`).
    """

    name: str
    title: str
    default_top: str
    options: tuple[Option, ...]
    build: Callable[..., wiring.Component]
    check: Callable[..., None]
    pixels_per_clock: Callable[..., int]
    port_map: Callable[..., list[dict]]
    describe: Callable[[Any], dict]
    summary: Callable[[Any], list[str]]
    notes: Callable[[Any], list[str]]
    simulate: Callable[..., Any]
    compare: Callable[..., dict]
    testbench: str
    formal: Mapping[str, Callable[..., Any]] = field(default_factory=dict)
    extra_outputs: Callable[[Any, Mapping], dict[str, str]] | None = None
    extra_suffixes: tuple[str, ...] = ()

    def resolve(self, given: Mapping[str, int | None] | None = None) -> dict[str, int]:
        """The options from ``given`` (``None`` values: not given), defaults filled in;
        :class:`RvsmError` for an option this architecture does not take."""
        given = {k: v for k, v in (given or {}).items() if v is not None}
        names = [o.name for o in self.options]
        extra = [k for k in given if k not in names]
        if extra:
            takes = ", ".join(f"--{n}" for n in names) or "no options"
            raise RvsmError(f"--{extra[0]} does not apply to --arch {self.name} (it takes "
                            f"{takes})")
        return {o.name: int(given.get(o.name, o.default)) for o in self.options}

    def component(self, contract: ArrayContract, **options: int) -> wiring.Component:
        """The component for ``contract``, after the size rule (:class:`RvsmError`)."""
        self.check(contract, **options)
        return self.build(contract, **options)

    def run(self, contract: ArrayContract, codes: np.ndarray, thresholds: np.ndarray,
            clear_before: tuple[int, ...] = (), **options: int) -> dict:
        """Simulate in ``amaranth.sim`` and compare with :meth:`ArrayContract.run`."""
        expected = contract.run(codes, thresholds, clear_before)
        got = self.simulate(contract, codes, thresholds, clear_before=clear_before,
                            **options)
        return self.compare(contract, expected, got, **options)


def require_spike_sensor(contract: ArrayContract, what: str) -> None:
    """Refuse (:class:`RvsmError`) a contract of the event sensor for ``what`` (e.g. "the
    formal properties"), which is written for the spike camera's accumulators only."""
    if contract.kind.output is not Output.SPIKES:
        raise RvsmError(f"{what} of the event sensor (sensor = {contract.sensor!r}) are not "
                        "written yet: they state the spike camera's accumulator rules; the "
                        "event sensor's RTL is checked by co-simulation (docs/events.md)")
