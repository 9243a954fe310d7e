"""A sweep's device constraint: which designs fit a device at a camera's size and rate.

A sweep file may say, before its tables::

    fits = "ecp5-85"                                  # or a list of devices
    camera = { size = "250x400", rate_hz = 40000 }    # clock_mhz = 100 fixes the clock
    memory_organisation = "packed"                    # rtl | per-scale | packed (default)
    max_utilisation = 0.8                             # LUT4 / FF share allowed (default)
    package = "CABGA554"                              # default: the device's first
    io_links = "side"                                 # side (default) | bank

:func:`assess_design` checks one design of a results database against each device
(:func:`rvsm.rtl.fpga.feasibility.assess`: its state at the camera's size packed into
the device's block RAMs, its logic at the lanes the rate needs from the sweep's lane
cost, its Fmax from the device's timing model or the sweep's own place and route, its
pixels in and spikes out over the package's pairs);
:func:`fit_markdown` ranks the feasible designs by PSNR cost and says, for each other
one, which budget it breaks and by how much.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any

from rvsm.model.fixed.point_toml import load_point_file, parse_design_point
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.block_ram import ORGANISATIONS, StateLayout
from rvsm.rtl.fpga.camera import clock_needed_hz
from rvsm.rtl.fpga.devices import BUDGETS, get_budget
from rvsm.rtl.fpga.feasibility import (
    DEFAULT_MAX_UTILISATION,
    Camera,
    Feasibility,
    LogicCost,
    MeasuredFmax,
    assess,
)
from rvsm.rtl.fpga.io_budget import SCOPES, IoPlan, io_plan

__all__ = ["CONSTRAINT_KEYS", "FitConstraint", "assess_design", "devices_text",
           "fit_markdown", "parse_constraint", "point_io_plans"]

#: Top-level keys of a sweep file that state the device constraint.
CONSTRAINT_KEYS = ("fits", "camera", "memory_organisation", "max_utilisation", "package",
                   "io_links")


@dataclass(frozen=True)
class FitConstraint:
    """Devices (``fits``) a design must fit at ``camera``, with the state in
    ``organisation`` and at most ``max_utilisation`` of the LUT4 and flip-flops."""

    devices: tuple[str, ...]
    camera: Camera
    organisation: str = "packed"
    max_utilisation: float = DEFAULT_MAX_UTILISATION
    #: The package (None: each device's default) and what one link's clock reaches.
    package: str | None = None
    io_links: str = "side"

    def text(self) -> str:
        """``"ecp5-85 at 250x400 at 40,000 Hz (packed state, 80 % of the logic)"``."""
        pkg = f" in {self.package}" if self.package else ""
        return (f"{', '.join(self.devices)}{pkg} at {self.camera.text()} ({self.organisation} "
                f"state memory, at most {100 * self.max_utilisation:.0f} % of LUT4 and FF, "
                f"I/O links per {self.io_links})")


def parse_constraint(data: dict[str, Any], source: str) -> FitConstraint | None:
    """The constraint in a sweep file's top-level keys (None without ``fits``);
    :class:`RvsmError` naming ``source``, the key and the valid choices otherwise."""
    if "fits" not in data and "camera" not in data:
        for key in CONSTRAINT_KEYS:
            if key in data:
                raise RvsmError(f"{source}: {key} needs fits = \"DEVICE\" and camera = "
                                "{ size = \"HxW\", rate_hz = R }")
        return None
    if "fits" not in data or "camera" not in data:
        raise RvsmError(f"{source}: fits and camera go together: fits = \"ecp5-85\" and "
                        "camera = { size = \"250x400\", rate_hz = 40000 }")
    fits = data["fits"]
    names = [fits] if isinstance(fits, str) else fits
    if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
        raise RvsmError(f"{source}: fits must be a device name or a list of them; choose "
                        f"from: {', '.join(BUDGETS)}")
    for n in names:
        if n not in BUDGETS:
            raise RvsmError(f"{source}: fits: unknown device {n!r}; choose one of: "
                            f"{', '.join(BUDGETS)}")
    camera = Camera.parse(data["camera"], f"{source}: camera")
    org = data.get("memory_organisation", "packed")
    if org not in ORGANISATIONS:
        raise RvsmError(f"{source}: memory_organisation must be one of "
                        f"{', '.join(ORGANISATIONS)}, got {org!r}")
    util = data.get("max_utilisation", DEFAULT_MAX_UTILISATION)
    if isinstance(util, bool) or not isinstance(util, (int, float)) or not 0 < util <= 1:
        raise RvsmError(f"{source}: max_utilisation must be a number in (0, 1], "
                        f"got {util!r}")
    package = data.get("package")
    if package is not None:
        if not isinstance(package, str):
            raise RvsmError(f"{source}: package must be a name like \"CABGA554\"")
        for n in names:
            try:
                get_budget(n).package_io(package)
            except RvsmError as exc:
                raise RvsmError(f"{source}: package: {exc}") from None
    links = data.get("io_links", "side")
    if links not in SCOPES:
        raise RvsmError(f"{source}: io_links must be one of {', '.join(SCOPES)}, got "
                        f"{links!r}")
    return FitConstraint(tuple(dict.fromkeys(names)), camera, org, float(util), package,
                         links)


def _logic(row: dict[str, Any]) -> LogicCost | None:
    rec = row.get("hw_record")
    if not rec:
        return None
    rec = json.loads(rec) if isinstance(rec, str) else rec
    return LogicCost.from_record(rec)


#: (toml, row's hardware fields, constraint) -> verdicts: a report's refusal check and its
#: tables judge the same designs once.
_ASSESSED: dict[tuple, dict[str, Feasibility]] = {}


def assess_design(toml: str, row: dict[str, Any], constraint: FitConstraint
                  ) -> dict[str, Feasibility]:
    """Per device of ``constraint``: the :class:`Feasibility` of the design point
    ``toml`` at the camera's size, with the logic and measured Fmax of its results
    ``row`` (a :meth:`~rvsm.sim.sweep.store.SweepStore.results` row); memoised."""
    key = (toml, *(json.dumps(row.get(k), sort_keys=True) for k in (
        "hw_record", "fmax_mhz", "hw_lanes", "hw_size")), constraint)
    if key not in _ASSESSED:
        if len(_ASSESSED) > 4096:
            _ASSESSED.clear()
        _ASSESSED[key] = _assess(toml, row, constraint)
    return dict(_ASSESSED[key])


def _assess(toml: str, row: dict[str, Any], constraint: FitConstraint
            ) -> dict[str, Feasibility]:
    cam = constraint.camera
    point = parse_design_point(toml, "design").with_size(cam.height, cam.width)
    layout = StateLayout.from_contract(point.contract())
    measured = None
    if row.get("fmax_mhz") is not None and row.get("hw_lanes"):
        lanes = json.loads(row["hw_lanes"]) if isinstance(row["hw_lanes"], str) \
            else row["hw_lanes"]
        measured = MeasuredFmax(float(row["fmax_mhz"]), int(lanes[0]),
                                f"this sweep's place and route at {row.get('hw_size')}")
    logic = _logic(row)
    out = {}
    for name in constraint.devices:
        dev = get_budget(name)
        fam_measured = measured if dev.family == "ecp5" else None  # measured on an ECP5
        out[name] = assess(layout, dev, cam, logic, measured=fam_measured,
                           max_utilisation=constraint.max_utilisation,
                           organisation=constraint.organisation,
                           package=constraint.package, io_links=constraint.io_links)
    return out


def _verdict_cells(f: Feasibility) -> str:
    c = f.checks
    return (f"{f.lanes} | {f.clock_needed_hz / 1e6:.1f} MHz | "
            f"{_ratio(c['memory'])} | {_ratio(c['lut4'])} | {_ratio(c['ff'])} | "
            f"{_ratio(c['fmax'])} | {_ratio(c['io'])}")


def _psnr(d) -> float:
    """Mean PSNR of the fixed twin over a design's runs (dB): the image quality itself,
    where the PSNR cost is only the loss against the design's own float model."""
    return sum(r["psnr_fixed"] for r in d.rows) / len(d.rows)


def _ratio(c) -> str:
    fig = "?" if c.figure is None else f"{c.figure:,.0f}"
    bud = "?" if c.budget is None else f"{c.budget:,.0f}"
    mark = {True: "", False: " **x**", None: " ?"}[c.ok]
    return f"{fig} / {bud}{mark}"


def fit_markdown(designs: list, constraint: FitConstraint) -> list[str]:
    """Markdown lines: per device its budget, the feasible designs ranked by PSNR cost,
    and every other design with the budgets it breaks (``designs``: report summaries
    with ``feasibility`` filled by :func:`assess_design`)."""
    lines = [f"## Fits {constraint.text()}", "",
             "Each design at the fewest lanes P (dividing the width) whose clock "
             "`H * W/P * rate` its Fmax reaches and where its state and logic fit "
             "(rtl/fpga/feasibility.py). Cells are *needed / budget*: DP16KD or the "
             "device's block RAM (the state packed as stated, the line buffer in "
             "distributed RAM where the device has it), LUT4 and FF at P lanes against "
             "the allowed share of the device, clock needed / Fmax in MHz, and the I/O "
             "(pairs used / pairs of the edge-clock banks, or the binding pair count when "
             "it breaks: rtl/fpga/io_budget.py); **x** "
             "marks a broken budget, ? one without a figure. The PSNR cost is against each "
             "design's own float model (a design with fewer scales also loses what its "
             "float model loses: compare the mean PSNR of the fixed twin).", ""]
    head = ("| rank | design | worst \\|cost\\| | mean PSNR | P | clock | block RAM | LUT4 | "
            "FF | clock / Fmax (MHz) | I/O pairs |\n|---|---|---|---|---|---|---|---|---|---|---|")
    for name in constraint.devices:
        dev = get_budget(name)
        lines += [f"### {name} ({dev.status})", "", dev.summary() + ".", "",
                  dev.package_io(constraint.package).summary() + ".", ""]
        ok = sorted((d for d in designs if d.feasibility[name].feasible),
                    key=lambda d: (d.worst_cost, d.label))
        lines += [f"**{len(ok)} of {len(designs)} designs fit.**", ""]
        if ok:
            lines += ["Feasible designs, ranked by PSNR cost:", "", head]
            lines += [f"| {i} | {d.label} | {d.worst_cost:.3f} dB | {_psnr(d):.2f} dB | "
                      f"{_verdict_cells(d.feasibility[name])} |" for i, d in enumerate(ok, 1)]
            best = ok[0]
            lines += ["", f"Best: **{best.label}** ({best.worst_cost:.3f} dB), "
                      f"{best.feasibility[name].summary()}.", "", "```toml",
                      best.toml.rstrip(), "```", ""]
        bad = sorted((d for d in designs if not d.feasibility[name].feasible),
                     key=lambda d: (d.worst_cost, d.label))
        if bad:
            lines += ["Designs that do not fit, and why:", "",
                      "| design | worst \\|cost\\| | mean PSNR | P | clock | block RAM | LUT4 | "
                      "FF | clock / Fmax (MHz) | I/O pairs | breaks |",
                      "|---|---|---|---|---|---|---|---|---|---|---|"]
            for d in bad:
                f = d.feasibility[name]
                why = "; ".join(c.text() for c in (f.broken or f.unknown))
                lines.append(f"| {d.label} | {d.worst_cost:.3f} dB | {_psnr(d):.2f} dB | "
                             f"{_verdict_cells(f)} | {why} |")
            lines.append("")
        memo = (ok or bad)[0].feasibility[name] if (ok or bad) else None
        if memo is not None:
            lines += [f"State memories of {(ok or bad)[0].label} at P = {memo.lanes}:", ""]
            lines += [f"- {r}" for r in memo.packing.rows()] + [""]
    return lines


def point_io_plans(point_file: str, rate_hz: float, package: str | None = None,
                   io_links: str | None = None) -> list[IoPlan]:
    """The I/O plans of a point file at its own size and ``rate_hz`` steps/s, its core
    clock ``[rtl] freq_mhz`` (else the clock its lanes need) on its ``[rtl] device``
    (else the ECP5-85): every package of its part (or ``package``, e.g. an
    ``"LFE5UM5G-85F CABGA381"``), links per bank and per side (or ``io_links``)."""
    point, settings = load_point_file(point_file)
    if not rate_hz > 0:
        raise RvsmError(f"--rate-hz must be > 0, got {rate_hz:g}")
    dev = get_budget(settings.device or "ecp5-85")
    core = (settings.freq_mhz * 1e6 if settings.freq_mhz else
            clock_needed_hz(point.height, point.width, settings.lanes or 1, rate_hz))
    packages = ([dev.package_io(package)] if package else
                [p for p in dev.io if p.part == dev.io[0].part])  # the -5G: same pins
    if any(p.estimate_only for p in packages):
        raise RvsmError(f"{dev.name}: no per-bank I/O figures (estimate only); "
                        "rvsm sweep devices lists the ECP5 packages that have them")
    return [io_plan(point.contract(), rate_hz, p, core, scope=s)
            for p in packages for s in ([io_links] if io_links else SCOPES)]


def devices_text() -> str:
    """One line per device budget (``rvsm sweep devices``), and one per package's I/O."""
    rows = []
    for b in BUDGETS.values():
        rows.append(b.summary() + (f" [{b.notes}]" if b.notes else ""))
        rows += [f"  I/O {p.summary()}" for p in b.io]
    return "\n".join(rows)
