"""Smoke tests of ``rvsm table`` / ``rvsm robustness`` at tiny sizes."""

from __future__ import annotations

import csv

import pytest

from rvsm.model.kernels.receptive_fields import MODEL_NAMES
from rvsm.sim.cli import main
from rvsm.sim.studies.robustness import ROBUST_MODELS


def test_table_cli_tiny(tmp_path):
    out = tmp_path / "table"
    rc = main(["table", "--scenes", "character,flyball", "--size", "24x32", "--frames", "3",
               "--steps-per-frame", "6", "-q", "-o", str(out)])
    assert rc == 0
    for name in ("table.md", "table.csv", "fig6.png"):
        assert (out / name).stat().st_size > 0
    rows = list(csv.DictReader((out / "table.csv").open()))
    assert len(rows) == 2 * 2 * len(MODEL_NAMES)
    md = (out / "table.md").read_text().splitlines()
    header = [c.strip() for c in md[0].strip("|").split("|")]
    assert header == ["Metric", "Method", "character", "character(N)", "flyball", "flyball(N)"]
    body = [line for line in md[2:] if line.startswith("|")]
    assert len(body) == 3 * len(MODEL_NAMES)
    labels = [c.strip() for c in (line.strip("|").split("|")[1] for line in body)]
    assert labels[:9] == ["FSM", "One DoG", "Two DoG", "Three DoG", "Four DoG",
                          "One Gauss", "Two Gauss", "Three Gauss", "Four Gauss"]
    for line in md[2:2 + len(MODEL_NAMES)]:  # at least one bold per column block overall
        assert line.count("|") == len(header) + 1
    assert sum("**" in line for line in body) >= 3


def test_robustness_cli_tiny(tmp_path):
    out = tmp_path / "rob"
    rc = main(["robustness", "--ks", "0,2", "--size", "12x12", "--steps", "300", "-q",
               "-o", str(out)])
    assert rc == 0
    for name in ("robustness.csv", "robustness.json", "fig8.png"):
        assert (out / name).stat().st_size > 0
    rows = list(csv.DictReader((out / "robustness.csv").open()))
    assert len(rows) == 2 * len(ROBUST_MODELS)
    # k = 0: dark current exactly 2 per step, threshold 400 -> FSM fires every 200 steps
    fsm0 = next(r for r in rows if r["model"] == "fsm" and float(r["k"]) == 0)
    assert float(fsm0["asas"]) == pytest.approx(1 / 300)


def test_bad_arguments_are_user_errors(capsys):
    assert main(["table", "--size", "big", "-q"]) == 2
    assert main(["table", "--scenes", "nope", "--size", "24x32", "-q"]) == 2
    assert main(["robustness", "--ks", "a,b", "-q"]) == 2
    assert "rvsm: error:" in capsys.readouterr().err


def test_one_size_syntax_for_every_command(tmp_path, capsys):
    """``H*W`` works for ``rvsm table`` as for ``rvsm simulate`` (one size parser)."""
    assert main(["table", "--scenes", "character", "--size", "24*32", "--frames", "3",
                 "--steps-per-frame", "2", "-q", "-o", str(tmp_path / "t")]) == 0
    assert main(["table", "--size", "6x6", "-q"]) == 2
    assert main(["verilog", str(tmp_path / "p.toml"), "--size", "big"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[0].startswith("rvsm: error: size must be at least 8x8")
    assert err[1].startswith("rvsm: error: bad size 'big'") and len(err) == 2
