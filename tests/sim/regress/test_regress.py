"""``rvsm regress``: plans validated in one line, runs resumable in SQLite without
counting twice, verdicts and exit statuses, merged coverage and JUnit XML."""

from __future__ import annotations

from pathlib import Path
from xml.etree import ElementTree as ET

import pytest

from rvsm.model.infra.errors import RvsmError, ToolError
from rvsm.sim.cli import main
from rvsm.sim.regress.plan import load_plan, parse_plan
from rvsm.sim.regress.run import run_regression
from rvsm.sim.regress.store import RegressionStore
from rvsm.sim.regress.work import scene_for
from tests.sim.regress.conftest import TINY_PLAN as TINY
from tests.sim.regress.conftest import write_plan


def test_plan_expands_and_refuses_bad_fields(tmp_path: Path) -> None:
    """Runs are scenes-then-seeds x models x lanes x simulators with unique keys; every
    bad field is one RvsmError naming it."""
    plan = parse_plan(TINY.replace('lanes = [2]', 'lanes = [2, 4]')
                      .replace('[run]', '[run]\nmodels = ["dog2", "fsm"]'), "p")
    assert len(plan.runs) == 3 * 2 * 2
    assert len({r.key for r in plan.runs}) == len(plan.runs)
    assert plan.runs[0].label == "scene:coin dog2 6x8 stream P=2 icarus"
    with pytest.raises(RvsmError, match=r"unknown section \[extra\]"):
        parse_plan(TINY + "[extra]\n", "p")
    cases = {
        'lanes = [3]': "run.lanes: 3 must be an integer >= 1 dividing the width 8",
        'simulators = ["ghdl"]': "run.simulators: 'ghdl' is not one of",
        'steps = 0': "run.steps must be an integer >= 1",
        'seeds = [-1]': "run.seeds must be integers >= 0",
        'scenes = ["nope"]': "run.scenes: 'nope' is not a built-in scene name",
        'harness = "fast"': "run.harness must be one of",
    }
    for line, message in cases.items():
        key = line.split(" =")[0]
        text = "\n".join(line if ln.startswith(key + " =") else ln
                         for ln in TINY.splitlines())
        with pytest.raises(RvsmError, match=message.replace("(", r"\(")):
            parse_plan(text, "p")
    with pytest.raises(RvsmError, match="run.harness"):
        parse_plan(TINY.replace('[run]', '[run]\narch = "parallel"'), "p")
    with pytest.raises(RvsmError, match="needs scenes, seeds or protocol_seeds"):
        parse_plan(TINY.replace('scenes = ["coin"]', "").replace("seeds = [1, 2]", ""), "p")
    with pytest.raises(RvsmError, match="run.code_coverage needs harness"):
        parse_plan(TINY.replace("[run]", "[run]\ncode_coverage = true"), "p")
    with_cov = parse_plan(TINY.replace("[run]", "[run]\ncode_coverage = true")
                          .replace('"icarus"', '"verilator"'), "p")
    assert all(r.code_coverage for r in with_cov.runs)
    with pytest.raises(RvsmError, match="unknown key run.colour"):
        parse_plan(TINY.replace("[run]", "[run]\ncolour = 1"), "p")


def test_protocol_seeds_run_the_protocol_testbench(tmp_path: Path) -> None:
    """``protocol_seeds`` add per-cycle protocol runs (stream only); they pass and their
    bins (clears at positions of the frame, threshold writes meeting reads) join the
    closure report."""
    text = TINY.replace('scenes = ["coin"]', "").replace("seeds = [1, 2]",
                                                          "protocol_seeds = [3]")
    plan = parse_plan(text, "p")
    assert [(r.stimulus, r.harness, r.code_coverage) for r in plan.runs] == \
        [("protocol:3", "cycle", False)]
    with pytest.raises(RvsmError, match="protocol_seeds drive the stream"):
        parse_plan(text.replace("[run]", '[run]\narch = "parallel"')
                   .replace('harness = "chunk"', ""), "p")
    s = run_regression(plan, tmp_path / "r.sqlite", tmp_path / "w", workers=0,
                       progress=False)
    assert (s.ran, s.count("pass"), s.exit_status) == (1, 1, 0)
    cov = s.rows[0]["coverage"]
    assert cov[0]["thr_write_same_edge"] is not None
    assert sum(n or 0 for k, n in cov[0].items() if k.startswith("clear_at_")) > 0


def test_regression_runs_resumes_and_reports(tmp_path: Path) -> None:
    """In this process (workers=0): every run passes, coverage merges over the seeds,
    JUnit has one case per run; a second call runs nothing and counts nothing twice."""
    plan = load_plan(write_plan(tmp_path))
    db, work, junit = tmp_path / "r.sqlite", tmp_path / "w", tmp_path / "r.xml"
    s = run_regression(plan, db, work, workers=0, junit=junit, progress=False)
    assert (s.ran, s.skipped, s.count("pass"), s.exit_status) == (3, 0, 3, 0)
    scale0 = next(line for line in s.closure if "scale 0:" in line)
    hit, total = (int(v) for v in scale0.split(":")[1].split()[0].split("/"))
    assert total > 9 and hit > 0  # the nine stimulus bins and the lanes at the borders
    assert not any("measured no functional coverage" in line for line in s.closure)
    suite = ET.parse(junit).getroot().find("testsuite")
    assert suite is not None and suite.get("tests") == "3" and suite.get("failures") == "0"
    assert len(suite.findall("testcase")) == 3
    again = run_regression(plan, db, work, workers=0, progress=False)
    assert (again.ran, again.skipped, len(again.rows)) == (0, 3, 3)
    with RegressionStore(db) as store:
        assert len(store.rows()) == 3


def test_regress_exit_statuses(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                               capsys: pytest.CaptureFixture) -> None:
    """A mismatching run is exit 1 (named, a JUnit failure); a tool failure is exit 3
    and is retried by the next call; a bad plan is exit 2."""
    import rvsm.sim.cosim.verify as verify_module

    def mismatching(*args, **kwargs):
        return {"mismatches": 2, "compared": 10, "coverage": None, "run_dir": "r",
                "waves": "w.fst", "first_mismatch": {"step": 3, "scale": 0, "row": 1,
                                                     "column": 2}}

    def failing(*args, **kwargs):
        raise ToolError("verilator build (make) exited with status 2; log: x.log")

    plan = write_plan(tmp_path, TINY.replace('scenes = ["coin"]', "").replace("[1, 2]", "[1]"))
    common = ["--workers", "0", "--no-progress", "--work", str(tmp_path / "w")]
    monkeypatch.setattr(verify_module, "random_verify", failing)
    assert main(["regress", str(plan), "-o", str(tmp_path / "a.sqlite"), *common]) == 3
    out = capsys.readouterr().out
    assert "ERROR seed:1" in out and "rerun the same command" in out
    monkeypatch.setattr(verify_module, "random_verify", mismatching)
    junit = tmp_path / "a.xml"
    assert main(["regress", str(plan), "-o", str(tmp_path / "a.sqlite"), "--junit",
                 str(junit), *common]) == 1
    out = capsys.readouterr().out
    assert "1 ran now" in out and "FAIL seed:1" in out and "step=3" in out
    assert ET.parse(junit).getroot().find("testsuite/testcase/failure") is not None
    bad = write_plan(tmp_path, TINY.replace("steps = 40", "steps = -1"))
    assert main(["regress", str(bad), "-o", str(tmp_path / "b.sqlite"), *common]) == 2
    assert "run.steps must be an integer >= 1" in capsys.readouterr().err


def test_scene_runs_render_enough_frames() -> None:
    """A scene run longer than a built-in scene's default length renders more frames."""
    plan = parse_plan(TINY.replace("steps = 40", "steps = 1234"), "p")
    scene = scene_for(plan.runs[0])
    assert scene.num_steps >= 1234 and scene.shape == (6, 8)
