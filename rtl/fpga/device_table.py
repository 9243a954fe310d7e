"""The one device list as a table: per device its status, the largest camera it holds and
the full sensor on it, all from the feasibility model (docs/design-space.md renders it).

For each device of :data:`~rvsm.rtl.fpga.devices.BUDGETS` (the names every command
takes), :func:`device_rows` judges the shipped point's design (points/ecp5-85-40khz.toml:
dog2, shared thresholds, 14-bit accumulators; its lane cost
:data:`~rvsm.rtl.fpga.placed_logic.SHIPPED_LANE_COST`) with
:func:`~rvsm.rtl.fpga.feasibility.assess` in the organisation the RTL builds (``"rtl"``):

* **largest camera at the rate** -- the largest ``5k x 8k`` camera (the sensor's 250x400
  aspect, ``k <= K_MAX``) the design holds at ``rate_hz`` with the array clocked at
  ``clock_mhz`` (100 MHz, the shipped point's; the lanes are the fewest that clock needs):
  on a placed-and-routed device every budget holds; on an estimate-only one none breaks
  (its Fmax and I/O are unknown, said in the row); the I/O in the device's package with
  the most user I/O (:func:`package_of`), links per side. ``k`` is found by bisection: a larger
  camera needs more state and more lanes, so once it breaks it stays broken;
* **the full sensor** -- the verdict at 250x400: the lanes and clock where it holds, or
  the budgets it breaks and by how much.

The search over designs (``rvsm sweep``) found the shipped point the best fit of the
ECP5-85 at 250x400 (docs/design-space.md); on the other devices only this design is
judged here.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from rvsm.model.fixed.point_toml import load_point_file
from rvsm.rtl.fpga.block_ram import StateLayout
from rvsm.rtl.fpga.devices import BUDGETS, DeviceBudget
from rvsm.rtl.fpga.feasibility import Camera, Feasibility, LogicCost, assess
from rvsm.rtl.fpga.package_io import PackageIo
from rvsm.rtl.fpga.placed_logic import SHIPPED_LANE_COST

__all__ = ["K_MAX", "SHIPPED_POINT", "DeviceRow", "device_rows", "device_table_markdown",
           "largest_camera", "package_of"]

#: The design judged on every device (path relative to the project's root).
SHIPPED_POINT = "points/ecp5-85-40khz.toml"
#: Largest ``k`` of a ``5k x 8k`` camera tried (``k = 50``: 250x400).
K_MAX = 100
_ROOT = Path(__file__).resolve().parents[2]


@dataclass(frozen=True)
class DeviceRow:
    """One device's row: ``largest`` the verdict at the largest camera held (None: not
    even 5x8), ``full`` the verdict at 250x400."""

    device: DeviceBudget
    largest: Feasibility | None
    full: Feasibility


def _holds(f: Feasibility) -> bool:
    """Every budget holds (placed device) or none breaks (estimate-only device)."""
    return f.feasible if BUDGETS[f.device].placed else not f.broken


def _judge(device: DeviceBudget, height: int, width: int, rate_hz: float,
           clock_mhz: float) -> Feasibility:
    point, _ = load_point_file(_ROOT / SHIPPED_POINT)
    layout = StateLayout.from_contract(point.with_size(height, width).contract())
    return assess(layout, device, Camera(height, width, rate_hz, clock_mhz * 1e6),
                  LogicCost.from_record(SHIPPED_LANE_COST), organisation="rtl",
                  package=package_of(device).name)


def package_of(device: DeviceBudget) -> PackageIo:
    """The device's package with the most user I/O (the one that carries the most links)."""
    return max(device.io, key=lambda p: p.user_io or 0)


def largest_camera(device: DeviceBudget, rate_hz: float = 40_000.0,
                   clock_mhz: float = 100.0, k_max: int = K_MAX) -> Feasibility | None:
    """The verdict at the largest ``5k x 8k`` camera held (module docstring), or None."""
    lo, hi, best = 1, k_max, None
    while lo <= hi:
        k = (lo + hi) // 2
        f = _judge(device, 5 * k, 8 * k, rate_hz, clock_mhz)
        if _holds(f):
            best, lo = f, k + 1
        else:
            hi = k - 1
    return best


def device_rows(rate_hz: float = 40_000.0, clock_mhz: float = 100.0,
                k_max: int = K_MAX) -> list[DeviceRow]:
    """:class:`DeviceRow` of every device of the one list, in its order."""
    return [DeviceRow(dev, largest_camera(dev, rate_hz, clock_mhz, k_max),
                      _judge(dev, 250, 400, rate_hz, clock_mhz)) for dev in BUDGETS.values()]


def _verdict(f: Feasibility) -> str:
    """``"P = 40 at 100.0 MHz"`` or what breaks."""
    head = f"P = {f.lanes} at {f.clock_needed_hz / 1e6:.1f} MHz"
    if _holds(f):
        unknown = ", ".join(c.name for c in f.unknown)
        return head + (f" ({unknown} unknown)" if unknown else "")
    return "breaks " + "; ".join(
        f"{c.name} {c.figure:,.0f} / {c.budget:,.0f} {c.unit}" for c in f.broken)


def _source(dev: DeviceBudget) -> str:
    if dev.name == "ecp5-85":
        return ("feasibility model, refit on this device's place and route of the full "
                "sensor (docs/datasheet-ecp5-85-40khz/results/fpga.json)")
    if dev.placed:
        return "feasibility model; Fmax model of the ECP5-85 (same fabric); rvsm fpga places it"
    return (f"feasibility model only: {dev.tool} chip-database counts, LUT4 and FF from "
            "ECP5 synthesis, no Fmax model")


def device_table_markdown(rows: list[DeviceRow], rate_hz: float = 40_000.0,
                          clock_mhz: float = 100.0) -> list[str]:
    """The table's Markdown lines (docs/design-space.md, "One device list")."""
    lines = [f"| device | status | largest 5:8 camera at {rate_hz:,.0f} Hz, {clock_mhz:g} MHz | "
             "250x400 (the shipped point's design) | source |", "|---|---|---|---|---|"]
    for r in rows:
        big = ("none (not even 5x8)" if r.largest is None else
               f"{r.largest.camera.height}x{r.largest.camera.width}: {_verdict(r.largest)}")
        full = ("holds: " if _holds(r.full) else "") + _verdict(r.full)
        pk = package_of(r.device).package
        lines.append(f"| {r.device.name}{'' if pk.startswith('(') else f' ({pk})'} | "
                     f"{r.device.status} | {big} | {full} | "
                     f"{_source(r.device)} |")
    return lines
