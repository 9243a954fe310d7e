"""The datasheet's Board section against a saved board report: the tiny board build of
tests/data/board-tiny/ (made by the command in its README line; tests/rtl/fpga/
test_board_flow.py reruns that build and compares it with these files)."""

from __future__ import annotations

import csv
import io
import json
import re
from pathlib import Path

import pytest

from rvsm.model.fixed.point_toml import load_design_point
from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.board.front_end import link_formats
from rvsm.rtl.board.status import link_registers, link_registers_markdown
from rvsm.rtl.fpga.package_io import ECP5_GEARINGS
from rvsm.sim.studies.datasheet_board import (
    SITE_FIELDS,
    board_command,
    board_lines,
    link_rows,
    load_board_report,
    pin_plan_csv,
)

DATA = Path(__file__).resolve().parents[2] / "data"
POINT = DATA / "board-tiny.toml"
REPORT = DATA / "board-tiny" / "fpga-board.json"
PLAN = DATA / "board-tiny" / "pin_plan.json"


def _section(report):
    contract = load_design_point(POINT).with_size(report["height"], report["width"]).contract()
    return "\n".join(board_lines(report, contract, "tests/data/board-tiny.toml", str(REPORT),
                                 "[Reproduce](#reproduce)", "../docs")), contract


def _table(text: str, header: str) -> list[list[str]]:
    """The rows of the Markdown table whose header line starts with ``header``."""
    lines = text.split("\n")
    start = next(i for i, line in enumerate(lines) if line.startswith(header))
    rows = []
    for line in lines[start + 2:]:
        if not line.startswith("|"):
            break
        rows.append([c.strip() for c in line.strip("|").split("|")])
    return rows


def test_the_section_tables_are_the_report_and_its_pin_plan():
    report = load_board_report(REPORT, PLAN)
    plan = json.loads(PLAN.read_text())
    raw = json.loads(REPORT.read_text())
    b = raw["board"]
    assert report.sites == plan["sites"] == b["sites"]
    text, contract = _section(report)
    assert text.startswith("## Board\n") and "[Reproduce](#reproduce)" in text
    assert f"**{b['package']}**: {b['pins_used']} of {b['pins_available']} pins" in text
    # the pin plan: one row a port, every field as planned
    pins = _table(text, "| port | ball |")
    assert pins == [[str(s[k]) if s[k] != "" else "-" for k, _ in SITE_FIELDS]
                    for s in plan["sites"]]
    assert {r[0] for r in pins} >= {"rx0_clk", "tx0_clk", "spi_sck", "spi_miso", "clk_osc"}
    # every clock nextpnr timed, Fmax against its constraint
    clocks = _table(text, "| clock | net |")
    assert len(clocks) == len(b["clocks"])
    for (role, net, fmax, want, verdict), (name, c) in zip(clocks, b["clocks"].items(),
                                                           strict=True):
        assert (role, net, float(fmax), float(want)) == \
            (c["role"], f"`{name}`", round(c["achieved_mhz"], 1), c["constraint_mhz"])
        assert verdict == ("met" if c["met"] else "MISSED")
    prims = _table(text, "| primitive | used |")
    assert prims == [[k, str(v["used"]), str(v["available"])] for k, v in b["primitives"].items()]
    # links: pairs placed, the payload they carry, the rate against the published limit
    rx, tx = link_formats(contract, raw["lanes"])
    links = {r[0]: r for r in _table(text, "| link | carries |")}
    limit = ECP5_GEARINGS[0].max_mbps_per_pair
    for name, fmt in (("rx0", rx), ("tx0", tx)):
        row = links[name]
        assert row[2] == f"{fmt.data_pairs} + 1, 1"
        assert row[4] == f"{fmt.payload_bits} of {8 * fmt.data_pairs}"
        sclk = next(c["constraint_mhz"] for c in b["clocks"].values()
                    if c["role"] == f"link {name} SCLK")
        assert row[6].startswith(f"{4 * sclk:g} Mbit/s") and row[7] == f"{limit:g} Mbit/s"
        assert row[8] == ("yes" if 4 * sclk <= limit else "NO")
    assert "FPGA-TN-02035" in text
    # rejected packages with the planner's reason; the registers as status.py renders them
    for p in b["rejected_packages"]:
        assert f"- {p['package']}: {p['reason'].removeprefix(p['package'] + ': ')}" in text
    assert link_registers_markdown(link_registers(rx.pairs)).strip() in text
    assert "LINK_CONTROL.train" in text and "Training and reset sequence" in text
    # the CSV beside the page: the same rows
    rows = list(csv.reader(io.StringIO(pin_plan_csv(report))))
    assert rows[0] == ["port", "ball", "bank", "site", "pair", "io_type"]
    assert rows[1:] == [[str(s[k]) for k, _ in SITE_FIELDS] for s in plan["sites"]]


def test_link_rates_come_from_the_sclk_constraint():
    report = load_board_report(REPORT)
    contract = load_design_point(POINT).with_size(report["height"], report["width"]).contract()
    rows = {r["link"]: r for r in link_rows(report, contract)}
    sclk = {c["role"]: c["constraint_mhz"] for c in report["board"]["clocks"].values()}
    assert rows["rx0"]["mbps_per_pair"] == 4 * sclk["link rx0 SCLK"]
    assert rows["tx0"]["mbps_per_pair"] == 4 * sclk["link tx0 SCLK"]
    # a report of another lane count does not pass as this point's links
    wide = load_design_point(POINT).with_size(2, 8).contract()
    other = dict(report)
    other["lanes"] = 8
    copy = type(report)(other)
    copy.path, copy.sites, copy.sites_from = report.path, report.sites, report.sites_from
    with pytest.raises(RvsmError, match="pairs placed"):
        link_rows(copy, wide)


def test_an_older_report_takes_its_sites_from_the_pin_plan(tmp_path: Path):
    raw = json.loads(REPORT.read_text())
    del raw["board"]["sites"]
    old = tmp_path / "old.json"
    old.write_text(json.dumps(raw))
    with pytest.raises(RvsmError, match="--board-pin-plan"):
        load_board_report(old)
    assert load_board_report(old, PLAN).sites == json.loads(PLAN.read_text())["sites"]
    plan = json.loads(PLAN.read_text())
    plan["sites"][0]["ball"] = "Z99"
    bad = tmp_path / "pin_plan.json"
    bad.write_text(json.dumps(plan))
    with pytest.raises(RvsmError, match="not the one of"):
        load_board_report(REPORT, bad)
    not_board = tmp_path / "fpga.json"
    del raw["board"]
    not_board.write_text(json.dumps(raw))
    with pytest.raises(RvsmError, match="not a board report"):
        load_board_report(not_board)


def test_without_a_report_the_section_names_the_command():
    text = "\n".join(board_lines(None, None, "points/ecp5-85-40khz.toml",
                                 "docs/x/results/fpga-board.json", "[Reproduce](#reproduce)",
                                 "../docs"))
    assert ("`rvsm fpga points/ecp5-85-40khz.toml --board --json -o build/bench-board > "
            "docs/x/results/fpga-board.json`") in text
    assert text.count("\n") < 5 and "[Reproduce](#reproduce)" in text


def test_the_reconstructed_command_parses_and_names_the_build():
    from rvsm.sim.cli.main import build_parser

    report = load_board_report(REPORT)
    cmd = board_command("tests/data/board-tiny.toml", report, str(REPORT))
    args = build_parser().parse_args(cmd.split(" > ")[0].split()[1:])
    assert args.board and args.interface == "axis" and args.json
    assert re.search(r"--size 2x4\b", cmd) is None  # the point is 2x4 itself
    assert args.point == "tests/data/board-tiny.toml"

