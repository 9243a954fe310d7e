"""The datasheet's first and last sections: the summary a designer reads first, and the one
"Reproduce" section with every command whole.

:func:`summary_lines` -- one table: device and package, clock and Fmax with its margin,
lanes, throughput, latency, state memory, utilisation, the board build, PSNR against the
float models and what was verified (each row from the figures the page's sections show).

:func:`reproduce_steps` -- for the page and each saved result, the command that makes it
again and where that command comes from: recorded in the result (``command``), given in
the ``--commands`` file (a command the result does not record, reconstructed from the
point and the command the docs quote, with its source; it wins over a recorded one), or
built here from what the result records (labelled so). A command is never cut short with "...".
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from rvsm.rtl.fpga.camera import state_memory
from rvsm.sim.studies.datasheet_inputs import DatasheetInputs
from rvsm.sim.studies.datasheet_interfaces import Interfaces
from rvsm.sim.studies.point_quality import better_or_worse

if TYPE_CHECKING:
    from rvsm.rtl.fpga.feasibility import Feasibility

__all__ = ["ReproduceStep", "margin_text", "reproduce_lines", "reproduce_steps",
           "summary_lines"]

#: The anchor of the Reproduce section (sections link to it).
REPRODUCE = "[Reproduce](#reproduce)"


@dataclass(frozen=True)
class ReproduceStep:
    """One command of the Reproduce section: what it makes, the ``command`` (whole; a
    ``> FILE`` redirection saves its JSON) and ``origin`` (recorded or reconstructed,
    and from what)."""

    what: str
    command: str
    origin: str


def margin_text(have: float, need: float, unit: str) -> str:
    """``15.7 % headroom`` (``have >= need``) or ``short by 8.0 %`` of ``need``."""
    pct = 100.0 * (have - need) / need
    return (f"{pct:.1f} % headroom ({have - need:,.1f} {unit})" if have >= need
            else f"short by {-pct:.1f} % ({need - have:,.1f} {unit})")


def _verify_steps(v: dict[str, Any]) -> str:
    return f"{v['steps']:,} steps" if isinstance(v.get("steps"), int) else "the run"


def _verified(inputs: DatasheetInputs) -> str:
    parts = []
    v = inputs.verify
    if v is not None:
        ok = "0 mismatches" if v["mismatches"] == 0 else f"{v['mismatches']:,} MISMATCHES"
        spikes = (f" ({v['expected_spikes']:,} spikes)"
                  if isinstance(v.get("expected_spikes"), int) else "")
        size = f" at {v['height']}x{v['width']}" if v.get("height") else ""
        parts.append(f"RTL against the twin over {_verify_steps(v)}{size}: {ok} in "
                     f"{v['compared']:,} accumulator-steps compared{spikes}")
    if inputs.regress is not None:
        r = inputs.regress
        parts.append(f"regression {r.count('pass')} of {len(r.cases)} pass")
    if inputs.formal is not None:
        f = inputs.formal
        n_ok = sum(c["status"] == "pass" for c in f["checks"])
        parts.append(f"formal {n_ok} of {len(f['checks'])} checks pass at "
                     f"{f['size'][0]}x{f['size'][1]}")
    if inputs.mutate is not None:
        m = inputs.mutate
        parts.append(f"mutation {m['killed']} of {m['mutations']} killed")
    return ("; ".join(parts) if parts else "nothing given") + f" ({_see('Verification')})"


def _board(report: dict[str, Any] | None) -> str:
    """The board row: package, pins and clocks of a saved ``rvsm fpga --board`` report."""
    if report is None:
        return f"not placed with its links ({_see('Board')})"
    b = report["board"]
    missed = [c["role"] for c in b["clocks"].values() if not c["met"]]
    return (f"{b['package']}: {b['pins_used']} of {b['pins_available']} pins, every port at "
            f"a named site, at {report['height']}x{report['width']}; "
            + ("every clock met" if not missed else f"MISSED: {', '.join(missed)}")
            + f" ({_see('Board')})")


def _see(section: str) -> str:
    """A link to ``section`` of the page."""
    return f"[{section}](#{'-'.join(section.lower().split())})"


def _package(inputs: DatasheetInputs) -> str:
    """The package the I/O budget judges: the point's ``[rtl] package``, else the
    device's default (in its part name)."""
    dev = inputs.device
    own = inputs.point_file.package_on(dev.name)
    if own:
        return f"{own} (the point's [rtl] package)"
    return dev.part.split("(")[-1].rstrip(")") if "(" in dev.part else "not stated"


def summary_lines(inputs: DatasheetInputs, feas: Feasibility, io: Interfaces) -> list[str]:
    """The summary table (module docstring); ``io`` the interfaces at ``feas.lanes``."""
    point, dev, fp = inputs.point_file.point, inputs.device, inputs.fpga
    c = point.contract()
    h, w = point.shape
    p, clock = feas.lanes, feas.clock_needed_hz
    geo = io.geometry
    fmax = feas.checks["fmax"]
    rows: list[tuple[str, str]] = [
        ("device", f"{dev.name}: {dev.part.split(' (')[0]}, "
                   + (f"placed by {dev.tool}" if dev.placed else
                      f"**{dev.status}** ({dev.status_reason})")),
        ("package", _package(inputs)),
    ]
    if fmax.budget is None:
        clk = f"{clock / 1e6:.1f} MHz needed; Fmax unknown"
    else:
        how = "measured (nextpnr)" if fp and fp.get("fmax_mhz") else "timing model"
        clk = (f"{clock / 1e6:.1f} MHz needed; Fmax {fmax.budget:.1f} MHz {how}: "
               + margin_text(fmax.budget, clock / 1e6, "MHz"))
    rows.append(("clock", clk + f" ({_see('Clock')})"))
    rows.append(("lanes", f"P = {p} pixels a cycle: {geo.groups} beats a row, "
                          f"{geo.beats_per_frame:,} beats a step (frame)"))
    thr = (f"{inputs.rate_hz:,.0f} steps/s of {h}x{w} = {h * w * inputs.rate_hz:,.0f} "
           "pixel-steps/s")
    if fmax.budget is not None:
        thr += f"; at Fmax up to {fmax.budget * 1e6 * p / (h * w):,.0f} steps/s"
    rows.append(("throughput", thr))
    us = 1e6 / clock
    rows.append(("latency", f"pixel to spike {geo.pixel_to_spike} cycles = "
                            f"{geo.pixel_to_spike * us:.2f} us native, "
                            f"{io.axi_pixel_to_spike} cycles = "
                            f"{io.axi_pixel_to_spike * us:.2f} us AXI, at "
                            f"{clock / 1e6:.1f} MHz (lag {geo.lag} beats)"))
    st = state_memory(c)
    shared = c.shared_thresholds is not None
    total = st.total - (st.thresholds if shared else 0)
    rows.append(("state memory", f"{total / 1e6:.3f} Mbit: accumulators "
                 f"{st.accumulators / 1e6:.3f} Mbit, line buffers {st.line_buffers / 1e3:.1f} "
                 "Kbit, thresholds " + (f"in {c.num_scales} shared registers" if shared
                                        else f"{st.thresholds / 1e6:.3f} Mbit")
                 + f"; {feas.packing.bram} {dev.bram_kind.name} "
                 f"({_see('Memory map and interfaces')})"))
    if fp is not None:
        used = ", ".join(f"{k} {fp[key]['used']:,} of {fp[key]['available']:,} "
                         f"({100 * fp[key]['used'] / fp[key]['available']:.1f} %)"
                         for k, key in (("LUT4", "lut4"), ("FF", "ff"),
                                        (dev.bram_kind.name, "bram")))
        rows.append(("utilisation",
                     f"measured (place and route): {used} ({_see('Resources')})"))
    else:
        rows.append(("utilisation", f"estimate only: {feas.summary()} ({_see('Resources')})"))
    rows.append(("board", _board(inputs.board)))
    q = inputs.quality.rows_with(False) or inputs.quality.rows
    if q:
        n = len(q)
        twin = sum(r.psnr_twin for r in q) / n
        own = sum(r.psnr_float for r in q) / n
        dflt = sum(r.psnr_default_float for r in q) / n
        rows.append(("PSNR against the float model",
                     f"twin {twin:.2f} dB, mean of {n} scenes, noise off: "
                     f"{better_or_worse(twin - own, 2)} dB against its own float model "
                     f"({own:.2f} dB), {better_or_worse(twin - dflt, 2)} dB against the "
                     f"default dog4 float model ({dflt:.2f} dB) ({_see('Image quality')})"))
    rows.append(("verified", _verified(inputs)))
    return ["## Summary", "", "| | |", "|---|---|",
            *[f"| {k} | {v} |" for k, v in rows], "",
            f"Every figure's command: {REPRODUCE}.", ""]


def _redirect(command: str, path: str | None) -> str:
    return command if not path or ">" in command else f"{command} > {path}"


def _recorded(result: dict[str, Any] | None, key: str, inputs: DatasheetInputs,
              path: str | None) -> tuple[str, str] | None:
    """The --commands file's command (with its source), else the result's own."""
    given = inputs.commands.get(key)
    if given is not None:
        return given[0], f"reconstructed: {given[1]}"
    if result is not None and isinstance(result.get("command"), str) and \
            "..." not in result["command"]:
        return _redirect(result["command"], path), "recorded in the saved result"
    return None


def reproduce_steps(inputs: DatasheetInputs, lanes: int) -> list[ReproduceStep]:
    """The page's command, each saved result's (module docstring), then the Verilog
    builds at ``lanes`` whose port and register files the interfaces section shows."""
    pf = inputs.point_file
    steps = [ReproduceStep("this page (from the saved results below)", inputs.command,
                           "the command that made it")]
    fp = inputs.fpga
    if fp is not None:
        got = _recorded(fp, "fpga", inputs, inputs.fpga_path) or (
            f"rvsm fpga {(fp.get('settings') or {}).get('point', pf.path)} --json -o "
            f"{fp.get('work_dir', 'build/fpga')} > {inputs.fpga_path}",
            "reconstructed from the result's settings: its point and work folder")
        steps.append(ReproduceStep(f"place and route (`{inputs.fpga_path}`)", *got))
    if inputs.board is not None:
        from rvsm.sim.studies.datasheet_board import board_command

        got = _recorded(inputs.board, "board", inputs, inputs.board_path) or (
            board_command(pf.path, inputs.board, inputs.board_path),
            "reconstructed from the result's settings: its point, size, front end and "
            "work folder")
        sites = getattr(inputs.board, "sites_from", "its board.sites")
        if sites != "its board.sites":
            got = (got[0], f"{got[1]}; the pin plan {sites} is pin_plan.json of the work "
                           "folder")
        steps.append(ReproduceStep(f"place and route on the board's pins "
                                   f"(`{inputs.board_path}`)", *got))
    if inputs.quality_path is not None:
        got = _recorded({"command": inputs.quality.command}, "quality", inputs,
                        inputs.quality_path)
        if got is not None:
            steps.append(ReproduceStep(f"image quality (`{inputs.quality_path}`)", *got))
    for key, result, path, what in (
            ("verify", inputs.verify, inputs.verify_path, "RTL against the twin"),
            ("formal", inputs.formal, inputs.formal_path, "formal checks"),
            ("mutate", inputs.mutate, inputs.mutate_path, "mutation testing")):
        if result is None:
            continue
        got = _recorded(result, key, inputs, path)
        if got is None and key == "mutate":
            size, lanes, checks = result.get("size"), result.get("lanes"), result.get("checks")
            got = (" ".join([f"rvsm mutate {pf.path}"]
                            + ([f"--size {size[0]}x{size[1]}"] if size else [])
                            + ([f"--lanes {lanes}"] if lanes else [])
                            + ([f"--checks {','.join(checks)}"] if checks else [])
                            + [f"--json > {path}"]),
                   "reconstructed from the result's size, lanes and checks, on this point")
        if got is None:
            got = ("", "NOT RECORDED: the result holds no command line; give it with "
                   "--commands FILE.toml")
        steps.append(ReproduceStep(f"{what} (`{path}`)", *got))
    if inputs.regress is not None:
        got = _recorded(None, "regress", inputs, inputs.regress_path) or (
            f"rvsm regress regressions/{inputs.regress.suites[0]}.toml --junit "
            f"{inputs.regress_path}", "reconstructed from the JUnit suite's name")
        steps.append(ReproduceStep(f"regression (`{inputs.regress_path}`)", *got))
    p = lanes
    if p:
        steps += [ReproduceStep(
            "the AXI IP's Verilog, register map (`.regs.md/.json/.h`) and ports "
            "(`.ports.json`) of the interfaces section", f"rvsm verilog {pf.path} --lanes {p} "
            "--interface axis -o build/ip", "the command that writes them"),
            ReproduceStep("the bare array's Verilog and ports", f"rvsm verilog {pf.path} "
                          f"--lanes {p} -o build/native", "the command that writes them")]
    return steps


def reproduce_lines(inputs: DatasheetInputs, lanes: int) -> list[str]:
    """The Reproduce section: each command whole, in a code block, with its origin."""
    lines = ["## Reproduce", "", "Every figure on this page, remade. Run from the "
             "repository's root; a command ending in `> FILE` saves the JSON the page "
             "reads. The long ones (place and route, the full-size run, mutation) take "
             "tens of minutes each on 2 cores.", ""]
    for s in reproduce_steps(inputs, lanes):
        lines += [f"**{s.what}** ({s.origin})" + (":" if s.command else "."), ""]
        lines += ["```", s.command, "```", ""] if s.command else []
    return lines
