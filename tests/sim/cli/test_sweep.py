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
    # a rate the device cannot meet: one line naming the budgets, exit 2, no report
    rep = tmp_path / "rep-1mhz"
    fits = ["--fits", "ecp5-85", "--camera", "250x400", "--rate-hz", "1000000"]
    assert main(["sweep", "report", str(db), "-o", str(rep), *fits]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "no design meets 250x400 at 1,000,000 Hz" in err[0]
    assert "fmax 250 / 116 MHz (+116 %)" in err[0] and not rep.exists()
    assert main(["sweep", "report", str(db), "-o", str(rep), *fits,
                 "--allow-infeasible"]) == 0
    out_lines = capsys.readouterr().out.splitlines()
    assert "fits ecp5-85: 0 of 4 design(s)" in out_lines
    assert max(len(line) for line in out_lines) < 300
    # a prime width: the only lane counts and the clock each needs
    assert main(["sweep", "report", str(db), "-o", str(rep), "--fits", "ecp5-85",
                 "--camera", "251x401", "--rate-hz", "40000"]) == 2
    assert "401 is prime, so only 1 (4,026.0 MHz), 401 (10.0 MHz)" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text(SWEEP.replace('"adc.bits"', '"adc.bitz"'))
    assert main(["sweep", str(bad), "-o", str(db)]) == 2
    assert "adc.bitz" in capsys.readouterr().err
    assert main(["sweep", "report", str(tmp_path / "missing.sqlite")]) == 2
