"""``rvsm formal`` at the tiny point: exit 0 (proven, --json shape), 1 (a counterexample
block naming property, source line, step and VCD; an unreached cover), 2 (bad input, one
line), 3 (a missing solver, one line)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from rvsm.model.infra.errors import ToolError
from rvsm.rtl.parallel.architecture import PARALLEL
from rvsm.rtl.parallel.harnesses import ParallelProperties
from rvsm.rtl.stream.dimensions import StreamGeometry
from rvsm.sim.cli import main
from rvsm.sim.formal import sby


@pytest.fixture
def formal(tmp_path: Path, formal_point_toml: Path):
    """``rvsm formal POINT --arch parallel -o tmp/out EXTRA...`` -> exit status."""
    def run(*extra: str) -> int:
        return main(["formal", str(formal_point_toml), "--arch", "parallel",
                     "-o", str(tmp_path / "out"), *extra])
    return run


def test_proven_json(formal, tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    assert formal("--json", "--check", "properties") == 0
    out = json.loads(capsys.readouterr().out)
    assert (out["arch"], out["ok"], out["exit_status"], out["size"]) == \
        ("parallel", True, 0, [2, 2])
    (check,) = out["checks"]
    assert (check["check"], check["mode"], check["status"]) == ("properties", "prove",
                                                                 "pass")
    assert check["depth"] == ParallelProperties.depth and check["counterexample"] is None
    assert {p["status"] for p in check["properties"]} == {"proven"}
    assert {"fire.threshold_implies_spike", "reset.subtract"} <= {
        p["name"] for p in check["properties"]}
    assert set(check["properties"][0]) == {"name", "kind", "src", "status", "depth",
                                           "description"}
    assert json.loads((tmp_path / "out" / "report.json").read_text())["ok"] is True


def test_counterexample_block(formal, tmp_path: Path, capsys: pytest.CaptureFixture,
                              monkeypatch: pytest.MonkeyPatch) -> None:
    def buggy(contract, mutation=None, **options):
        return ParallelProperties(contract, mutation="parallel.threshold_off_by_one")

    monkeypatch.setitem(PARALLEL.formal, "properties", buggy)
    assert formal("--mode", "bmc", "--depth", "3") == 1
    out = capsys.readouterr().out
    block = out[out.index("COUNTEREXAMPLE"):]
    assert "rtl/parallel/harnesses.py:" in block and "step:   1" in block
    vcd = Path(block.split("trace:")[1].split()[0])
    assert vcd.is_file() and vcd.parent == tmp_path / "out"
    assert "failed" in out and "a property FAILED" in out


def test_unreached_cover_is_exit_1(formal, capsys: pytest.CaptureFixture) -> None:
    assert formal("--mode", "cover", "--depth", "1", "--json") == 1
    check = json.loads(capsys.readouterr().out)["checks"][0]
    assert check["status"] == "fail" and "not covered" in {
        p["status"] for p in check["properties"]}


@pytest.mark.parametrize("extra, message", [
    (("--size", "2x"), "size"),
    (("--depth", "0"), "--depth"),
    (("--check", "nope"), "unknown formal check"),
    (("--lanes", "2"), "lanes"),
    (("--size", "8x10"), "tiny arrays"),
])
def test_bad_input_is_exit_2(formal, tmp_path: Path, capsys: pytest.CaptureFixture,
                             extra: tuple[str, ...], message: str) -> None:
    assert formal(*extra) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1


def test_bad_mode_is_a_usage_error(formal) -> None:
    with pytest.raises(SystemExit) as exc:
        formal("--mode", "sim")
    assert exc.value.code == 2


def test_missing_solver_is_exit_3(formal, tmp_path: Path, capsys: pytest.CaptureFixture,
                                  monkeypatch: pytest.MonkeyPatch) -> None:
    def missing(name: str) -> str:
        raise ToolError(f"{name} not found; install it with `pip install z3-solver`")

    monkeypatch.setattr(sby, "find_tool", missing)
    assert formal() == 3
    err = capsys.readouterr().err.strip()
    assert "not found" in err and len(err.splitlines()) == 1


def test_solver_over_its_time_limit_is_exit_3(formal, capsys: pytest.CaptureFixture) -> None:
    assert formal("--timeout", "0.2") == 3
    captured = capsys.readouterr()
    errors = [line for line in captured.err.splitlines() if line.startswith("rvsm: error")]
    assert len(errors) == 1 and "time limit" in errors[0]
    assert "not checked" in captured.out and "cover" not in captured.out.split("note:")[0]


def test_stream_checks_run_side_by_side(formal_point_toml: Path, formal_point,
                                        tmp_path: Path,
                                        capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "stream"
    assert main(["formal", str(formal_point_toml), "--arch", "stream", "--size", "3x4",
                 "--lanes", "2", "--model", "fsm", "--check", "equivalence", "tail",
                 "-j", "2", "--json", "-o", str(out)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert (report["model"], report["size"], report["options"]) == ("fsm", [3, 4],
                                                                   {"lanes": 2})
    # in the registry's order whatever the order asked, each to two frames plus the lag
    geo = StreamGeometry(replace(formal_point, model="fsm").with_size(3, 4).contract(), 2)
    depth = 2 * geo.beats_per_frame + geo.lag + 2
    assert [(c["check"], c["mode"], c["status"], c["depth"]) for c in report["checks"]] == [
        ("tail", "bmc", "pass", depth), ("equivalence", "bmc", "pass", depth)]
    assert (out / "tail" / "formal.log").is_file()


def test_the_ip_register_file_is_proven(formal_point_toml: Path, tmp_path: Path,
                                        capsys: pytest.CaptureFixture) -> None:
    """``--interface axis`` checks the AXI IP: its register file (docs/ip.md)."""
    from rvsm.rtl.ip.register_harness import RegisterFileProperties

    argv = ["formal", str(formal_point_toml), "--arch", "stream", "--interface", "axis",
            "--size", "3x4", "--lanes", "2", "-o", str(tmp_path / "o")]
    assert main([*argv, "--check", "registers", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert (report["arch"], report["options"]) == ("stream_axis",
                                                   {"lanes": 2, "fifo_depth": 16})
    assert [(c["check"], c["mode"], c["status"], c["depth"]) for c in report["checks"]] == [
        ("registers", "prove", "pass", RegisterFileProperties.depth)]
    for bad, message in ((["--check", "tail"], "unknown formal check 'tail' for --arch "
                          "stream_axis"), (["--interface", "native", "--fifo-depth", "8"],
                                           "--interface axis only")):
        assert main([*argv, *bad]) == 2
        err = capsys.readouterr().err.strip()
        assert message in err and len(err.splitlines()) == 1


@pytest.mark.parametrize("extra, message", [
    (("--jobs", "0"), "--jobs"),
    (("--model", "dog9"), "--model"),
])
def test_stream_bad_input_is_exit_2(formal_point_toml: Path, tmp_path: Path,
                                    capsys: pytest.CaptureFixture,
                                    extra: tuple[str, ...], message: str) -> None:
    argv = ["formal", str(formal_point_toml), "--arch", "stream", "--size", "3x4",
            "--lanes", "2", "-o", str(tmp_path / "o"), *extra]
    try:
        status = main(argv)
    except SystemExit as exc:  # argparse's choices
        status = exc.code
    assert status == 2
    assert message in capsys.readouterr().err


def test_full_size_point_is_refused_at_once(tmp_path: Path,
                                            capsys: pytest.CaptureFixture) -> None:
    """A point without a tiny size (here: a file of only a comment, the default 250x400)
    is refused with one line before any solver starts; no output folder is made."""
    point = tmp_path / "point.toml"
    point.write_text("# rvsm fixed-point design point\n")
    out = tmp_path / "out"
    assert main(["formal", str(point), "--arch", "stream", "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert "tiny arrays" in err and "250x400" in err and len(err.splitlines()) == 1
    assert not out.exists()


def test_help_names_every_registered_check(capsys: pytest.CaptureFixture) -> None:
    """``rvsm formal --help`` listed 5 of the stream's 8 checks (issue 34): the list now
    comes from the registry."""
    from rvsm.rtl.architectures.registry import ARCHITECTURES, WRAPPERS
    from rvsm.sim.cli.main import main

    with pytest.raises(SystemExit):
        main(["formal", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for name, arch in (*ARCHITECTURES.items(), *WRAPPERS.items()):
        for check in arch.formal:
            assert check in text, (name, check)
    assert "stream --interface axis: registers" in text
