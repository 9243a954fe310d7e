"""The shipped point's datasheet (docs/datasheet-ecp5-85-40khz/) agrees with the saved results
it was made from and with the point as it is now: a changed point, a rerun measurement or a
hand edit of the page fails here until `make datasheet` remakes the page. It is laid out for
its reader: the summary first, every command whole in one Reproduce section at the end,
figures that read as what they count, and complete interfaces."""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

import pytest

from rvsm.model.fixed.point_toml import load_point_file
from rvsm.sim.studies.point_quality import PointQuality

ROOT = Path(__file__).resolve().parents[3]
POINT = ROOT / "points" / "ecp5-85-40khz.toml"
SHEET = ROOT / "docs" / "datasheet-ecp5-85-40khz"
RESULTS = SHEET / "results"
#: The full-size board report (make bench-board), when saved; its pin plan if the
#: report predates board.sites.
BOARD, BOARD_PLAN = RESULTS / "fpga-board.json", RESULTS / "pin_plan.json"


@pytest.fixture(scope="module")
def page() -> str:
    return (SHEET / "datasheet.md").read_text(encoding="utf-8")


def _json(name: str) -> dict:
    return json.loads((RESULTS / name).read_text(encoding="utf-8"))


def _section(page: str, title: str) -> str:
    """The text of section ``## title`` up to the next ``## ``."""
    return page.split(f"\n## {title}\n", 1)[1].split("\n## ", 1)[0]


def _headings(page: str) -> list[str]:
    return [line[3:] for line in page.splitlines() if line.startswith("## ")]


def _reproduce_commands(page: str) -> list[str]:
    return re.findall(r"```\n(.*?)\n```", _section(page, "Reproduce"), re.S)


def test_the_summary_comes_first_and_reproduce_last(page):
    heads = _headings(page)
    assert heads[0] == "Summary" and heads[-1] == "Reproduce"
    rows = dict(re.findall(r"^\| ([^|]+) \| (.+) \|$", _section(page, "Summary"), re.M))
    for key in ("device", "package", "clock", "lanes", "throughput", "latency",
                "state memory", "utilisation", "PSNR against the float model", "verified"):
        assert key in rows, key
    r = _json("fpga.json")
    assert f"Fmax {r['fmax_mhz']:.1f} MHz" in rows["clock"] and "headroom" in rows["clock"]
    package = load_point_file(POINT)[1].package  # the I/O budget's: the point's [rtl] one
    assert rows["package"].split()[0] == package and "P = 40" in rows["lanes"]
    verdict = _section(page, "Resources").split("Verdict of the estimate: ", 1)[1]
    assert verdict.startswith("feasible on ecp5-85") and "I/O" in verdict
    assert f"{r['lut4']['used']:,} of {r['lut4']['available']:,}" in rows["utilisation"]
    v = _json("verify.json")
    assert f"{v['compared']:,} accumulator-steps" in rows["verified"]
    assert f"{v['expected_spikes']:,} spikes" in rows["verified"]
    assert "dB against its own float model" in rows["PSNR against the float model"]
    # every other section points to Reproduce instead of repeating the page's command
    for title in heads[1:-1]:
        assert "[Reproduce](#reproduce)" in _section(page, title), title
    assert page.count("rvsm datasheet points/ecp5-85-40khz.toml") == 1


def test_reproduce_has_every_command_whole_and_each_parses(page):
    from rvsm.sim.cli.main import build_parser

    commands = _reproduce_commands(page)
    # the page, fpga, (the board report when saved), quality, verify, formal, mutate,
    # regress, the two Verilog builds
    assert len(commands) == 9 + BOARD.is_file()
    parser = build_parser()
    parsed = {}
    for cmd in commands:
        assert "..." not in cmd and cmd.startswith("rvsm "), cmd
        words = shlex.split(cmd.split(" > ")[0])[1:]
        parsed[words[0]] = parser.parse_args(words)  # argparse exits on a bad word
        if " > " in cmd:
            assert cmd.split(" > ")[1].startswith("docs/datasheet-ecp5-85-40khz/results/")
    d = parsed["datasheet"]
    for name in ("fpga.json", "quality.json", "verify.json", "formal.json", "mutate.json",
                 "regress.xml", "commands.toml"):
        assert f"docs/datasheet-ecp5-85-40khz/results/{name}" in commands[0], name
    assert (d.point, d.output) == ("points/ecp5-85-40khz.toml", "docs/datasheet-ecp5-85-40khz")
    # the reconstructed commands make what the saved results record
    v, a = _json("verify.json"), parsed["verify"]
    assert (a.scene, a.fixed, a.sim, a.harness, a.steps) == \
        (v["scene"], v["point"], v["simulator"], v["harness"], v["steps"])
    assert (a.frames - 1) * a.steps_per_frame == v["steps"]
    f, a = _json("formal.json"), parsed["formal"]
    assert (a.size, a.lanes) == ("x".join(map(str, f["size"])), f["options"]["lanes"])
    point, _ = load_point_file(ROOT / a.point)
    assert point.model == f["model"] and point.threshold_storage == "shared"
    m, a = _json("mutate.json"), parsed["mutate"]
    assert a.point == "points/ecp5-85-40khz.toml"
    assert (m["size"], m["lanes"], m["checks"]) == \
        ([int(x) for x in a.size.split("x")], a.lanes, a.checks.split(","))
    assert "regressions/ecp5-85-40khz.toml" in " ".join(commands)
    assert (ROOT / "regressions" / "ecp5-85-40khz.toml").is_file()
    for png in ("resources.png", "clock.png", "quality_costs.png", "reconstructions.png"):
        assert f"]({png})" in page and (SHEET / png).stat().st_size > 1000, png


def test_figures_read_as_what_they_count(page):
    assert not re.search(r"\(-\d+ %\)", page)  # headroom printed as headroom
    assert "% headroom" in page and "spare (" in page
    assert "spikes compared" not in page  # accumulator-steps, and the spikes among them
    v = _json("verify.json")
    assert (f"{v['compared']:,} accumulator-steps compared ({v['accumulators']:,} "
            f"accumulators x {v['steps']:,} steps), {v['expected_spikes']:,} of them "
            "spikes") in page
    steps = re.findall(r"(\d+) steps \((\d+) frame intervals x (\d+) steps; (\d+) frames\)",
                       page)
    assert steps
    for total, intervals, per, frames in steps:
        assert int(total) == int(intervals) * int(per) and int(frames) == int(intervals) + 1
    assert "chip cost" not in page and "quantisation cost" not in page
    assert "better by 1.399" in page  # the chip against dog4 float, mean, noise off
    # shared thresholds: one register per scale, not a row of (A - 1)-bit thresholds
    assert not re.search(r"\| \d+ \(A - 1\) \|", page) and "(A-1) |" not in page
    assert "| `threshold.storage` | shared | thresholds: one register per scale" in page
    for field in ("adc.log_frac_bits", "threshold.contrast", "scale_contrast"):
        assert field not in page, field  # an event-sensor field on a spike point


def test_links_of_the_page_and_the_point_files_resolve(page):
    links = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", page)
    assert "../integration.md" in links and "../ip.md" in links
    for link in links:
        assert (SHEET / link).exists(), link
    for f in (POINT, ROOT / "regressions" / "ecp5-85-40khz.toml"):
        for doc in re.findall(r"docs/[\w./-]+\.md", f.read_text(encoding="utf-8")):
            assert (ROOT / doc).is_file(), f"{f.name}: {doc}"


def test_interfaces_list_every_payload_field_and_register_bit(page):
    from rvsm.rtl.architectures.registry import get_architecture

    point, build = load_point_file(POINT)
    contract, p = point.contract(), build.lanes
    text = _section(page, "Memory map and interfaces")
    assert "pack differently" in text and "Reset, initialisation and flush" in text
    ip = get_architecture("stream", "axis")
    regmap = ip.register_map(contract, **ip.resolve({"lanes": p, "fifo_depth": 16}))
    for r in regmap.registers:
        for f in r.fields:
            hi = f.lsb + f.width - 1
            bits = f"[{hi}:{f.lsb}]" if f.width > 1 else f"[{f.lsb}]"
            assert f"| `{r.name}` | {bits} | `{f.name}` |" in text, (r.name, f.name)
    assert "| `THR_ADDR` | [16] | `scale` |" in text and "| `CONTROL` | [0] | `clear` |" in text
    native = {r["name"]: r for r in get_architecture("stream").port_map(contract, lanes=p)}
    axi = {r["name"]: r for r in ip.port_map(contract, lanes=p, fifo_depth=16)}
    for port in (native["spikes_payload"], axi["m_axis_tdata"]):
        covered = 0
        for f in port["fields"]:
            lo, w = f["offset"], f["width"]
            bits = f"[{lo + w - 1}:{lo}]" if w > 1 else f"[{lo}]"
            assert f"| {bits} | `{f['name']}` | {w} |" in text, (port["name"], f["name"])
            covered += w
        assert covered == port["width"]  # the fields fill the payload
    n = contract.adc_bits
    assert f"| [{p * n - 1}:{(p - 1) * n}] | `code{p - 1}` | {n} |" in text  # codes_payload
    assert f"| [{8 * p - 2}:{8 * (p - 1)}] | `code{p - 1}` | {n} |" in text  # s_axis_tdata


def test_place_and_route_figures_are_nextpnrs_of_this_point(page):
    point, build = load_point_file(POINT)
    r = _json("fpga.json")
    assert (r["model"], r["height"], r["width"], r["lanes"], r["mode"]) == \
        (point.model, point.height, point.width, build.lanes, "place-and-route")
    for key in ("lut4", "ff", "bram"):
        used = r[key]
        share = 100 * used["used"] / used["available"]
        assert f"| {used['used']:,} ({share:.1f} %) |" in page, key
        assert used["used"] <= used["available"]
    needed_hz = point.height * point.width * 40_000 / build.lanes
    assert r["fmax_mhz"] * 1e6 >= needed_hz  # the camera's clock is met
    assert f"**{r['fmax_mhz']:.1f} MHz**" in page and "the clock is met, " in page


def test_image_quality_tables_are_the_saved_study_of_this_point(page):
    point, _ = load_point_file(POINT)
    q = PointQuality.from_json((RESULTS / "quality.json").read_text(encoding="utf-8"))
    assert q.point == point.to_dict()  # the study of the point as it is now
    assert q.size == (250, 400) and {r.scene for r in q.rows} >= {"coin", "flyball"}
    assert {r.noise for r in q.rows} == {False, True}
    for noise in (False, True):
        for line in q.markdown(noise):
            assert line in page, line


def test_verification_results_are_the_saved_ones(page):
    v = _json("verify.json")
    assert v["mismatches"] == 0 and v["steps"] == 40_000
    assert f"{v['compared']:,}" in page


def test_formal_mutation_and_regression_results_are_the_saved_ones(page):
    f = _json("formal.json")
    assert f["ok"] and f["model"] == "dog2" and len(f["checks"]) >= 5
    assert "| formal checks, dog2" in page and "PASS: 7 of 7 checks pass: protocol pass" in page
    m = _json("mutate.json")
    assert f"{m['killed']} of {m['mutations']} mutations killed" in page
    assert "regression ecp5-85-40khz" in page


def test_board_section_is_the_saved_board_report_or_names_its_command(page):
    """With results/fpga-board.json: the section's pin plan, links and clocks are the
    report's and pin_plan.csv beside the page is its pin plan; without it: one line
    naming the command that makes it, and no CSV."""
    from rvsm.sim.studies.datasheet_board import load_board_report, pin_plan_csv

    text = _section(page, "Board")
    if not BOARD.is_file():
        assert ("`rvsm fpga points/ecp5-85-40khz.toml --board --json -o build/bench-board "
                "> docs/datasheet-ecp5-85-40khz/results/fpga-board.json`") in text
        assert not (SHEET / "pin_plan.csv").exists()
        return
    report = load_board_report(BOARD, BOARD_PLAN if BOARD_PLAN.is_file() else None)
    b = report["board"]
    assert f"**{b['package']}**: {b['pins_used']} of {b['pins_available']} pins" in text
    for s in report.sites:
        assert "| " + " | ".join(str(s[k]) if s[k] != "" else "-" for k in
                                 ("port", "ball", "bank", "pio", "pair", "io_type")) + " |" \
            in text, s["port"]
    for net, c in b["clocks"].items():
        assert (f"| {c['role']} | `{net}` | {c['achieved_mhz']:.1f} | "
                f"{c['constraint_mhz']:g} | {'met' if c['met'] else 'MISSED'} |") in text
    assert (SHEET / "pin_plan.csv").read_text(encoding="utf-8") == pin_plan_csv(report)
    point, build = load_point_file(POINT)
    assert (report["model"], report["lanes"]) == (point.model, build.lanes)
