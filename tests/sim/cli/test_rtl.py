"""``rvsm verilog`` and ``rvsm verify`` (Icarus, tiny arrays)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from rvsm.model.fixed.design_point import default_design_point
from rvsm.model.fixed.point_toml import save_design_point
from rvsm.model.fixed.stimulus import Stimulus, load_stimulus, save_stimulus
from rvsm.sim.cli import main


def test_cli_verilog_writes_verilog_and_port_map(tmp_path: Path,
                                                capsys: pytest.CaptureFixture) -> None:
    point = replace(default_design_point().with_size(2, 3), model="fsm")
    save_design_point(tmp_path / "p.toml", point)
    assert main(["verilog", str(tmp_path / "p.toml"), "-o", str(tmp_path / "out"),
                 "--arch", "parallel"]) == 0
    names = {p.name for p in (tmp_path / "out").iterdir()}
    assert names == {f"rvsm_array{ext}" for ext in (".v", ".ports.json", ".ports.md", ".vlt",
                                                     ".core", ".sdc")}
    assert "latency 1 cycle(s)" in capsys.readouterr().out


def test_cli_verify_design_point(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    """``rvsm verify SCENE --fixed point.toml --json`` on a small dog1 point."""
    point = tmp_path / "p.toml"
    save_design_point(point, default_design_point().with_size(4, 6))
    rc = main(["verify", "coin", "--fixed", str(point), "--sim", "icarus", "--steps", "40",
               "--size", "4x6", "--json", "--work", str(tmp_path / "work")])
    out = json.loads(capsys.readouterr().out)
    assert rc == 0
    assert out["simulator"] == "icarus" and out["mismatches"] == 0
    assert out["compared"] == 40 * 4 * 4 * 6


@pytest.mark.slow  # 45 s; the long-run harness's replay stays in the default suite
def test_stimulus_file_replays_on_icarus(tmp_path: Path, capsys: pytest.CaptureFixture,
                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """``rvsm stimulus`` writes what the testbench reads: ``rvsm verify --stimulus FILE``."""
    point = tmp_path / "p.toml"
    save_design_point(point, default_design_point().with_size(4, 4))
    stim = tmp_path / "s.npz"
    assert main(["stimulus", "coin", "--fixed", str(point), "--steps", "25",
                 "-o", str(stim)]) == 0
    capsys.readouterr()
    work = str(tmp_path / "work")
    rc = main(["verify", "--stimulus", str(stim), "--sim", "icarus", "--json", "--work", work])
    out = json.loads(capsys.readouterr().out)
    assert rc == 0 and out["mismatches"] == 0
    assert out["compared"] == 25 * 4 * 4 * 4 and out["expected_spikes"] > 0

    # clears in the middle of the stream, then a tampered expectation: exit 1, named
    s = load_stimulus(stim)
    cleared = replace(s, clear_before=(8, 16),
                      spikes=s.contract.run(s.codes, s.thresholds, (8, 16)))
    save_stimulus(stim, cleared)
    assert main(["verify", "--stimulus", str(stim), "--json", "--work", work]) == 0
    assert json.loads(capsys.readouterr().out)["mismatches"] == 0
    wrong = cleared.spikes.copy()
    wrong[12, 1, 2, 3] = 1 if wrong[12, 1, 2, 3] != 1 else 0
    save_stimulus(stim, replace(cleared, spikes=wrong))
    # a file whose expectation does not follow from its own codes is a bad stimulus (2),
    # named before any simulator runs; --recompute-expected replays it from its codes
    runs = Path(work) / "runs"
    before = len(list(runs.iterdir()))
    assert main(["verify", "--stimulus", str(stim), "--steps", "20", "--work", work]) == 2
    err = capsys.readouterr().err
    assert "bad stimulus" in err and "step 12, scale 1, row 2, column 3" in err
    assert len(list(runs.iterdir())) == before  # nothing was simulated
    assert main(["verify", "--stimulus", str(stim), "--steps", "20", "--json",
                 "--recompute-expected", "--work", work]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["mismatches"] == 0 and out["expectation"] == "recomputed"
    assert main(["verify", "coin", "--fixed", str(point), "--recompute-expected"]) == 2
    assert "--stimulus FILE only" in capsys.readouterr().err

    # an RTL that disagrees with a consistent file: exit 1, with a waveform (the check is
    # bypassed here to stand for such an RTL)
    monkeypatch.setattr(Stimulus, "first_inconsistency", lambda self: None)
    assert main(["verify", "--stimulus", str(stim), "--steps", "20", "--json",
                 "--work", work]) == 1
    out = json.loads(capsys.readouterr().out)
    assert out["mismatches"] == 1 and out["first_mismatch"]["step"] == 12
    assert out["waves"].endswith(".fst") and Path(out["waves"]).exists()
    assert out["first_mismatch_time_ns"] > 0  # where to jump to in the waveform
    assert main(["verify", "--stimulus", str(stim), "--steps", "20", "--work", work]) == 1
    text = capsys.readouterr().out
    assert f"first mismatch at {out['first_mismatch_time_ns']} ns" in text
    assert "open it with: gtkwave" in text


def test_verify_random_corner_stimulus_reports_coverage(
    tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    """``rvsm verify --random SEED``: seeded corner stimulus, coverage per scale."""
    point = tmp_path / "p.toml"
    save_design_point(point, replace(default_design_point().with_size(4, 4), model="dog1"))
    args = ["verify", "--random", "5", "--fixed", str(point), "--size", "6x6", "--steps",
            "200", "--work", str(tmp_path / "work")]
    assert main([*args, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["mismatches"] == 0 and out["seed"] == 5 and out["steps"] == 200
    # 18-bit accumulators: 200 steps of this seed reach every bin, the bottom rail too
    assert len(out["coverage"]) == 1 and all(n for n in out["coverage"][0].values())
    assert main(args) == 0
    assert "coverage scale 0: 9/9 bins hit" in capsys.readouterr().out
    assert main(["verify", "--random", "5", "--fixed", str(point)]) == 2
    assert "--size, --steps" in capsys.readouterr().err


def test_verify_needs_scene_and_point_or_stimulus(tmp_path: Path,
                                                  capsys: pytest.CaptureFixture) -> None:
    assert main(["verify", "coin"]) == 2
    assert main(["verify", "coin", "--stimulus", str(tmp_path / "s.npz")]) == 2
    assert main(["verify", "--stimulus", str(tmp_path / "missing.npz")]) == 2
    err = capsys.readouterr().err
    assert "--stimulus" in err and "does not exist" in err


def test_every_command_defaults_to_the_stream_array_and_names_it(
        tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    point = tmp_path / "p.toml"
    save_design_point(point, replace(default_design_point().with_size(4, 6), model="fsm"))
    assert main(["verilog", str(point), "-o", str(tmp_path / "out")]) == 0
    printed = capsys.readouterr().out
    meta = json.loads((tmp_path / "out" / "rvsm_stream_array.ports.json").read_text())
    assert meta["arch"] == "stream"
    lag = meta["timing"]["lag"]
    assert "architecture stream (lanes 1)" in printed
    assert (f"lag {lag} beats (the spikes of input beat p come out 2 cycles after beat "
            f"p + {lag} is accepted: {lag + 1} cycles after beat p") in printed
    assert meta["pixel_to_spike"] == lag + 1
    assert main(["verilog", str(point), "-o", str(tmp_path / "par"), "--arch",
                 "parallel"]) == 0
    assert "architecture parallel," in capsys.readouterr().out
    par = json.loads((tmp_path / "par" / "rvsm_array.ports.json").read_text())
    assert par["arch"] == "parallel" and par["pixel_to_spike"] == par["latency"]
    assert main(["verify", "coin", "--fixed", str(point), "--steps", "6", "--json",
                 "--work", str(tmp_path / "work"), "--lanes", "2"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["arch"] == "stream" and out["options"] == {"lanes": 2}


@pytest.mark.parametrize("command", ["verilog", "verify", "fpga"])
def test_an_option_of_another_architecture_is_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture, command: str) -> None:
    point = tmp_path / "p.toml"
    save_design_point(point, default_design_point().with_size(4, 6))
    args = {"verilog": ["verilog", str(point), "-o", str(tmp_path / "o")],
            "verify": ["verify", "coin", "--fixed", str(point), "--work", str(tmp_path / "w")],
            "fpga": ["fpga", str(point), "--size", "4x6", "-o", str(tmp_path / "f")]}[command]
    assert main([*args, "--lanes", "3", "--arch", "parallel"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--lanes does not apply to --arch parallel" in err[0]
    assert not any(tmp_path.glob("[owf]"))
