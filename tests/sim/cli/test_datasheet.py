"""``rvsm quality`` and ``rvsm datasheet`` at a tiny size: the page has every section, the
figures follow the inputs given, and refused inputs leave nothing behind."""

from __future__ import annotations

import contextlib
import csv
import json
from pathlib import Path

import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.sim.cli import datasheet as cli
from rvsm.sim.cli import main
from rvsm.sim.studies import point_quality
from rvsm.sim.studies.datasheet import FIRST, LAST, SECTIONS
from rvsm.sim.studies.datasheet_inputs import load_point_file, load_regress

TINY = ["--size", "16x24", "--frames", "3", "--scenes", "coin", "--quiet"]
PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> dict[str, Path]:
    """A 16x24 point with ``[rtl] lanes = 4``, its saved quality result, and fake
    fpga / verify / JUnit results with known numbers."""
    d = tmp_path_factory.mktemp("inputs")
    point = d / "point.toml"
    assert main(["config", "new", "--size", "16x24", "-o", str(point)]) == 0
    point.write_text(point.read_text() + "\n[rtl]\nlanes = 4\n")
    quality = d / "quality.json"
    assert main(["quality", str(point), *TINY, "-o", str(d / "q.csv")]) == 0
    study = point_quality.run_point_quality(load_point_file(point).point, ["coin"],
                                            size=(16, 24), frames=3)
    quality.write_text(study.to_json())
    fpga = {"arch": "stream", "model": "dog4", "height": 16, "width": 24, "lanes": 4,
            "device": "ecp5-85", "mode": "place-and-route", "fmax_mhz": 123.4,
            "lut4": {"used": 12345, "available": 83640}, "ff": {"used": 6789,
                                                                "available": 83640},
            "bram": {"used": 17, "available": 208},
            "slope": {"lanes": [4, 8], "lut4": [0, 0], "ff": [0, 0], "lut4_per_lane": 1111.0,
                      "ff_per_lane": 999.0, "lut4_fixed": 222.0, "ff_fixed": 33.0}}
    (d / "fpga.json").write_text(json.dumps(fpga))
    (d / "verify.json").write_text(json.dumps({"sim": "verilator", "arch": "stream",
                                               "compared": 4321, "mismatches": 0}))
    (d / "junit.xml").write_text(
        '<?xml version="1.0"?><testsuites><testsuite name="smoke" tests="2">'
        '<testcase name="run-a"/><testcase name="run-b"><failure message="x"/></testcase>'
        "</testsuite></testsuites>\n")
    (d / "formal.json").write_text(json.dumps({
        "arch": "stream", "options": {"lanes": 2}, "ok": True, "size": [3, 4], "model": "dog2",
        "checks": [{"check": "protocol", "mode": "bmc", "depth": 30, "status": "pass"},
                   {"check": "tail", "mode": "prove", "depth": 12, "status": "pass"}]}))
    (d / "mutate.json").write_text(json.dumps({"checks": ["cosim", "formal"], "mutations": 15,
                                               "killed": 14, "survivors": ["stream.odd"]}))
    return {"point": point, "quality": quality, "csv": d / "q.csv", "fpga": d / "fpga.json",
            "verify": d / "verify.json", "junit": d / "junit.xml",
            "formal": d / "formal.json", "mutate": d / "mutate.json"}


def test_defaults_match_the_study():
    assert cli.DEFAULT_FRAMES == point_quality.DEFAULT_FRAMES
    assert cli.DEFAULT_STEPS_PER_FRAME == point_quality.DEFAULT_STEPS_PER_FRAME


def test_quality_json_and_csv(files, capsys):
    assert main(["quality", str(files["point"]), *TINY, "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["size"] == [16, 24] and d["frames"] == 3 and d["steps"] == 20
    assert [(r["scene"], r["noise"]) for r in d["rows"]] == [("coin", False), ("coin", True)]
    for r in d["rows"]:  # the default point: the chip costs what quantisation costs
        assert r["chip_cost_db"] == r["quantisation_cost_db"]
    # the same seeds: the saved study and the CSV hold the same numbers
    saved = json.loads(files["quality"].read_text())
    assert [r["psnr_twin"] for r in saved["rows"]] == [r["psnr_twin"] for r in d["rows"]]
    rows = list(csv.DictReader(files["csv"].open()))
    assert [r["noise"] for r in rows] == ["off", "on"]
    assert float(rows[0]["psnr_twin"]) == pytest.approx(d["rows"][0]["psnr_twin"], abs=1e-4)


def test_quality_refusals(files, capsys):
    assert main(["quality", str(files["point"]), *TINY, "--noise", "maybe"]) == 2
    assert main(["quality", str(files["point"]), "--scenes", "nowhere"]) == 2
    assert main(["quality", str(files["point"]), "--size", "4x4"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and all(e.startswith("rvsm: error: ") for e in err)


def _sections(md: str) -> list[str]:
    return [line[3:] for line in md.splitlines() if line.startswith("## ")]


def test_datasheet_with_every_saved_result(files, tmp_path):
    out = tmp_path / "sheet"
    rc = main(["datasheet", str(files["point"]), "-o", str(out), "--quality",
               str(files["quality"]), "--fpga", str(files["fpga"]), "--verify",
               str(files["verify"]), "--regress", str(files["junit"]), "--formal",
               str(files["formal"]), "--mutate", str(files["mutate"]), "--quiet"])
    assert rc == 0
    md = (out / "datasheet.md").read_text()
    assert _sections(md) == [FIRST, *SECTIONS, LAST]
    for name in ("resources.png", "clock.png", "quality_costs.png", "reconstructions.png"):
        assert (out / name).read_bytes().startswith(PNG)
        assert f"]({name})" in md
    assert md.count("Sources:") == len(SECTIONS)
    # the fake results record no command and no --commands gives one: said, not invented
    reproduce = md.split("## Reproduce")[1]
    assert reproduce.count("NOT RECORDED") == 2 and "..." not in reproduce  # verify, formal
    assert "rvsm mutate " in reproduce and "rvsm regress regressions/smoke.toml" in reproduce
    # the fake fpga report's numbers, and its slope as the logic per lane
    assert "12,345" in md and "6,789" in md and "| DP16KD | 17 (8.2 %)" in md
    assert "123.4 MHz" in md and "1,111 LUT4 and 999 FF per lane" in md
    # the estimate at the sensor's size: nextpnr's 1.199 x (222 + 4 x 1111) LUT4 (one bank:
    # no multiplexer) and the line buffer's RAM (rtl/fpga/placed_logic.py)
    assert "1.199 x (222 + 4 x 1111 per lane)" in md
    assert "| LUT4 | 12,345 (14.8 %) | 5," in md
    # lanes from the point's [rtl] table; clock = 16 x 24/4 x 40 kHz
    assert "P = 4 lanes ([rtl] lanes of the point)" in md and "**3.8 MHz**" in md
    assert "`THR_DATA0`" in md and "`s_axis_tdata`" in md and "`codes_payload`" in md
    assert "PASS: 0 mismatches in 4,321 accumulator-steps compared" in md
    assert "1 of 2 test cases pass, 1 fail" in md and "| - run-b | | fail |" in md
    assert ("PASS: 2 of 2 checks pass: protocol pass (bmc, depth 30); tail pass (prove, "
            "depth 12)" in md and "dog2 3x4, P = 2" in md)
    # a per-pixel threshold memory: its own row and its cost; THR_ADDR's word and scale
    assert "| `threshold.storage` | per-pixel | thresholds S x H x W x (A - 1)" in md
    # 16 rows x 6 groups = 96 words (7 bits); 4 scales at [17:16]
    assert "| `THR_ADDR` | [6:0] | `word` |" in md and "| `THR_ADDR` | [17:16] | `scale` |" in md
    assert "pack differently" in md
    assert "threshold.contrast" not in md and "adc.log_frac_bits" not in md
    # the summary's clock row: 123.4 MHz against 3.84 MHz needed, as headroom
    assert "Fmax 123.4 MHz measured (nextpnr): 3113.5 % headroom" in md
    assert "14 of 15 mutations killed; survivors: stream.odd" in md
    assert "| not run |" not in md.split("## Verification")[1]
    q = json.loads(files["quality"].read_text())
    assert f"| coin | {q['rows'][0]['psnr_twin']:.2f} |" in md


def test_datasheet_marks_an_estimate_only_device(files, tmp_path):
    out = tmp_path / "sheet"
    assert main(["datasheet", str(files["point"]), "-o", str(out), "--device", "gw5ast-138",
                 "--no-synthesis", "--quality", str(files["quality"]), "--quiet"]) == 0
    md = (out / "datasheet.md").read_text()
    summary = md.split("## Summary")[1].split("\n## ")[0]
    assert "gw5ast-138: GW5AST-LV138FPG676AC1/I0, **estimate only** (rvsm fpga has no " \
           "gowin flow" in summary and "placed by" not in summary
    assert "Device gw5ast-138 (estimate only): " in md.split("## Resources")[1]


def test_datasheet_runs_the_study_and_says_what_is_missing(files, tmp_path, monkeypatch):
    from rvsm.rtl.fpga import lane_cost

    seen = []

    def fake(point, **kw):
        seen.append(point.shape)
        return lane_cost.LaneCost(size=(16, 16), lanes=(1, 2), logic=(600, 1100),
                                  ff=(300, 700), lut4_per_lane=500.0, ff_per_lane=400.0,
                                  lut4_base=100.0, accumulator_bits=0, threshold_bits=0,
                                  line_buffer_bits=0, fmax_mhz=None, seconds=1.0)

    monkeypatch.setattr(lane_cost, "lane_cost", fake)
    out = tmp_path / "sheet"
    assert main(["datasheet", str(files["point"]), "-o", str(out), "--lanes", "8",
                 "--rate-hz", "10000", *TINY]) == 0
    md = (out / "datasheet.md").read_text()
    assert seen == [(16, 24)]
    assert "500 LUT4 and 400 FF per lane" in md and "100 + 8 x 500 per lane" in md
    assert "P = 8 lanes (--lanes)" in md and "16 x 24/8 x 10,000" in md
    assert "measured: not given" in md and "timing model" in md
    verification = md.split("## Verification")[1]
    assert verification.count("| not run |") == 4  # verify, regress, formal, mutate
    assert "rvsm quality" in md.split("## Image quality")[1]


def test_commands_file_gives_the_reproduce_commands(files, tmp_path):
    commands = tmp_path / "commands.toml"
    commands.write_text('[verify]\ncommand = "rvsm verify coin --fixed point.toml --steps 20 '
                        '--json"\nsource = "the test quotes it"\n')
    out = tmp_path / "sheet"
    assert main(["datasheet", str(files["point"]), "-o", str(out), "--quality",
                 str(files["quality"]), "--verify", str(files["verify"]), "--commands",
                 str(commands), "--no-synthesis", "--quiet"]) == 0
    reproduce = (out / "datasheet.md").read_text().split("## Reproduce")[1]
    assert ("(reconstructed: the test quotes it):\n\n```\nrvsm verify coin --fixed "
            "point.toml --steps 20 --json\n```") in reproduce


def test_regress_database_is_read(tmp_path):
    from rvsm.sim.regress.store import RegressionStore

    db = tmp_path / "r.sqlite"
    with RegressionStore(db) as store:
        store.db.executemany("INSERT INTO runs (key, plan, label, status) VALUES (?,?,?,?)",
                             [("k1", "smoke", "a", "pass"), ("k2", "smoke", "b", "error"),
                              ("k3", "smoke", "c", "pass")])
        store.db.commit()
    r = load_regress(db)
    assert r.suites == ("smoke",) and (r.count("pass"), r.count("error")) == (2, 1)
    other = tmp_path / "x.sqlite"
    import sqlite3

    with contextlib.closing(sqlite3.connect(other)) as con:
        con.execute("CREATE TABLE t (a)")
        con.commit()
    with pytest.raises(RvsmError, match="not a regression database|cannot read"):
        load_regress(other)


@pytest.mark.parametrize("case", ["missing", "bad_json", "other_point", "bad_lanes",
                                  "bad_fpga", "device", "bad_rtl", "bad_formal",
                                  "cut_command", "unknown_command"])
def test_datasheet_refusals_leave_nothing(files, tmp_path, capsys, case):
    out = tmp_path / "sheet"
    other = tmp_path / "other.json"
    args = ["datasheet", str(files["point"]), "-o", str(out), "--no-synthesis", *TINY]
    if case == "missing":
        args += ["--fpga", str(tmp_path / "nowhere.json")]
    elif case == "bad_json":
        other.write_text("{not json")
        args += ["--verify", str(other)]
    elif case == "other_point":
        q = json.loads(files["quality"].read_text())
        q["point"]["adc_bits"] = 5
        other.write_text(json.dumps(q))
        args += ["--quality", str(other)]
    elif case == "bad_lanes":
        args += ["--lanes", "5"]
    elif case == "bad_fpga":
        other.write_text(json.dumps({"lut4": {"used": 1}}))
        args += ["--fpga", str(other)]
    elif case == "device":
        args += ["--device", "no-such-chip"]
    elif case == "bad_formal":
        other.write_text(json.dumps({"checks": "all fine"}))
        args += ["--formal", str(other)]
    elif case in ("cut_command", "unknown_command"):  # a command cut short, a stray table
        table = "verify" if case == "cut_command" else "simulate"
        other.write_text(f'[{table}]\ncommand = "rvsm verify coin ..."\nsource = "docs"\n')
        args += ["--commands", str(other)]
    else:
        point = tmp_path / "p.toml"
        point.write_text(files["point"].read_text().replace("lanes = 4", "lanes = 0"))
        args[1] = str(point)
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("rvsm: error: ")
    assert not out.exists()


def test_datasheet_board_section_and_csv_follow_board_fpga(files, tmp_path, capsys):
    """``--board-fpga``: the Board section and ``pin_plan.csv`` beside the page, the
    board build's command in Reproduce; a report of another model is refused with
    nothing written; remade without it, the section names the command and the CSV goes.
    The report is the tiny board build's (tests/data/board-tiny/, the FSM point; its
    tables are checked in tests/sim/studies/test_datasheet_board.py) relabelled as this
    dog4 point's, whose links at 2x4 and one lane have the same pairs."""
    from rvsm.sim.studies.datasheet_board import load_board_report, pin_plan_csv

    saved = Path(__file__).resolve().parents[2] / "data" / "board-tiny" / "fpga-board.json"
    out = tmp_path / "sheet"
    base = ["datasheet", str(files["point"]), "-o", str(out), "--quality",
            str(files["quality"]), "--fpga", str(files["fpga"]), "--quiet"]
    assert main([*base, "--board-fpga", str(saved)]) == 2
    assert "the board report is of model fsm" in capsys.readouterr().err
    assert not out.exists()
    board = json.loads(saved.read_text())
    board["model"] = "dog4"
    mine = tmp_path / "fpga-board.json"
    mine.write_text(json.dumps(board))
    assert main([*base, "--board-fpga", str(mine)]) == 0
    md = (out / "datasheet.md").read_text()
    assert _sections(md) == [FIRST, *SECTIONS, LAST]
    section = md.split("\n## Board\n")[1].split("\n## ")[0]
    b = board["board"]
    assert f"**{b['package']}**: {b['pins_used']} of {b['pins_available']} pins" in section
    assert "](pin_plan.csv)" in section
    assert (out / "pin_plan.csv").read_text() == pin_plan_csv(load_board_report(mine))
    assert "place and route on the board's pins" in md and "--interface axis --board" in md
    assert main([*base, "--force"]) == 0
    md = (out / "datasheet.md").read_text()
    section = md.split("\n## Board\n")[1].split("\n## ")[0]
    assert f"--board --json -o build/bench-board > {out.as_posix()}/results/fpga-board.json" \
        in section
    assert not (out / "pin_plan.csv").exists()
