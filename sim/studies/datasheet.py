"""The datasheet of a design point: one Markdown page for a hardware designer choosing a chip.

:func:`build_datasheet` turns a :class:`DatasheetInputs` (the point, the device, the
camera rate, and whatever was measured elsewhere) into the page's Markdown and its
figures, section by section, after a **Summary** table (:mod:`.datasheet_summary`):

1. **Design point** -- every field, and what each costs in state bits at the sensor's
   size (:func:`~rvsm.rtl.fpga.camera.state_memory`: accumulators, thresholds, line
   buffers) and in logic per lane (:mod:`rvsm.rtl.fpga.lane_cost`, or the slope of a
   saved ``rvsm fpga --slope-lanes`` report);
2. **Resources** -- measured by nextpnr (a saved ``rvsm fpga --json``) beside the
   feasibility model's estimate at the sensor's size (:func:`~rvsm.rtl.fpga.feasibility.assess`
   on :mod:`rvsm.rtl.fpga.devices` budgets), each labelled;
3. **Clock** -- Fmax against the clock the camera needs, ``H * W/P * rate``;
4. **Memory map and interfaces** -- the state memories at ``P`` lanes, the AXI4-Lite
   register map of the IP with every bit field, the ports of the bare array and of the
   IP with every payload's bit ranges, the reset, initialisation and flush sequence
   (:mod:`.datasheet_interfaces`);
5. **Board** -- the chip on a board, from a saved ``rvsm fpga --board --json`` report:
   package, links and their rates against the published limit, the pin plan (also
   ``pin_plan.csv``), the timing of every clock, the training and reset sequence and
   the link registers (:mod:`.datasheet_board`); without it, the command that makes it;
6. **Image quality** -- the study of :mod:`rvsm.sim.studies.point_quality` and a picture of
   the reconstructions;
7. **Verification** -- saved ``rvsm verify --json`` and ``rvsm regress --junit`` results,
   "not run" for what is not given.

Every section ends with a "Sources" line naming the code behind its figures and pointing
to the one **Reproduce** section at the end, which has every command whole.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from rvsm.model.fixed.point_toml import to_toml_dict
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.block_ram import StateLayout
from rvsm.rtl.fpga.camera import clock_needed_hz, state_memory
from rvsm.rtl.fpga.feasibility import Camera, Feasibility, LogicCost, MeasuredFmax, assess
from rvsm.sim.studies import datasheet_board as board
from rvsm.sim.studies import datasheet_figures as figs
from rvsm.sim.studies.datasheet_inputs import DatasheetInputs
from rvsm.sim.studies.datasheet_interfaces import Interfaces, interfaces_lines, interfaces_of
from rvsm.sim.studies.datasheet_summary import (
    REPRODUCE,
    margin_text,
    reproduce_lines,
    summary_lines,
)
from rvsm.sim.studies.datasheet_verification import verification_lines

__all__ = ["Datasheet", "DatasheetInputs", "build_datasheet", "logic_of"]

#: The page's file name and its section titles, in order.
PAGE = "datasheet.md"
SECTIONS = ("Design point", "Resources", "Clock", "Memory map and interfaces",
            board.TITLE, "Image quality", "Verification")
#: Before and after them.
FIRST, LAST = "Summary", "Reproduce"


@dataclass
class Datasheet:
    """The page's Markdown, its figures by file name (matplotlib figures) and other
    files beside it by name (text: the board's ``pin_plan.csv``)."""

    markdown: str
    figures: dict[str, Any] = field(default_factory=dict)
    files: dict[str, str] = field(default_factory=dict)


def logic_of(inputs: DatasheetInputs) -> LogicCost | None:
    """The logic model: the slope of the saved ``rvsm fpga --slope-lanes`` report if it
    has one, else the lane cost synthesis, else None."""
    slope = (inputs.fpga or {}).get("slope")
    if isinstance(slope, dict) and "lut4_per_lane" in slope:
        return LogicCost(float(slope["lut4_per_lane"]), float(slope["lut4_fixed"]),
                         float(slope["ff_per_lane"]), float(slope["ff_fixed"]),
                         f"rvsm fpga --slope-lanes ({inputs.fpga_path})")
    if inputs.lane_cost:
        rec = inputs.lane_cost
        (h, w), (p1, p2) = rec["size"], rec["lanes"]
        return LogicCost.from_record(rec, f"lane cost model (yosys synth_ecp5 at {h}x{w}, "
                                          f"P = {p1} and {p2})")
    return None


def _assess(inputs: DatasheetInputs, logic: LogicCost | None) -> Feasibility:
    point = inputs.point_file.point
    h, w = point.shape
    lanes = inputs.lanes or inputs.point_file.lanes
    clock = None
    if lanes is not None:
        if w % lanes:
            raise RvsmError(f"lanes {lanes} must divide the array width {w}")
        clock = clock_needed_hz(h, w, lanes, inputs.rate_hz)  # pins P = lanes
    measured = None
    fp = inputs.fpga
    if fp is not None and fp.get("fmax_mhz") and inputs.device.family == "ecp5":
        measured = MeasuredFmax(float(fp["fmax_mhz"]), int(fp["lanes"]),
                                f"rvsm fpga at {fp['height']}x{fp['width']}")
    shared = point.shared_thresholds
    layout = StateLayout.from_contract(point.contract(), shared_thresholds=shared)
    return assess(layout, inputs.device, Camera(h, w, inputs.rate_hz, clock), logic,
                  measured=measured, organisation=inputs.organisation,
                  package=inputs.point_file.package_on(inputs.device.name))


def _bits(n: float) -> str:
    return f"{n / 1e6:.3f} Mbit" if n >= 1e5 else f"{n / 1e3:.1f} Kbit" if n >= 1e3 \
        else f"{n:.0f} bit"


def sensor_fields(sensor: str) -> list[Any]:
    """The design point's fields a ``sensor`` kind uses: a field documented as
    ``"sensor dvs: ..."`` belongs to that kind alone."""
    from rvsm.model.fixed.point_fields import FIELDS

    def kind_of(doc: str) -> str | None:
        head = doc.split(":", 1)[0]
        return head.split()[1] if head.startswith("sensor ") and " " in head else None

    return [f for f in FIELDS if kind_of(f.doc) in (None, sensor)]


def _point_section(inputs: DatasheetInputs, logic: LogicCost | None,
                   feas: Feasibility) -> list[str]:
    pf, point = inputs.point_file, inputs.point_file.point
    st = state_memory(point.contract())
    s, (h, w) = st.num_scales, point.shape
    shared = point.shared_thresholds
    lines = [f"## {SECTIONS[0]}", "", f"`{pf.path}`: {point.model} "
             f"({point.sensor}), {h}x{w} pixels, {s} scale(s)"
             + (f"; `[rtl]` {', '.join(f'{k} = {v}' for k, v in pf.rtl.items())}"
                if pf.rtl else "") + ". The fields this sensor kind uses:", "",
             "| field | value | meaning |", "|---|---|---|"]
    values = to_toml_dict(point)
    lines += [f"| `{f.path}` | {values[f.section][f.key]} | {f.doc} |"
              for f in sensor_fields(point.sensor) if f.key in values.get(f.section, {})]
    tb = st.threshold_bits
    thr_row = (f"| `threshold.storage` | shared | thresholds: one register per scale, "
               f"S x (A - 1) | {s} x {tb} bit in registers, no memory | 0 (registers) |"
               if shared else
               f"| `threshold.storage` | per-pixel | thresholds S x H x W x (A - 1), "
               f"A - 1 = {tb} | {_bits(st.thresholds)} | {_bits(s * h * w)} per bit of A |")
    per_lane = ("not estimated (no synthesis: see Sources)" if logic is None else
                f"{logic.lut4_per_lane:,.0f} LUT4 and {logic.ff_per_lane:,.0f} FF per "
                f"lane, {logic.lut4_base:,.0f} LUT4 fixed ({logic.source})")
    lines += ["", f"What each choice costs at {h}x{w} ({s} scales, window radius "
              f"L = {st.radius}):", "",
              "| field | value | state it sets | bits | one more step costs |",
              "|---|---|---|---|---|",
              f"| `datapath.accumulator_bits` | {st.accumulator_bits} | accumulators "
              f"S x H x W x A | {_bits(st.accumulators)} | {_bits(s * h * w)} per bit |",
              thr_row,
              f"| `adc.bits` | {st.adc_bits} | line buffers 2L x W x N | "
              f"{_bits(st.line_buffers)} | {_bits(2 * st.radius * w)} per bit |",
              f"| `array.model` | {point.model} | S = {s} scales, L = {st.radius} | "
              f"{_bits(st.total if not shared else st.total - st.thresholds)} in all | "
              f"{_bits(h * w * (st.accumulator_bits + (0 if shared else st.threshold_bits)))}"
              f" per scale |",
              f"| `weights.bits`, `weights.frac_bits` | {point.weight_bits}, "
              f"{point.weight_frac_bits} | logic only | - | {per_lane} |", "",
              f"Block RAM at P = {feas.lanes} ({feas.organisation} organisation, "
              f"{inputs.device.name}): {feas.packing.bram} {inputs.device.bram_kind.name}.",
              "", "Sources: rtl/fpga/camera.py and rtl/fpga/block_ram.py; logic per lane: "
              + ("the saved `rvsm fpga --slope-lanes` report" if inputs.fpga and
                 (inputs.fpga.get("slope") or {}) else
                 "lane_cost (yosys synth_ecp5 at 16x16, P = 1 and 2), as `rvsm sweep` "
                 "measures it" if inputs.lane_cost else
                 "not run (omit --no-synthesis, or give --fpga from `rvsm fpga POINT "
                 "--slope-lanes 2 --json`)") + f"; commands: {REPRODUCE}.", ""]
    return lines


def budget_text(check: Any) -> str:
    """A budget check as a designer reads it: ``fits: 192 of 208 DP16KD, 16 spare (8 %
    of the budget)`` or ``BREAKS: 400 of 208 DP16KD, over by 192 (92 %)``; then its
    detail (how the figure was obtained)."""
    fig, bud, unit = check.figure, check.budget, check.unit
    if fig is None or bud is None:
        text = f"unknown: {check.detail}"
        return text
    if fig <= bud:
        text = (f"fits: {fig:,.0f} of {bud:,.0f} {unit}, {bud - fig:,.0f} spare "
                f"({100 * (bud - fig) / bud:.0f} % of the budget)")
    else:
        text = (f"BREAKS: {fig:,.0f} of {bud:,.0f} {unit}, over by {fig - bud:,.0f} "
                f"({100 * (fig - bud) / bud:.0f} %)")
    return text + (f"; {check.detail}" if check.detail else "")


def _pct(used: float | None, avail: float | None) -> float | None:
    return None if used is None or not avail else 100.0 * used / avail


def _resources_section(inputs: DatasheetInputs, feas: Feasibility) -> tuple[list[str], Any]:
    dev, fp = inputs.device, inputs.fpga
    c = feas.checks
    est = {"LUT4": c["lut4"].figure, "FF": c["ff"].figure, dev.bram_kind.name: c["memory"].figure}
    avail = {"LUT4": dev.lut4, "FF": dev.ff, dev.bram_kind.name: dev.bram}
    meas: dict[str, float | None] = {k: None for k in est}
    if fp is not None:
        meas = {"LUT4": fp["lut4"]["used"], "FF": fp["ff"]["used"],
                dev.bram_kind.name: fp["bram"]["used"]}
    where = (f"measured by nextpnr ({fp.get('mode', '?')}) at {fp['height']}x{fp['width']}, "
             f"P = {fp['lanes']}, on {fp['device']}" if fp else "measured: not given")
    own = inputs.point_file.package_on(dev.name)
    pk = f"; in {own}, the point's [rtl] package (the I/O budget's)" if own else ""
    lines = [f"## {SECTIONS[1]}", "", f"Device {dev.summary()}{pk}.", "",
             f"| resource | measured | estimate (feasibility model) at "
             f"{feas.camera.height}x{feas.camera.width}, P = {feas.lanes} | device | "
             "estimate verdict |", "|---|---|---|---|---|"]
    for k in est:
        m = "not given" if meas[k] is None else f"{meas[k]:,.0f} ({_pct(meas[k], avail[k]):.1f} %)"
        e = "not estimated" if est[k] is None else \
            f"{est[k]:,.0f} ({_pct(est[k], avail[k]):.1f} %)"
        check = {"LUT4": c["lut4"], "FF": c["ff"]}.get(k, c["memory"])
        verdict = budget_text(check) if check.ok is not None else \
            "unknown: no logic figure (see Sources)"
        lines.append(f"| {k} | {m} | {e} | {avail[k]:,} | {verdict} |")
    harness = ("" if not fp or fp.get("harness_lut4") is None else
               f" The measured figures include the I/O harness `rvsm fpga` adds "
               f"({fp['harness_lut4']:,} LUT4 and {fp.get('harness_ff', 0):,} FF by yosys' "
               "count); the estimate is the design's alone.")
    lutram = ("" if not feas.packing.lutram else
              f" The line buffer's {feas.packing.lutram} {dev.lutram.name} are logic sites: "
              f"counted in the LUT4 ({dev.lutram.lut4} each), not in the block RAM.")
    lines += ["", f"Measured column: {where}.{harness}{lutram} The estimate is the "
              "feasibility model (rtl/fpga/feasibility.py): state packed into the device's "
              "block RAM, logic = fixed + P x per lane refit on the full sensor's place and "
              "route (rtl/fpga/placed_logic.py), at most "
              f"{c['lut4'].budget / dev.lut4 * 100 if c['lut4'].budget else 80:.0f} % of "
              "the LUT4 and FF; it is an **estimate**, not a placed design. "
              f"Verdict of the estimate: {feas.summary()}.", "",
              "![resources](resources.png)", "",
              "Sources: measured: " + (f"`rvsm fpga` saved as `{inputs.fpga_path}`" if fp
                                       else "not run (give --fpga FILE.json from `rvsm "
                                       "fpga POINT --json`)")
              + f"; estimate: rtl/fpga/feasibility.py; commands: {REPRODUCE}.", ""]
    rows = [(k, _pct(meas[k], avail[k]), _pct(est[k], avail[k])) for k in est]
    return lines, figs.resources_figure(rows, dev.name)


def _clock_section(inputs: DatasheetInputs, feas: Feasibility) -> tuple[list[str], Any]:
    h, w = inputs.point_file.point.shape
    fmax = feas.checks["fmax"]
    lanes = [p for p in range(1, w + 1) if w % p == 0]
    clocks = [clock_needed_hz(h, w, p, inputs.rate_hz) / 1e6 for p in lanes]
    how = fmax.detail.split("; ", 1)[-1]
    lanes_from = ("--lanes" if inputs.lanes else "[rtl] lanes of the point"
                  if inputs.point_file.lanes else "the fewest lanes that fit")
    lines = [f"## {SECTIONS[2]}", "",
             f"Camera {h}x{w} at {inputs.rate_hz:,.0f} steps/s: clock = H x W/P x rate = "
             f"{h} x {w}/{feas.lanes} x {inputs.rate_hz:,.0f} = "
             f"**{feas.clock_needed_hz / 1e6:.1f} MHz** at P = {feas.lanes} lanes "
             f"({lanes_from}).", "",
             "Fmax: " + ("unknown" if fmax.budget is None else f"**{fmax.budget:.1f} MHz**")
             + f" ({how}); " + {True: "the clock is met", False: "the clock is NOT met",
                                None: "not known whether the clock is met"}[fmax.ok]
             + ("" if fmax.budget is None else ", " + margin_text(
                 fmax.budget, feas.clock_needed_hz / 1e6, "MHz")) + ".", "",
             "| P | clock needed (MHz) |", "|---|---|"]
    near = [i for i, p in enumerate(lanes) if p == feas.lanes]
    idx = sorted(set(range(max(0, near[0] - 3), min(len(lanes), near[0] + 4)))) if near else []
    lines += [f"| {lanes[i]}{' (chosen)' if lanes[i] == feas.lanes else ''} | "
              f"{clocks[i]:.1f} |" for i in idx]
    measured = "the saved `rvsm fpga` report" if inputs.fpga and inputs.fpga.get("fmax_mhz") \
        else "no place and route given: the device's timing model (rtl/fpga/devices.py)"
    lines += ["", "![clock](clock.png)", "",
              f"Sources: Fmax from {measured}; clock from rtl/fpga/camera.py; commands: "
              f"{REPRODUCE}.", ""]
    label = "Fmax" + ("" if fmax.budget is None else f" {fmax.budget:.0f} MHz")
    return lines, figs.clock_figure(lanes, clocks, fmax.budget, feas.lanes, label)


def _interfaces_section(inputs: DatasheetInputs, feas: Feasibility,
                        io: Interfaces) -> list[str]:
    contract = inputs.point_file.point.contract()
    lines = [f"## {SECTIONS[3]}", "", f"State memories at P = {feas.lanes} "
             f"({feas.organisation} organisation) on {inputs.device.name}:", ""]
    lines += [f"- {r}" for r in feas.packing.rows()]
    lines += ["", *interfaces_lines(contract, io, inputs.fifo_depth, feas.clock_needed_hz,
                                    inputs.docs)]
    lines += ["", "Sources: the architectures' port maps and register map, as `rvsm verilog` "
              "writes them beside the Verilog (`ports.json`, `rvsm_axis_ip.regs.md/.json/.h`);"
              f" state memories from rtl/fpga/block_ram.py; commands: {REPRODUCE}.", ""]
    return lines


def _quality_section(inputs: DatasheetInputs) -> tuple[list[str], dict[str, Any]]:
    q = inputs.quality
    h, w = q.size
    out: dict[str, Any] = {"quality_costs.png": figs.costs_figure(q)}
    lines = [f"## {SECTIONS[5]}", "",
             f"PSNR (dB) and SSIM against the ground truth on {len({r.scene for r in q.rows})}"
             f" built-in scene(s) at {h}x{w}, {q.steps_text()}, seed "
             f"{q.point.get('seed')}, {q.method} reconstruction, {q.match} brightness "
             "matching. **Twin against own float**: the fixed twin's PSNR against its own "
             "float model's (what the fixed point costs); **chip against dog4 float**: the "
             "twin's PSNR against the default design point's float model (dog4), what "
             "this chip gives a user instead of the default float model.", ""]
    for noise in (False, True):
        if q.rows_with(noise):
            lines += [f"Noise {'on' if noise else 'off'}:", "", *q.markdown(noise), ""]
    lines += ["![costs per scene](quality_costs.png)", ""]
    if inputs.picture is not None:
        scene, step, images = inputs.picture
        out["reconstructions.png"] = figs.reconstruction_figure(
            images, f"{scene}, step {step}, {h}x{w}, noise off")
        lines += [f"Reconstructions of {scene} at step {step} (noise off): ground truth, "
                  "float dog4, own float, fixed twin.", "",
                  "![reconstructions](reconstructions.png)", ""]
    else:
        lines += ["No reconstruction picture: drawn for spike-camera points only.", ""]
    picture = "; picture: drawn by this page's command" if inputs.picture is not None else ""
    lines += [f"Sources: {inputs.quality_source}{picture}; commands: {REPRODUCE}.", ""]
    return lines, out


def _board_section(inputs: DatasheetInputs) -> list[str]:
    """The Board section (:mod:`.datasheet_board`) of the saved board report, at the
    report's own size."""
    rep, point = inputs.board, inputs.point_file.point
    contract = None if rep is None else point.with_size(rep["height"], rep["width"]).contract()
    return board.board_lines(rep, contract, inputs.point_file.path,
                             inputs.board_path or "FILE.json", REPRODUCE, inputs.docs)


def _anchor(title: str) -> str:
    """The Markdown anchor of a section title (GitHub's rule for plain words)."""
    return "-".join(title.lower().split())


def build_datasheet(inputs: DatasheetInputs) -> Datasheet:
    """The page and its figures (module docstring)."""
    logic = logic_of(inputs)
    feas = _assess(inputs, logic)
    point = inputs.point_file.point
    lines = [f"# Datasheet: {point.model} {point.shape[0]}x{point.shape[1]} on "
             f"{inputs.device.name}", "",
             "Contents: " + ", ".join(f"[{t}](#{_anchor(t)})" for t in (FIRST, *SECTIONS, LAST))
             + f". Every figure's command is in {REPRODUCE}, at the end.", ""]
    io = interfaces_of(point.contract(), feas.lanes, inputs.fifo_depth)
    lines += summary_lines(inputs, feas, io) + _point_section(inputs, logic, feas)
    res, res_fig = _resources_section(inputs, feas)
    clk, clk_fig = _clock_section(inputs, feas)
    lines += res + clk + _interfaces_section(inputs, feas, io) + _board_section(inputs)
    qual, qual_figs = _quality_section(inputs)
    lines += qual + verification_lines(inputs, SECTIONS[6]) + reproduce_lines(inputs, feas.lanes)
    files = {board.CSV_NAME: board.pin_plan_csv(inputs.board)} if inputs.board else {}
    return Datasheet("\n".join(lines), {"resources.png": res_fig, "clock.png": clk_fig,
                                        **qual_figs}, files)
