"""How a co-simulation runs, whatever it drives: :class:`RunSettings`, the one parameter
object of :func:`~.verify.verify`, :func:`~.verify.random_verify` and
:func:`~.verify.replay` (simulator, waves, work folder, architecture and its options, the
testbench harness), and the harness rules (:func:`choose_harness`, :func:`check_harness`,
:func:`check_code_coverage`).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.architectures.registry import (
    DEFAULT_ARCHITECTURE,
    architectures_with,
    get_architecture,
)
from rvsm.rtl.capabilities import Architecture
from rvsm.sim.cosim.builds.cocotb_adapter import check_simulator
from rvsm.sim.cosim.long_runs.long_run import DEFAULT_CHUNK_STEPS

if TYPE_CHECKING:
    from rvsm.model.fixed.contract import ArrayContract
    from rvsm.model.fixed.stimulus_chunks import StimulusChunks

#: The testbenches ``rvsm verify --harness`` chooses: per cycle from Python, or the
#: long-run harness (the simulator runs the cycles; streaming array only); ``auto``
#: picks the long-run harness for a streaming run of more than :data:`AUTO_CHUNK_BEATS`
#: input beats, else the per-cycle testbench (:func:`choose_harness`).
HARNESSES = ("auto", "cycle", "chunk")
#: Beats above which ``auto`` takes the long-run harness: the per-cycle testbench runs
#: about 600-15,000 cycles/s, so beyond this a run takes seconds to minutes in it.
AUTO_CHUNK_BEATS = 100_000
#: The work folder when none is given: builds in ``builds/``, runs in ``runs/``.
DEFAULT_WORK = Path("build") / "verify"


@dataclass(frozen=True)
class RunSettings:
    """How a co-simulation runs: simulator ``sim`` (``icarus``/``verilator``), ``waves``
    (keep an FST), ``work_dir`` (shared ``builds/``, one folder per run in ``runs/``), the
    architecture ``arch`` (a registry value) and its ``options`` (e.g. ``lanes``), the
    testbench ``harness`` (:data:`HARNESSES`) and, for the long-run harness, ``progress``
    (a bar on stderr), ``chunk_steps`` (steps per chunk) and ``code_coverage``
    (Verilator line and toggle coverage).

    Built by :meth:`of`, which checks the simulator, the architecture and the harness."""

    sim: str = "icarus"
    waves: bool = False
    work_dir: str | os.PathLike = DEFAULT_WORK
    arch: Architecture = field(default_factory=lambda: get_architecture(DEFAULT_ARCHITECTURE))
    harness: str = "cycle"
    progress: bool = False
    chunk_steps: int = DEFAULT_CHUNK_STEPS
    code_coverage: bool = False
    options: Mapping[str, int | None] = field(default_factory=dict)

    @classmethod
    def of(cls, sim: str = "icarus", **keywords: Any) -> RunSettings:
        """The settings of ``keywords``: the fields above by name (``arch`` a name or a
        registry value), every other keyword an architecture option; :class:`RvsmError`
        for an unknown simulator or harness, or the long-run harness on an architecture
        it does not drive."""
        check_simulator(sim)
        names = {f.name for f in fields(cls)} - {"sim", "options"}
        given = {k: v for k, v in keywords.items() if k in names}
        a = get_architecture(given.pop("arch", DEFAULT_ARCHITECTURE))
        harness = given.get("harness", "cycle")
        check_harness(harness, a)
        return cls(sim=sim, arch=a, options={k: v for k, v in keywords.items()
                                             if k not in names}, **given)

    def keywords(self) -> dict[str, Any]:
        """These settings (``sim`` apart) as the keywords of :func:`~.verify.verify`,
        :func:`~.verify.random_verify` and :func:`~.verify.replay`."""
        named = {f.name: getattr(self, f.name) for f in fields(self)
                 if f.name not in ("sim", "options")}
        return {**named, **self.options}

    def resolve(self, contract: ArrayContract) -> dict[str, int]:
        """The architecture's options (defaults filled in), after its size rule for
        ``contract`` (:class:`RvsmError`)."""
        resolved = self.arch.resolve(self.options)
        self.arch.check(contract, **resolved)
        return resolved

    def choose(self, pixels: int, steps: int, reloadable: bool = True) -> str:
        """The harness for ``pixels * steps`` (``auto`` resolved, :func:`choose_harness`),
        code coverage refused outside the long-run harness on Verilator."""
        harness = choose_harness(self.harness, self.arch, pixels, steps, self.options,
                                 reloadable=reloadable)
        check_code_coverage(self.code_coverage, harness, self.sim)
        return harness

    def check_chunks(self, source: StimulusChunks, name: str) -> dict:
        """:func:`~.long_runs.long_run.check_chunks` of ``source`` in the long-run
        harness."""
        from rvsm.sim.cosim.long_runs.long_run import check_chunks

        return check_chunks(source, self.sim, work_dir=self.work_dir, name=name,
                            arch=self.arch, waves=self.waves, progress=self.progress,
                            chunk_steps=self.chunk_steps, code_coverage=self.code_coverage,
                            **self.options)


def choose_harness(harness: str, arch: str | Architecture, pixels: int, steps: int,
                   options: Mapping, reloadable: bool = True) -> str:
    """``harness``, with ``"auto"`` resolved: ``"chunk"`` for an architecture with a
    long-run harness (the streaming array) when ``pixels * steps / lanes`` (input beats)
    exceeds :data:`AUTO_CHUNK_BEATS` and the stimulus can be opened again in the
    simulator (``reloadable``), else ``"cycle"``."""
    if harness != "auto":
        return harness
    long_run = get_architecture(arch).long_run_testbench is not None
    lanes = int(options.get("lanes") or 1)
    if long_run and reloadable and pixels * steps // lanes > AUTO_CHUNK_BEATS:
        return "chunk"
    return "cycle"


def check_code_coverage(code_coverage: bool, harness: str, sim: str) -> None:
    """Refuse code coverage outside the long-run harness on Verilator."""
    if code_coverage and (harness != "chunk" or sim != "verilator"):
        raise RvsmError("code coverage is built for Verilator runs in the long-run harness: "
                        "use --sim verilator --harness chunk")


def check_harness(harness: str, arch: str | Architecture) -> None:
    """Refuse (:class:`RvsmError`) an unknown harness, or the long-run one for an
    architecture it does not drive."""
    if harness not in HARNESSES:
        raise RvsmError(f"unknown harness {harness!r}; choose one of {', '.join(HARNESSES)}")
    a = get_architecture(arch)
    if harness == "chunk" and a.long_run_testbench is None:
        names = architectures_with(lambda x: x.long_run_testbench)
        raise RvsmError(f"--harness chunk drives the {', '.join(names)} "
                        f"architecture only; use --harness cycle for --arch {a.name}")
