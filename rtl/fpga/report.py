"""What ``rvsm fpga`` reports: parsed tool outputs and the :class:`FpgaReport`.

* :func:`parse_yosys_stat` reads ``stat -json`` after ``synth_ecp5``: ECP5 cell counts and
  LUT4 sites (``LUT4 + 2 * CCU2C + 4 * TRELLIS_DPR16X4``: a carry cell fills two LUT4
  sites, a 16x4 distributed RAM four) -- the synthesis-only area.
* :func:`parse_nextpnr_report` reads nextpnr's ``--report`` JSON: ``fmax`` (MHz, the
  slowest clock), ``utilization`` (``TRELLIS_COMB`` = LUT4 sites incl. carry and RAM
  halves, ``TRELLIS_FF``, ``DP16KD``) and the register-to-register critical path.
* :class:`FpgaReport` combines them with the design, the harness overhead, throughput
  (pixel-steps/s = pixels per clock x Fmax; what the sensor camera needs) and the full
  sensor's state memory; :meth:`FpgaReport.to_json` and :meth:`FpgaReport.table`.
"""

from __future__ import annotations

import json
import re
from dataclasses import asdict, dataclass, field
from typing import Any

from rvsm.model.infra.errors import ToolError
from rvsm.rtl.fpga.board_flow import board_lines
from rvsm.rtl.fpga.camera import (
    CAMERA_STEP_HZ,
    StateMemory,
    clock_needed_hz,
    cycles_per_step,
    lanes_needed,
)
from rvsm.rtl.fpga.devices import Device

__all__ = [
    "CriticalPath",
    "FpgaReport",
    "LaneSlope",
    "Usage",
    "parse_nextpnr_report",
    "parse_yosys_stat",
]


@dataclass(frozen=True)
class Usage:
    """Used and available count of one resource."""

    used: int
    available: int

    @property
    def percent(self) -> float:
        """``100 * used / available``."""
        return 100.0 * self.used / self.available if self.available else 0.0


def parse_yosys_stat(data: dict) -> dict[str, Any]:
    """``stat -json`` after ``synth_ecp5`` -> ``{"cells": {type: n}, "lut4", "ff", "bram"}``.

    Raises :class:`ToolError` if the JSON has no design statistics.
    """
    design = data.get("design")
    if design is None:
        modules = data.get("modules") or {}
        if len(modules) != 1:
            raise ToolError("yosys statistics hold no flattened design")
        design = next(iter(modules.values()))
    cells = {k: int(v) for k, v in design.get("num_cells_by_type", {}).items()
             if not k.startswith("$scopeinfo")}
    lut4 = cells.get("LUT4", 0) + 2 * cells.get("CCU2C", 0) \
        + 4 * cells.get("TRELLIS_DPR16X4", 0)
    return {"cells": cells, "lut4": lut4, "ff": cells.get("TRELLIS_FF", 0),
            "bram": cells.get("DP16KD", 0)}


@dataclass(frozen=True)
class CriticalPath:
    """nextpnr's worst register-to-register path: ends, delays (ns) and nets.

    ``start`` is the first net (the launching register's output bit), ``end`` the
    capturing cell (``reg (FF)`` for a flip-flop of register ``reg``); ``nets`` the
    routed nets with non-zero delay, in path order.
    """

    start: str
    end: str
    delay_ns: float
    logic_ns: float
    routing_ns: float
    logic_steps: int
    nets: tuple[str, ...]

    def summary(self) -> str:
        """One line: ``start -> end: 8.1 ns (logic 3.0, routing 5.1; 7 logic steps)``."""
        return (f"{self.start} -> {self.end}: {self.delay_ns:.2f} ns (logic "
                f"{self.logic_ns:.2f}, routing {self.routing_ns:.2f}; {self.logic_steps} "
                "logic steps)")


def _critical_path(paths: list[dict]) -> CriticalPath | None:
    """The longest clock-to-same-clock path in nextpnr's ``critical_paths``."""
    best = None
    for p in paths:
        src, dst = str(p.get("from", "")), str(p.get("to", ""))
        if not (src.startswith("posedge") or src.startswith("negedge")) or src != dst:
            continue
        steps = p.get("path", [])
        delay = sum(float(s.get("delay", 0.0)) for s in steps)
        if best is None or delay > best[0]:
            best = (delay, steps)
    if best is None or not best[1]:
        return None
    delay, steps = best
    logic = sum(float(s.get("delay", 0.0)) for s in steps if s.get("type") != "routing")
    first_net = next((str(s["net"]) for s in steps if s.get("type") == "routing"
                      and "net" in s), None)
    return CriticalPath(
        start=first_net or _readable(str(steps[0].get("from", {}).get("cell", "?"))),
        end=_readable(str(steps[-1].get("to", {}).get("cell", "?"))),
        delay_ns=delay, logic_ns=logic, routing_ns=delay - logic,
        logic_steps=sum(1 for s in steps
                        if s.get("type") == "logic" and float(s.get("delay", 0.0)) > 0),
        nets=tuple(str(s["net"]) for s in steps if s.get("type") == "routing"
                   and "net" in s and float(s.get("delay", 0.0)) > 0),
    )


_FF_CELL = re.compile(r"^(?P<reg>.*?)_TRELLIS_FF_Q(?:_\d+)?$")


def _readable(cell: str) -> str:
    """``a.acc$1_TRELLIS_FF_Q_9`` -> ``a.acc$1 (FF)``: the register a flip-flop belongs to
    (yosys' numeric suffix only makes cell names unique; it is not the bit)."""
    m = _FF_CELL.match(cell)
    return f"{m['reg']} (FF)" if m else cell


def parse_nextpnr_report(data: dict) -> dict[str, Any]:
    """nextpnr ``--report`` JSON -> ``fmax_mhz``, ``clocks``, ``lut4``/``ff``/``bram``
    (:class:`Usage`), ``utilization`` (raw) and ``critical_path`` (or ``None``).

    Raises :class:`ToolError` if the report has no clock or no utilisation.
    """
    fmax = data.get("fmax") or {}
    util = data.get("utilization") or {}
    if not fmax or not util:
        raise ToolError("nextpnr report holds no Fmax or utilisation (no clocked logic?)")
    clocks = {name: float(v["achieved"]) for name, v in fmax.items()}
    constraints = {name: float(v.get("constraint", 0.0)) for name, v in fmax.items()}

    def use(kind: str) -> Usage:
        u = util.get(kind, {"used": 0, "available": 0})
        return Usage(int(u["used"]), int(u["available"]))

    return {
        "fmax_mhz": min(clocks.values()),
        "clocks": clocks,
        "constraints": constraints,
        "lut4": use("TRELLIS_COMB"),
        "ff": use("TRELLIS_FF"),
        "bram": use("DP16KD"),
        "utilization": {k: {"used": int(v["used"]), "available": int(v["available"])}
                        for k, v in util.items()},
        "critical_path": _critical_path(data.get("critical_paths") or []),
    }


@dataclass(frozen=True)
class LaneSlope:
    """Logic per lane as the slope between two lane counts (yosys counts, harness
    excluded): ``lanes`` (P1, P2), LUT4 sites (``LUT4 + 2 CCU2C + 4 TRELLIS_DPR16X4``)
    and flip-flops at each, the per-lane slopes and the fixed part at zero lanes."""

    lanes: tuple[int, int]
    lut4: tuple[int, int]
    ff: tuple[int, int]

    @property
    def lut4_per_lane(self) -> float:
        """``(LUT4(P2) - LUT4(P1)) / (P2 - P1)``."""
        return (self.lut4[1] - self.lut4[0]) / (self.lanes[1] - self.lanes[0])

    @property
    def ff_per_lane(self) -> float:
        """``(FF(P2) - FF(P1)) / (P2 - P1)``."""
        return (self.ff[1] - self.ff[0]) / (self.lanes[1] - self.lanes[0])

    @property
    def lut4_fixed(self) -> float:
        """LUT4 at zero lanes: ``LUT4(P1) - P1 * slope``."""
        return self.lut4[0] - self.lanes[0] * self.lut4_per_lane

    @property
    def ff_fixed(self) -> float:
        """Flip-flops at zero lanes."""
        return self.ff[0] - self.lanes[0] * self.ff_per_lane

    def to_dict(self) -> dict[str, Any]:
        """Fields and the derived slopes and fixed parts."""
        return {"lanes": list(self.lanes), "lut4": list(self.lut4), "ff": list(self.ff),
                "lut4_per_lane": self.lut4_per_lane, "ff_per_lane": self.ff_per_lane,
                "lut4_fixed": self.lut4_fixed, "ff_fixed": self.ff_fixed}


@dataclass
class FpgaReport:
    """Area, timing and sensor arithmetic of one array on one ECP5.

    ``lanes`` is pixels per clock (the stream array's P; ``H*W`` for the fully parallel
    array). ``fmax_mhz`` and ``critical_path`` are ``None`` in synthesis-only mode,
    where ``lut4``/``ff``/``bram`` come from yosys instead of nextpnr. Area includes the
    I/O harness (``harness_ff`` exact, ``harness_lut4`` about).
    """

    arch: str
    model: str
    height: int
    width: int
    lanes: int
    device: Device
    speed: int
    target_mhz: float
    mode: str  # "place-and-route" or "synthesis-only"
    lut4: Usage
    ff: Usage
    bram: Usage
    harness_ff: int
    harness_lut4: int
    sensor_height: int
    sensor_width: int
    sensor_state: StateMemory
    fmax_mhz: float | None = None
    critical_path: CriticalPath | None = None
    synth_cells: dict[str, int] = field(default_factory=dict)
    seconds: dict[str, float] = field(default_factory=dict)
    work_dir: str = ""
    netlist: str = "verilog"
    memory: str = "dp16kd"
    seed: int | None = None
    slope: LaneSlope | None = None
    step_hz: float = CAMERA_STEP_HZ
    board: dict[str, Any] | None = None

    @property
    def lut4_per_lane(self) -> float:
        """LUT4 sites divided by the lanes, harness and fixed part included (the slope
        without them is :attr:`slope`, when measured)."""
        return self.lut4.used / self.lanes

    @property
    def pixel_steps_per_s(self) -> float | None:
        """``lanes x Fmax``: pixel-steps per second at Fmax (``None`` without Fmax)."""
        return None if self.fmax_mhz is None else self.lanes * self.fmax_mhz * 1e6

    @property
    def sensor_pixel_steps_per_s(self) -> float:
        """What the sensor needs: ``sensor_height x sensor_width x step_hz``."""
        return self.sensor_height * self.sensor_width * self.step_hz

    @property
    def clock_needed_mhz(self) -> float:
        """Clock the sensor needs with this many lanes (MHz, 100 % duty)."""
        return clock_needed_hz(self.sensor_height, self.sensor_width, self.lanes,
                               self.step_hz) / 1e6

    @property
    def lanes_needed(self) -> int | None:
        """Fewest lanes dividing the sensor width that keep up at Fmax (``None``: none)."""
        if self.fmax_mhz is None:
            return None
        return lanes_needed(self.sensor_height, self.sensor_width, self.fmax_mhz * 1e6,
                            self.step_hz)

    def to_json(self) -> str:
        """The report as one JSON object (derived figures included)."""
        d = asdict(self)
        d["device"] = self.device.name
        for k in ("lut4", "ff", "bram"):
            d[k]["percent"] = round(getattr(self, k).percent, 2)
        d["sensor_state"] = self.sensor_state.to_dict()
        d["sensor_state"]["bram_blocks_at_lanes"] = self.sensor_state.bram_blocks(
            min(self.lanes, self.sensor_width))
        d.update(
            lut4_per_lane=self.lut4_per_lane,
            pixel_steps_per_s=self.pixel_steps_per_s,
            sensor_pixel_steps_per_s=self.sensor_pixel_steps_per_s,
            sensor_cycles_per_step=cycles_per_step(self.sensor_height, self.sensor_width,
                                                   self.lanes),
            sensor_clock_needed_mhz=self.clock_needed_mhz,
            sensor_lanes_needed_at_fmax=self.lanes_needed,
        )
        if self.critical_path is not None:
            d["critical_path"]["summary"] = self.critical_path.summary()
        d["slope"] = self.slope.to_dict() if self.slope is not None else None
        d["sensor_lanes_extrapolated"] = self.lanes_extrapolated
        return json.dumps(d)

    @property
    def lanes_extrapolated(self) -> bool | None:
        """Whether :attr:`lanes_needed` differs from the lanes Fmax was measured at (an
        extrapolation: a wider array routes longer nets); ``None`` without Fmax."""
        need = self.lanes_needed
        return None if self.fmax_mhz is None else need != self.lanes

    def table(self) -> str:
        """Human-readable report (one fact per line)."""
        dev = self.device
        st = self.sensor_state
        sh, sw = self.sensor_height, self.sensor_width
        rows = [
            f"design        {self.arch} array, {self.model}, {self.height}x{self.width}, "
            f"{self.lanes} pixel(s) per clock",
            f"device        {dev.name} ({dev.nextpnr_flag} "
            f"{self.board['package'] if self.board else dev.package}, speed "
            f"{self.speed}), {self.mode}",
        ]
        if self.fmax_mhz is not None:
            ok = "meets" if self.fmax_mhz >= self.target_mhz else "misses"
            seed = f", placer seed {self.seed}" if self.seed is not None else ""
            rows.append(f"Fmax          {self.fmax_mhz:.1f} MHz ({ok} the {self.target_mhz:g} "
                        f"MHz target{seed})")
            rows.append("critical path " + (self.critical_path.summary()
                                            if self.critical_path is not None else
                                            "not in nextpnr's report"))
        else:
            rows.append("Fmax          not measured (synthesis only; area from yosys)")
        src = "nextpnr" if self.mode == "place-and-route" else "yosys"
        rows += [
            f"LUT4          {self.lut4.used:,} / {self.lut4.available:,} "
            f"({self.lut4.percent:.1f} %, {src}); {self.lut4_per_lane:,.0f} per lane with "
            "the fixed part" + ("" if self.slope else " (--slope-lanes: the slope)"),
            f"FF            {self.ff.used:,} / {self.ff.available:,} ({self.ff.percent:.1f} %)",
            f"block RAM     {self.bram.used} / {self.bram.available} DP16KD "
            f"({self.bram.percent:.1f} %), state memories "
            + ("instantiated with the output register" if self.memory == "dp16kd"
               else "inferred by yosys"),
        ]
        if self.board is None:
            rows.append(f"I/O harness   {self.harness_ff:,} FF and about {self.harness_lut4:,} "
                        "LUT4 of the above (LFSR stimulus, XOR-compacted outputs)")
        else:
            rows += board_lines(self.board)
        if self.slope is not None:
            sl = self.slope
            rows.append(
                f"per lane      {sl.lut4_per_lane:,.0f} LUT4 and {sl.ff_per_lane:,.0f} FF "
                f"(slope between P = {sl.lanes[0]} and {sl.lanes[1]}, yosys, harness "
                f"excluded); fixed part {sl.lut4_fixed:,.0f} LUT4 and {sl.ff_fixed:,.0f} FF")
        if self.pixel_steps_per_s is not None:
            rows.append(f"throughput    {self.pixel_steps_per_s:.3g} pixel-steps/s "
                        f"({self.lanes} x {self.fmax_mhz:.1f} MHz)")
        rows.append(
            f"camera        {sh}x{sw} at {self.step_hz / 1e3:g} kHz needs "
            f"{self.sensor_pixel_steps_per_s:.3g} pixel-steps/s; {self.lanes} lane(s): "
            f"{cycles_per_step(sh, sw, self.lanes):,} cycles/step, clock "
            f"{self.clock_needed_mhz:,.1f} MHz")
        if self.fmax_mhz is not None:
            need = self.lanes_needed
            where = (f"the {self.fmax_mhz:.1f} MHz measured at P = {self.lanes}, "
                     f"{self.height}x{self.width}")
            if need is None:
                rows.append(f"              at {where}: more lanes than pixels in a row")
            else:
                rows.append(
                    f"              at {where}: {need} lanes (clock "
                    f"{clock_needed_hz(sh, sw, need, self.step_hz) / 1e6:.1f} MHz)")
                if self.lanes_extrapolated:
                    rows.append(
                        f"              (extrapolated from P = {self.lanes}: {need} lanes "
                        "route longer nets and may not reach this Fmax; place and route "
                        f"--lanes {need} to confirm)")
        holders = st.holders()
        rows += [
            f"sensor state  {sh}x{sw} x {st.num_scales} scales: accumulators "
            f"{st.accumulators / 1e6:.2f} Mbit ({st.accumulator_bits} bits each), "
            f"thresholds {st.thresholds / 1e6:.2f} Mbit ({st.threshold_bits} bits each), "
            f"line buffers {st.line_buffers / 1e3:.1f} Kbit",
            "              " + (
                "fits the block RAM of " + ", ".join(holders) if holders else
                "no ECP5 holds it: block RAM is " + ", ".join(
                    f"{n} {f['bram_bits'] / 1e6:.2f} Mbit ({f['pixels_that_fit']:,} pixels)"
                    for n, f in st.fits().items())),
        ]
        if st.shared_thresholds:
            rows.append("              (threshold.storage = \"shared\": one threshold "
                        "register per scale, no threshold memory)")
        elif st.thresholds_uniform:
            rows.append("              (this point has no fixed-pattern noise: one threshold "
                        "register per scale would replace the threshold memory)")
        return "\n".join(rows)
