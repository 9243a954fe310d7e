"""A sweep's device constraint: parsing, the report's ranking and the CLI."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.rtl.fpga.lane_cost import LaneSynthesis
from rvsm.sim.cli import main
from rvsm.sim.sweep.fit import parse_constraint
from rvsm.sim.sweep.report import write_report
from rvsm.sim.sweep.run import run_sweep
from rvsm.sim.sweep.spec import parse_sweep
from tests.conftest import TINY_SWEEP_BODY, TINY_SWEEP_HEAD

HEAD, BODY = TINY_SWEEP_HEAD, TINY_SWEEP_BODY


def test_constraint_parsed_with_its_defaults():
    spec = parse_sweep(HEAD + 'memory_organisation = "rtl"\n' + BODY)
    c = spec.constraint
    assert c.devices == ("ecp5-85",) and (c.camera.height, c.camera.width) == (250, 400)
    assert c.camera.rate_hz == 40000 and c.organisation == "rtl" and c.max_utilisation == 0.8
    assert parse_sweep(BODY).constraint is None
    two = parse_constraint({"fits": ["ecp5-85", "gw5ast-138"],
                            "camera": {"size": "250x400", "rate_hz": 4e4}}, "s")
    assert two.devices == ("ecp5-85", "gw5ast-138")


@pytest.mark.parametrize("text,msg", [
    ('fits = "ecp5-99"\ncamera = { size = "250x400", rate_hz = 40000 }\n',
     r"s.toml: fits: unknown device 'ecp5-99'; choose one of: ecp5-25, ecp5-45, ecp5-85, "),
    ('fits = "ecp5-85"\ncamera = { size = "250by400", rate_hz = 40000 }\n',
     r"s.toml: camera.size: "),
    ('fits = "ecp5-85"\n', r"fits and camera go together"),
    ('max_utilisation = 0.5\n', r"max_utilisation needs fits"),
    (HEAD + 'max_utilisation = 1.5\n', r"max_utilisation must be a number in \(0, 1\]"),
    (HEAD + 'memory_organisation = "diagonal"\n', r"one of rtl, per-scale, packed"),
    ('fitz = "ecp5-85"\n', r"unknown section \[fitz\]; valid: .*top-level keys: fits, camera"),
    (HEAD + 'io_links = "chip"\n', r"io_links must be one of side, bank, got 'chip'"),
    (HEAD + 'package = "QFN9"\n', r"s.toml: package: ecp5-85 has no package 'QFN9'; choose "),
])
def test_bad_constraints_are_one_line_naming_the_choices(text, msg):
    with pytest.raises(RvsmError, match=msg):
        parse_sweep(text + BODY, "s.toml")


@pytest.fixture
def fake_synthesis(monkeypatch):
    """yosys replaced by a linear logic model: dog1 400 LUT4 + 500 FF per lane, dog2 twice
    that, 100 of each at zero lanes (the hardware measurement is tested elsewhere)."""
    import rvsm.rtl.fpga.lane_cost as lane_cost_module

    def fake(point, lanes, **kw):
        k = point.num_scales
        return LaneSynthesis(lanes=lanes, logic=100 + 400 * k * lanes,
                             ff=100 + 500 * k * lanes, fmax_mhz=None, seconds=0.0)

    monkeypatch.setattr(lane_cost_module, "lane_synthesis", fake)


def test_report_ranks_what_fits_and_says_what_breaks(tmp_path, capsys, fake_synthesis):
    db = tmp_path / "r.sqlite"
    run_sweep(parse_sweep(HEAD + BODY), db, workers=0, progress=False)
    # in the CABGA756: the package that carries the full sensor's links
    big = parse_constraint({"fits": ["ecp5-85"], "package": "CABGA756",
                            "camera": {"size": "250x400", "rate_hz": 40000}}, "test")
    files, info = write_report(db, tmp_path / "rep", constraint=big)
    text = (tmp_path / "rep" / "report.md").read_text()
    # dog1, per-pixel thresholds, packed at P = 40: 100 + 95 DP16KD of 208; dog2 twice
    assert [d["label"].split(",")[0] for d in info["fits"]["ecp5-85"]] == ["array.model=dog1"]
    (bad,) = info["infeasible"]["ecp5-85"]
    assert bad["label"].startswith("array.model=dog2")
    assert "memory BREAKS: 390 / 208 DP16KD (+88 %)" in bad["summary"]
    assert "## Fits ecp5-85 in CABGA756 at 250x400 at 40,000 Hz" in text
    assert "**1 of 2 designs fit.**" in text and "195 / 208" in text
    # logic at P = 40: nextpnr's 1.199 x (100 + 40 x 400 LUT4 + the read multiplexers of
    # 3 banks of 40 x 18 and 40 x 17 bits, 2 LUT4 a bit + 14.1 an extra bank) + the line
    # buffer's 140 16x4 RAMs x 4 (rtl/fpga/placed_logic.py)
    lut = 1.199 * (100 + 40 * 400 + 2 * 720 + 2 * 680 + 4 * 14.1) + 560
    assert f"{lut:,.0f} / 66,912" in text
    # the same database checked against another device and camera from the command line
    capsys.readouterr()
    assert main(["sweep", "report", str(db), "-o", str(tmp_path / "rep2"), "--fits",
                 "ecp5-25,ice40-up5k", "--camera", "16x24", "--rate-hz", "1000"]) == 0
    out = capsys.readouterr().out
    assert "fits ecp5-25: 2 of 2 design(s)" in out
    # no Fmax model for the iCE40: unverified, not feasible
    assert "fits ice40-up5k (estimate only): 0 of 2 design(s)" in out
    assert ": unverified fmax ?" in out
    assert "### ice40-up5k (estimate only)" in (tmp_path / "rep2" / "report.md").read_text()
    # 100x400 at 100 kHz: the array's 4e9 pixel-steps/s on a state that fits; on the
    # CABGA381 dog2's transmit link (20 + 2 pairs) needs more true-LVDS pairs than a side
    # has, dog1's 37-pair receive link more pairs than a side has: nothing fits, exit 2
    fast = ["--fits", "ecp5-85", "--camera", "100x400", "--rate-hz", "100000"]
    assert main(["sweep", "report", str(db), "-o", str(tmp_path / "rep3"), *fast]) == 2
    err = capsys.readouterr().err
    assert "io" in err and len(err.strip().splitlines()) == 1
    assert main(["sweep", "report", str(db), "-o", str(tmp_path / "rep3"), *fast,
                 "--allow-infeasible"]) == 0
    out = capsys.readouterr().out
    (dog2,) = [ln for ln in out.splitlines() if ln.startswith("  x array.model=dog2")]
    # the line short, the detail in report.md and --json
    assert dog2.endswith(": P = 40 at 100.0 MHz: breaks io 22 / 17 true-LVDS transmit "
                         "pairs on one edge clock (+29 %)")
    (dog1,) = [ln for ln in out.splitlines() if ln.startswith("  x array.model=dog1")]
    assert "breaks io 37 / 33 receive pairs on one edge clock" in dog1
    assert "| 22 / 17 **x** |" in (tmp_path / "rep3" / "report.md").read_text()
    assert main(["sweep", "report", str(db), "-o", str(tmp_path / "rep4"), *fast,
                 "--package", "CABGA756", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)["report"]
    assert [d["label"].split(",")[0] for d in got["fits"]["ecp5-85"]] == [
        "array.model=dog1", "array.model=dog2"]
    io = {d["label"].split(",")[0]: d["io"] for d in got["verdicts"]["ecp5-85"]}
    assert io["array.model=dog2"]["package"] == "LFE5U-85F CABGA756"
    assert (io["array.model=dog2"]["input"]["data_pairs"],
            io["array.model=dog2"]["output"]["data_pairs"]) == (35, 20)
    assert io["array.model=dog2"]["figure"] == 59 and io["array.model=dog2"]["budget"] == 112


def test_cli_devices_and_bad_values_exit_2(tmp_path, capsys, fake_synthesis):
    assert main(["sweep", "devices"]) == 0
    out = capsys.readouterr().out
    assert "ecp5-85 (placed and routed): LFE5U-85F speed 6" in out and "208 DP16KD" in out
    assert "512x36 (pseudo-dual)" in out and "ice40-up5k (estimate only): " in out
    rows = [r for r in out.splitlines() if not r.startswith("  ")]
    assert len(rows) == 13 and all(("(placed and routed)" in r) != ("(estimate only)" in r)
                                   for r in rows)
    f = tmp_path / "s.toml"
    f.write_text(HEAD.replace("ecp5-85", "nosuch") + BODY)
    assert main(["sweep", str(f), "-o", str(tmp_path / "x.sqlite")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "unknown device 'nosuch'; choose one of: ecp5-25" in err[0]
    db = tmp_path / "r.sqlite"
    run_sweep(parse_sweep(BODY), db, workers=0, progress=False)
    assert main(["sweep", "report", str(db), "--fits", "ecp5-85"]) == 2  # no camera
    assert "fits and camera go together" in capsys.readouterr().err
    assert main(["sweep", "report", str(db), "--fits", "nosuch", "--camera", "4x4",
                 "--rate-hz", "1"]) == 2
    assert "choose one of" in capsys.readouterr().err


def test_point_io_command_gives_the_figures_docs_quote(capsys, monkeypatch):
    root = Path(__file__).resolve().parents[3]
    doc = (root / "docs" / "design-space.md").read_text()
    block = doc.split("<!-- io-figures -->\n```text\n", 1)[1].split("```", 1)[0]
    monkeypatch.chdir(root)
    assert main(["sweep", "io", "points/ecp5-85-40khz.toml"]) == 0
    out = capsys.readouterr().out.splitlines()
    missing = [ln for ln in block.splitlines() if ln not in out]
    assert not missing, f"docs/design-space.md quotes lines rvsm sweep io does not print: " \
                        f"{missing}"
    assert main(["sweep", "io", "points/ecp5-85-40khz.toml", "--package", "CABGA381",
                 "--io-links", "bank", "--json"]) == 0
    (plan,) = json.loads(capsys.readouterr().out)
    assert (plan["fits"], plan["figure"], plan["budget"]) == (False, 22, 9)
    assert main(["sweep", "io"]) == 2 and "needs a point file" in capsys.readouterr().err
    assert main(["sweep", "io", "points/ecp5-85-40khz.toml", "--package", "QFN9"]) == 2
    assert "choose one of: LFE5U-85F CABGA381" in capsys.readouterr().err
