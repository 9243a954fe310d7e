"""Fixtures shared by the whole suite.

- :func:`small_contract`: a factory of small :class:`ArrayContract` s from a model's
  quantised kernels (4-bit ADC by default), for RTL and co-simulation tests.
- :func:`amaranth_sim`: runs an ``amaranth.sim`` test bench on a component; with
  ``pytest --waves DIR`` it also writes one VCD per run into ``DIR`` (named after the
  test), so a failing RTL test can be opened in a waveform viewer.
- :func:`cosim_work` / :func:`rtl_builds`: a work folder per worker and a Verilog build
  cache shared by every pytest-xdist worker of the session.
- :func:`fsm_point` / :func:`fake_tool`: the smallest design point for the FPGA flow, and
  stand-in tool scripts for its failure paths.
- :func:`formal_point`: a tiny design point with narrow widths (2x2, dog2, 2-bit ADC,
  6-bit accumulators, subtract reset) for the formal checks.
- :func:`shell_env`: the environment in which documented shell lines run (README, docs).
- :func:`default_signals`: ``preexec_fn`` for a child a test signals: SIGINT, SIGTERM and
  SIGHUP back to their defaults, so the test does not depend on how pytest was started
  (a background job or ``nohup`` ignores SIGINT or SIGHUP, and children inherit that).
"""

from __future__ import annotations

import dataclasses
import os
import re
import stat
import sys
from collections.abc import Awaitable, Callable
from pathlib import Path

import pytest

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.design_point import DesignPoint, default_design_point
from rvsm.model.fixed.weights import model_contract as weights_model_contract

# The one-line notice of a numba compile (rvsm.model.infra.compile_notice) would add a line to the
# stderr a test checks whenever a kernel is not yet cached: off for the suite and its
# children; tests/model/infra/test_compile_notice.py turns it on where it is the subject.
os.environ["RVSM_COMPILE_NOTICE"] = "0"


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--waves", metavar="DIR", default=None,
                     help="write a VCD of every amaranth.sim run into DIR")


#: A tiny sweep's constraint line and body (two models, one scene at 16x24, syntheses at
#: 4x4): the sweep tests' smallest real run (tests/sim/sweep/).
TINY_SWEEP_HEAD = 'fits = "ecp5-85"\ncamera = { size = "250x400", rate_hz = 40000 }\n'
TINY_SWEEP_BODY = """
[axes]
"array.model" = ["dog1", "dog2"]
[run]
scenes = ["coin"]
size = "16x24"
frames = 3
[hardware]
enabled = true
size = "4x4"
"""


def model_contract(model: str, h: int, w: int, frac_bits: int = 6, acc_bits: int = 10,
                   shift: int = 1, reset: str = "subtract", adc_bits: int = 4) -> ArrayContract:
    """A small contract from ``model``'s quantised kernels (round-half-up weights):
    :func:`rvsm.model.fixed.weights.model_contract`."""
    return weights_model_contract(model, h, w, frac_bits, acc_bits, shift, reset, adc_bits)


@pytest.fixture
def small_contract() -> Callable[..., ArrayContract]:
    """:func:`model_contract`: ``small_contract("dog4", 3, 5, acc_bits=12)``."""
    return model_contract


class AmaranthSim:
    """Runs test benches through :func:`rvsm.rtl.amaranth_sim.run_simulation`."""

    def __init__(self, waves_dir: Path | None, test_name: str) -> None:
        self.waves_dir = waves_dir
        self.test_name = re.sub(r"[^A-Za-z0-9_.-]+", "_", test_name)
        self.runs = 0

    def vcd_path(self) -> Path | None:
        """The next VCD file of this test, or None without ``--waves``."""
        if self.waves_dir is None:
            return None
        self.runs += 1
        self.waves_dir.mkdir(parents=True, exist_ok=True)
        return self.waves_dir / f"{self.test_name}-{self.runs}.vcd"

    def run(self, dut: object, bench: Callable[[object], Awaitable[None]]) -> None:
        """Simulate ``dut`` with ``bench(ctx)`` as its test bench until the bench returns."""
        from rvsm.rtl.amaranth_sim import run_simulation

        run_simulation(dut, bench, self.vcd_path())


@pytest.fixture
def amaranth_sim(request: pytest.FixtureRequest) -> AmaranthSim:
    """An :class:`AmaranthSim` for this test (VCDs with ``pytest --waves DIR``)."""
    waves = request.config.getoption("--waves")
    return AmaranthSim(Path(waves) if waves else None, request.node.name)


@pytest.fixture(scope="session")
def cosim_work(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One co-simulation work folder per worker."""
    return tmp_path_factory.mktemp("cocotb")


@pytest.fixture(scope="session")
def rtl_builds(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Build cache shared by every xdist worker of this session (safe: atomic renames)."""
    base = tmp_path_factory.getbasetemp()
    root = base.parent if base.name.startswith("popen-gw") else base
    return root / "rvsm-builds"


@pytest.fixture
def fsm_point() -> DesignPoint:
    """The default design point with the FSM model: the smallest RTL, for tool flows."""
    return dataclasses.replace(default_design_point(), model="fsm")


#: The tiny design point of the formal checks (``make formal``).
FORMAL_POINT = Path(__file__).parent / "data" / "formal-tiny.toml"


@pytest.fixture
def formal_point_toml() -> Path:
    """The path of the tiny formal design point (:data:`FORMAL_POINT`)."""
    return FORMAL_POINT


@pytest.fixture
def formal_point() -> DesignPoint:
    """``tests/data/formal-tiny.toml``, the point of ``make formal`` (seconds of solver
    time per check): 2x2 pixels, dog2 (two signed scales, negative surround), 2-bit ADC,
    5 fraction bits, shift 1, 6-bit accumulators, reset subtract."""
    from rvsm.model.fixed.point_toml import load_design_point

    return load_design_point(FORMAL_POINT)


@pytest.fixture
def fake_tool() -> Callable[[Path, str], Path]:
    """Factory ``fake_tool(path, body)``: an executable ``/bin/sh`` script at ``path``
    running ``body``, standing in for yosys or nextpnr."""

    def make(path: Path, body: str) -> Path:
        path.write_text("#!/bin/sh\n" + body)
        path.chmod(path.stat().st_mode | stat.S_IXUSR)
        return path

    return make


@pytest.fixture
def shell_env() -> dict[str, str]:
    """``os.environ`` with this interpreter's folder first on ``PATH``, so that ``rvsm`` in
    a shell line is this checkout's console script."""
    return dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}"
                f"{os.environ.get('PATH', '')}")


def default_signals() -> None:
    """In a child before exec: SIGINT, SIGTERM and SIGHUP at their default dispositions."""
    import signal

    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        signal.signal(sig, signal.SIG_DFL)
