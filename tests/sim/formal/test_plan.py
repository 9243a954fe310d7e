"""Formal plans (``rvsm formal --plan``): the shipped equivalence matrix parses into its 54
runs, a bad plan is one line naming the field, and a tiny plan runs (every run's line,
the matrix JSON, the worst status: 0, 1 with a counterexample)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from rvsm.model.infra.errors import RvsmError
from rvsm.model.kernels.receptive_fields import MODEL_NAMES
from rvsm.rtl.parallel.architecture import PARALLEL
from rvsm.rtl.parallel.harnesses import ParallelProperties
from rvsm.sim.cli import main
from rvsm.sim.formal.plan import load_formal_plan, parse_formal_plan

ROOT = Path(__file__).resolve().parents[3]
TINY = ROOT / "tests/data/formal-tiny.toml"


def _plan(formal: str, override: str = "", name: str = "t") -> str:
    return (f'[regression]\nname = "{name}"\n[base]\nfile = "{TINY}"\n[formal]\n{formal}\n'
            + override)


def test_the_equivalence_matrix_is_every_model_size_and_reset() -> None:
    plan = load_formal_plan(ROOT / "regressions/formal-equivalence.toml")
    assert (plan.name, plan.arch.name, plan.timeout) == ("equivalence", "stream", 3600.0)
    assert len(plan.runs) == len(MODEL_NAMES) * 3 * 2 == 54
    assert {r.model for r in plan.runs} == set(MODEL_NAMES)
    assert {(r.size, r.options["lanes"]) for r in plan.runs} == {
        ((3, 4), 2), ((3, 3), 1), ((3, 6), 3)}
    composed = {(r.model, r.size) for r in plan.runs if r.checks != ("equivalence",)}
    assert composed == {("dog4", (3, 4)), ("dog4", (3, 6))}
    assert {r.checks for r in plan.runs} == {("equivalence",), ("window", "sums", "composed")}
    first, second = plan.runs[:2]  # configs, then models, then reset modes
    assert (first.model, second.model, plan.runs[2].model) == ("fsm", "fsm", "gauss1")
    assert (first.reset, second.reset) == ("subtract", "zero")
    assert first.contract.reset == "subtract" and second.contract.reset == "zero"
    assert (first.contract.height, first.contract.width) == (3, 4)
    assert first.folder("equivalence") == f"equivalence-{first.model}-3x4-lanes2-subtract"


@pytest.mark.parametrize("formal, override, message", [
    ('models = ["dog9"]\nconfigs = [{ size = "3x4", lanes = 2 }]', "", "formal.models"),
    ('configs = [{ size = "3x4", lanes = 3 }]', "", "fsm at 3x4: lanes must be"),
    ('configs = [{ size = "3x4", lanes = 2 }]\nchecks = ["nope"]', "", "formal.checks"),
    ('arch = "parallel"\nconfigs = [{ size = "2x2", lanes = 2 }]', "", "--lanes"),
    ('configs = [{ lanes = 2 }]', "", "size"),
    ('configs = [{ size = "3x4", lanes = 2 }]\ndepth = 3', "", "formal.depth"),
    ('configs = [{ size = "3x4", lanes = 2 }]', '[[override]]\nconfigs = [{ size = "3x3", '
     'lanes = 1 }]\n', "override.configs"),
    ('configs = [{ size = "3x4", lanes = 2 }]\ntimeout = 0', "", "formal.timeout"),
])
def test_a_bad_plan_names_the_field(formal: str, override: str, message: str) -> None:
    with pytest.raises(RvsmError, match=message):
        parse_formal_plan(_plan(formal, override), "p.toml")


@pytest.fixture
def tiny_plan(tmp_path: Path) -> Path:
    """The fully parallel array's properties at 2x2, fsm, both reset modes: two runs."""
    path = tmp_path / "plan.toml"
    path.write_text(_plan('arch = "parallel"\nmodels = ["fsm"]\nconfigs = [{ size = "2x2" '
                          '}]\nchecks = ["properties"]', name="tiny"))
    return path


def test_a_plan_runs_and_writes_its_matrix(tiny_plan: Path, tmp_path: Path,
                                           capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "out"
    assert main(["formal", "--plan", str(tiny_plan), "-j", "2", "-o", str(out)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("[1/2] fsm") and "subtract" in lines[0]
    assert "pass" in lines[0] and "zero" in lines[1]
    assert "2/2 passed" in lines[-1]
    data = json.loads((out / "tiny-matrix.json").read_text())
    assert [(r["reset"], r["status"], r["checks"]) for r in data["runs"]] == [
        ("subtract", 0, ["properties"]), ("zero", 0, ["properties"])]
    assert all(Path(r["folder"], "report.json").is_file() for r in data["runs"])


def test_a_counterexample_makes_the_plan_exit_1(tiny_plan: Path, tmp_path: Path,
                                                capsys: pytest.CaptureFixture,
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    def buggy(contract, mutation=None, **options):
        return ParallelProperties(contract, mutation="parallel.threshold_off_by_one")

    monkeypatch.setitem(PARALLEL.formal, "properties", buggy)
    # with --json too, stderr says how far the plan is every heartbeat (8 s; 0.2 s here)
    monkeypatch.setattr("rvsm.sim.cosim.builds.build_notes.HEARTBEAT_SECONDS", 0.2)
    assert main(["formal", "--plan", str(tiny_plan), "--mode", "bmc", "--depth", "3",
                 "-o", str(tmp_path / "out"), "--json"]) == 1
    captured = capsys.readouterr()
    runs = json.loads(captured.out)["runs"]
    assert [r["status"] for r in runs] == [1, 1]
    assert re.search(r"rvsm: still formal plan tiny: [012]/2 run\(s\) done \(\d+:\d\d "
                     r"elapsed\)", captured.err), captured.err


def test_plan_refuses_a_point_and_its_options(tiny_plan: Path, tmp_path: Path,
                                              capsys: pytest.CaptureFixture) -> None:
    for extra in ([str(TINY)], ["--size", "2x2"], ["--lanes", "2"], ["--check", "x"],
                  ["--interface", "axis"], ["--fifo-depth", "8"]):
        assert main(["formal", "--plan", str(tiny_plan), "-o", str(tmp_path / "o"),
                     *extra]) == 2
        err = capsys.readouterr().err.strip()
        assert "cannot be combined with --plan" in err and len(err.splitlines()) == 1
    assert main(["formal", "-o", str(tmp_path / "o")]) == 2
    assert "--plan" in capsys.readouterr().err
