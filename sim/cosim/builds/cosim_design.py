"""What co-simulation builds and what a build is: :class:`CosimDesign` (a registered
architecture, its resolved options, its top; the one place co-simulation chooses what
to build, :func:`cosim_design`) and :class:`SimBuild` (a finished build of the cache,
:mod:`.build_cache`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.architectures.registry import (
    DEFAULT_ARCHITECTURE,
    architectures_with,
    get_architecture,
)
from rvsm.rtl.architectures.verilog import GeneratedVerilog, write_outputs
from rvsm.rtl.capabilities import Architecture
from rvsm.rtl.rtl_digest import rtl_digest
from rvsm.sim.cosim.builds.chunk_harness import HARNESS_TOP

__all__ = ["CosimDesign", "SimBuild", "cosim_design"]


@dataclass(frozen=True)
class CosimDesign:
    """What co-simulation builds: the registered architecture, its resolved options
    (e.g. ``{"lanes": 8}``), the top name and the cocotb testbench module."""

    arch: Architecture
    options: dict[str, int]
    top: str

    def testbench(self, harness: bool = False) -> str:
        """The architecture's cocotb testbench module: per cycle, or in the long-run
        harness (``harness``; :class:`RvsmError` when it has none)."""
        if not harness:
            return self.arch.testbench
        if self.arch.long_run_testbench is None:
            names = architectures_with(lambda a: a.long_run_testbench)
            raise RvsmError(f"the long-run harness drives {', '.join(names)} only, not the "
                            f"{self.arch.name} architecture")
        return self.arch.long_run_testbench

    def write(self, contract: ArrayContract, out: Path
              ) -> tuple[dict[str, Path], GeneratedVerilog]:
        """Write ``<top>.v``, ``<top>.ports.json`` and ``<top>.ports.md`` into ``out``."""
        return write_outputs(contract, out, self.arch, self.top, **self.options)

    def digest(self, contract: ArrayContract) -> str:
        """:func:`rvsm.rtl.rtl_digest.rtl_digest` of this design of ``contract``."""
        return rtl_digest(contract, self.arch.name, self.options)


def cosim_design(arch: str | Architecture = DEFAULT_ARCHITECTURE, top: str | None = None,
                 **options: int | None) -> CosimDesign:
    """The design co-simulated: architecture ``arch`` of the registry with ``options``
    (defaults filled in; an option it does not take is an :class:`RvsmError`) and its
    default top unless ``top``. The one place co-simulation chooses what to build."""
    a = get_architecture(arch)
    return CosimDesign(a, a.resolve(options), top or a.default_top)


@dataclass(frozen=True)
class SimBuild:
    """A finished build: simulator, build directory, top name, Verilog, timings (s), its
    testbench module."""

    sim: str
    build_dir: Path
    top: str
    verilog: Path
    generate_seconds: float
    build_seconds: float
    cached: bool
    test_module: str
    waves: bool = False
    arch: Architecture = field(default_factory=get_architecture)  # a registry value
    options: dict[str, int] = field(default_factory=dict)  # the architecture's options
    harness: bool = False  # built inside the long-run harness (:mod:`.chunk_harness`)

    @property
    def ports_json(self) -> Path:
        """The array's port map ``<array top>.ports.json`` beside its Verilog."""
        return self.verilog.with_suffix(".ports.json")

    @property
    def hdl_top(self) -> str:
        """The simulation's top module: the harness's, or the array's own."""
        return HARNESS_TOP if self.harness else self.top
