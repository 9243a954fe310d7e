"""``rvsm sweep [run] FILE`` and ``rvsm sweep report DB``."""

from __future__ import annotations

from pathlib import Path

from rvsm.sim.cli import main

SWEEP = (Path(__file__).parents[2] / "data" / "small-sweep.toml").read_text()


def test_cli_run_report_and_errors(tmp_path, capsys):
    f = tmp_path / "s.toml"
    f.write_text(SWEEP)
    db = tmp_path / "r.sqlite"
    assert main(["sweep", str(f), "-o", str(db), "--workers", "0", "--no-progress"]) == 0
    assert main(["sweep", "run", str(f), "-o", str(db), "--workers", "0",
                 "--no-progress"]) == 0
    assert "8 already done, 0 computed" in capsys.readouterr().out
    out = tmp_path / "rep"
    assert main(["sweep", "report", str(db), "-o", str(out)]) == 0
    assert {p.name for p in out.iterdir()} >= {"report.md", "pareto.png", "width-cost.png"}
    bad = tmp_path / "bad.toml"
    bad.write_text(SWEEP.replace('"adc.bits"', '"adc.bitz"'))
    assert main(["sweep", str(bad), "-o", str(db)]) == 2
    assert "adc.bitz" in capsys.readouterr().err
    assert main(["sweep", "report", str(tmp_path / "missing.sqlite")]) == 2
