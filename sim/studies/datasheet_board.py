"""The datasheet's Board section: the chip on a camera board, from a saved
``rvsm fpga POINT --board --json`` report (``rvsm datasheet --board-fpga FILE``).

:func:`load_board_report` checks the report (an ``rvsm fpga`` report with a ``board``
object) and, when the report predates ``board.sites``, takes the sites from the build's
``pin_plan.json`` (``--board-pin-plan``); given both, they must agree.
:func:`board_lines` writes the section, every figure from the report and the code:

- the package chosen and each smaller package rejected, with the planner's reason;
- the links: pairs (data, framing lane, forwarded clock), side and banks, payload bits a
  core cycle (:func:`~rvsm.rtl.board.front_end.link_formats` at the report's lanes), the
  rate per pair (``GEAR_BITS`` bits per SCLK of the X2 gearing at the SCLK constraint
  nextpnr was given) against the device's published limit and its source
  (:data:`~rvsm.rtl.fpga.package_io.ECP5_GEARINGS`);
- the pin plan (port, ball, bank, PIO site, pair, I/O type), also :func:`pin_plan_csv`
  for board layout tools;
- the timing of every clock nextpnr timed (Fmax against its constraint, met or MISSED)
  and the I/O and clocking primitives used;
- the training and reset sequence (the constants of :mod:`rvsm.rtl.board`) and the link
  registers (:func:`~rvsm.rtl.board.status.link_registers_markdown`).

Without a report the section names the command that makes it.
"""

from __future__ import annotations

import csv
import io
import os
from typing import Any

from rvsm.model.fixed.contract import ArrayContract
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.board.aligner import GOOD_WORDS
from rvsm.rtl.board.front_end import link_formats
from rvsm.rtl.board.model import GEAR_BITS, MARK, TRAIN, TRAIN_PERIOD, WORD_BITS
from rvsm.rtl.board.receiver import CLOCK_TIMEOUT, LOSS_WORDS
from rvsm.rtl.board.status import link_registers, link_registers_markdown
from rvsm.rtl.board.transmitter import RESET_TRAINING
from rvsm.rtl.fpga.package_io import ECP5_GEARINGS
from rvsm.sim.studies.datasheet_inputs import load_fpga_report, read_json_object

__all__ = ["CSV_NAME", "REPORT_NAME", "SITE_FIELDS", "TITLE", "BoardReport", "board_command",
           "board_lines", "link_rows", "load_board_report", "pin_plan_csv"]

#: The section's title, the CSV written beside the page, and where a page's folder keeps
#: its board report (``make datasheet``: ``results/fpga-board.json``).
TITLE = "Board"
CSV_NAME = "pin_plan.csv"
REPORT_NAME = "results/fpga-board.json"
#: A site's fields (``pin_plan.json`` / ``board.sites``) and their column names.
SITE_FIELDS = (("port", "port"), ("ball", "ball"), ("bank", "bank"), ("pio", "site"),
               ("pair", "pair"), ("io_type", "I/O type"))
#: What each front end is, for the page.
FRONT_ENDS = {"IpBoardFrontEnd": "the AXI IP between the links, its registers over SPI "
                                 "(`--interface axis`)",
              "BoardFrontEnd": "the streaming array between the links, a serial status "
                               "and control port"}
_HINT = "make it with rvsm fpga POINT --board --json > FILE.json"


class BoardReport(dict):
    """An ``rvsm fpga --board --json`` report (a dict) with its ``path`` and the
    ``sites`` of every port."""

    path: str
    sites: list[dict[str, Any]]
    sites_from: str


def _sites(sites: Any, where: str) -> list[dict[str, Any]]:
    if not isinstance(sites, list) or not sites or not all(
            isinstance(s, dict) and all(k in s for k, _ in SITE_FIELDS) for s in sites):
        raise RvsmError(f"{where}: sites must list every port with "
                        f"{', '.join(k for k, _ in SITE_FIELDS)}; {_HINT}")
    return sites


def load_board_report(path: str | os.PathLike, pin_plan: str | os.PathLike | None = None
                      ) -> BoardReport:
    """The report at ``path`` (:func:`load_fpga_report` plus a ``board`` object with
    ``package``, ``pins_used``, ``pins_available``, ``clocks``, ``primitives``,
    ``rejected_packages``, ``links``) and the sites: ``board.sites``, else those of
    ``pin_plan`` (the build's ``pin_plan.json``). :class:`RvsmError` naming the file."""
    d = load_fpga_report(path)
    b = d.get("board")
    keys = ("package", "pins_used", "pins_available", "clocks", "primitives",
            "rejected_packages", "links")
    if not isinstance(b, dict) or any(k not in b for k in keys):
        raise RvsmError(f"{path}: not a board report (no board object with "
                        f"{', '.join(keys)}); {_HINT}")
    if d.get("mode") != "place-and-route":
        raise RvsmError(f"{path}: a board report comes from place and route; {_HINT}")
    own = _sites(b["sites"], str(path)) if "sites" in b else None
    plan = None
    if pin_plan is not None:
        p = read_json_object(pin_plan, "pin plan", "it is pin_plan.json of the rvsm fpga "
                                                   "--board output folder")
        plan = _sites(p.get("sites"), str(pin_plan))
        if p.get("package") != b["package"] or (own is not None and own != plan):
            raise RvsmError(f"{pin_plan}: the pin plan is not the one of {path} (package "
                            "or sites differ)")
    sites = own if own is not None else plan
    if sites is None:
        raise RvsmError(f"{path}: the report has no board.sites (an older rvsm fpga); give "
                        "the pin_plan.json of its output folder with --board-pin-plan")
    if len(sites) != b.get("ports", len(sites)):
        raise RvsmError(f"{path}: {len(sites)} sites for {b['ports']} ports")
    out = BoardReport(d)
    out.path, out.sites = str(path), sites
    out.sites_from = "its board.sites" if own is not None else f"`{pin_plan}`"
    return out


def board_command(point: str, report: BoardReport | None, path: str | None) -> str:
    """The command that makes ``report`` again (or, without one, the shipped point's
    full-size board build saved as ``path``)."""
    if report is None:
        return f"rvsm fpga {point} --board --json -o build/bench-board > {path or 'FILE.json'}"
    settings = report.get("settings") or {}
    words = [f"rvsm fpga {settings.get('point', point)}"]
    if (report.get("sensor_height"), report.get("sensor_width")) != \
            (report["height"], report["width"]):
        words.append(f"--size {report['height']}x{report['width']}")
    if settings.get("lanes") is not None and "lanes" not in settings.get("from_point", []):
        words.append(f"--lanes {report['lanes']}")
    if report.get("target_mhz") and "freq_mhz" not in settings.get("from_point", []):
        words.append(f"--freq {report['target_mhz']:g}")
    if report["board"].get("front_end") == "IpBoardFrontEnd":
        words.append("--interface axis")
    words.append(f"--board --json -o {report.get('work_dir', 'build/bench-board')}")
    return " ".join(words) + f" > {path}"


def _clock_of(report: BoardReport, role: str) -> dict[str, Any] | None:
    return next((c for c in report["board"]["clocks"].values() if c["role"] == role), None)


def link_rows(report: BoardReport, contract: ArrayContract) -> list[dict[str, Any]]:
    """Per link of the report: ``link``, ``direction``, ``data_pairs`` (framing lane
    included), ``clock_pairs``, ``side``, ``banks``, ``payload_bits`` (a core cycle),
    ``sclk_mhz`` (its constraint) and ``mbps_per_pair`` (``GEAR_BITS`` x SCLK).
    ``contract``: the array of the report (its height, width and model); the pairs
    placed must be those the links need at the report's lanes."""
    rx, tx = link_formats(contract, report["lanes"])
    ports = [s["port"] for s in report.sites]
    rows = []
    for name, place in report["board"]["links"].items():
        direction = "rx" if name.startswith("rx") else "tx"
        fmt = rx if direction == "rx" else tx
        data = sum(1 for p in ports if p.startswith(f"{name}_d") and p[len(name) + 2:].isdigit())
        if data != fmt.pairs:
            raise RvsmError(f"{report.path}: link {name} has {data} pairs placed, the "
                            f"point at P = {report['lanes']} needs {fmt.pairs}")
        clock = _clock_of(report, f"link {name} SCLK")
        sclk = None if clock is None else float(clock["constraint_mhz"])
        rows.append({"link": name, "direction": direction, "data_pairs": data,
                     "clock_pairs": int(f"{name}_clk" in ports), "side": place["side"],
                     "banks": place["banks"], "payload_bits": fmt.payload_bits,
                     "sclk_mhz": sclk,
                     "mbps_per_pair": None if sclk is None else GEAR_BITS * sclk})
    return rows


def pin_plan_csv(report: BoardReport) -> str:
    """The pin plan as CSV (one row a port; columns :data:`SITE_FIELDS`)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow([col.replace("/", "").replace(" ", "_").lower() for _, col in SITE_FIELDS])
    for s in report.sites:
        w.writerow([s[k] for k, _ in SITE_FIELDS])
    return buf.getvalue()


def _links_table(report: BoardReport, rows: list[dict[str, Any]]) -> list[str]:
    x2 = ECP5_GEARINGS[0]
    side = {"L": "left", "R": "right"}
    out = ["| link | carries | pairs: data + framing lane, clock | side, banks | payload "
           "bits a core cycle | SCLK (constraint) | rate per pair | published limit | "
           "within |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        carries = "pixel codes in" if r["direction"] == "rx" else "spikes out"
        rate = "unknown (no SCLK clock in the report)" if r["mbps_per_pair"] is None else \
            f"{r['mbps_per_pair']:g} Mbit/s ({GEAR_BITS} bits a SCLK)"
        ok = "unknown" if r["mbps_per_pair"] is None else \
            ("yes" if r["mbps_per_pair"] <= x2.max_mbps_per_pair else "NO")
        out.append(f"| {r['link']} | {carries} | {r['data_pairs'] - 1} + 1, "
                   f"{r['clock_pairs']} | {side.get(r['side'], r['side'])}, "
                   f"{' + '.join(map(str, r['banks']))} | {r['payload_bits']} of "
                   f"{WORD_BITS * (r['data_pairs'] - 1)} | "
                   + ("-" if r["sclk_mhz"] is None else f"{r['sclk_mhz']:g} MHz")
                   + f" | {rate} | {x2.max_mbps_per_pair:g} Mbit/s | {ok} |")
    return out + ["", f"Rate per pair: the {x2.name.upper()} gearing ({x2.primitives}) "
                  f"moves {GEAR_BITS} bits a pair each SCLK (half the edge clock), {WORD_BITS} "
                  "bits (one word) each core cycle; the SCLK is the constraint nextpnr "
                  f"timed the link with. Published limit: {x2.source}."]


def _timing_lines(b: dict[str, Any]) -> list[str]:
    out = ["| clock | net | Fmax (MHz) | constraint (MHz) | verdict |", "|---|---|---|---|---|"]
    for net, c in b["clocks"].items():
        out.append(f"| {c['role']} | `{net}` | {c['achieved_mhz']:.1f} | "
                   f"{c['constraint_mhz']:g} | {'met' if c['met'] else 'MISSED'} |")
    verdict = ("every clock meets its constraint" if b.get("all_clocks_met") else
               "NOT every clock meets its constraint: "
               + ", ".join(c["role"] for c in b["clocks"].values() if not c["met"])
               + " MISSED")
    note = b.get("edge_clock_note", "")
    out += ["", f"{verdict}. {note[:1].upper()}{note[1:]}".rstrip(". ") + ".", "",
            "| primitive | used | available on the die |", "|---|---|---|"]
    out += [f"| {k} | {v['used']} | {v['available']} |" for k, v in b["primitives"].items()]
    return out


def _sequence_lines(front_end: str | None) -> list[str]:
    regs = front_end == "IpBoardFrontEnd"
    poll = ("poll `LINK_STATUS` over SPI until `locked` and `aligned` are 1 and "
            "`train_request` 0, then `STATUS.busy` 0" if regs else
            "reads the status word on `spi_miso` until `locked` and `aligned` are 1")
    return [
        f"1. Release reset (`rst_n`) with the oscillator running; the core and transmit "
        "clocks come from the PLL and wait for its lock. The receive SCLK domain stays in "
        f"reset while the forwarded clock is dead ({CLOCK_TIMEOUT} core cycles without "
        "a change).",
        f"2. The transmitter sends {RESET_TRAINING} training words after its reset: "
        f"`TRAIN` = 0x{TRAIN:02X} on every pair, `MARK` = 0x{MARK:02X} on all pairs at "
        f"once every {TRAIN_PERIOD}th word. `rx0_train_request` is high while the receive "
        f"link is not locked: the sensor sends training words (at least "
        f"{3 * TRAIN_PERIOD}: three MARK periods) until it falls.",
        f"3. The receiver aligns each pair ({GOOD_WORDS} `TRAIN` words in a row at one "
        "bit slip), lines the pairs up on `MARK` (deskew) and locks; then it reads the "
        "framing lane.",
        f"4. The host {poll}; the sensor then starts frames (the first beat with `sof`).",
        f"5. Running: {LOSS_WORDS} bad words in a row on a pair, or a lost forwarded "
        "clock, drop `locked`, count a lock loss and raise `rx0_train_request`; the sensor "
        "trains again and the link relocks by itself. "
        + ("Writing `LINK_CONTROL.train` = 1 retrains on purpose; "
           "`LINK_CONTROL.counters_reset` zeroes the counters." if regs else
           "The serial port's `train` bit retrains on purpose; `counters_reset` zeroes "
           "the counters."),
    ]


def board_lines(report: BoardReport | None, contract: ArrayContract | None,
                point_path: str, path_hint: str, reproduce: str, docs: str) -> list[str]:
    """The Board section (module docstring). ``contract``: the array of the report (its
    size and lanes); ``path_hint``: where the shipped page keeps the report (for the
    line naming the command when ``report`` is None); ``reproduce``: the link to the
    Reproduce section; ``docs``: the path from the page to ``docs/``."""
    head = [f"## {TITLE}", ""]
    if report is None or contract is None:
        return head + [f"Not placed with its links. Sources: not run: "
                       f"`{board_command(point_path, None, path_hint)}` makes the report, "
                       f"`--board-fpga` gives it to this page ({docs}/fpga.md, Board "
                       f"build); commands: {reproduce}.", ""]
    b = report["board"]
    fe = b.get("front_end") or "BoardFrontEnd"
    rows = link_rows(report, contract)
    rx_pairs = next(r["data_pairs"] for r in rows if r["direction"] == "rx")
    lines = head + [
        f"`rvsm fpga --board` placed {FRONT_ENDS.get(fe, fe)} ({fe}, "
        f"[board.md]({docs}/board.md)) at {report['height']}x{report['width']}, "
        f"P = {report['lanes']}, on {report['device']} **{b['package']}**: "
        f"{b['pins_used']} of {b['pins_available']} pins, {len(report.sites)} ports each "
        "at a named site, nextpnr run without `--lpf-allow-unconstrained`.", "",
        f"**Package.** {b['package']}" + (
            ", the smallest ECP5-85 package that carries the links; smaller ones "
            "rejected by the pin planner:" if b["rejected_packages"] else
            ": the first package tried carries the links."), ""]
    lines += [f"- {p['package']}: {p['reason'].removeprefix(p['package'] + ': ')}"
              for p in b["rejected_packages"]]
    lines += ["", "**Links** (source-synchronous LVDS, a forwarded clock pair each; the "
              "framing lane carries `sof`, `eol`, parity and the training marks):", ""]
    lines += _links_table(report, rows)
    lines += ["", f"**Pin plan** ({len(report.sites)} ports; also [{CSV_NAME}]({CSV_NAME}) "
              "for board layout tools; a differential port is its true pin, the "
              "complement implied):", "",
              "| " + " | ".join(col for _, col in SITE_FIELDS) + " |",
              "|" + "---|" * len(SITE_FIELDS)]
    lines += ["| " + " | ".join(str(s[k]) if s[k] != "" else "-" for k, _ in SITE_FIELDS)
              + " |" for s in report.sites]
    lines += ["", "**Timing of every clock** (nextpnr) and the I/O and clocking "
              "primitives used:", "", *_timing_lines(b), "",
              "**Training and reset sequence:**", "", *_sequence_lines(fe), "",
              f"**Link registers** (the AXI IP's register file from 0x080, {rx_pairs} "
              "receive pairs" + ("" if fe == "IpBoardFrontEnd" else
                                 "; the build placed here, without the IP, gives the same "
                                 "status in its serial port's status word instead")
              + "):", ""]
    lines += [link_registers_markdown(link_registers(rx_pairs)).rstrip("\n"), "",
              f"Sources: `rvsm fpga --board` saved as `{report.path}` (its `board` object: "
              f"package, clocks, primitives; the sites from {report.sites_from}); payload "
              "from rtl/board/front_end.py, limit from rtl/fpga/package_io.py, registers "
              "from rtl/board/status.py; "
              f"commands: {reproduce}.", ""]
    return lines
