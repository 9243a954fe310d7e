"""Does a design point fit a device at a camera's size and rate? Four budgets, each a verdict.

A camera of ``H x W`` pixels at ``rate_hz`` steps/s needs ``H * ceil(W/P) * rate_hz`` Hz at
``P`` lanes (:func:`~rvsm.rtl.fpga.camera.clock_needed_hz`). :func:`assess` takes the
lane counts that divide ``W`` from the fewest up and checks at each:

* **memory**: the state (:class:`~rvsm.rtl.fpga.block_ram.StateLayout`) packs into the
  device's block RAMs in the chosen organisation, counting aspects, ports and lanes in
  wide words (:func:`~rvsm.rtl.fpga.block_ram.pack_state`), and the line buffer into its
  distributed RAM (or block RAM);
* **lut4** and **ff**: the logic at ``P`` lanes, ``base + P * per_lane`` from the lane
  cost model (:mod:`rvsm.rtl.fpga.lane_cost`: ECP5 LUT4 and flip-flops from yosys), the
  LUT4 with the bank read multiplexers and nextpnr's packing factor refit on the full
  sensor's place and route (:func:`~rvsm.rtl.fpga.placed_logic.placed_lut4`) plus the
  line buffer's distributed RAM (4 LUT4 per 16x4), fits ``max_utilisation`` (80 % by
  default: routing headroom) of the device; on other families the ECP5 figures stand in
  for their LUT4 (a proxy, said in the verdict);
* **fmax**: the Fmax at ``P`` reaches the clock the camera needs: the smaller of the
  device's timing model (:class:`~rvsm.rtl.fpga.devices.TimingModel`) and a measured
  place-and-route figure of this point when one is given; no figure: unknown;
* **io**: the ADC codes in and the spikes out at the camera's rate over the package's
  pairs (:func:`~rvsm.rtl.fpga.io_budget.io_plan`: X2 gearing, a clock and a framing
  pair per link, output pairs on true-LVDS drivers, links placed by the pin planner's
  edge-clock rule, :func:`~rvsm.rtl.fpga.pin_plan.edge_clock_placements`);
  unknown on a package without per-bank figures (every family but the ECP5).

The point is feasible at the fewest lanes where all of them hold; otherwise the verdicts are
those at the fewest lanes that meet the clock (without an Fmax figure: the lanes whose
worst excess over the memory, logic and I/O budgets is least, the fewest if several; when no
lane count meets the clock: the most), so a report can say which budget a point breaks
and by how much. With ``camera.clock_hz`` the
lanes are those that clock needs (:func:`~rvsm.rtl.fpga.camera.lanes_needed`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from rvsm.model.infra.errors import RvsmError
from rvsm.model.scene.loaders import parse_size
from rvsm.rtl.fpga.block_ram import StateLayout, StatePacking, pack_state
from rvsm.rtl.fpga.camera import clock_needed_hz, lanes_needed
from rvsm.rtl.fpga.devices import BUDGETS, ESTIMATE_ONLY, DeviceBudget
from rvsm.rtl.fpga.io_budget import SCOPES, IoPlan, io_plan
from rvsm.rtl.fpga.placed_logic import placed_lut4

__all__ = ["DEFAULT_MAX_UTILISATION", "Camera", "Check", "Feasibility", "LogicCost",
           "MeasuredFmax", "assess"]

#: Largest share of a device's LUT4 and flip-flops a point may use (routing headroom).
DEFAULT_MAX_UTILISATION = 0.8


@dataclass(frozen=True)
class Camera:
    """A sensor: ``height x width`` pixels at ``rate_hz`` steps/s; ``clock_hz`` fixes the
    array clock (None: the lanes follow from the Fmax)."""

    height: int
    width: int
    rate_hz: float
    clock_hz: float | None = None

    @classmethod
    def parse(cls, raw: Any, where: str = "camera") -> Camera:
        """From ``{size = "250x400", rate_hz = 40000, clock_mhz = 100}`` (``clock_mhz``
        optional); :class:`RvsmError` naming ``where`` and the field otherwise."""
        if not isinstance(raw, dict):
            raise RvsmError(f"{where} must be a table like "
                            "{ size = \"250x400\", rate_hz = 40000 }")
        extra = set(raw) - {"size", "rate_hz", "clock_mhz"}
        if extra or "size" not in raw or "rate_hz" not in raw:
            raise RvsmError(f"{where} takes size, rate_hz and optionally clock_mhz, got "
                            f"{', '.join(sorted(raw)) or 'nothing'}")
        try:
            h, w = parse_size(str(raw["size"]))
        except RvsmError as exc:
            raise RvsmError(f"{where}.size: {exc}") from None
        rate = raw["rate_hz"]
        if isinstance(rate, bool) or not isinstance(rate, (int, float)) or not rate > 0:
            raise RvsmError(f"{where}.rate_hz must be a number > 0, got {rate!r}")
        clock = raw.get("clock_mhz")
        if clock is not None and (isinstance(clock, bool) or not isinstance(clock, (int, float))
                                  or not clock > 0):
            raise RvsmError(f"{where}.clock_mhz must be a number > 0, got {clock!r}")
        return cls(h, w, float(rate), None if clock is None else float(clock) * 1e6)

    @property
    def pixel_steps_per_s(self) -> float:
        """``H * W * rate_hz``."""
        return self.height * self.width * self.rate_hz

    def text(self) -> str:
        """``"250x400 at 40,000 Hz"`` (and the clock if fixed)."""
        clock = "" if self.clock_hz is None else f", clock {self.clock_hz / 1e6:g} MHz"
        return f"{self.height}x{self.width} at {self.rate_hz:,.0f} Hz{clock}"


@dataclass(frozen=True)
class LogicCost:
    """Logic of the streaming array at ``P`` lanes: ``lut4_base + P * lut4_per_lane``
    LUT4 and ``ff_base + P * ff_per_lane`` flip-flops (ECP5, yosys); ``source`` says
    where the figures come from."""

    lut4_per_lane: float
    lut4_base: float
    ff_per_lane: float
    ff_base: float
    source: str = "lane cost model (yosys synth_ecp5)"

    @classmethod
    def from_record(cls, rec: dict[str, Any], source: str | None = None) -> LogicCost:
        """From a :class:`~rvsm.rtl.fpga.lane_cost.LaneCost` record (``to_dict``)."""
        p1 = rec["lanes"][0]
        ff_base = rec["ff"][0] - rec["ff_per_lane"] * p1
        return cls(float(rec["lut4_per_lane"]), float(rec["lut4_base"]),
                   float(rec["ff_per_lane"]), float(ff_base),
                   source or f"lane cost model (yosys synth_ecp5 at {rec.get('size', '?')}, "
                             f"P = {rec['lanes'][0]} and {rec['lanes'][1]})")


@dataclass(frozen=True)
class MeasuredFmax:
    """A place-and-route Fmax of this point: ``fmax_mhz`` at ``lanes``, from ``source``."""

    fmax_mhz: float
    lanes: int
    source: str


@dataclass(frozen=True)
class Check:
    """One budget's verdict: ``ok`` (None: unknown), the ``figure`` the point needs and
    the ``budget`` the device gives, in ``unit``, and how the figure was obtained."""

    name: str
    ok: bool | None
    figure: float | None
    budget: float | None
    unit: str
    detail: str = ""

    @property
    def over_by(self) -> float | None:
        """``figure / budget - 1`` (positive: over budget), or None."""
        if self.figure is None or not self.budget:
            return None
        return self.figure / self.budget - 1

    def text(self) -> str:
        """``"memory 400 / 208 DP16KD (+92 %)"``."""
        verdict = {True: "ok", False: "BREAKS", None: "unknown"}[self.ok]
        if self.figure is None or self.budget is None:
            nums = f"{_num(self.figure)} / {_num(self.budget)} {self.unit}"
        else:
            nums = (f"{_num(self.figure)} / {_num(self.budget)} {self.unit} "
                    f"({100 * (self.figure / self.budget - 1):+.0f} %)")
        return f"{self.name} {verdict}: {nums}" + (f"; {self.detail}" if self.detail else "")


def _num(v: float | None) -> str:
    if v is None:
        return "?"
    return f"{v:,.0f}" if abs(v) >= 100 or float(v).is_integer() else f"{v:,.1f}"


@dataclass(frozen=True)
class Feasibility:
    """The verdicts of one point on one device for one camera at ``lanes`` lanes."""

    device: str
    camera: Camera
    lanes: int
    clock_needed_hz: float
    organisation: str
    checks: dict[str, Check]
    packing: StatePacking = field(repr=False)
    #: The I/O plan (None: the package has no per-bank figures).
    io: IoPlan | None = field(default=None, repr=False)

    @property
    def feasible(self) -> bool:
        """Every check holds."""
        return all(c.ok is True for c in self.checks.values())

    @property
    def broken(self) -> list[Check]:
        """The checks that fail."""
        return [c for c in self.checks.values() if c.ok is False]

    @property
    def unknown(self) -> list[Check]:
        """The checks without a figure."""
        return [c for c in self.checks.values() if c.ok is None]

    def summary(self) -> str:
        """``"feasible at P = 40"`` or what breaks, with figures."""
        head = f"P = {self.lanes} at {self.clock_needed_hz / 1e6:.1f} MHz"
        dev = self.device + ("" if BUDGETS[self.device].placed else f" ({ESTIMATE_ONLY})")
        if self.feasible:
            io = self.checks.get("io")
            return f"feasible on {dev} at {head}" + (
                f"; I/O {io.figure:,.0f} / {io.budget:,.0f} {io.unit}" if io else "")
        bad = self.broken or self.unknown
        word = "breaks" if self.broken else "unverified"
        return f"{word} on {dev} at {head}: " + "; ".join(c.text() for c in bad)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready verdicts."""
        return {"device": self.device, "status": BUDGETS[self.device].status,
                "camera": self.camera.text(), "lanes": self.lanes,
                "clock_needed_mhz": self.clock_needed_hz / 1e6,
                "organisation": self.organisation, "feasible": self.feasible,
                "checks": {k: {"ok": c.ok, "figure": c.figure, "budget": c.budget,
                               "unit": c.unit, "detail": c.detail}
                           for k, c in self.checks.items()},
                "memories": self.packing.rows(),
                "io": None if self.io is None else self.io.to_dict()}


def _fmax(device: DeviceBudget, lanes: int, measured: MeasuredFmax | None
          ) -> tuple[float | None, str]:
    """The Fmax (MHz) at ``lanes`` and how it was obtained (module docstring)."""
    model = device.timing.fmax_mhz(lanes) if device.timing else None
    if measured is not None and (model is None or measured.fmax_mhz <= model[0]):
        return measured.fmax_mhz, (f"measured: {measured.fmax_mhz:.1f} MHz at P = "
                                   f"{measured.lanes} ({measured.source})"
                                   + ("" if measured.lanes == lanes else
                                      f", taken for P = {lanes}"))
    if model is not None:
        return model[0], f"timing model {device.timing.family} speed {device.timing.speed}: " \
                         f"{model[1]}"
    return None, f"no Fmax model for {device.family} and none measured"


def _io_check(layout: StateLayout, device: DeviceBudget, camera: Camera, core_hz: float,
              package: str | None, io_links: str) -> tuple[Check, IoPlan | None]:
    pk = device.package_io(package)
    if pk.estimate_only:
        return Check("io", None, None, pk.user_io, "pins",
                     f"{pk.name}: no per-bank I/O figures ({pk.source})"), None
    plan = io_plan(layout, camera.rate_hz, pk, core_hz, scope=io_links)
    figure, budget, unit, detail = plan.verdict()
    return Check("io", plan.fits, figure, budget, unit, detail), plan


def _checks_at(layout: StateLayout, device: DeviceBudget, camera: Camera, lanes: int,
               logic: LogicCost | None, measured: MeasuredFmax | None,
               max_utilisation: float, organisation: str, package: str | None = None,
               io_links: str = "side"
               ) -> tuple[dict[str, Check], StatePacking, float, IoPlan | None]:
    need = clock_needed_hz(camera.height, camera.width, lanes, camera.rate_hz)
    sp = pack_state(layout, lanes, device, organisation)
    extra_ok = sp.extra <= device.extra_ram
    lut_ok = device.lutram is None or sp.lutram <= device.lutram.available
    mem_detail = [f"{organisation} organisation"]
    if sp.extra:
        mem_detail.append(f"{sp.extra} / {device.extra_ram} {device.extra_kind.name}")
    if sp.lutram:
        mem_detail.append(f"line buffer {sp.lutram} {device.lutram.name}")
    if sp.unplaceable:
        mem_detail.append(f"no primitive's ports serve {', '.join(sp.unplaceable)}")
    checks = {"memory": Check(
        "memory", sp.bram <= device.bram and extra_ok and lut_ok and not sp.unplaceable,
        sp.bram, device.bram, device.bram_kind.name, ", ".join(mem_detail))}
    if logic is None:
        checks["lut4"] = Check("lut4", None, None, device.lut4 * max_utilisation, "LUT4",
                               "no logic figure (sweep [hardware] off)")
        checks["ff"] = Check("ff", None, None, device.ff * max_utilisation, "FF", "")
    else:
        proxy = "" if device.family == "ecp5" else f"; ECP5 figures as a proxy on {device.family}"
        lut, how = placed_lut4(logic.lut4_base, logic.lut4_per_lane, layout, lanes,
                               sp.lutram_lut4)
        lut_budget = device.lut4 * max_utilisation
        ff = logic.ff_base + lanes * logic.ff_per_lane
        ff_budget = device.ff * max_utilisation
        checks["lut4"] = Check(
            "lut4", lut <= lut_budget, lut, lut_budget, "LUT4",
            f"{how}, {100 * max_utilisation:.0f} % of {device.lut4:,} ({logic.source}; "
            f"placed by rtl/fpga/placed_logic.py{proxy})")
        checks["ff"] = Check(
            "ff", ff <= ff_budget, ff, ff_budget, "FF",
            f"{logic.ff_base:.0f} + {lanes} x {logic.ff_per_lane:.0f} per lane, "
            f"{100 * max_utilisation:.0f} % of {device.ff:,}")
    fmax, how = _fmax(device, lanes, measured)
    checks["fmax"] = Check("fmax", None if fmax is None else fmax * 1e6 >= need,
                           need / 1e6, fmax, "MHz", f"clock needed / Fmax; {how}")
    checks["io"], plan = _io_check(layout, device, camera, camera.clock_hz or need, package,
                                   io_links)
    return checks, sp, need, plan


def assess(layout: StateLayout, device: DeviceBudget, camera: Camera,
           logic: LogicCost | None, *, measured: MeasuredFmax | None = None,
           max_utilisation: float = DEFAULT_MAX_UTILISATION,
           organisation: str = "packed", package: str | None = None,
           io_links: str = "side") -> Feasibility:
    """The :class:`Feasibility` of ``layout`` (at the camera's size) on ``device`` (module
    docstring) in ``package`` (None: the device's default), links placed per ``io_links``
    (:data:`~rvsm.rtl.fpga.io_budget.SCOPES`). ``layout`` must be the camera's size."""
    if (layout.height, layout.width) != (camera.height, camera.width):
        raise RvsmError(f"the state layout is {layout.height}x{layout.width}, the camera "
                        f"{camera.height}x{camera.width}")
    if not 0 < max_utilisation <= 1:
        raise RvsmError(f"max_utilisation must be in (0, 1], got {max_utilisation}")
    if io_links not in SCOPES:
        raise RvsmError(f"io_links must be one of {', '.join(SCOPES)}, got {io_links!r}")
    device.package_io(package)  # an unknown package fails here, naming the choices
    if camera.clock_hz is not None:
        p = lanes_needed(camera.height, camera.width, camera.clock_hz, camera.rate_hz)
        lanes = [p] if p is not None else [camera.width]
    else:
        lanes = [p for p in range(1, camera.width + 1) if camera.width % p == 0]
    results = []
    for p in lanes:
        checks, sp, need, plan = _checks_at(layout, device, camera, p, logic, measured,
                                            max_utilisation, organisation, package, io_links)
        result = Feasibility(device.name, camera, p, need, organisation, checks, sp, plan)
        if result.feasible:
            return result
        results.append(result)
    timed = [r for r in results if r.checks["fmax"].ok is True]
    if timed:
        return timed[0]
    untimed = [r for r in results if r.checks["fmax"].ok is None]
    if untimed:  # the nearest miss: the least worst excess over a budget
        return min(untimed, key=lambda r: max(
            (c.over_by for c in r.checks.values() if c.over_by is not None and c.name != "fmax"),
            default=0.0))
    return results[-1]
