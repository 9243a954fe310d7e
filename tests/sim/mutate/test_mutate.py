"""``rvsm mutate``: the shipped RTL passes every check, a known mutant is killed by the
check aimed at it, and the command's statuses and report."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.fixed.point_toml import save_design_point
from rvsm.rtl.mutations import MUTATIONS
from rvsm.sim.cli import main
from rvsm.sim.mutate.checks import COSIM_CHECKS
from rvsm.sim.mutate.run import run_mutants, tiny_formal_point

CHECK = {c.name: c for c in COSIM_CHECKS}


@pytest.fixture(scope="module")
def contract():
    return default_design_point().with_size(4, 6).contract()


@pytest.mark.parametrize("reset", ["subtract", "zero"])
def test_the_shipped_stream_array_passes_every_check(contract, reset) -> None:
    c = dataclasses.replace(contract, reset=reset)
    for check in COSIM_CHECKS:
        assert check.mismatches(c, "stream", 2, None) == 0, check.name


@pytest.mark.parametrize(("mutation", "check", "reset"), [
    ("stream.threshold_off_by_one", "exact", "zero"),
    ("stream.no_threshold_forwarding", "threshold_collisions", "subtract"),
    ("stream.clear_forgets_scale0", "clear", "zero"),
    ("stream.advance_during_stall", "stall", "zero"),
    ("stream.zero_instead_of_subtract", "random", "subtract"),
])
def test_a_mutant_is_killed_by_the_check_aimed_at_it(contract, mutation, check,
                                                    reset) -> None:
    c = dataclasses.replace(contract, reset=reset)
    assert CHECK[check].mismatches(c, "stream", 2, mutation) > 0


def test_the_tiny_formal_point_is_valid() -> None:
    for arch in ("stream", "parallel"):
        point = tiny_formal_point(default_design_point(), arch)
        assert point.contract().accumulator_bits == 6


def test_run_mutants_reports_kills_and_survivors(monkeypatch) -> None:
    point = default_design_point().with_size(4, 6)
    names = ("stream.threshold_off_by_one", "stream.clear_forgets_scale0")
    results = run_mutants(point, ("stream",), 2, ("cosim",), first_kill=True, names=names)
    assert [r.mutation.name for r in results] == list(names)
    assert all(r.killed for r in results)
    assert "exact" in results[0].killed_by[0] and "clear" in results[1].killed_by[0]
    # with only the random check, the clear bug survives (nothing clears)
    import rvsm.sim.mutate.run as run_module

    monkeypatch.setattr(run_module, "COSIM_CHECKS", (CHECK["random"],))
    (r,) = run_mutants(point, ("stream",), 2, ("cosim",), names=names[1:])
    assert not r.killed and r.passed


def _point(tmp_path: Path) -> Path:
    path = tmp_path / "p.toml"
    save_design_point(path, default_design_point())
    return path


def test_cli_list_json_and_statuses(tmp_path, capsys, monkeypatch) -> None:
    assert main(["mutate", "--list", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)
    assert {m["mutation"] for m in listed} == set(MUTATIONS)
    point = _point(tmp_path)
    out = tmp_path / "m"
    assert main(["mutate", str(point), "--arch", "stream", "--checks", "cosim", "--size",
                 "4x6", "--mutation", "stream.swapped_lanes", "--json", "-o", str(out)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["killed"] == 1 and data["results"][0]["killed_by"]
    assert json.loads((out / "report.json").read_text())["mutations"] == 1
    import rvsm.sim.mutate.run as run_module

    monkeypatch.setattr(run_module, "COSIM_CHECKS", ())  # no check: every mutant survives
    assert main(["mutate", str(point), "--arch", "stream", "--checks", "cosim", "--size",
                 "4x6", "--mutation", "stream.swapped_lanes", "-o", str(out)]) == 1
    assert "survivors: stream.swapped_lanes" in capsys.readouterr().out
    for bad in (["--checks", "sim"], ["--lanes", "0"], ["--mutation", "nope"],
                ["--size", "4x5"]):
        assert main(["mutate", str(point), "--arch", "stream", *bad,
                     "-o", str(out)]) == 2
        err = capsys.readouterr().err
        assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


@pytest.mark.slow
def test_every_mutation_is_killed(tmp_path, capsys) -> None:
    """The whole run (``make mutate``): co-simulation and formal checks."""
    assert main(["mutate", str(_point(tmp_path)), "--json", "-o", str(tmp_path / "m")]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["killed"] == data["mutations"] == len(MUTATIONS)


def test_a_shared_point_skips_the_threshold_memory_mutations() -> None:
    """threshold.storage = "shared": the shipped array passes every check with one
    threshold per scale, the memory's mutations are skipped with a word, the others
    still die."""
    point = dataclasses.replace(default_design_point().with_size(4, 6),
                                threshold_storage="shared")
    c = point.contract()
    for check in COSIM_CHECKS:
        assert check.mismatches(c, "stream", 2, None) == 0, check.name
    assert MUTATIONS["stream.no_threshold_forwarding"].skip_reason(c)
    assert MUTATIONS["stream.no_threshold_forwarding"].skip_reason(
        default_design_point().contract()) is None
    said: list[str] = []
    names = ("stream.no_threshold_forwarding", "stream.threshold_off_by_one")
    results = run_mutants(point, ("stream",), 2, ("cosim",), first_kill=True, names=names,
                          progress=said.append)
    assert [r.mutation.name for r in results] == ["stream.threshold_off_by_one"]
    assert results[0].killed
    assert any("no_threshold_forwarding: skipped" in line for line in said)


def test_mutate_says_its_mutant_and_check_every_heartbeat(tmp_path, capsys,
                                                          monkeypatch) -> None:
    """While it works, ``mutate`` (with ``--json`` too) says on stderr which mutant and
    which check it is on, every heartbeat (8 s; 0.2 s here), and that it checks the
    shipped RTL first."""
    import re

    import rvsm.sim.mutate.run as run_module

    monkeypatch.setattr(run_module, "HEARTBEAT_SECONDS", 0.2)
    monkeypatch.setattr(run_module, "COSIM_CHECKS", (CHECK["random"],))  # fast
    assert main(["mutate", str(_point(tmp_path)), "--arch", "stream", "--checks", "cosim",
                 "--size", "4x6", "--mutation", "stream.swapped_lanes", "--json", "-o",
                 str(tmp_path / "m")]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["killed"] == 1
    err = captured.err.splitlines()
    assert err[0] == "mutate: stream: checking the shipped RTL first (cosim)"
    beat = r"\(\d+:\d\d elapsed\)"
    assert any(re.fullmatch(rf"mutate: the shipped stream RTL, check cosim:\w+ "
                            rf"\((subtract|zero) reset\) {beat}", line) for line in err), err
    assert any(re.fullmatch(rf"mutate: 1/1 stream.swapped_lanes, check cosim:\w+ "
                            rf"\((subtract|zero) reset\) {beat}", line) for line in err), err
