"""``rvsm verilog`` and ``rvsm verify`` (Icarus, tiny arrays)."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import pytest

from rvsm.model.fixed.config import default_design_point, save_design_point
from rvsm.sim.cli import main


def test_cli_verilog_writes_verilog_and_port_map(tmp_path: Path,
                                                capsys: pytest.CaptureFixture) -> None:
    point = replace(default_design_point().with_size(2, 3), model="fsm")
    save_design_point(tmp_path / "p.toml", point)
    assert main(["verilog", str(tmp_path / "p.toml"), "-o", str(tmp_path / "out")]) == 0
    names = {p.name for p in (tmp_path / "out").iterdir()}
    assert names == {"rvsm_array.v", "rvsm_array.ports.json", "rvsm_array.ports.md"}
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
