"""What an RTL architecture provides: :class:`Architecture`, filled in by each package.

An architecture (the fully parallel array :mod:`rvsm.rtl.parallel`, the streaming array
:mod:`rvsm.rtl.stream`, the AXI IP around the streaming array :mod:`rvsm.rtl.ip`) is one
:class:`Architecture` value. Besides how to build, describe and simulate its component,
it states every capability the simulation side branches on, so ``rvsm.sim`` never tests
an architecture's name or imports its package:

* its cocotb testbenches (:attr:`Architecture.testbench`, per cycle;
  :attr:`Architecture.long_run_testbench`, the long-run harness);
* its beat stream (:class:`BeatStream`): how codes become input beats and output beats
  are checked, for the testbenches of an array that streams;
* its protocol scripts (:class:`ProtocolScripts`, ``rvsm verify --protocol``);
* what its ``amaranth.sim`` driver can do beyond codes and clears
  (:attr:`Architecture.simulate_keywords`, :attr:`Architecture.running_threshold_writes`);
* its mutation sites (:class:`MutationSites`, ``rvsm mutate``);
* its formal harnesses (:attr:`Architecture.formal`, ``rvsm formal``);
* its wrappers: the interfaces an architecture is offered with (``--interface axis``)
  are registered beside it (:func:`rvsm.rtl.architectures.registry.register`).

The registry (:mod:`rvsm.rtl.architectures.registry`) lists them; every command, the
co-simulation and the FPGA flow look an architecture up there once and pass the value on.
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
from rvsm.rtl.mutations import Mutation

__all__ = ["Architecture", "BeatStream", "MutationSites", "Option", "ProtocolScripts",
           "require_spike_sensor"]


@dataclass(frozen=True)
class Option:
    """An integer option of an architecture (a command-line ``--<name>``, underscores
    as dashes; ``metavar`` names its value in the help, default the initial)."""

    name: str
    default: int
    help: str
    metavar: str | None = None


@dataclass(frozen=True)
class BeatStream:
    """The numbers of an array that streams: codes go in ``lanes`` pixels per beat, each
    output beat carries the spikes of one position (the streaming array and the IP
    around it). Pure functions, no simulator: what the cocotb testbenches and the
    long-run harness's twin need to drive and check such an array.

    * ``geometry(contract, lanes)``: its geometry (``lanes``, ``lag``,
      ``beats_per_frame``, ``schedule``, ``timing()``: the port map's ``timing``);
    * ``threshold_writes(geometry, thresholds)``: ``(address, word)`` writes that load
      thresholds ``(S, H, W)`` through the threshold port;
    * ``pack_lanes(values, bits)``: beats ``(K, lanes)`` as integers, lane 0 lowest;
    * ``output_beats``: the class of received beats (``from_words(rows, groups, last,
      pos, neg, scales, lanes)``, or built from ``(rows, groups, last, spikes)``);
    * ``check_beats(schedule, expected, got)``: received beats against the spikes
      ``(T, S, H, W)`` (``compared``, ``mismatches``, ``first_mismatch``, ...);
    * ``checker(schedule)``: the same check fed a chunk at a time (``expect``,
      ``receive``, ``restart``, ``result``);
    * ``border_coverage(contract, lanes)``: the spikes each lane saw at the image
      borders (``update(spikes)``, ``bins()``).
    """

    geometry: Callable[[ArrayContract, int], Any]
    threshold_writes: Callable[[Any, np.ndarray], list[tuple[int, int]]]
    pack_lanes: Callable[[np.ndarray, int], list[int]]
    output_beats: type
    check_beats: Callable[[Any, np.ndarray, Any], dict]
    checker: Callable[[Any], Any]
    border_coverage: Callable[[ArrayContract, int], Any]


@dataclass(frozen=True)
class ProtocolScripts:
    """Seeded cycle-by-cycle scripts of an array's ports (stalls, clears at any position
    of a frame, threshold writes meeting the read of their word) with their expected
    output beats and cycles: ``rvsm verify --protocol SEED``.

    * ``testbench``: the cocotb module that plays a script (a name: rtl imports no sim);
    * ``random_script(contract, lanes, steps, seed)``: the seeded script;
    * ``save(path, script)`` / ``load(path)``: its file, the testbench's input;
    * ``check(script, got, cycles)``: received beats and their cycles against it;
    * ``coverage(script)``: per scale, the protocol bins it reaches;
    * ``summary(coverage)``: those bins as report lines.
    """

    testbench: str
    random_script: Callable[[ArrayContract, int, int, int], Any]
    save: Callable[[Any, Any], None]
    load: Callable[[Any], Any]
    check: Callable[..., dict]
    coverage: Callable[[Any], list[dict[str, int | None]]]
    summary: Callable[[list[dict[str, int | None]]], list[str]]


@dataclass(frozen=True)
class MutationSites:
    """An architecture's deliberate bugs (:mod:`rvsm.rtl.mutations`, ``rvsm mutate``) and
    where its formal checks catch them: ``mutations`` (the registered ones of this
    architecture), the tiny array ``formal_size`` (H, W) and model ``formal_model``
    (``None``: the point's own) the formal checks run at, and ``formal_checks``: the
    checks a mutant faces, cheapest first (a mutant usually dies in seconds)."""

    mutations: tuple[Mutation, ...]
    formal_size: tuple[int, int]
    formal_model: str | None = None
    formal_checks: tuple[str, ...] = ()


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
      component in ``amaranth.sim``; its output goes to ``compare``. It also takes
      ``mutation=NAME`` (a deliberately broken component) when the architecture has
      ``mutation_sites``. ``simulate_keywords`` names what else
      it takes: ``idle_every`` (the input paused after every k-th beat),
      ``threshold_updates`` (``{frame: thresholds (S, H, W)}`` written while the input
      pauses);
    * ``running_threshold_writes(contract, codes, thresholds, seed, top, mutation=None,
      **options)``: threshold writes while the input streams, many meeting the read of
      their own word; returns the thresholds each frame reads ``(T, S, H, W)`` and the
      output for ``compare`` (``None``: the array cannot be written while it runs);
    * ``compare(contract, expected, output, **options)``: the expected-output model: the
      contract's spikes ``(T, S, H, W)`` against what the RTL produced; returns
      ``compared``, ``mismatches``, ``first_mismatch``, ``mismatch_list``;
    * ``testbench``: its per-cycle cocotb testbench module (a name: rtl imports no sim);
      ``long_run_testbench``: its testbench in the long-run harness (``None``: no long
      runs; the harness needs a ``beats`` stream); ``register_testbench``: the testbench
      that drives its register file against the register model (``None``: no register
      file);
    * ``beats``: its :class:`BeatStream` (``None``: it does not stream);
    * ``protocol``: its :class:`ProtocolScripts` (``None``: none);
    * ``mutation_sites``: its :class:`MutationSites` (``None``: no mutations);
    * ``formal``: formal harness factories by check name (``"properties"``,
      ``"equivalence"``): ``factory(contract, mutation=None, **options)`` returns a
      :class:`~rvsm.rtl.formal_harness.FormalHarness` (``rvsm formal``);
    * ``formal_storage``: check name -> the ``threshold.storage`` it is about (the
      others skip it, :meth:`formal_skip_reason`);
    * ``extra_outputs(component, provenance)``: more files for ``rvsm verilog`` beside
      the Verilog, ``{suffix: text}`` with the suffixes of ``extra_suffixes`` (the IP's
      register map, :mod:`rvsm.rtl.ip.architecture`);
    * ``register_map(contract, **options)``: its register map without building it
      (``None``: no register file).
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
    long_run_testbench: str | None = None
    register_testbench: str | None = None
    register_map: Callable[..., Any] | None = None
    beats: BeatStream | None = None
    protocol: ProtocolScripts | None = None
    simulate_keywords: frozenset[str] = frozenset()
    running_threshold_writes: Callable[..., tuple[np.ndarray, Any]] | None = None
    mutation_sites: MutationSites | None = None
    formal_storage: Mapping[str, str] = field(default_factory=dict)

    def formal_skip_reason(self, check: str, contract: ArrayContract) -> str | None:
        """Why formal check ``check`` does not apply to ``contract`` (``None``: it does):
        a check about one ``threshold.storage`` (:attr:`formal_storage`, e.g. the
        streaming array's threshold memories) on a point with the other."""
        storage = self.formal_storage.get(check)
        if storage is None or storage == contract.threshold_storage:
            return None
        return (f"it checks the {storage} threshold storage; this point has "
                f"threshold.storage = {contract.threshold_storage!r}")

    def takes(self, option: str) -> bool:
        """Whether this architecture has the option called ``option``."""
        return any(o.name == option for o in self.options)

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

    def resolve_own(self, given: Mapping[str, int | None]) -> dict[str, int]:
        """:meth:`resolve` of the options in ``given`` that this architecture takes (the
        others ignored: one setting for several architectures, e.g. ``rvsm mutate``'s
        ``--lanes``)."""
        return self.resolve({k: v for k, v in given.items() if self.takes(k)})

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
